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


def _env_path(name):
    value = os.environ.get(name)
    return pathlib.Path(value) if value else None


@pytest.fixture(scope="session")
def cli():
    """Path of the `seif` executable (SEIF_CLI)."""
    path = _env_path("SEIF_CLI")
    if path is None or not path.exists():
        pytest.skip("SEIF_CLI does not name the seif executable (run through ctest, or set it)")
    return path


@pytest.fixture(scope="session")
def shared_data():
    """The shared data folder (SEIF_SHARED_DATA_DIR)."""
    path = _env_path("SEIF_SHARED_DATA_DIR")
    if path is None or not path.is_dir():
        pytest.skip("SEIF_SHARED_DATA_DIR is not set or not a folder: no shared data")
    return path


@pytest.fixture(scope="session")
def victoria_park_isam(shared_data):
    path = shared_data / "victoria-park-isam" / "victoria_park.txt"
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    return path


@pytest.fixture(scope="session")
def source_dir():
    path = _env_path("SEIF_SOURCE_DIR")
    if path is None:
        path = pathlib.Path(__file__).resolve().parents[2]
    return path


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
    config = seif.FilterConfig()
    config.noise = world.noise
    return config
