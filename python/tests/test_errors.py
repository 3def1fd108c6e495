"""Every C++ error reaches Python as its seif.Error subclass with the library's message."""
import os

import numpy as np

import pytest

import seif
from conftest import run_cli


def test_hierarchy():
    for cls in (seif.DataError, seif.NumericError, seif.InvalidArgument, seif.UnknownLandmark):
        assert issubclass(cls, seif.Error)
    assert issubclass(seif.Error, Exception)
    assert issubclass(seif.InvalidArgument, ValueError)
    assert issubclass(seif.UnknownLandmark, LookupError)


@pytest.fixture
def malformed_isam(tmp_path):
    path = tmp_path / "bad.txt"
    path.write_text("ODOMETRY 0 1 1.0 0.0 0.0 0.0001 0 0 4e-06 0 4e-06\n"
                    "ODOMETRY 1 2 1.0 zero 0.0 0.0001 0 0 4e-06 0 4e-06\n")
    return path


def drain(source):
    return sum(1 for _ in source)


def test_malformed_file_is_data_error_naming_file_and_line(malformed_isam):
    with pytest.raises(seif.DataError) as info:
        drain(seif.open_dataset(malformed_isam, "isam"))
    message = str(info.value)
    assert message.startswith(f"{malformed_isam}:2: ")
    assert info.value.file == str(malformed_isam)
    assert info.value.line == 2


def test_a_path_that_is_not_utf8_is_named_as_the_os_has_it(tmp_path):
    """The file of a DataError is os.fsdecode's text of the path (it round-trips through
    os.fsencode); the message shows the bytes that are not UTF-8 as escapes."""
    folder = os.path.join(os.fsencode(tmp_path), b"caf\xe9")
    os.mkdir(folder)
    path = os.path.join(folder, b"bad.txt")
    with open(path, "w") as f:
        f.write("ODOMETRY 0 1 1.0 zero 0.0 0.0001 0 0 4e-06 0 4e-06\n")
    with pytest.raises(seif.DataError) as info:
        drain(seif.open_dataset(os.fsdecode(path), "isam"))
    assert os.fsencode(info.value.file) == path
    assert info.value.line == 1
    assert "caf\\xe9" in str(info.value)


def test_data_error_message_is_the_clis(cli, malformed_isam, tmp_path):
    """The Python message is the C++ what() unchanged: the CLI prints the same text."""
    with pytest.raises(seif.DataError) as info:
        seif.run_dataset(seif.RunRequest(str(malformed_isam), "seif"), str(tmp_path))
    proc = run_cli(cli, "run", "--dataset", malformed_isam, "--out", tmp_path, check=False)
    assert proc.returncode == 2
    assert str(info.value) in proc.stderr


PAPER = seif.paper_filter_config(seif.NoiseModel())


def test_a_config_without_models_is_invalid_argument():
    """No silent fallback to the paper's models: a filter needs both of its models."""
    for spec in ("ekf", "eif", "seif", "batch"):
        with pytest.raises(seif.InvalidArgument, match="no motion model"):
            seif.make_filter(spec, np.zeros(3), seif.FilterConfig())
    config = seif.FilterConfig()
    config.motion = PAPER.motion
    with pytest.raises(seif.InvalidArgument, match="no sensor model"):
        seif.make_filter("seif", np.zeros(3), config)


def test_bad_spec_is_invalid_argument():
    with pytest.raises(seif.InvalidArgument, match="unknown filter 'kalman'"):
        seif.make_filter("kalman", np.zeros(3), PAPER)
    with pytest.raises(seif.InvalidArgument, match="sparsify"):
        seif.make_filter("seif:sparsify=never", np.zeros(3), PAPER)
    with pytest.raises(seif.InvalidArgument):
        seif.parse_filter_spec("ekf:active=3")
    with pytest.raises(seif.InvalidArgument):
        seif.DatasetFormat("csv")


def test_model_error_is_invalid_argument():
    sensor = seif.RangeBearingModel(0.1, 0.1)
    with pytest.raises(seif.InvalidArgument):
        sensor.inverse(np.zeros(3), np.array([0.0, 0.3]))  # zero range
    with pytest.raises(seif.InvalidArgument):
        seif.VelocityModel(0.1, 0.1).linearize(np.zeros(3), seif.OdometryIncrement())  # not its input
    with pytest.raises(seif.InvalidArgument):
        seif.RangeBearingModel(np.array([[1.0, 0.0], [0.0, -1.0]]))  # noise not SPD


@pytest.mark.parametrize("spec", ["ekf", "eif", "seif"])
def test_unknown_landmark(spec):
    f = seif.make_filter(spec, np.zeros(3), PAPER)
    f.update([seif.Observation(3, np.array([0.5, 0.2]))])
    assert f.landmark_ids() == [3]
    with pytest.raises(seif.UnknownLandmark) as info:
        f.landmark(4)
    assert "landmark 4" in str(info.value)
    with pytest.raises(seif.UnknownLandmark):
        f.landmark_covariance(4)
    with pytest.raises(seif.UnknownLandmark):
        f.predict_measurement(4)


