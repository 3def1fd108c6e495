"""Checkpoints from Python: save / load and pickling continue a run bit-identically."""
import json
import os
import pickle
import signal

import numpy as np
import pytest

import seif
from conftest import paper_config


@pytest.fixture(scope="module")
def paper_world():
    return seif.simulated_dataset("paper", seed=4)


@pytest.mark.parametrize("spec", ["ekf", "eif", "seif", "seif:sparsify=eseif,beta=4",
                                  "seif:relax-order=random,linearization=fej"])
@pytest.mark.parametrize("how", ["pickle", "file"])
def test_resumed_filter_is_bit_identical(paper_world, spec, how, tmp_path):
    data, world = paper_world
    start, config = seif.start_pose(data), paper_config(world)
    straight = seif.make_filter(spec, start, config)
    for step in data.steps:
        straight.step(step.u, step.observations)

    f = seif.make_filter(spec, start, config)
    for k, step in enumerate(data.steps):
        f.step(step.u, step.observations)
        if k + 1 in (50, 220, 401):  # interrupted three times
            if how == "pickle":
                f = pickle.loads(pickle.dumps(f))
            else:
                f.save(tmp_path / "f.ckpt", steps_consumed=k + 1)
                f = seif.load(tmp_path / "f.ckpt")  # a Path as well as a str
    assert f.name == straight.name
    assert f.landmark_ids() == straight.landmark_ids()
    np.testing.assert_array_equal(f.mean(), straight.mean())
    np.testing.assert_array_equal(f.pose_covariance(), straight.pose_covariance())
    assert f.stats().as_dict() == straight.stats().as_dict()


def test_deferred_motion_pickles_with_its_held_controls(paper_world):
    """seif:motion=deferred holds the controls between observations: pickled while it holds
    some (the sensor sees one step in three), the filter continues bit-identically, and its
    pose meanwhile is the held motion's."""
    data, world = paper_world
    start, config = seif.start_pose(data), paper_config(world)
    steps = [(step.u, step.observations if k % 3 == 0 else []) for k, step in enumerate(data.steps)]
    options = seif.SeifOptions()
    options.motion = "deferred"
    assert options.motion == seif.SeifOptions.Motion.Deferred
    straight = seif.make_filter("seif:profile=consistent", start, config)
    assert straight.options.motion.text == "deferred"
    for u, z in steps:
        straight.step(u, z)
    f = seif.make_filter("seif:profile=consistent", start, config)
    immediate = seif.make_filter("seif:profile=consistent,motion=immediate,mean=exact", start, config)
    exact = seif.make_filter("seif:profile=consistent,mean=exact", start, config)
    for k, (u, z) in enumerate(steps):
        f.step(u, z)
        immediate.step(u, z)
        exact.step(u, z)
        if k in (100, 251):  # two controls held
            f = pickle.loads(pickle.dumps(f))
            np.testing.assert_allclose(exact.pose(), immediate.pose(), atol=1e-2)
    np.testing.assert_array_equal(f.mean(), straight.mean())
    np.testing.assert_array_equal(f.pose_covariance(), straight.pose_covariance())


def test_settle_applies_the_held_controls_without_moving_the_posterior(paper_world):
    """settle() applies the controls a deferred SEIF holds (what a query would do first); the
    run continues to the same estimates as one never settled."""
    data, world = paper_world
    start, config = seif.start_pose(data), paper_config(world)
    steps = [(step.u, step.observations if k % 3 == 0 else []) for k, step in enumerate(data.steps)]
    straight = seif.make_filter("seif:profile=consistent,mean=exact", start, config)
    settled = seif.make_filter("seif:profile=consistent,mean=exact", start, config)
    for k, (u, z) in enumerate(steps):
        straight.step(u, z)
        settled.step(u, z)
        if k % 3 == 2:  # two controls held
            pose = settled.pose()
            settled.settle()
            np.testing.assert_array_equal(settled.pose(), pose)
    np.testing.assert_allclose(settled.mean(), straight.mean(), atol=1e-6)


