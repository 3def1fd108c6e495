"""Each example of examples/python runs to the end (in seconds) and produces its output."""
import os
import re
import subprocess
import sys

import pytest

import seif

# The examples import the same seif as this suite, whatever the working directory.
PACKAGE_PARENT = os.path.dirname(os.path.dirname(os.path.abspath(seif.__file__)))


def run_example(source_dir, name, cwd, *args):
    script = source_dir / "examples" / "python" / name
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=PACKAGE_PARENT)
    proc = subprocess.run([sys.executable, str(script), *map(str, args)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"{name} failed:\n{proc.stdout}\n{proc.stderr}"
    return proc.stdout


def test_own_loop(source_dir, tmp_path):
    out = run_example(source_dir, "own_loop.py", tmp_path)
    m = re.search(r"final pose error ([0-9.]+) m, landmark error mean ([0-9.]+) m over (\d+) landmarks", out)
    assert m, out
    # The driver's loop localises within a fraction of the 2 m circle and maps all 12 landmarks.
    assert float(m.group(1)) < 0.5 and float(m.group(2)) < 0.5
    assert int(m.group(3)) == 12


def test_paper_world(source_dir, tmp_path):
    out = run_example(source_dir, "paper_world.py", tmp_path)
    rows = {line.split()[0]: line.split() for line in out.splitlines() if line.startswith(("ekf ", "seif"))}
    assert set(rows) == {"ekf", "seif", "seif:mean=exact"}
    # The SEIF's H has fewer links than the EKF's dense one.
    assert int(rows["seif"][3]) < int(rows["ekf"][3])


def test_victoria_park(source_dir, victoria_park_isam, tmp_path):
    png = tmp_path / "vp.png"
    out = run_example(source_dir, "victoria_park.py", tmp_path, victoria_park_isam, png)
    assert "wrote" in out
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert png.stat().st_size > 10_000


def test_unknown_association(source_dir, tmp_path):
    out = run_example(source_dir, "unknown_association.py", tmp_path, 400)
    right = re.search(r"([0-9.]+) % associated right", out)
    ceiling = re.search(r"ceiling: ([0-9.]+) % individually, ([0-9.]+) % jointly", out)
    assert right and ceiling, out
    # On the park, clutter and misses included, nearest neighbour is close to the ceiling.
    assert float(ceiling.group(1)) > 98.5
    assert float(right.group(1)) > float(ceiling.group(1)) - 2.0
    # The streamed run (run_filter with the associator) decides as the run loop's hook did.
    first = re.search(r"(\d+) observations, (\d+) with a truth id kept: ([0-9.]+) %", out)
    recorded = re.search(r"recorded (\d+) observations: (\d+) correct, (\d+) wrong, (\d+) in a duplicate", out)
    assert first and recorded, out
    assert recorded.group(1) == first.group(1)
    correct, wrong, duplicate = (int(recorded.group(i)) for i in (2, 3, 4))
    assert correct + wrong + duplicate == int(first.group(2))
    assert abs(100.0 * correct / int(first.group(2)) - float(first.group(3))) < 0.006
