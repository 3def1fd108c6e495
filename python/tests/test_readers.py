"""Readers (open_dataset) and the simulator through Python, checked against the files."""
import collections

import numpy as np
import pytest

import seif


def test_simulated_folder_events_match_the_log(simulated_folder):
    log = seif.read_mrclam(simulated_folder)
    source = seif.open_dataset(simulated_folder, "auto")
    info = source.info
    assert info.format == "mrclam"
    assert info.has_groundtruth
    assert set(info.landmarks) == set(log.landmarks)
    assert isinstance(info.motion, seif.VelocityModel)
    assert isinstance(info.sensor, seif.RangeBearingModel)
    kinds = collections.Counter()
    observed = 0
    for event in source:
        kinds[type(event).__name__] += 1
        if isinstance(event, seif.ObservationEvent):
            observed += len(event.observations)
            assert all(isinstance(z, seif.Observation) for z in event.observations)
        elif isinstance(event, seif.ControlEvent):
            assert isinstance(event.input, seif.VelocityControl)
    assert kinds["ControlEvent"] == len(log.odometry)
    assert kinds["TimedPose"] == len(log.groundtruth)
    assert observed == len(log.measurements)
    assert source.progress() == pytest.approx(1.0)


def test_simulator_is_deterministic_and_round_trips(tmp_path):
    config = seif.preset_config(seif.WorldPreset.Paper, 20, 50, 3)
    a, stats = seif.simulate_with_stats(config)
    b = seif.simulate(config)
    assert [(r.time, r.v, r.w) for r in a.odometry] == [(r.time, r.v, r.w) for r in b.odometry]
    assert stats.measurements == len(a.measurements)
    seif.write_mrclam(tmp_path, a)
    back = seif.read_mrclam(tmp_path)
    assert [(m.time, m.subject, m.range, m.bearing) for m in back.measurements] == \
        [(m.time, m.subject, m.range, m.bearing) for m in a.measurements]
    data = seif.build_dataset(a)
    assert len(data) > 0 and data.landmarks.keys() == a.landmarks.keys()


def test_victoria_park_isam_counts(victoria_park_isam):
    counts = collections.Counter(line.split()[0] for line in victoria_park_isam.read_text().splitlines() if line.strip())
    source = seif.open_dataset(str(victoria_park_isam))
    assert source.info.format == "isam"
    controls = observations = 0
    for event in source:
        if isinstance(event, seif.ControlEvent):
            controls += 1
            assert isinstance(event.input, seif.OdometryIncrement)
        elif isinstance(event, seif.ObservationEvent):
            observations += len(event.observations)
    assert controls == counts["ODOMETRY"]
    assert observations == counts["LANDMARK"]


def test_robot_log_source_runs_like_the_dataset():
    config = seif.preset_config("paper", 0, 120, 5)
    log = seif.simulate(config)
    source = seif.RobotLogSource(log, config.noise)
    f = seif.make_filter("seif", source.info.start_pose, source.info.filter_config())
    out = seif.run_filter(f, source)
    g = seif.make_filter("seif", source.info.start_pose, source.info.filter_config())
    data = seif.build_dataset(log)
    seif.run_filter(g, data)
    assert out.steps == len(data)
    np.testing.assert_array_equal(f.mean(), g.mean())