def test_checkpoint_extras_and_errors(paper_world, tmp_path):
    data, world = paper_world
    f = seif.make_filter("seif", seif.start_pose(data), paper_config(world))
    for step in data.steps[:30]:
        f.step(step.u, step.observations)
    f.save(tmp_path / "a.ckpt", steps_consumed=30, values={"note": "thirty"})
    g, steps, values = seif.load_checkpoint(str(tmp_path / "a.ckpt"))
    assert steps == 30 and values == {"note": "thirty"}
    np.testing.assert_array_equal(g.mean(), f.mean())

    raw = (tmp_path / "a.ckpt").read_bytes()
    (tmp_path / "cut.ckpt").write_bytes(raw[: len(raw) // 3])
    with pytest.raises(seif.DataError, match="cut.ckpt"):
        seif.load(str(tmp_path / "cut.ckpt"))
    with pytest.raises(seif.DataError):
        seif.load_bytes(b"SEIF? not a checkpoint", "junk")
    batch = seif.make_filter("batch", seif.start_pose(data), paper_config(world))
    with pytest.raises(seif.InvalidArgument, match="batch"):
        pickle.dumps(batch)


def test_marginal_remove_and_merge_from_python(paper_world):
    data, world = paper_world
    f = seif.make_filter("eif", seif.start_pose(data), paper_config(world))
    for step in data.steps[:200]:
        f.step(step.u, step.observations)
    ids = f.landmark_ids()
    mean, cov = f.marginal([ids[0], ids[2]])
    dense = f.covariance()
    rows = [0, 1, 2, 3, 4, 7, 8]  # pose, slot 0, slot 2
    np.testing.assert_allclose(cov, dense[np.ix_(rows, rows)], rtol=1e-8, atol=1e-14)
    np.testing.assert_array_equal(mean, f.mean()[rows])
    _, local = f.marginal([ids[0]], mode=seif.MarginalMode.Local)
    assert np.trace(local) <= np.trace(dense[np.ix_([0, 1, 2, 3, 4], [0, 1, 2, 3, 4])]) + 1e-15
    f.remove_landmark(ids[1])
    assert not f.has_landmark(ids[1])
    f.merge_landmarks(ids[0], ids[3])
    assert f.has_landmark(ids[0]) and not f.has_landmark(ids[3])
    with pytest.raises(seif.UnknownLandmark):
        f.marginal([ids[1]])


def test_conservative_marginal_from_python(paper_world):
    """seif:bounds=true keeps an upper bound: the conservative marginal is never below the exact
    one; without the bounds it is refused; the bounds survive pickling bit for bit."""
    data, world = paper_world
    f = seif.make_filter("seif:bounds=true", seif.start_pose(data), paper_config(world))
    for step in data.steps[:200]:
        f.step(step.u, step.observations)
    ids = f.landmark_ids()[:3]
    _, exact = f.marginal(ids, mode=seif.MarginalMode.Exact)
    _, bound = f.marginal(ids, mode=seif.MarginalMode.Conservative)
    assert np.linalg.eigvalsh(bound - exact).min() >= -1e-9 * np.linalg.eigvalsh(exact).max()
    again = pickle.loads(pickle.dumps(f))
    np.testing.assert_array_equal(again.marginal(ids, mode=seif.MarginalMode.Conservative)[1], bound)
    plain = seif.make_filter("seif", seif.start_pose(data), paper_config(world))
    plain.step(data.steps[0].u, data.steps[0].observations)
    with pytest.raises(seif.InvalidArgument, match="bounds"):
        plain.marginal([], mode=seif.MarginalMode.Conservative)
    assert seif.SeifOptions().bounds is False


def test_run_loop_with_a_python_observer(paper_world):
    data, world = paper_world

    class Recorder(seif.RunObserver):
        def __init__(self):
            super().__init__()
            self.steps, self.finished = [], False

        def after_update(self, filter, step, k, seconds):
            self.steps.append((k, filter.pose()))

        def on_finish(self, filter, seconds):
            self.finished = True

    rec = Recorder()
    f = seif.make_filter("seif", seif.start_pose(data), paper_config(world))
    n = seif.run_loop(f, data, [rec])
    assert n == len(data.steps) and rec.finished
    assert [k for k, _ in rec.steps] == list(range(len(data.steps)))
    g = seif.make_filter("seif", seif.start_pose(data), paper_config(world))
    seif.run_filter(g, data)
    np.testing.assert_array_equal(f.mean(), g.mean())
    np.testing.assert_array_equal(rec.steps[-1][1], g.pose())
    # An association hook that drops every observation: the map stays empty.
    h = seif.make_filter("ekf", seif.start_pose(data), paper_config(world))
    seif.run_loop(h, data, associate=lambda filt, step, k, z: [])
    assert h.landmark_ids() == []

    # stop() ends the run early but whole: on_stop with the steps consumed, then on_finish.
    class Stops(Recorder):
        def __init__(self):
            super().__init__()
            self.stopped = None

        def on_stop(self, filter, steps):
            self.stopped = steps

    rec = Stops()
    s = seif.make_filter("seif", seif.start_pose(data), paper_config(world))
    assert seif.run_loop(s, data, [rec], stop=lambda: len(rec.steps) == 40) == 40
    assert rec.stopped == 40 and rec.finished
    assert rec.steps[-1][0] == 39


def _ctrl_c_at_report(n):
    """A progress callback that sends this process SIGINT (Ctrl-C) at its n-th call."""
    reports = []

    def callback(fraction):
        reports.append(fraction)
        if len(reports) == n:
            os.kill(os.getpid(), signal.SIGINT)

    return callback


def test_sigterm_stops_a_run_whole_once_the_application_maps_it_to_keyboard_interrupt(tmp_path):
    """Python kills a process on SIGTERM by default; an application that wants `seif run`'s
    behaviour (stop, write the outputs) installs signal.default_int_handler for it."""
    folder = tmp_path / "data"
    seif.write_mrclam(folder, seif.simulate(seif.preset_config("paper", 0, 3000, 3)))
    reports = []

    def sigterm_at_the_second_report(fraction):
        reports.append(fraction)
        if len(reports) == 2:
            os.kill(os.getpid(), signal.SIGTERM)

    out = tmp_path / "out"
    out.mkdir()
    previous = signal.signal(signal.SIGTERM, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            seif.run_dataset(seif.RunRequest(str(folder), "seif"), str(out), sigterm_at_the_second_report)
    finally:
        signal.signal(signal.SIGTERM, previous)
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["interrupted"] is True
    assert metrics["steps"] == 1025


def test_keyboard_interrupt_stops_a_run_whole_and_its_checkpoint_resumes(tmp_path):
    """Ctrl-C during run_dataset: the run stops after the step it is in, writes its outputs and
    the checkpoint, then KeyboardInterrupt is raised; the checkpoint resumes to the whole run."""
    folder = tmp_path / "data"
    seif.write_mrclam(folder, seif.simulate(seif.preset_config("paper", 0, 3000, 3)))
    whole = tmp_path / "whole"
    whole.mkdir()
    seif.run_dataset(seif.RunRequest(str(folder), "seif"), str(whole))

    request = seif.RunRequest(str(folder), "seif")
    request.checkpoint = str(tmp_path / "run.ckpt")
    ctrl_c_at_the_second_report = _ctrl_c_at_report(2)  # progress comes every 1024 steps
    part = tmp_path / "part"
    part.mkdir()
    with pytest.raises(KeyboardInterrupt):
        seif.run_dataset(request, str(part), ctrl_c_at_the_second_report)
    metrics = json.loads((part / "metrics.json").read_text())
    assert metrics["interrupted"] is True
    assert metrics["steps"] == 1025
    part_tum = (part / "trajectory.tum").read_text().splitlines()
    assert len(part_tum) == 1 + 1026  # the header, the start pose and 1025 steps
    assert part_tum == (whole / "trajectory.tum").read_text().splitlines()[: len(part_tum)]

    resume = seif.RunRequest(str(folder), "seif")
    resume.resume = request.checkpoint
    resumed = tmp_path / "resumed"
    resumed.mkdir()
    report = seif.run_dataset(resume, str(resumed))
    assert not report.output.interrupted
    for name in ("trajectory.tum", "dead_reckoning.tum", "map.csv"):
        assert (resumed / name).read_bytes() == (whole / name).read_bytes(), name


def test_value_types_pickle_by_value(paper_world):
    """Records, options and models pickle by value: a run from an unpickled dataset, config and
    options is bit-identical to one from the originals."""
    data, world = paper_world
    start, config = seif.start_pose(data), paper_config(world)
    options = seif.SeifOptions()
    options.sparsify = "eseif"
    options.active = 5
    copies = pickle.loads(pickle.dumps((data, config, options)))
    assert copies[2].sparsify == seif.SeifOptions.Sparsify.Eseif and copies[2].active == 5
    a = seif.make_filter("seif", start, config, options)
    b = seif.make_filter("seif", start, copies[1], copies[2])
    for step, twin in zip(data.steps, copies[0].steps):
        a.step(step.u, step.observations)
        b.step(twin.u, twin.observations)
    np.testing.assert_array_equal(a.mean(), b.mean())
    z = seif.Observation(4, np.array([1.5, -0.25]), np.diag([0.01, 0.002]))
    z.truth = 9
    back = pickle.loads(pickle.dumps(z))
    assert (back.landmark, back.truth) == (4, 9)
    np.testing.assert_array_equal(back.z, z.z)
    np.testing.assert_array_equal(back.noise, z.noise)
    car = seif.AckermannModel(seif.AckermannGeometry(), 0.1, 0.01)
    assert repr(pickle.loads(pickle.dumps(car)).geometry) == repr(car.geometry)
    request = seif.RunRequest("somewhere", "ekf")
    request.association.method = "jcbb"
    assert pickle.loads(pickle.dumps(request)).association.method == seif.AssociationMethod.Jcbb


def test_an_associator_pickles_and_continues_as_the_original():
    """Associator.state_bytes / from_state_bytes (and pickling): the restored associator gives
    the rest of the run the same landmark ids as the original, each beside its own filter."""
    data, world = seif.simulated_dataset("park", steps=500, seed=3, clutter=1.0, detection_probability=0.9)
    config = seif.paper_filter_config(world.noise)
    options = seif.AssociationOptions()
    options.method = seif.AssociationMethod.Jcbb
    options.provisional = seif.ProvisionalPlace.Held
    a = seif.Associator(options)
    f = seif.make_filter("ekf", seif.start_pose(data), config)
    half = len(data.steps) // 2
    for k, step in enumerate(data.steps[:half]):
        f.predict(step.u)
        f.update(a.associate(f, k, step.observations))
    b = pickle.loads(pickle.dumps(a))
    assert b.state_bytes() == a.state_bytes()
    g = pickle.loads(pickle.dumps(f))
    for k, step in enumerate(data.steps[half:], start=half):
        f.predict(step.u)
        g.predict(step.u)
        za, zb = a.associate(f, k, step.observations), b.associate(g, k, step.observations)
        assert [z.landmark for z in za] == [z.landmark for z in zb], k
        f.update(za)
        g.update(zb)
    assert a.counts.new_landmarks > 0 and a.counts.new_landmarks == b.counts.new_landmarks
    np.testing.assert_array_equal(f.mean(), g.mean())
    with pytest.raises(seif.DataError, match="damaged.bin"):
        seif.Associator.from_state_bytes(a.state_bytes()[:-3], "damaged.bin")


def test_a_run_checkpoint_with_association_loads_and_resumes(tmp_path):
    """A run with association stopped by Ctrl-C: its checkpoint's values are str where text and
    bytes where binary (the run's outputs, the associator), save_checkpoint takes them back, and
    the checkpoint resumes to the whole run."""
    folder = tmp_path / "data"
    world = seif.preset_config("park", 0, 1500, 2)
    world.clutter = 1.0
    seif.write_mrclam(folder, seif.simulate(world))
    request = seif.RunRequest(str(folder), "seif")
    request.association.method = seif.AssociationMethod.NearestNeighbour
    request.association.marginal = seif.MarginalMode.Local
    whole = tmp_path / "whole"
    whole.mkdir()
    seif.run_dataset(request, str(whole))

    request.checkpoint = str(tmp_path / "run.ckpt")
    ctrl_c_at_the_second_report = _ctrl_c_at_report(2)
    part = tmp_path / "part"
    part.mkdir()
    with pytest.raises(KeyboardInterrupt):
        seif.run_dataset(request, str(part), ctrl_c_at_the_second_report)
    f, steps, values = seif.load_checkpoint(request.checkpoint)
    assert steps == 1025
    assert isinstance(values["filter"], str) and values["filter"] == "seif"
    assert isinstance(values[seif.ASSOCIATOR_KEY], bytes)
    restored = seif.Associator.from_state_bytes(values[seif.ASSOCIATOR_KEY])
    assert restored.options.method == seif.AssociationMethod.NearestNeighbour
    seif.save_checkpoint(f, tmp_path / "again.ckpt", steps, values)  # bytes and str values back
    assert seif.load_checkpoint(tmp_path / "again.ckpt")[2] == values

    resume = seif.RunRequest(str(folder), "seif")
    resume.resume = str(tmp_path / "again.ckpt")
    resumed = tmp_path / "resumed"
    resumed.mkdir()
    report = seif.run_dataset(resume, str(resumed))
    assert report.association.observations > 0
    for name in ("trajectory.tum", "map.csv"):
        assert (resumed / name).read_bytes() == (whole / name).read_bytes(), name
