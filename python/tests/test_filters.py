"""Filters driven from Python against the same filters driven by the C++ run loop, the
SEIF's sparse information matrix, and EKF = EIF."""
import numpy as np
import pytest
import scipy.sparse

import seif
from conftest import paper_config


@pytest.fixture(scope="module")
def paper_world():
    """The paper's simulated world (50 landmarks, 500 steps), seed 11."""
    return seif.simulated_dataset("paper", seed=11)


@pytest.mark.parametrize("spec", ["seif", "ekf", "eif", "seif:sparsify=eseif,linearization=fej", "batch"])
def test_python_loop_equals_cpp_run_filter(paper_world, spec):
    data, world = paper_world
    start = seif.start_pose(data)
    config = paper_config(world)

    # Stepped from Python, one predict/update at a time, recording the poses.
    mine = seif.make_filter(spec, start, config)
    poses = [mine.pose()]
    for step in data.steps:
        mine.predict(step.u)
        mine.update(step.observations)
        poses.append(mine.pose())
    mine.finish()

    # The library's own loop on the same data.
    theirs = seif.make_filter(spec, start, config)
    out = seif.run_filter(theirs, data)

    assert out.steps == len(data.steps) == len(poses) - 1
    assert mine.landmark_ids() == theirs.landmark_ids()
    assert len(mine.landmark_ids()) > 10
    np.testing.assert_array_equal(mine.mean(), theirs.mean())
    np.testing.assert_array_equal(mine.pose(), theirs.pose())
    np.testing.assert_array_equal(mine.pose_covariance(), theirs.pose_covariance())
    if not theirs.smoother:  # a smoother's trajectory is replaced by the smoothed one
        np.testing.assert_array_equal(np.array(poses), out.trajectory_array()[:, 1:])
    assert mine.stats().as_dict() == out.final_stats.as_dict()


def test_step_equals_predict_then_update(paper_world):
    data, world = paper_world
    a = seif.make_filter("seif", seif.start_pose(data), paper_config(world))
    b = seif.make_filter("seif", seif.start_pose(data), paper_config(world))
    for step in data.steps[:100]:
        a.step(step.u, step.observations)
        # predict(increment) with the model linearised here: what predict(input) does.
        b.predict(seif.VelocityModel(world.noise.sigma_v, world.noise.sigma_w).linearize(b.mean()[:3], step.u))
        b.update(step.observations, seif.RangeBearingModel(world.noise.sigma_range, world.noise.sigma_bearing))
    np.testing.assert_array_equal(a.mean(), b.mean())


def test_seif_information_is_sparse_and_equals_dense(paper_world):
    data, world = paper_world
    f = seif.make_filter("seif", seif.start_pose(data), paper_config(world))
    seif.run_filter(f, data)
    H = f.information()
    assert isinstance(H, scipy.sparse.csc_matrix)
    dense = f.information_dense()
    n = 3 + 2 * len(f.landmark_ids())
    assert H.shape == dense.shape == (n, n)
    np.testing.assert_array_equal(H.toarray(), dense)
    assert abs(H - H.T).max() <= 1e-9 * abs(H).max()  # symmetric to rounding
    # Sparse: the SEIF keeps far fewer links than the dense n x n.
    assert H.nnz < 0.5 * n * n
    # Links counted by stats() are the off-diagonal non-zero 2x2 landmark blocks and
    # robot blocks of H.
    blocks = set()
    coo = H.tocoo()
    slot = lambda i: -1 if i < 3 else (i - 3) // 2
    for i, j in zip(coo.row, coo.col):
        a, b = slot(i), slot(j)
        if a < b:
            blocks.add((a, b))
    assert len(blocks) == f.stats().links
    # The posterior's mean solves H mu = b; the amortised mean() lags it.
    mu = f.posterior_mean()
    np.testing.assert_allclose(dense @ mu, f.information_vector(), rtol=0, atol=1e-8 * abs(f.information_vector()).max())
    assert abs(mu - f.mean()).max() > 1e-9
    ekf = seif.make_filter("ekf", seif.start_pose(data), paper_config(world))
    assert ekf.posterior_mean() is None


