"""seif: SLAM with Sparse Extended Information Filters (EKF, EIF, SEIF, batch MAP).

Python bindings of the seif C++ library. Everything of the C++ module ``seif._core`` is
re-exported here; this file adds a few helpers on top. Conventions are the library's: SI
units, poses (x, y, theta) as numpy arrays, state order [x, y, theta, l1x, l1y, ...].

Main entry points:

* ``make_filter(spec, start, config)`` -> a filter (``SlamFilter``: ``EkfSlam``, ``EifSlam``,
  ``SeifSlam``, ``BatchMap``) to drive with ``predict`` / ``update`` / ``step``;
* ``open_dataset(path, format="auto")`` -> an iterable ``EventSource`` with ``.info``;
* ``run_dataset(RunRequest, out_dir)`` -> ``RunReport`` (``seif run`` as one call);
* ``simulate(preset_config(...))`` / ``simulated_dataset(...)`` -> the simulator's data,
  ``run_filter(filter, dataset)`` -> ``RunOutput``;
* experiments: ``run_paper_experiment``, ``run_consistency``, ``run_bench_case``.

Errors raise ``seif.Error`` subclasses: ``DataError``, ``NumericError``,
``InvalidArgument``, ``UnknownLandmark``.
"""

from . import _core
from ._core import *  # noqa: F401,F403  (the bindings: every public name of seif._core)

import numpy as _np

__version__ = _core.__version__


def _filter_from_bytes(data, name):
    """Unpickling: the filter in checkpoint bytes (a Python function, so pickle can name it)."""
    return _core.load_bytes(data, name)


def _reduce_filter(self):
    """Pickling: a filter travels as its checkpoint (``checkpoint_bytes``), bit-exactly."""
    return (_filter_from_bytes, (_core.checkpoint_bytes(self), "pickle of a " + self.name + " filter"))


def _save_filter(self, path, steps_consumed=0, values=None):
    """Saves the filter's whole state to the checkpoint ``path``; ``seif.load(path)`` reads it."""
    _core.save_checkpoint(self, path, steps_consumed, values or {})


def _associator_from_bytes(data, name):
    """Unpickling: the associator in its state bytes."""
    return _core.Associator.from_state_bytes(data, name)


def _reduce_associator(self):
    """Pickling: an associator travels as its checkpoint state (``state_bytes``), bit-exactly."""
    return (_associator_from_bytes, (self.state_bytes(), "pickle of an associator"))


_core.SlamFilter.__reduce__ = _reduce_filter
_core.Associator.__reduce__ = _reduce_associator
_core.SlamFilter.save = _save_filter

__all__ = [name for name in dir(_core) if not name.startswith("_")] + [
    "simulated_dataset",
    "observations",
    "run",
    "read_tum",
    "read_map_csv",
    "plot_run",
    "render_figure",
]


def simulated_dataset(preset="paper", landmarks=0, steps=0, seed=1, **fields):
    """The simulator's world as an in-memory ``Dataset`` plus its ``WorldConfig``.

    ``preset``: ``"paper"``, ``"uniform"`` or ``"corridor"`` (or a ``WorldPreset``);
    ``landmarks`` / ``steps`` <= 0 take the preset's defaults; other ``WorldConfig`` fields
    (``paper_path``, ``sensor_range``, ...) may be given by name. Returns ``(dataset, config)``;
    ``paper_filter_config(config.noise)`` is the filter configuration with the world's true noise.
    """
    config = _core.preset_config(preset, landmarks, steps, seed)
    for name, value in fields.items():
        if not hasattr(config, name):
            raise _core.InvalidArgument(f"WorldConfig has no field '{name}'")
        setattr(config, name, value)
    return _core.build_dataset(_core.simulate(config)), config


def observations(rows):
    """A list of ``Observation`` from rows ``(landmark_id, z1, z2)`` (a list or an (n, 3) array).

    For a range-bearing sensor z = (range [m], bearing [rad]).
    """
    out = []
    for row in rows:
        landmark, z1, z2 = row
        out.append(_core.Observation(int(landmark), _np.array([z1, z2], dtype=float)))
    return out


def run(dataset, out_dir, filter="seif", progress=None, **fields):
    """``run_dataset`` from keyword arguments: ``run("victoria_park.txt", "out", filter="ekf")``.

    Other ``RunRequest`` fields (``format``, ``outlier_gate``, ``map_covariances``, ...) may be
    given by name. ``out_dir`` must exist.
    """
    request = _core.RunRequest(str(dataset), filter)
    for name, value in fields.items():
        if not hasattr(request, name):
            raise _core.InvalidArgument(f"RunRequest has no field '{name}'")
        setattr(request, name, value)
    return _core.run_dataset(request, str(out_dir), progress)


def read_tum(path):
    """A TUM trajectory file (``trajectory.tum``) as an (n, 8) array: t x y z qx qy qz qw."""
    return _np.loadtxt(path, ndmin=2)


