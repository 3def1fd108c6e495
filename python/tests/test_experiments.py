"""The experiments' library entry points from Python (GIL released, callbacks re-acquire)."""
import json
import math
import os
import signal
import threading
import time

import numpy as np
import pytest

import seif


def test_paper_experiment_is_deterministic_and_matches_its_filters():
    options = seif.PaperOptions()
    options.steps = 120
    options.extra = ["eif"]
    names = [f.name for f in seif.paper_filters(options)]
    a = seif.run_paper_experiment(4, options)
    b = seif.run_paper_experiment(4, options)
    assert [r.name for r in a.filters] == names
    assert [r.mse for r in a.filters] == [r.mse for r in b.filters]
    assert all(r.mapped > 0 and r.mse >= r.aligned_mse for r in a.filters)
    summary = seif.summarize_paper_filter(0, [a, b])
    assert summary.name == names[0] and summary.error.n == 2


def test_paper_detail_filters_reproduce_the_run():
    options = seif.PaperOptions()
    options.steps = 80
    run, detail = seif.run_paper_experiment_detail(2, options)
    ekf = detail.filters[0]
    assert ekf.name == "ekf"
    world = seif.paper_world(2, options)
    mse, count = seif.landmark_mse(ekf, world_truth(world))
    assert count == run.filters[0].mapped
    assert mse == run.filters[0].mse
    # The same EKF rebuilt and stepped from Python gives the same map.
    config = seif.paper_filter_config(world.noise)
    mine = seif.make_filter("ekf", seif.start_pose(detail.data), config)
    for step in detail.data.steps:
        mine.step(step.u, step.observations)
    np.testing.assert_array_equal(mine.mean(), ekf.mean())
    snap = seif.snapshot_by_id(ekf)
    assert snap.ids == sorted(ekf.landmark_ids())


def world_truth(world):
    return seif.simulate(world).landmarks


def test_consistency_runs_on_threads_with_a_progress_callback():
    options = seif.ConsistencyOptions()
    options.world = seif.preset_config("paper", 20, 60, 1)
    options.runs = 3
    options.samples = 4
    options.threads = 2
    options.filters = [seif.parse_filter_spec("ekf"), seif.parse_filter_spec("seif")]
    calls, threads = [], set()

    def progress(done, total):
        calls.append((done, total))
        threads.add(threading.get_ident())

    result = seif.run_consistency(options, progress)
    assert result.runs == 3 and [f.name for f in result.filters] == ["ekf", "seif"]
    assert sorted(calls)[-1] == (3, 3)
    assert len(result.sample_steps) == 4
    assert result.pose_band.lo < 3 < result.pose_band.hi
    report = json.loads(seif.consistency_json(result, options))
    assert report["runs"] == 3
    assert "ekf" in seif.consistency_table(result)
    # Per-run errors, paired across filters: the ratio of their means.
    ekf, sf = result.filters
    assert len(ekf.mse_runs) == 3 and abs(sum(ekf.mse_runs) / 3 - ekf.mse_final) < 1e-15
    r = seif.paired_ratio(sf.mse_runs, ekf.mse_runs)
    assert r.pairs == 3 and abs(r.ratio - sf.mse_final / ekf.mse_final) < 1e-12 and r.ci95 > 0
    options.posterior_mean = True
    result = seif.run_consistency(options)
    assert [(f.name, f.spec, f.posterior_mean) for f in result.filters] == [
        ("ekf", 0, False), ("seif", 1, False), ("seif [posterior mean]", 1, True)]
    assert all(not f.failed_runs for f in result.filters)
    # A filter that diverges is listed with its runs; the study goes on.
    options.posterior_mean = False
    options.world = seif.preset_config("paper", 20, 120, 5)
    options.filters = [seif.parse_filter_spec("ekf"), seif.parse_filter_spec("seif:sparsify=conservative,active=2")]
    result = seif.run_consistency(options)
    assert not result.filters[0].failed_runs
    stopped = result.filters[1].failed_runs
    assert stopped and all(f.run in ("seed 5", "seed 6", "seed 7") for f in stopped)
    assert "conservative sparsification" in stopped[0].error
    assert sum(math.isnan(v) for v in result.filters[1].landmark_nees_runs) == len(stopped)


