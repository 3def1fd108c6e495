"""The same run from Python (run_dataset) and from the CLI (`seif run`) writes the same
files, and metrics.json holds the same values (timings and the command line aside)."""
import importlib.util
import json
import pathlib

import numpy as np
import pytest

import seif
from conftest import run_cli

# metrics.json keys that legitimately differ between two runs.
def as_written(values):
    """The values as the result files print them (%.9g), read back."""
    return np.vectorize(lambda v: float(f"{v:.9g}"))(np.asarray(values, dtype=float))


# The CLI and the library share --beta = SeifOptions.beta = 4; the CLI is
# pinned to the library's default so that both runs use the same options.
LIBRARY_BETA = ["--beta", str(seif.SeifOptions().beta)]

VOLATILE = {"seconds", "seconds_wall", "seconds_trajectory_and_map", "us_per_step", "us_per_step_median",
            "command_line"}


def compare_outputs(cli_dir, py_dir):
    for name in ("trajectory.tum", "dead_reckoning.tum", "map.csv"):
        assert (cli_dir / name).read_bytes() == (py_dir / name).read_bytes(), name
    cli_metrics = json.loads((cli_dir / "metrics.json").read_text())
    py_metrics = json.loads((py_dir / "metrics.json").read_text())
    assert cli_metrics.keys() == py_metrics.keys()
    for key in cli_metrics.keys() - VOLATILE:
        assert cli_metrics[key] == py_metrics[key], key
    return py_metrics


@pytest.mark.parametrize("spec", ["seif", "ekf", "seif:sparsify=eseif"])
def test_simulated_folder_python_equals_cli(cli, simulated_folder, tmp_path, spec):
    cli_dir, py_dir = tmp_path / "cli", tmp_path / "py"
    cli_dir.mkdir()
    py_dir.mkdir()
    run_cli(cli, "run", "--dataset", simulated_folder, "--filter", spec, "--out", cli_dir, *LIBRARY_BETA)

    fractions = []
    request = seif.RunRequest(str(simulated_folder), spec)
    report = seif.run_dataset(request, str(py_dir), progress=fractions.append)
    metrics = compare_outputs(cli_dir, py_dir)

    # The report holds what metrics.json says.
    assert report.output.steps == metrics["steps"] > 0
    assert report.landmarks == metrics["landmarks"]
    assert report.errors.ate == metrics["ate_rmse"]
    assert report.errors.landmark == metrics["landmark_rmse"]
    assert report.info.format == "mrclam"
    # The progress callback ran (with the GIL re-acquired) and ended at 1.
    assert fractions and fractions[-1] == pytest.approx(1.0)
    assert all(0.0 <= f <= 1.0 for f in fractions)
    # trajectory.tum = the report's trajectory (x, y columns).
    tum = seif.read_tum(py_dir / "trajectory.tum")
    np.testing.assert_array_equal(tum[:, 1:3], as_written(report.output.trajectory_array()[:, 1:3]))


def test_run_summary_is_what_seif_run_prints(cli, simulated_folder, tmp_path):
    """seif.run_summary gives the report `seif run` prints, its timings aside."""
    import re
    out = tmp_path / "out"
    out.mkdir()
    printed = run_cli(cli, "run", "--dataset", simulated_folder, "--filter", "ekf", "--out", out).stdout
    request = seif.RunRequest(str(simulated_folder), "ekf")
    text = seif.run_summary(request, seif.run_dataset(request, str(tmp_path)), str(out))

    def untimed(report):
        lines = [line for line in report.splitlines() if not line.startswith("  time:")]
        return [re.sub(r"[0-9.]+ us/step", "us/step", line) for line in lines]

    assert "landmark RMSE" in text and f"wrote {out}/" in text
    assert untimed(text) == untimed(printed)