def test_dense_filters_information_sparse_view(paper_world):
    data, world = paper_world
    f = seif.make_filter("eif", seif.start_pose(data), paper_config(world))
    for step in data.steps[:60]:
        f.step(step.u, step.observations)
    np.testing.assert_array_equal(f.information().toarray(), f.information_dense())


def test_ekf_equals_eif(paper_world):
    data, world = paper_world
    ekf = seif.make_filter("ekf", seif.start_pose(data), paper_config(world))
    eif = seif.make_filter("eif", seif.start_pose(data), paper_config(world))
    for step in data.steps:
        ekf.step(step.u, step.observations)
        eif.step(step.u, step.observations)
    assert ekf.landmark_ids() == eif.landmark_ids()
    np.testing.assert_allclose(ekf.mean(), eif.mean(), rtol=0, atol=1e-8)
    np.testing.assert_allclose(ekf.covariance(), eif.covariance(), rtol=0, atol=1e-10)
    H = eif.information_dense()
    np.testing.assert_allclose(np.linalg.inv(ekf.covariance()), H, rtol=0, atol=1e-6 * np.abs(H).max())
    for lid in ekf.landmark_ids():
        np.testing.assert_allclose(ekf.landmark(lid), eif.landmark(lid), atol=1e-8)
        np.testing.assert_allclose(ekf.landmark_covariance(lid), eif.landmark_covariance(lid), atol=1e-10)


def test_filter_accessors_agree(paper_world):
    data, world = paper_world
    f = seif.make_filter("seif", seif.start_pose(data), paper_config(world))
    seif.run_filter(f, data)
    mean = f.mean()
    np.testing.assert_allclose(mean[:2], f.pose()[:2], atol=0)
    cov = f.covariance()
    np.testing.assert_allclose(cov[:3, :3], f.pose_covariance(), atol=1e-12)
    for k, lid in enumerate(f.landmark_ids()):
        assert f.has_landmark(lid)
        np.testing.assert_array_equal(f.landmark(lid), mean[3 + 2 * k:5 + 2 * k])
        np.testing.assert_allclose(f.landmark_covariance(lid), cov[3 + 2 * k:5 + 2 * k, 3 + 2 * k:5 + 2 * k],
                                   atol=1e-12)
    lid = f.landmark_ids()[0]
    pm = f.predict_measurement(lid)
    z, _, _ = seif.RangeBearingModel(world.noise.sigma_range, world.noise.sigma_bearing).predict(f.pose(), f.landmark(lid))
    np.testing.assert_allclose(pm.z, z, atol=1e-12)
    assert np.all(np.linalg.eigvalsh(pm.S) > 0)
    assert not f.has_landmark(10 ** 6)
    assert f.rejected_observations() == 0
    assert f.name == "seif"
    assert set(f.active_landmarks()) <= set(f.landmark_ids())
    assert len(f.active_landmarks()) <= f.options.active


def test_seif_options_and_config_fields():
    options = seif.SeifOptions()
    options.sparsify = "eseif"
    options.mean = seif.SeifOptions.Mean.Exact
    options.active = 4
    assert options.sparsify == seif.SeifOptions.Sparsify.Eseif
    assert options.sparsify.text == "eseif"
    # A bad name: the enum's constructor raises the library's message; an implicit
    # conversion (assignment) fails as pybind11's TypeError.
    with pytest.raises(seif.InvalidArgument, match="sideways"):
        seif.SeifOptions.RelaxOrder("sideways")
    with pytest.raises(TypeError):
        options.relax_order = "sideways"
    config = seif.FilterConfig()
    assert config.motion is None and config.sensor is None
    config.motion = seif.VelocityModel(0.1, 0.05)
    config.sensor = seif.CartesianModel(np.eye(2) * 0.01)
    config.linearization = "fej"
    assert config.linearization == seif.Linearization.FirstEstimates
    f = seif.make_filter("seif", np.zeros(3), config, options)
    assert isinstance(f, seif.SeifSlam)
    assert f.options.active == 4 and f.options.sparsify.text == "eseif"
    assert "Cartesian" in f.sensor_model
    # The amortised mean's over-relaxation must lie in (0, 2): the filter refuses it otherwise.
    options.omega = 2.0
    with pytest.raises(seif.InvalidArgument, match="omega=2 is outside"):
        seif.make_filter("seif", np.zeros(3), config, options)
    options.omega = 1.95
    assert seif.make_filter("seif", np.zeros(3), config, options).options.omega == 1.95
    # The wildfire order's threshold must be positive (conditional standard deviations).
    options.relax_order = "wildfire"
    assert options.relax_order == seif.SeifOptions.RelaxOrder.Wildfire
    options.wildfire = 0.0
    with pytest.raises(seif.InvalidArgument, match="wildfire=0 is outside"):
        seif.make_filter("seif", np.zeros(3), config, options)
    options.wildfire = 0.05
    assert seif.make_filter("seif", np.zeros(3), config, options).options.wildfire == 0.05


