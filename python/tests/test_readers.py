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


def test_raw_victoria_park_detections_and_their_truth(tmp_path):
    (tmp_path / "controls.txt").write_text("1.0 2.0 0.1\n2.0 2.0 0.1\n")
    (tmp_path / "tree_detections.txt").write_text("1.5 0 10.0 1.5 0.3\n1.5 0 20.0 3.141593 0.2\n")
    (tmp_path / "tree_observations_associated_UTS.txt").write_text("1.5 10.0 1.5 7 0 0\n")
    options = seif.DatasetOptions()
    assert options.detections == seif.Detections.Associated
    options.detections = "raw"
    assert "detections" in repr(options)
    scans = [e for e in seif.open_dataset(str(tmp_path), "auto", options) if isinstance(e, seif.ObservationEvent)]
    z = scans[0].observations
    assert [o.landmark for o in z] == [seif.UNKNOWN_LANDMARK] * 2
    assert [o.truth for o in z] == [7, seif.UNKNOWN_LANDMARK]
    assert z[1].z[1] == pytest.approx(np.pi / 2, abs=0)
    associated = [e for e in seif.open_dataset(str(tmp_path)) if isinstance(e, seif.ObservationEvent)]
    assert [(o.landmark, o.truth) for o in associated[0].observations] == [(7, 7)]
    with pytest.raises(seif.InvalidArgument):
        seif.open_dataset(str(tmp_path), "mrclam", options)


def test_simulator_clutter_and_missed_detections():
    config = seif.preset_config("paper", 0, 200, 4)
    assert (config.clutter, config.detection_probability) == (0.0, 1.0)
    config.clutter = 1.0
    config.detection_probability = 0.9
    assert "clutter" in repr(config)
    log, stats = seif.simulate_with_stats(config)
    clutter = [m for m in log.measurements if m.subject == seif.CLUTTER_SUBJECT]
    assert len(clutter) == stats.clutter > 100
    assert stats.missed_detections > 0
    truths = [(z.landmark, z.truth) for step in seif.build_dataset(log).steps for z in step.observations]
    assert sum(1 for lm, t in truths if t == seif.UNKNOWN_LANDMARK and lm == seif.UNKNOWN_LANDMARK) == len(clutter)
    assert all(lm == t for lm, t in truths)


def test_run_loop_streams_a_source_with_its_ground_truth(simulated_folder):
    """run_loop over an EventSource: the same trajectory as run_filter on the same folder, and
    the observers get the ground truth the stream carries (on_ground_truth) as it comes."""
    class Watch(seif.RunObserver):
        def __init__(self):
            super().__init__()
            self.truth, self.poses = [], []

        def on_ground_truth(self, pose):
            self.truth.append(pose.time)

        def after_update(self, filter, step, k, seconds):
            self.poses.append(filter.pose())

    source = seif.open_dataset(simulated_folder)
    f = seif.make_filter("seif", source.info.start_pose, source.info.filter_config())
    watch = Watch()
    steps = seif.run_loop(f, source, [watch])
    reference = seif.run_filter(seif.make_filter("seif", source.info.start_pose, source.info.filter_config()),
                                seif.open_dataset(simulated_folder))
    assert steps == len(watch.poses) == reference.steps
    np.testing.assert_array_equal(np.array(watch.poses), reference.trajectory_array()[1:, 1:4])
    assert len(watch.truth) > steps / 2 and watch.truth == sorted(watch.truth)