def test_stream_through_python_equals_cli_trajectory(cli, simulated_folder, tmp_path):
    """Events read in Python, steps assembled and filtered in Python = the CLI's trajectory."""
    run_cli(cli, "run", "--dataset", simulated_folder, "--filter", "seif", "--out", tmp_path)
    source = seif.open_dataset(simulated_folder)
    f = seif.make_filter("seif", source.info.start_pose, source.info.filter_config())
    out = seif.run_filter(f, source)
    tum = seif.read_tum(tmp_path / "trajectory.tum")
    ours = out.trajectory_array()
    assert tum.shape[0] == ours.shape[0]
    np.testing.assert_array_equal(tum[:, 1:3], as_written(ours[:, 1:3]))
    np.testing.assert_allclose(tum[:, 0], ours[:, 0], rtol=0, atol=5e-7)  # %.6f stamps
    cli_map = seif.read_map_csv(tmp_path / "map.csv")
    assert list(cli_map["id"].astype(int)) == f.landmark_ids()
    for row in cli_map:
        np.testing.assert_array_equal([row["x"], row["y"]], as_written(f.landmark(int(row["id"]))))


def test_victoria_park_isam_python_equals_cli(cli, victoria_park_isam, tmp_path):
    cli_dir, py_dir = tmp_path / "cli", tmp_path / "py"
    cli_dir.mkdir()
    py_dir.mkdir()
    run_cli(cli, "run", "--dataset", victoria_park_isam, "--filter", "seif", "--out", cli_dir, *LIBRARY_BETA)
    report = seif.run(victoria_park_isam, py_dir, filter="seif")
    compare_outputs(cli_dir, py_dir)
    assert report.info.format == "isam"
    assert report.landmarks > 0


def _without_machine_keys(value):
    """JSON without what measures the machine or names the invocation (timings, threads)."""
    machine = ("seconds", "us_per", "jobs", "command_line", "version", "time_definition", "time_unit")
    if isinstance(value, dict):
        return {k: _without_machine_keys(v) for k, v in value.items() if not any(m in k for m in machine)}
    if isinstance(value, list):
        return [_without_machine_keys(v) for v in value]
    return value


def test_paper_python_equals_cli(cli, tmp_path):
    """`seif paper` and seif.run_paper + PaperReport.write: the same numbers in every file."""
    cli_dir, py_dir = tmp_path / "cli", tmp_path / "py"
    run_cli(cli, "paper", "--runs", 3, "--seed", 5, "--jobs", 2, "--filters", "seif:sparsify=eseif",
            "--no-figures", "--out", cli_dir)
    request = seif.PaperRequest()
    request.runs, request.seed, request.jobs = 3, 5, 1  # results do not depend on the threads
    request.options.extra = ["seif:sparsify=eseif"]
    done = []
    report = seif.run_paper(request, progress=lambda d, t: done.append((d, t)))
    assert done[-1] == (3, 3)
    assert [r.seed for r in report.runs] == [5, 6, 7] and not report.failed
    report.write(str(py_dir))
    written = sorted(p.relative_to(cli_dir) for p in cli_dir.rglob("*.json"))
    assert written == sorted(p.relative_to(py_dir) for p in py_dir.rglob("*.json"))
    assert pathlib.Path("results.json") in written
    for name in written:
        cli_json = _without_machine_keys(json.loads((cli_dir / name).read_text()))
        py_json = _without_machine_keys(json.loads((py_dir / name).read_text()))
        assert cli_json == py_json, name
    results = json.loads((py_dir / "results.json").read_text())
    assert "ekf" in report.summary_text()
    assert any(f.get("filter_spec") == seif.canonical_filter_spec(seif.parse_filter_spec("seif:sparsify=eseif"))
               for f in results["filters"])