def test_the_option_table_names_every_option_once():
    """filter_options() is the table the spec parser, the CLI's flags and metrics.json share:
    each SEIF option is an attribute of SeifOptions, and a canonical spec parses back."""
    rows = seif.filter_options()
    assert len({r["key"] for r in rows}) == len(rows)
    owners = {("seif",): seif.SeifOptions(), ("batch",): seif.BatchOptions()}
    for row in rows:
        if row["profile"]:  # a shorthand for other options
            spec = seif.parse_filter_spec("seif:profile=" + row["choices"])
            assert seif.canonical_filter_spec(spec).startswith("seif:linearization=invariant,iterations=3")
            continue
        owner = owners.get(row["filters"], seif.FilterSpec())
        assert hasattr(owner, row["attribute"]), row
        value = getattr(owner, row["attribute"])
        if isinstance(value, float):  # a real prints as the table writes it: 0 for 0.0
            assert value == float(row["default"]), row
            continue
        text = str(value).lower() if isinstance(value, bool) else str(getattr(value, "text", value))
        assert text == row["default"], row
        if row["choices"]:
            name = "batch" if row["filters"] == ("batch",) else "seif"
            for choice in row["choices"].split("|"):
                spec = seif.parse_filter_spec(f"{name}:{row['key']}={choice}")
                back = seif.parse_filter_spec(seif.canonical_filter_spec(spec))
                assert getattr(back, name).__repr__() == getattr(spec, name).__repr__()
                if row["filters"] == ("batch",):
                    assert getattr(back.batch, row["attribute"]).text == choice
    spec = seif.parse_filter_spec("seif:active=4,relax-order=random,seed=3")
    canonical = seif.canonical_filter_spec(spec)
    assert canonical.startswith("seif:linearization=standard,") and "relax-order=random" in canonical
    back = seif.parse_filter_spec(canonical)
    assert (back.seif.active, back.seif.seed, back.seif.relax_order.text) == (4, 3, "random")


def test_batch_options_and_report(paper_world):
    """The batch's start and solver from Python, its report after finish()."""
    data, world = paper_world
    start = seif.start_pose(data)
    config = paper_config(world)
    costs = {}
    for init in ("ekf", "seif", "odometry"):
        options = seif.BatchOptions()
        options.init = init
        batch = seif.BatchMap(start, config, options)
        assert batch.smoother_report is None
        for step in data.steps:
            batch.step(step.u, step.observations)
        batch.finish()
        report = batch.smoother_report
        assert report.init == init and report.converged
        assert report.costs[0] == report.initial_cost > report.final_cost == report.costs[-1]
        assert report.poses == batch.nodes <= len(data.steps) + 1
        assert len(batch.trajectory_covariances()) == len(data.steps) + 1
        costs[init] = report.final_cost
    assert costs["seif"] == pytest.approx(costs["ekf"], rel=1e-9)
    assert costs["odometry"] == pytest.approx(costs["ekf"], rel=1e-9)
    spec = seif.parse_filter_spec("batch:init=seif,solver=kkt")
    assert str(spec.batch.init) in ("Init.Seif", "seif") or spec.batch.init == seif.BatchOptions.Init.Seif
    smoother = seif.make_smoother("ekf", start, config)
    for step in data.steps:
        smoother.step(step.u, step.observations)
    smoother.finish()
    assert smoother.smoother_report.init == "ekf"
    assert smoother.smoother_report.final_cost == pytest.approx(costs["ekf"], rel=1e-9)