def read_map_csv(path):
    """``map.csv`` as a structured numpy array with its header's column names (id, x, y, ...)."""
    return _np.genfromtxt(path, delimiter=",", names=True, ndmin=1)


FIGURES = ("run_map", "paper", "consistency", "bench")


def render_figure(name, *args):
    """Runs the CLI's figure script ``name`` (``run_map``, ``paper``, ``consistency`` or ``bench``,
    shipped in the package's ``figures/`` folder) with this interpreter and ``args``, as the CLI
    does after each command: ``render_figure("paper", out_dir)`` after ``PaperReport.write``,
    ``render_figure("consistency", out_dir)`` after ``write_consistency_results``,
    ``render_figure("bench", "out/bench.json", "out/bench.png")`` after writing
    ``BenchReport.json()``. ``RuntimeError`` when matplotlib is missing or the script fails."""
    import pathlib
    import subprocess
    import sys

    import importlib.util

    if name not in FIGURES:
        raise InvalidArgument(f"render_figure: unknown figure '{name}' (expected one of {', '.join(FIGURES)})")
    if importlib.util.find_spec("matplotlib") is None:
        raise RuntimeError(f"render_figure {name}: matplotlib is not installed (apt-get install python3-matplotlib)")
    script = pathlib.Path(__file__).with_name("figures") / f"{name}.py"
    done = subprocess.run([sys.executable, str(script), *map(str, args)], capture_output=True, text=True,
                          errors="replace")
    if done.returncode != 0:
        raise RuntimeError(f"render_figure {name} failed: {done.stderr.strip()}")


def plot_run(run_dir, title=None):
    """``seif plot``: draws the output folder of a run (``seif run`` or ``run_dataset``) into
    ``run_dir/map.png`` and returns its path: the trajectory, the map with each landmark's 95 %
    covariance ellipse, the dead reckoning and, when the run stored GPS (``gps.csv``), the
    fixes with the trajectory and map rigidly aligned to them (else to the ground truth,
    ``groundtruth.tum`` and ``landmarks_groundtruth.csv``, drawn too), and with ``associations.csv``
    each observation scored wrong, the duplicate and the unlabelled landmarks
    (``render_figure("run_map", ...)``). ``DataError`` when a file the figure needs is missing, ``RuntimeError`` when drawing fails."""
    import pathlib

    run_dir = pathlib.Path(run_dir)
    for name in ("trajectory.tum", "map.csv"):
        if not (run_dir / name).is_file():
            error = DataError(f"{run_dir / name}: missing: run_dir must be the output folder of a run")
            error.file, error.line = str(run_dir / name), 0
            raise error
    png = run_dir / "map.png"
    args = [png, "--ellipses"]
    if (run_dir / "gps.csv").is_file():
        args += ["--gps", run_dir / "gps.csv"]
    if title:
        args += ["--title", title]
    render_figure("run_map", *args, run_dir)
    return png


# ---- pickling of value types: records rebuilt from their fields, models from their parameters
_CONSTRUCTOR_ARGS = {
    "VelocityModel": ("sigma_v", "sigma_w", "form"),
    "AckermannModel": ("geometry", "sigma_speed", "sigma_steering", "form"),
    "OdometryModel": (),
    "RangeBearingModel": ("noise", "mount"),
    "CartesianModel": ("noise", "mount"),
    "ControlEvent": ("time", "input", "pose"),
    "Observation": ("landmark", "z", "noise"),
    "ObservationEvent": ("time", "observations"),
    "Step": ("time", "u", "observations"),
}


def _rebuild(cls, args, fields):
    """Unpickling of a value type: cls(*args), then its other fields set."""
    value = cls(*args)
    for name, field in fields.items():
        setattr(value, name, field)
    return value


def _settable_fields(cls):
    return [name for klass in cls.__mro__ for name, attr in vars(klass).items()
            if isinstance(attr, property) and attr.fset is not None]


def _make_reduce(args, fields):
    def reduce(self):
        return (_rebuild, (type(self), tuple(getattr(self, a) for a in args),
                           {f: getattr(self, f) for f in fields if f not in args}))
    return reduce


def _enable_pickling():
    """Every record whose fields are all settable (NoiseModel, SeifOptions, RunRequest, Step, ...)
    and every model pickles by value; a filter pickles as its checkpoint (above)."""
    for name in dir(_core):
        cls = getattr(_core, name)
        if not isinstance(cls, type) or issubclass(cls, BaseException) or "__reduce__" in vars(cls):
            continue
        if name in _CONSTRUCTOR_ARGS:
            cls.__reduce__ = _make_reduce(_CONSTRUCTOR_ARGS[name], _settable_fields(cls))
            continue
        props = [a for klass in cls.__mro__ for a in vars(klass).values() if isinstance(a, property)]
        if not props or any(p.fset is None for p in props):
            continue
        try:
            cls()
        except TypeError:
            continue
        cls.__reduce__ = _make_reduce((), _settable_fields(cls))


_enable_pickling()