def test_ctrl_c_stops_a_consistency_study_and_keeps_the_runs_it_finished():
    """SIGINT while the study runs (sent here from the progress callback after two runs, one
    thread): KeyboardInterrupt, whose .result summarises the runs finished as a study of those
    alone would. Python's own handler is back afterwards."""
    options = seif.ConsistencyOptions()
    options.world = seif.preset_config("paper", 20, 60, 1)
    options.runs = 50
    options.samples = 4
    options.threads = 1
    options.filters = [seif.parse_filter_spec("ekf")]

    def ctrl_c_after_two(done, total):
        if done == 2:
            os.kill(os.getpid(), signal.SIGINT)

    before = signal.getsignal(signal.SIGINT)
    with pytest.raises(KeyboardInterrupt, match="2 of 50 runs finished") as stopped:
        seif.run_consistency(options, ctrl_c_after_two)
    assert signal.getsignal(signal.SIGINT) is before
    partial = stopped.value.result
    assert partial.interrupted and partial.runs == 2 and partial.runs_requested == 50
    assert partial.run_names == ["seed 1", "seed 2"]
    options.runs = 2
    whole = seif.run_consistency(options)
    assert not whole.interrupted
    assert partial.filters[0].mse_runs == whole.filters[0].mse_runs
    assert json.loads(seif.consistency_json(partial, options))["interrupted"] is True
    # From another thread the study leaves SIGINT to Python: Python's handler (here one that
    # records it) runs on the main thread, and the study runs to its end.
    seen, caught = {}, []

    def ctrl_c_after_one(done, total):
        if done == 1:
            os.kill(os.getpid(), signal.SIGINT)

    signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        worker = threading.Thread(target=lambda: seen.update(result=seif.run_consistency(options, ctrl_c_after_one)))
        worker.start()
        worker.join()
        deadline = time.monotonic() + 10
        while not caught and time.monotonic() < deadline:  # should the handler not have run yet
            time.sleep(0.01)
    finally:
        signal.signal(signal.SIGINT, before)
    assert caught == [signal.SIGINT]
    assert seen["result"].runs == 2 and not seen["result"].interrupted


def test_ctrl_c_stops_the_paper_study_and_keeps_the_runs_that_ran():
    request = seif.PaperRequest()
    request.runs = 20
    request.jobs = 1
    request.options.steps = 60

    def ctrl_c_after_two(done, total):
        if done == 2:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(KeyboardInterrupt, match="2 of 20 runs ran") as stopped:
        seif.run_paper(request, ctrl_c_after_two)
    report = stopped.value.result
    assert report.interrupted and len(report.runs) == 2
    assert "Interrupted: 2 of 20 runs ran" in report.summary_text()


def test_ctrl_c_stops_a_bench_study_before_its_next_case():
    request = seif.BenchRequest()
    request.filters = ["ekf"]
    request.landmarks = [100, 150, 200]
    request.window = 10
    request.repeat = 1
    rows = []

    def ctrl_c_after_the_first(row):
        rows.append(row)
        os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(KeyboardInterrupt, match="after 1 case ") as stopped:
        seif.run_bench(request, ctrl_c_after_the_first)
    report = stopped.value.result
    assert report.interrupted and [r.landmarks for r in report.rows] == [100] == [r.landmarks for r in rows]
    assert json.loads(report.json())["interrupted"] is True


def test_bench_case_and_cost_model():
    case = seif.BenchCase()
    case.filter = "seif"
    case.landmarks = 60
    case.window = 10
    m = seif.run_bench_case(case)
    assert m.filter == "seif" and m.steps == 10 and m.map_last > 0
    assert m.us_per_step_median > 0
    assert seif.step_cost_exponent("ekf") == 2
    assert seif.quantile([1.0, 2.0, 3.0], 0.5) == 2.0


def test_stats_helpers():
    s = seif.summarize([1.0, 2.0, 3.0, 4.0])
    assert s.n == 4 and s.mean == 2.5 and s.median == 2.5
    band = seif.nees_band95(50, 2)
    assert band.lo < 2 < band.hi
    # x = 2 y exactly: ratio 2, no spread; a NaN pair is left out.
    r = seif.paired_ratio([2.0, 4.0, float("nan"), 1.0], [1.0, 2.0, 3.0, None])
    assert r.ratio == 2.0 and r.ci95 == 0.0 and r.pairs == 2
    with pytest.raises(seif.InvalidArgument):
        seif.paired_ratio([1.0], [1.0, 2.0])


def test_gps_jumps_and_rmse():
    # A fix every 0.2 s at 2 m/s, one 100 m off: a jump, and the RMSE without it is zero.
    trajectory = [seif.TimedPose(0.2 * k, [0.4 * k, 0.0, 0.0]) for k in range(51)]
    gps = [seif.GpsFix(0.2 * k, [0.4 * k, 100.0 if k == 25 else 0.0]) for k in range(51)]
    jumps = seif.gps_jumps(gps)
    assert [k for k, j in enumerate(jumps) if j] == [25]
    rmse, compared, median = seif.gps_rmse(trajectory, gps)
    assert compared == 51 and rmse > 5.0 and median < rmse / 5
    kept = [g for g, j in zip(gps, jumps) if not j]
    assert seif.gps_rmse(trajectory, kept)[0] < 1e-9