@pytest.mark.parametrize("method", ["nn", "jcbb"])
@pytest.mark.parametrize("place", ["filter", "held"])
def test_association_from_python_equals_the_cpp_run(tmp_path, method, place):
    """An Associator driven from Python through run_loop's associate hook, on the park with
    clutter and missed detections: scored against the simulator's truth."""
    data, world = seif.simulated_dataset("park", seed=2, steps=400, clutter=0.5, detection_probability=0.9)
    config = paper_config(world)
    options = seif.AssociationOptions()
    options.method = method
    options.provisional = seif.ProvisionalPlace(place)
    associator = seif.Associator(options)
    f = seif.make_filter("ekf", seif.start_pose(data), config)
    seif.run_loop(f, data, associate=lambda filt, step, k, z: associator.associate(filt, k, z))
    associator.finish(f)
    counts = associator.counts
    assert counts.scored > 1000
    assert counts.correct / counts.scored > 0.98
    assert counts.landmarks_final == len(f.landmark_ids())
    truths = {associator.truth_of(i) for i in f.landmark_ids()}
    assert all(t >= 6 for t in truths), "every landmark labelled with a tree of the world"


@pytest.mark.parametrize("seed, spec", [(1, "ekf"), (2, "seif")])  # seed 1 merges, seed 2 keeps a duplicate
def test_a_streamed_run_records_every_association(tmp_path, seed, spec):
    """run_filter with an associator: one record per observation offered, each merge, and
    verdicts that add up to the associator's own score (as associations.csv does)."""
    config = seif.preset_config("park", 0, 1500, seed)
    config.clutter = 1.0
    config.detection_probability = 0.9
    source = seif.RobotLogSource(seif.simulate(config), config.noise)
    options = seif.AssociationOptions()
    options.method = seif.AssociationMethod.NearestNeighbour
    if spec == "seif":
        options.marginal = seif.MarginalMode.Local
    associator = seif.Associator(options)
    f = seif.make_filter(spec, source.info.start_pose, source.info.filter_config())
    out = seif.run_filter(f, source, associator=associator)
    counts = associator.counts
    assert len(out.associations) == counts.observations > 1000
    assert len(out.merges) == counts.merged
    assert out.associations_from == 0
    assert all(0 <= r.step < out.steps for r in out.associations)
    news = sum(r.decision.outcome == seif.ScanDecision.Outcome.New for r in out.associations)
    assert news == counts.new_landmarks
    verdicts, final = seif.association_verdicts(out, f, associator)
    assert len(verdicts) == len(final) == len(out.associations)
    V = seif.AssociationVerdict
    assert verdicts.count(V.Correct) == counts.correct > 0
    assert verdicts.count(V.Wrong) + verdicts.count(V.Duplicate) == counts.wrong
    ids = set(f.landmark_ids())
    for r, v, at in zip(out.associations, verdicts, final):
        if at != -1:
            assert at in ids and at == seif.merged_into(r.decision.landmark, out.merges)
        if v == V.Duplicate:
            assert associator.is_duplicate(at) and associator.truth_of(at) == r.truth
    assert sum(associator.is_duplicate(i) for i in ids) == counts.duplicate_landmarks
    assert (counts.merged if seed == 1 else counts.duplicate_landmarks) > 0
    moved = sum(at != r.decision.landmark for r, at in zip(out.associations, final) if at != -1)
    assert (moved > 0) == (counts.merged > 0)
    seif.write_associations_csv(tmp_path / "associations.csv", out, f, associator)
    rows = (tmp_path / "associations.csv").read_text().splitlines()
    assert rows[0].split(",")[-1] == "verdict" and len(rows) == 1 + len(out.associations)
    assert sum(row.endswith(",correct") for row in rows) == counts.correct