def test_smooth_python_equals_cli(cli, simulated_folder, tmp_path):
    """`seif run --smooth` and RunRequest.smooth: the same smoothed and filtered outputs, the same solve."""
    cli_dir, py_dir = tmp_path / "cli", tmp_path / "py"
    cli_dir.mkdir()
    py_dir.mkdir()
    run_cli(cli, "run", "--dataset", simulated_folder, "--filter", "seif", "--smooth", "--out", cli_dir, *LIBRARY_BETA)
    request = seif.RunRequest(str(simulated_folder), "seif")
    request.smooth = True
    report = seif.run_dataset(request, str(py_dir))
    for name in ("trajectory.tum", "map.csv", "trajectory_filter.tum", "map_filter.csv"):
        assert (cli_dir / name).read_bytes() == (py_dir / name).read_bytes(), name
    cli_metrics = json.loads((cli_dir / "metrics.json").read_text())
    py_metrics = json.loads((py_dir / "metrics.json").read_text())
    for key in ("init", "poses", "constraints", "iterations", "costs", "final_cost", "converged"):
        assert cli_metrics["batch"][key] == py_metrics["batch"][key], key
    assert cli_metrics["filter_before_smoothing"] == py_metrics["filter_before_smoothing"]
    assert report.smoother.init == "seif"
    assert report.smoother.final_cost == py_metrics["batch"]["final_cost"] < report.smoother.initial_cost
    assert report.filter_map_distance == py_metrics["filter_before_smoothing"]["map_distance_to_batch"] > 0
    ratio = py_metrics["filter_before_smoothing"]["landmark_covariance_ratio_to_batch"]
    assert list(report.filter_covariance_ratio) == [ratio["median"], ratio["p10"], ratio["p90"]]
    assert 0 < ratio["p10"] <= ratio["median"] <= ratio["p90"]
    assert report.filter_errors.ate == py_metrics["filter_before_smoothing"]["ate_rmse"]
    assert len(report.output.filter_trajectory) == len(report.output.trajectory)
    # The trajectory's distance from the batch's, against the two written trajectories.
    tum_batch = np.loadtxt(py_dir / "trajectory.tum", comments="#")
    tum_filter = np.loadtxt(py_dir / "trajectory_filter.tum", comments="#")
    gaps = np.linalg.norm(tum_filter[:, 1:3] - tum_batch[:, 1:3], axis=1)
    rms, median = report.filter_trajectory_distance
    assert [rms, median] == [py_metrics["filter_before_smoothing"]["trajectory_distance_to_batch"][k] for k in ("rms", "median")]
    assert rms == pytest.approx(np.sqrt(np.mean(gaps**2)), rel=1e-5, abs=1e-6) and rms > 0
    assert median == pytest.approx(np.median(gaps), rel=1e-5, abs=1e-6)


def test_convert_python_equals_cli(cli, victoria_park_isam, tmp_path):
    """seif.convert_dataset writes the bytes `seif convert` writes, both ways."""
    run_cli(cli, "convert", victoria_park_isam, "--to", "g2o", "--out", tmp_path / "cli.g2o")
    seif.convert_dataset(victoria_park_isam, tmp_path / "py.g2o", "g2o")
    assert (tmp_path / "cli.g2o").read_bytes() == (tmp_path / "py.g2o").read_bytes()
    run_cli(cli, "convert", tmp_path / "cli.g2o", "--to", "isam", "--out", tmp_path / "cli.txt")
    seif.convert_dataset(tmp_path / "py.g2o", tmp_path / "py.txt", seif.GraphFormat.Isam, input_format="g2o")
    assert (tmp_path / "cli.txt").read_bytes() == (tmp_path / "py.txt").read_bytes()
    with pytest.raises(seif.InvalidArgument, match="expected isam or g2o"):
        seif.GraphFormat("tum")


def test_consistency_results_python_equal_cli(cli, tmp_path):
    """write_consistency_results writes the nees.csv and table.md of `seif consistency`."""
    run_cli(cli, "consistency", "--preset", "paper", "--landmarks", "20", "--steps", "60", "--runs", "2",
            "--samples", "4", "--filters", "ekf,seif", "--no-figures", "--out", tmp_path / "cli")
    options = seif.ConsistencyOptions()
    options.world = seif.preset_config("paper", 20, 60, 1)
    options.runs = 2
    options.samples = 4
    options.filters = [seif.parse_filter_spec("ekf"), seif.parse_filter_spec("seif")]
    result = seif.run_consistency(options)
    (tmp_path / "py").mkdir()
    seif.write_consistency_results(result, options, tmp_path / "py")
    for name in ("nees.csv", "table.md"):
        assert (tmp_path / "cli" / name).read_text() == (tmp_path / "py" / name).read_text(), name
    assert seif.consistency_csv(result) == (tmp_path / "py" / "nees.csv").read_text()
    assert json.loads((tmp_path / "py" / "nees.json").read_text())["runs"] == 2
    if importlib.util.find_spec("matplotlib"):
        seif.render_figure("consistency", tmp_path / "py")
        assert (tmp_path / "py" / "nees_global.png").read_bytes()[:4] == b"\x89PNG"


