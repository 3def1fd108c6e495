"""What Python gets from the library is its own: list attributes and read-only properties are
copies (never views into C++ storage that a later assignment frees), hooks may keep what they
are handed, and mistakes in callbacks come back as Python exceptions, never a crash."""
import gc

import numpy as np
import pytest

import seif
from conftest import paper_config


@pytest.fixture
def world():
    return seif.simulated_dataset("paper", 20, 60, seed=2)


def test_list_attributes_are_copies_that_outlive_their_list(world):
    data, _ = world
    step = data.steps[5]
    ids = [o.landmark for o in step.observations]
    time = step.time
    data.steps = data.steps[:1]  # the C++ vector the step came from is replaced
    [seif.Observation(424242, np.array([9.9, 9.9])) for _ in range(20000)]  # reuse freed memory
    gc.collect()
    assert [o.landmark for o in step.observations] == ids
    assert step.time == time
    # A write into an element read from a list does not reach the dataset (it is a copy).
    data, _ = seif.simulated_dataset("paper", 20, 60, seed=2)
    data.steps[3].time = 123.0
    assert data.steps[3].time != 123.0


def test_read_only_properties_cannot_be_changed_behind_the_constructors_checks(world):
    data, w = world
    f = seif.make_filter("seif", seif.start_pose(data), paper_config(w))
    f.options.active = 0  # would bypass SeifSlam's range check if it were a view
    assert f.options.active == seif.SeifOptions().active
    model = seif.AckermannModel(seif.AckermannGeometry(2.83, 0.76, np.array([3.78, 0.5])), 0.1, 0.01)
    model.geometry.wheelbase = -5.0
    assert model.geometry.wheelbase == 2.83
    associator = seif.Associator(seif.AssociationOptions())
    associator.options.confirm = 0
    assert associator.options.confirm == seif.AssociationOptions().confirm


def test_a_run_loop_observer_may_keep_the_steps_it_sees(world):
    data, w = world

    class Keeper(seif.RunObserver):
        def __init__(self):
            super().__init__()
            self.kept = []

        def after_update(self, filter, step, k, seconds):
            self.kept.append(step)

    keeper = Keeper()
    counts = [len(s.observations) for s in data.steps]
    f = seif.make_filter("ekf", seif.start_pose(data), paper_config(w))
    seif.run_loop(f, data, [keeper])
    del data
    gc.collect()
    assert [len(s.observations) for s in keeper.kept] == counts


def test_none_among_the_observers_is_an_invalid_argument(world):
    data, w = world
    f = seif.make_filter("ekf", seif.start_pose(data), paper_config(w))
    with pytest.raises(seif.InvalidArgument, match=r"observers\[1\] is None"):
        seif.run_loop(f, data, [seif.RunObserver(), None])


def test_python_errors_in_hooks_pass_unchanged(world):
    data, w = world

    class Fails(seif.RunObserver):
        def after_predict(self, filter, step, k, seconds):
            if k == 3:
                raise ValueError("user bug")

    f = seif.make_filter("ekf", seif.start_pose(data), paper_config(w))
    with pytest.raises(ValueError, match="user bug"):
        seif.run_loop(f, data, [Fails()])

    def drop_at_3(filt, step, k, z):
        if k == 3:
            raise KeyError("no such landmark")
        return z

    g = seif.make_filter("ekf", seif.start_pose(data), paper_config(w))
    with pytest.raises(KeyError):
        seif.run_loop(g, data, associate=drop_at_3)

    # A hook that returns the wrong type is named, with the step.
    h = seif.make_filter("ekf", seif.start_pose(data), paper_config(w))
    with pytest.raises(seif.Error, match=r"step 0 .*associate\(filter, step, k, observations\) must return a list"):
        seif.run_loop(h, data, associate=lambda filt, step, k, z: None)
    with pytest.raises(seif.Error, match="stop\\(\\) must return True or False"):
        seif.run_loop(h, data, stop=lambda: "soon")


@pytest.mark.parametrize("threads", [1, 2])
def test_a_failing_progress_callback_on_worker_threads_raises_instead_of_aborting(threads):
    options = seif.ConsistencyOptions()
    options.world = seif.preset_config("paper", 10, 20, 1)
    options.runs = 4
    options.threads = threads
    options.filters = [seif.parse_filter_spec("ekf")]

    def fails(done, total):
        raise ZeroDivisionError("in the callback")

    with pytest.raises(ZeroDivisionError, match="in the callback"):
        seif.run_consistency(options, fails)