def test_a_discarded_scan_counts_nothing():
    """The filter refuses a scan's update and the caller goes on: discard_scan forgets the
    landmarks it started, and their ids are given again."""
    options = seif.AssociationOptions()
    options.method = seif.AssociationMethod.NearestNeighbour
    associator = seif.Associator(options)
    f = seif.make_filter("ekf", np.zeros(3), seif.paper_filter_config(seif.NoiseModel()))
    scan = [seif.Observation(-1, np.array([0.1, 0.5])), seif.Observation(-1, np.array([0.15, -0.8]))]
    first = [z.landmark for z in associator.associate(f, 0, scan)]
    assert associator.counts.new_landmarks == 2
    associator.discard_scan()
    assert associator.counts.new_landmarks == 0
    again = associator.associate(f, 1, scan)
    assert [z.landmark for z in again] == first
    f.update(again)
    associator.associate(f, 2, [])
    associator.discard_scan()  # once the next scan is associated, nothing is left to discard
    assert associator.counts.new_landmarks == 2
    assert sorted(f.landmark_ids()) == sorted(first)


def test_last_scan_says_what_became_of_each_observation():
    """Associator.last_scan: one decision per observation given, in their order; the matched
    and new ones are those returned, the ambiguous one is dropped."""
    options = seif.AssociationOptions()
    options.method = seif.AssociationMethod.NearestNeighbour
    options.confirm = 1  # every new landmark confirmed at once
    associator = seif.Associator(options)
    f = seif.make_filter("ekf", np.zeros(3), seif.paper_filter_config(seif.NoiseModel()))
    first = [seif.Observation(-1, np.array([0.1, 0.5]))]
    f.update(associator.associate(f, 0, first))
    (started,) = associator.last_scan
    assert started.outcome == seif.ScanDecision.Outcome.New
    assert started.applied and not started.provisional and started.d2 == float("inf")
    # The same point seen twice: one observation per landmark a scan, so the second, inside
    # the landmark's gates, is left without one.
    scan = [seif.Observation(-1, np.array([0.1, 0.5])), seif.Observation(-1, np.array([0.1, 0.5]))]
    kept = associator.associate(f, 1, scan)
    matched, second = associator.last_scan
    assert matched.outcome == seif.ScanDecision.Outcome.Matched and matched.landmark == started.landmark
    assert matched.d2 < seif.chi_square_quantile(0.99, 2)
    assert second.outcome == seif.ScanDecision.Outcome.Ambiguous and second.landmark == -1
    assert not second.applied and second.d2 <= seif.chi_square_quantile(0.9999, 2)
    assert [z.landmark for z in kept] == [matched.landmark]
    assert associator.counts.ambiguous_dropped == 1
    associator.associate(f, 2, [])
    assert associator.last_scan == []


def test_each_filter_names_the_marginal_its_gates_default_to():
    """AssociationOptions.marginal = None gates with the filter's own marginal: the SEIF's local
    one (constant time), the exact one elsewhere; the batch before it solves uses its start's."""
    config = seif.paper_filter_config(seif.NoiseModel())
    M = seif.MarginalMode
    expected = {"seif": M.Local, "seif:profile=consistent": M.Local, "ekf": M.Exact, "eif": M.Exact,
                "batch": M.Exact, "batch:init=seif": M.Local}
    for spec, mode in expected.items():
        assert seif.make_filter(spec, np.zeros(3), config).gate_marginal() == mode, spec


def test_the_association_option_table_names_every_attribute():
    """Each row of the table the flags and metrics.json come from is an attribute of
    AssociationOptions, with the same default."""
    options = seif.AssociationOptions()
    rows = seif.association_options()
    assert {r["key"] for r in rows} >= {"association", "gate-marginal", "accept-gate", "provisional", "drop-unlabelled"}
    for row in rows:
        value = getattr(options, row["attribute"])
        if isinstance(value, bool):
            assert row["default"] == ("true" if value else "false")
        elif isinstance(value, float):
            assert float(row["default"]) == value
        elif isinstance(value, int) and not hasattr(value, "name"):
            assert int(row["default"]) == value
        else:
            assert row["default"] in row["choices"].split("|")