def test_bench_study_python_equals_cli(cli, tmp_path):
    """run_bench is `seif bench`: the same cases, steps and map sizes (the times are measured anew)."""
    run_cli(cli, "bench", "--filters", "ekf,seif", "--landmarks", "100,200", "--window", "20", "--repeat", "1",
            "--out", tmp_path)
    cli_report = json.loads((tmp_path / "bench.json").read_text())
    request = seif.BenchRequest()
    request.filters = ["ekf", "seif"]
    request.landmarks = [100, 200]
    request.window = 20
    request.repeat = 1
    rows = []
    report = seif.run_bench(request, rows.append)
    assert [(r.filter, r.landmarks) for r in rows] == [(r.filter, r.landmarks) for r in report.rows]
    py_report = json.loads(report.json())
    assert py_report.keys() == cli_report.keys()
    shape = lambda rs: [(r["filter"], r["landmarks"], r.get("steps"), r.get("map_last")) for r in rs["results"]]
    assert shape(py_report) == shape(cli_report)
    assert all(r.measurement is not None and r.measurement.us_per_step_median > 0 for r in report.rows)
    assert report.targets.seif_growth is not None
    # The table `seif bench` prints, in the same layout (the times are measured anew).
    text = report.summary_text()
    assert text.splitlines()[0].split() == ["filter", "N", "mapped", "steps", "median", "us", "p90", "us", "peak",
                                            "MB", "filter", "MB", "B/landmark"]
    assert len(text.splitlines()) >= 1 + len(report.rows) and "SEIF median at N=200 / at N=100" in text
    printed = run_cli(cli, "bench", "--filters", "ekf,seif", "--landmarks", "100,200", "--window", "20", "--repeat",
                      "1", "--no-figure", "--out", tmp_path / "again").stdout
    assert text.splitlines()[0] in printed.splitlines()
    if importlib.util.find_spec("matplotlib"):
        (tmp_path / "py.json").write_text(report.json())
        seif.render_figure("bench", tmp_path / "py.json", tmp_path / "py.png")
        assert (tmp_path / "py.png").read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(seif.InvalidArgument, match="unknown figure"):
        seif.render_figure("pie")
    request.repeat = 0
    with pytest.raises(seif.InvalidArgument, match="repeat must be >= 1"):
        seif.run_bench(request)


def test_a_bench_case_shorter_than_its_window_repeats_a_bounded_number_of_times():
    """A 50-landmark corridor times 25 steps: a window of 10^5 would repeat it 4000 times; at
    most 20 times as often as asked, and no more once the case has used its time budget."""
    request = seif.BenchRequest()
    request.filters = ["seif"]
    request.landmarks = [50]
    request.window = 100000
    request.repeat = 1
    report = seif.run_bench(request)
    assert report.rows[0].measurement is not None
    medians = json.loads(report.json())["results"][0]["repeat_medians"]
    assert 1 < len(medians) <= 20
    request.max_seconds = 1e-3
    medians = json.loads(seif.run_bench(request).json())["results"][0]["repeat_medians"]
    assert len(medians) == 1


def test_plot_run_draws_what_seif_plot_draws(cli, simulated_folder, tmp_path):
    pytest.importorskip("matplotlib")
    run_cli(cli, "run", "--dataset", simulated_folder, "--filter", "seif", "--out", tmp_path)
    png = seif.plot_run(tmp_path, title="from Python")
    assert png == tmp_path / "map.png" and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(seif.DataError, match="map.csv") as e:
        (tmp_path / "map.csv").unlink()
        seif.plot_run(tmp_path)
    assert e.value.file == str(tmp_path / "map.csv")
