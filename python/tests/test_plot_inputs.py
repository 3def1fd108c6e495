"""scripts/figures/run_map.py (`seif plot`) checks its inputs: a corrupt file of a run folder
stops it with one line `run_map.py: FILE:LINE: what is wrong (found 'TEXT')` and status 2."""
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

from conftest import run_cli


@pytest.fixture(scope="module")
def good_run(tmp_path_factory, source_dir):
    """A small `seif run` folder (SEIF_CLI, else this tree's build/bin/seif) with a gps.csv."""
    pytest.importorskip("matplotlib", reason="run_map.py needs matplotlib")
    cli = pathlib.Path(os.environ.get("SEIF_CLI") or source_dir / "build" / "bin" / "seif")
    if not cli.is_file():
        pytest.skip(f"no seif executable at {cli} (set SEIF_CLI)")
    root = tmp_path_factory.mktemp("plot")
    run_cli(cli, "simulate", "--preset", "paper", "--seed", 1, "--steps", 100, "--out", root / "sim")
    run_cli(cli, "run", "--dataset", root / "sim", "--out", root / "run")
    # GPS fixes: every 10th pose of the trajectory, as `seif run` writes gps.csv
    poses = [line.split() for line in (root / "run" / "trajectory.tum").read_text().splitlines()[1:]]
    (root / "run" / "gps.csv").write_text("time,x,y\n" + "".join(f"{p[0]},{p[1]},{p[2]}\n" for p in poses[::10]))
    return root / "run"


@pytest.fixture(scope="module")
def associated_run(good_run, source_dir, tmp_path_factory):
    """good_run's data run again with nn association: the folder holds associations.csv."""
    cli = pathlib.Path(os.environ.get("SEIF_CLI") or source_dir / "build" / "bin" / "seif")
    root = tmp_path_factory.mktemp("plot-nn")
    run_cli(cli, "run", "--dataset", good_run.parent / "sim", "--association", "nn", "--out", root / "run")
    shutil.copy(good_run / "gps.csv", root / "run" / "gps.csv")
    return root / "run"


def plot(source_dir, run_dir):
    """run_map.py called as `seif plot RUN_DIR` calls it."""
    script = source_dir / "scripts" / "figures" / "run_map.py"
    args = [run_dir / "map.png", "--ellipses", "--gps", run_dir / "gps.csv", run_dir]
    return subprocess.run([sys.executable, str(script), *map(str, args)], capture_output=True, text=True)


def edit(name, line, change):
    """Replaces line `line` (from 1) of file `name` by change(line)."""
    def apply(run_dir):
        lines = (run_dir / name).read_text().split("\n")
        lines[line - 1] = change(lines[line - 1])
        (run_dir / name).write_text("\n".join(lines))
    return apply


def field(i, value, sep=" "):
    return lambda text: sep.join(value if k == i else f for k, f in enumerate(text.split(sep)))


def replace(name, text):
    return lambda run_dir: (run_dir / name).write_text(text)


def copy_field(name, line, source, i, sep):
    """Field i of line `line` set to field i of line `source` (a repeated id)."""
    def apply(run_dir):
        lines = (run_dir / name).read_text().split("\n")
        fields = lines[line - 1].split(sep)
        fields[i] = lines[source - 1].split(sep)[i]
        lines[line - 1] = sep.join(fields)
        (run_dir / name).write_text("\n".join(lines))
    return apply


def raw_bytes(name, line, data):
    """The first field of line `line` replaced by the bytes `data` (not text)."""
    def apply(run_dir):
        lines = (run_dir / name).read_bytes().split(b"\n")
        lines[line - 1] = data + b" " + b" ".join(lines[line - 1].split(b" ")[1:])
        (run_dir / name).write_bytes(b"\n".join(lines))
    return apply