def test_failure_inside_a_run_names_the_step():
    """A step that fails on its data (a zero-range first sighting) is rethrown by the run
    loop naming the step, as an InvalidArgument (seif::ModelError), not a NumericError."""
    data = seif.Dataset()
    good = seif.Step(1.0, seif.VelocityControl(0.1, 0.0, 1.0), [seif.Observation(1, np.array([1.0, 0.0]))])
    bad = seif.Step(2.0, seif.VelocityControl(0.1, 0.0, 1.0), [seif.Observation(2, np.array([0.0, 0.0]))])
    data.steps = [good, bad]
    with pytest.raises(seif.InvalidArgument, match="step 1"):
        seif.run_filter(seif.make_filter("ekf", np.zeros(3), PAPER), data)


def test_bad_world_config_is_invalid_argument():
    config = seif.preset_config("paper")
    config.steps = 0
    with pytest.raises(seif.InvalidArgument):
        seif.simulate(config)


def test_exception_in_progress_callback_propagates(simulated_folder, tmp_path):
    """A Python exception raised by a progress callback (called with the GIL re-acquired
    from inside the GIL-released run) stops the run and reaches the caller unchanged."""
    class Stop(Exception):
        pass

    def stop(*_):
        raise Stop("stopped by the user")

    with pytest.raises(Stop, match="stopped by the user"):
        seif.run_dataset(seif.RunRequest(str(simulated_folder), "seif"), str(tmp_path), stop)
    data, _ = seif.simulated_dataset("paper", steps=30)
    with pytest.raises(Stop):
        seif.run_filter(seif.make_filter("ekf", seif.start_pose(data), PAPER), data, stop)


def test_summaries_and_studies_refuse_what_they_cannot_read():
    """Out-of-range indices and empty datasets raise instead of reading past the end."""
    with pytest.raises(seif.InvalidArgument, match="no runs"):
        seif.summarize_paper_filter(0, [])
    options = seif.PaperOptions()
    options.landmarks, options.steps = 10, 20
    run = seif.run_paper_experiment(1, options)
    with pytest.raises(seif.InvalidArgument, match="filter 3 of runs with 3 filters"):
        seif.summarize_paper_filter(3, [run])
    dataset = seif.ConsistencyDataset()
    dataset.name = "empty"
    dataset.config = PAPER
    study = seif.ConsistencyOptions()
    study.datasets = [dataset]
    study.threads = 1
    study.filters = [seif.parse_filter_spec("ekf")]
    with pytest.raises(seif.InvalidArgument, match="'empty' holds no step"):
        seif.run_consistency(study)


def test_models_and_filters_refuse_bad_noise_and_start():
    with pytest.raises(seif.InvalidArgument, match="finite and > 0"):
        seif.RangeBearingModel(-0.1, 0.1)
    with pytest.raises(seif.InvalidArgument, match="finite and > 0"):
        seif.diagonal_noise(-1.0, float("nan"))
    for spec in ("ekf", "seif"):
        f = seif.make_filter(spec, np.zeros(3), PAPER)
        lopsided = np.array([[1.0, 5.0], [0.0, 1.0]])
        with pytest.raises(seif.InvalidArgument, match="not symmetric"):
            f.update([seif.Observation(1, np.array([1.0, 0.1]), lopsided)])
        assert f.landmark_ids() == []
    with pytest.raises(seif.InvalidArgument, match="start pose is not finite"):
        seif.make_filter("seif", np.array([np.nan, 0.0, 0.0]), PAPER)
    config = seif.paper_filter_config(seif.NoiseModel())
    config.initial_pose_sigma = np.array([np.nan, 0.1, 0.1])
    with pytest.raises(seif.InvalidArgument, match="initial_pose_sigma"):
        seif.make_filter("ekf", np.zeros(3), config)
    config.initial_pose_sigma = np.zeros(3)  # a known start: the EKF takes it, an information filter cannot
    assert seif.make_filter("ekf", np.zeros(3), config).pose_covariance().max() == 0.0
    with pytest.raises(seif.InvalidArgument, match="needs initial_pose_sigma > 0"):
        seif.make_filter("seif", np.zeros(3), config)


def test_a_dataset_built_in_memory_has_its_stamps_checked():
    data = seif.Dataset()
    step = seif.Step(1.0, seif.VelocityControl(0.1, 0.0, 1.0), [])
    late = seif.Step(float("nan"), seif.VelocityControl(0.1, 0.0, 1.0), [])
    data.steps = [step, late]
    with pytest.raises(seif.InvalidArgument, match="step 1's time nan"):
        seif.run_filter(seif.make_filter("ekf", np.zeros(3), PAPER), data)


def test_motion_models_refuse_a_non_finite_increment_and_a_singular_geometry():
    velocity = seif.VelocityModel(0.1, 0.1)
    with pytest.raises(seif.InvalidArgument, match="not finite"):
        velocity.linearize(np.array([np.nan, 0.0, 0.0]), seif.VelocityControl(0.1, 0.0, 1.0))
    # The encoder wheel on the turn's centre: the body speed is unbounded.
    car = seif.AckermannModel(seif.AckermannGeometry(2.0, 2.0, np.zeros(2)), 0.1, 0.01)
    with pytest.raises(seif.InvalidArgument, match="turn's centre"):
        car.body_velocity(seif.AckermannControl(1.0, np.pi / 4, 0.1))
