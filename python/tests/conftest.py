"""Shared fixtures of the Python suite (run by CTest as `python_tests`).

Environment (set by python/CMakeLists.txt): PYTHONPATH = the build's python dir,
SEIF_CLI = the seif executable of the same build, SEIF_SHARED_DATA_DIR = ../shared/data,
SEIF_SOURCE_DIR = the source tree. Tests that need a missing one skip, saying which.
"""
import os
import pathlib
import subprocess

import pytest

import seif


def _env_path(name, exists, what):
    """The path in environment variable `name`, or a skip saying why there is none."""
    value = os.environ.get(name)
    path = pathlib.Path(value) if value else None
    if path is None or not exists(path):
        pytest.skip(f"{name} does not name {what} (run through ctest, or set it)")
    return path


@pytest.fixture(scope="session")
def cli():
    """Path of the `seif` executable (SEIF_CLI)."""
    return _env_path("SEIF_CLI", pathlib.Path.is_file, "the seif executable")


@pytest.fixture(scope="session")
def shared_data():
    """The shared data folder (SEIF_SHARED_DATA_DIR)."""
    return _env_path("SEIF_SHARED_DATA_DIR", pathlib.Path.is_dir, "the shared data folder")


@pytest.fixture(scope="session")
def victoria_park_isam(shared_data):
    path = shared_data / "victoria-park-isam" / "victoria_park.txt"
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    return path


@pytest.fixture(scope="session")
def source_dir():
    """The source tree: SEIF_SOURCE_DIR, else the one holding this file."""
    value = os.environ.get("SEIF_SOURCE_DIR")
    return pathlib.Path(value) if value else pathlib.Path(__file__).resolve().parents[2]


def run_cli(cli, *args, check=True):
    """Runs the CLI; returns the CompletedProcess (text)."""
    proc = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True)
    if check and proc.returncode != 0:
        raise AssertionError(f"seif {' '.join(map(str, args))} failed ({proc.returncode}):\n{proc.stderr}")
    return proc


@pytest.fixture(scope="session")
def simulated_folder(tmp_path_factory):
    """A small paper world (200 steps) written as an MRCLAM folder by the library
    (the same writer `seif simulate` uses)."""
    folder = tmp_path_factory.mktemp("sim") / "paper"
    config = seif.preset_config("paper", 0, 200, 7)
    seif.write_mrclam(folder, seif.simulate(config))
    return folder


def paper_config(world):
    """The FilterConfig of a simulated world: its true noise, the paper's models."""
    return seif.paper_filter_config(world.noise)