def test_the_association_ceiling_from_python():
    """What the true map seen from the true pose associates: near all on the park, about nine
    in ten at the paper's density (docs/association.md, "The ceiling")."""
    fractions = {}
    for preset, landmarks in (("park", 0), ("uniform", 200)):
        config = seif.preset_config(preset, landmarks, 300, 1)
        config.clutter = 1.0
        source = seif.RobotLogSource(seif.simulate(config), config.noise)
        ceiling = seif.association_ceiling(source, source.info.sensor)
        assert ceiling.observations > 500 and ceiling.scans > 100
        assert ceiling.joint_truncated == 0
        fractions[preset] = ceiling.individual / ceiling.observations
    assert fractions["park"] > 0.99
    assert 0.8 < fractions["uniform"] < 0.95
    log = seif.simulate(seif.preset_config("park", 0, 50, 1))
    log.groundtruth = []
    assert seif.association_ceiling(seif.RobotLogSource(log, seif.NoiseModel()), seif.RangeBearingModel(0.5, 0.03)) is None


@pytest.mark.parametrize("spec", ["seif:rho=0.05", "seif:profile=consistent,active=20,sparsify=conservative,gauge=paper"])
def test_seif_information_scale_reaches_python(paper_world, spec):
    """rho and sparsify=conservative keep the store's information times kappa
    (information_scale): the covariances Python reads are the inverse of the information it reads."""
    data, world = paper_world
    f = seif.make_filter(spec, seif.start_pose(data), paper_config(world))
    seif.run_filter(f, data)
    assert f.information_scale > 1.0
    assert f.information_scalings > 0
    P = np.linalg.inv(f.information().toarray())
    np.testing.assert_allclose(f.pose_covariance(), P[:3, :3], rtol=1e-6, atol=1e-12)


def test_seif_gauge_reaches_python(paper_world):
    """gauge=kept, set from a spec or on SeifOptions: the sparsified SEIF holds no more
    information on the map's common translation than the unsparsified one (docs/consistency.md,
    "The gauge"), while the paper's rule claims some."""
    data, world = paper_world
    options = seif.SeifOptions()
    options.gauge = "kept"
    assert options.gauge == seif.SeifOptions.Gauge.Kept
    assert "gauge" in repr(options)

    def translation_information(spec):
        f = seif.make_filter(spec, seif.start_pose(data), paper_config(world))
        seif.run_filter(f, data)
        H = f.information().toarray()
        t = np.zeros(H.shape[0])
        t[0] = 1.0
        t[3::2] = 1.0
        t /= np.linalg.norm(t)
        return t @ H @ t

    reference = translation_information("seif:active=39,mean=exact")
    kept = translation_information("seif:active=4,mean=exact,gauge=kept")
    paper = translation_information("seif:active=4,mean=exact")
    assert kept < 1.01 * reference
    assert paper > 10.0 * reference


def test_seif_coarse_level_reaches_python(paper_world):
    """coarse=rigid, set from a spec or on SeifOptions: the amortised map lies nearer the
    posterior's mean H^-1 b than Gauss-Seidel alone leaves it (docs/consistency.md, "The
    mean's coarse level")."""
    data, world = paper_world
    options = seif.SeifOptions()
    options.coarse = "rigid"
    assert options.coarse == seif.SeifOptions.Coarse.Rigid
    assert "coarse" in repr(options)

    def lag(spec):
        f = seif.make_filter(spec, seif.start_pose(data), paper_config(world))
        seif.run_filter(f, data)
        return np.linalg.norm(f.mean()[3:] - f.posterior_mean()[3:])

    base = "seif:linearization=invariant,iterations=2,active=6,gauge=kept"
    assert lag(base + ",coarse=rigid") < 0.5 * lag(base)


def test_new_landmarks_never_take_an_id_the_filter_already_holds():
    """An associator given a filter with a map of its own numbers new landmarks past it."""
    f = seif.make_filter("ekf", np.zeros(3), seif.paper_filter_config(seif.NoiseModel()))
    f.update([seif.Observation(0, np.array([1.0, 0.0]))])  # the caller's landmark 0
    options = seif.AssociationOptions()
    options.method = seif.AssociationMethod.NearestNeighbour
    options.confirm = 1
    associator = seif.Associator(options)
    out = associator.associate(f, 0, [seif.Observation(9, np.array([5.0, 1.5]))])  # far from it
    assert [z.landmark for z in out] == [1]
    f.update(out)
    assert f.landmark_ids() == [0, 1]
    np.testing.assert_allclose(f.landmark(0), [1.0, 0.0], atol=1e-9)