# case: (corruption, file and line the message must name, the text it must quote)
CASES = {
    "trajectory not a number": (edit("trajectory.tum", 5, field(1, "abc")), "trajectory.tum", 5, "abc"),
    "trajectory nan": (edit("trajectory.tum", 5, field(2, "nan")), "trajectory.tum", 5, "nan"),
    "trajectory row of 2 fields": (edit("trajectory.tum", 5, lambda t: " ".join(t.split()[:2])), "trajectory.tum", 5, None),
    "trajectory row of 7 fields": (edit("trajectory.tum", 5, lambda t: " ".join(t.split()[:7])), "trajectory.tum", 5, None),
    "trajectory empty": (replace("trajectory.tum", ""), "trajectory.tum", 1, ""),
    "trajectory time backwards": (copy_field("trajectory.tum", 5, 2, 0, " "), "trajectory.tum", 5, None),
    "trajectory bytes not printable": (raw_bytes("trajectory.tum", 5, b"\x01\xff"), "trajectory.tum", 5, "\\x01\\xff"),
    "dead reckoning not a number": (edit("dead_reckoning.tum", 6, field(3, "abc")), "dead_reckoning.tum", 6, "abc"),
    "map coordinate nan": (edit("map.csv", 4, field(1, "nan", ",")), "map.csv", 4, "nan"),
    "map covariance nan": (edit("map.csv", 4, field(4, "nan", ",")), "map.csv", 4, "nan"),
    "map negative variance": (edit("map.csv", 4, field(5, "-5", ",")), "map.csv", 4, None),
    "map |cov_xy| too large": (edit("map.csv", 4, lambda t: ",".join(t.split(",")[:3] + ["1", "2", "1"])), "map.csv", 4, None),
    "map row of 5 fields": (edit("map.csv", 4, lambda t: ",".join(t.split(",")[:5])), "map.csv", 4, None),
    "map wrong header": (edit("map.csv", 1, lambda t: "foo,bar"), "map.csv", 1, "foo,bar"),
    "map empty": (replace("map.csv", ""), "map.csv", 1, ""),
    "map id repeated": (copy_field("map.csv", 4, 2, 0, ","), "map.csv", 4, None),
    "gps nan": (edit("gps.csv", 3, field(2, "nan", ",")), "gps.csv", 3, "nan"),
    "gps not a number": (edit("gps.csv", 3, field(1, "abc", ",")), "gps.csv", 3, "abc"),
    "gps no fix": (replace("gps.csv", "time,x,y\n"), "gps.csv", 1, ""),
    "ground truth nan": (edit("groundtruth.tum", 4, field(2, "nan")), "groundtruth.tum", 4, "nan"),
    "ground truth empty": (replace("groundtruth.tum", ""), "groundtruth.tum", 1, ""),
    "ground truth time backwards": (copy_field("groundtruth.tum", 5, 2, 0, " "), "groundtruth.tum", 5, None),
    "true landmark id repeated": (copy_field("landmarks_groundtruth.csv", 4, 2, 0, ","), "landmarks_groundtruth.csv", 4, None),
    "true landmark id not an integer": (edit("landmarks_groundtruth.csv", 3, field(0, "6.5", ",")), "landmarks_groundtruth.csv", 3, "6.5"),
    "true landmarks wrong header": (edit("landmarks_groundtruth.csv", 1, lambda t: "id,x"), "landmarks_groundtruth.csv", 1, "id,x"),
    "true landmark not a number": (edit("landmarks_groundtruth.csv", 3, field(2, "y", ",")), "landmarks_groundtruth.csv", 3, "y"),
}


# associations.csv, read when the folder has it: (corruption, line, quoted text)
ASSOCIATION_CASES = {
    "associations wrong header": (edit("associations.csv", 1, lambda t: "step,time"), 1, "step,time"),
    "associations row of 13 fields": (edit("associations.csv", 3, lambda t: ",".join(t.split(",")[:13])), 3, None),
    "associations unknown verdict": (edit("associations.csv", 3, field(13, "maybe", ",")), 3, "maybe"),
    "associations time nan": (edit("associations.csv", 3, field(1, "nan", ",")), 3, "nan"),
    "associations landmark not in the map": (edit("associations.csv", 3, field(11, "99999", ",")), 3, "99999"),
    "associations landmark not a number": (edit("associations.csv", 3, field(11, "x", ",")), 3, "x"),
    "associations verdict without a landmark": (edit("associations.csv", 3, field(11, "", ",")), 3, None),
    "associations time outside the trajectory": (edit("associations.csv", 3, field(1, "1e12", ",")), 3, "1e12"),
    "associations label not an integer": (edit("associations.csv", 3, field(12, "abc", ",")), 3, "abc"),
}


def test_good_folder_is_drawn(good_run, source_dir, tmp_path):
    run_dir = pathlib.Path(shutil.copytree(good_run, tmp_path / "run"))
    assert (run_dir / "groundtruth.tum").is_file() and (run_dir / "landmarks_groundtruth.csv").is_file()
    done = plot(source_dir, run_dir)
    assert done.returncode == 0, done.stderr
    assert (run_dir / "map.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def expect_one_line_error(source_dir, folder, tmp_path, corrupt, name, line, found):
    """`folder` copied, corrupted, then drawn: one line naming `name`:`line`, status 2, no figure."""
    run_dir = pathlib.Path(shutil.copytree(folder, tmp_path / "run"))
    corrupt(run_dir)
    done = plot(source_dir, run_dir)
    assert done.returncode == 2, done.stdout + done.stderr
    assert len(done.stderr.splitlines()) == 1 and "Traceback" not in done.stderr, done.stderr
    assert done.stderr.startswith(f"run_map.py: {run_dir / name}:{line}: "), done.stderr
    if found is not None:
        assert done.stderr.rstrip().endswith(f"(found '{found}')"), done.stderr
    assert not (run_dir / "map.png").exists()


@pytest.mark.parametrize("case", CASES)
def test_corrupt_input_is_one_line_and_exit_2(good_run, source_dir, tmp_path, case):
    expect_one_line_error(source_dir, good_run, tmp_path, *CASES[case])


def test_a_folder_with_associations_is_drawn(associated_run, source_dir, tmp_path):
    run_dir = pathlib.Path(shutil.copytree(associated_run, tmp_path / "run"))
    rows = (run_dir / "associations.csv").read_text().splitlines()
    assert len(rows) > 100 and any(r.endswith(",correct") for r in rows)
    done = plot(source_dir, run_dir)
    assert done.returncode == 0, done.stderr
    assert (run_dir / "map.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("case", ASSOCIATION_CASES)
def test_corrupt_associations_are_one_line_and_exit_2(associated_run, source_dir, tmp_path, case):
    corrupt, line, found = ASSOCIATION_CASES[case]
    expect_one_line_error(source_dir, associated_run, tmp_path, corrupt, "associations.csv", line, found)


def first_scored(run_dir, verdict):
    """The line number (from 1) and fields of associations.csv's first row with `verdict`."""
    lines = (run_dir / "associations.csv").read_text().split("\n")
    for n, line in enumerate(lines, 1):
        if line.endswith("," + verdict):
            return n, line.split(",")
    pytest.fail(f"no row with the verdict {verdict}")


@pytest.mark.parametrize("verdict,label", [("correct", ""), ("correct", "other"), ("wrong", "truth")])
def test_a_verdict_the_label_contradicts_is_refused(associated_run, source_dir, tmp_path, verdict, label):
    """A scored row's landmark has a label: equal to the truth when correct, else not."""
    n, fields = first_scored(associated_run, verdict)
    truth = fields[5]
    value = {"": "", "other": str(int(truth) + 1000), "truth": truth}[label]
    expect_one_line_error(source_dir, associated_run, tmp_path, edit("associations.csv", n, field(12, value, ",")),
                          "associations.csv", n, None)


@pytest.mark.parametrize("name", ["associations.csv", "groundtruth.tum", "landmarks_groundtruth.csv"])
@pytest.mark.parametrize("link", ["loop", "dangling"])
def test_a_broken_link_is_named_not_skipped(associated_run, source_dir, tmp_path, name, link):
    """A symbolic-link loop or a dangling link in place of an optional file is an error."""
    def corrupt(run_dir):
        (run_dir / name).unlink()
        os.symlink(name if link == "loop" else "nowhere", run_dir / name)
    expect_one_line_error(source_dir, associated_run, tmp_path, corrupt, name, 0, None)


def test_a_folder_with_associations_and_no_gps_is_aligned_to_the_ground_truth(associated_run, source_dir, tmp_path):
    run_dir = pathlib.Path(shutil.copytree(associated_run, tmp_path / "run"))
    (run_dir / "gps.csv").unlink()
    script = source_dir / "scripts" / "figures" / "run_map.py"
    done = subprocess.run([sys.executable, str(script), str(run_dir / "map.png"), str(run_dir)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert (run_dir / "map.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
