// The filters (filters/*.hpp): FilterConfig, SeifOptions, make_filter and the SlamFilter
// interface, with the SEIF's sparse information matrix as scipy.sparse.csc_matrix.
#include "bindings.hpp"

#include "filters/batch_map.hpp"
#include "filters/eif_slam.hpp"
#include "filters/ekf_slam.hpp"
#include <seif/association/association.hpp>
#include <seif/filters/factory.hpp>
#include "filters/seif_slam.hpp"
#include <seif/filters/slam_filter.hpp>

#include <Eigen/SparseCore>

#include <algorithm>

namespace seif::python {
namespace {

template <typename T>
std::shared_ptr<T> mutableModel(const std::shared_ptr<const T>& p) {
  return std::const_pointer_cast<T>(p);  // models are immutable: no method of theirs changes them
}

template <typename E>
std::string_view nameOf(E v) {
  return optionName(v);
}

void bindSeifOptions(py::module_& m) {
  py::class_<SeifOptions> o(m, "SeifOptions",
                            "The SEIF's options (filters/seif_slam.hpp). Enum fields take the enum or its "
                            "name, e.g. options.sparsify = 'eseif'.");
  bindNamedEnum<SeifOptions::Mean>(o, "Mean", "'amortized' | 'exact'", &SeifOptions::parseMean, &nameOf<SeifOptions::Mean>)
      .value("Amortized", SeifOptions::Mean::Amortized)
      .value("Exact", SeifOptions::Mean::Exact);
  bindNamedEnum<SeifOptions::Deactivate>(o, "Deactivate", "'weakest' | 'oldest'", &SeifOptions::parseDeactivate,
                                         &nameOf<SeifOptions::Deactivate>)
      .value("Weakest", SeifOptions::Deactivate::Weakest)
      .value("Oldest", SeifOptions::Deactivate::Oldest);
  bindNamedEnum<SeifOptions::Recovery>(o, "Recovery", "'before-update' | 'after-update'",
                                       &SeifOptions::parseRecovery, &nameOf<SeifOptions::Recovery>)
      .value("AfterMeasurement", SeifOptions::Recovery::AfterMeasurement)
      .value("BeforeMeasurement", SeifOptions::Recovery::BeforeMeasurement);
  bindNamedEnum<SeifOptions::RelaxOrder>(o, "RelaxOrder", "'cyclic' | 'random' | 'wildfire'", &SeifOptions::parseRelaxOrder,
                                         &nameOf<SeifOptions::RelaxOrder>)
      .value("Random", SeifOptions::RelaxOrder::Random)
      .value("Cyclic", SeifOptions::RelaxOrder::Cyclic)
      .value("Wildfire", SeifOptions::RelaxOrder::Wildfire);
  bindNamedEnum<SeifOptions::Sparsify>(o, "Sparsify", "'seif' | 'eseif'", &SeifOptions::parseSparsify,
                                       &nameOf<SeifOptions::Sparsify>)
      .value("Seif", SeifOptions::Sparsify::Seif)
      .value("Eseif", SeifOptions::Sparsify::Eseif)
      .value("Conservative", SeifOptions::Sparsify::Conservative);
  bindNamedEnum<SeifOptions::Covariance>(o, "Covariance", "'exact' | 'local' | 'conservative'",
                                         &SeifOptions::parseCovariance, &nameOf<SeifOptions::Covariance>)
      .value("Exact", SeifOptions::Covariance::Exact)
      .value("Local", SeifOptions::Covariance::Local)
      .value("Conservative", SeifOptions::Covariance::Conservative);
  bindNamedEnum<SeifOptions::Motion>(o, "Motion", "'immediate' | 'deferred'", &SeifOptions::parseMotion,
                                     &nameOf<SeifOptions::Motion>)
      .value("Immediate", SeifOptions::Motion::Immediate)
      .value("Deferred", SeifOptions::Motion::Deferred);
  bindNamedEnum<SeifOptions::Gauge>(o, "Gauge", "'paper' | 'kept'", &SeifOptions::parseGauge, &nameOf<SeifOptions::Gauge>)
      .value("Paper", SeifOptions::Gauge::Paper)
      .value("Kept", SeifOptions::Gauge::Kept);
  bindNamedEnum<SeifOptions::Coarse>(o, "Coarse", "'off' | 'rigid'", &SeifOptions::parseCoarse, &nameOf<SeifOptions::Coarse>)
      .value("Off", SeifOptions::Coarse::Off)
      .value("Rigid", SeifOptions::Coarse::Rigid);
  o.def(py::init<>())
      .def_readwrite("active", &SeifOptions::active, "theta_x: landmarks linked to the robot after each step")
      .def_readwrite("relax", &SeifOptions::relax, "K: landmarks relaxed per step besides the robot and the active ones")
      .def_readwrite("mean", &SeifOptions::mean, "amortized (constant time) or exact (sparse Cholesky)")
      .def_readwrite("deactivate", &SeifOptions::deactivate, "weakest (the paper) or oldest")
      .def_readwrite("recovery", &SeifOptions::recovery, "when the amortised mean is relaxed in update()")
      .def_readwrite("relax_order", &SeifOptions::relax_order, "which K landmarks each step relaxes")
      .def_readwrite("motion", &SeifOptions::motion, "immediate (every control) or deferred (composed until an observation)")
      .def_readwrite("seed", &SeifOptions::seed, "seed of the random choice of relaxed landmarks")
      .def_readwrite("sparsify", &SeifOptions::sparsify, "seif (the paper's conditioning), eseif or conservative")
      .def_readwrite("covariance", &SeifOptions::covariance, "exact, local or conservative marginal covariances")
      .def_readwrite("beta", &SeifOptions::beta, "ESEIF: landmarks whose observations relocalise the robot")
      .def_readwrite("reanchor", &SeifOptions::reanchor,
                     "linearization=invariant: re-anchor an observed landmark whose mean moved more than this [m]")
      .def_readwrite("blanket", &SeifOptions::blanket,
                     "local marginals: at most this many variables besides the queried ones, strongest links "
                     "first (0: the whole Markov blanket)")
      .def_readwrite("bounds", &SeifOptions::bounds,
                     "keep an upper bound on every landmark's covariance (MarginalMode.Conservative)")
      .def_readwrite("rho", &SeifOptions::rho,
                     "the journal paper's knob: H and b scaled by 1 - rho at each sparsification (0: off)")
      .def_readwrite("gauge", &SeifOptions::gauge,
                     "paper (eq. 44-51 as published) or kept: the sparsification claims no information on the "
                     "directions the posterior leaves free")
      .def_readwrite("stale", &SeifOptions::stale,
                     "deactivate first the active landmarks not observed in the last `stale` steps, the "
                     "longest unobserved first (0: off)")
      .def_readwrite("omega", &SeifOptions::omega,
                     "over-relaxation of the amortised mean, in (0, 2): each relaxed landmark moves omega times its "
                     "Gauss-Seidel step (1: eq. 42)")
      .def_readwrite("wildfire", &SeifOptions::wildfire,
                     "relax_order Wildfire: the move of a landmark's mean, in its conditional standard deviations, "
                     "that queues its neighbours for relaxation")
      .def_readwrite("coarse", &SeifOptions::coarse,
                     "off or rigid: the amortised mean also corrects the map's rigid motion each step (O(1))")
      .def("__repr__", [](py::handle s) {
        return reprOf(s, {"active", "relax", "mean", "deactivate", "recovery", "relax_order", "seed", "sparsify",
                          "covariance", "beta", "reanchor", "blanket", "bounds", "motion", "rho", "gauge", "coarse", "stale", "omega", "wildfire"});
      });
}

void bindBatchOptions(py::module_& m) {
  py::class_<BatchOptions> o(m, "BatchOptions",
                             "The batch MAP smoother's options (filters/batch_options.hpp): where it starts and its "
                             "linear solver. Enum fields take the enum or its name, e.g. options.init = 'seif'.");
  bindNamedEnum<BatchOptions::Init>(o, "Init", "'ekf' | 'seif' | 'odometry'", &BatchOptions::parseInit,
                                    &nameOf<BatchOptions::Init>)
      .value("Ekf", BatchOptions::Init::Ekf)
      .value("Seif", BatchOptions::Init::Seif)
      .value("Odometry", BatchOptions::Init::Odometry);
  bindNamedEnum<BatchOptions::Solver>(o, "Solver", "'cholesky' | 'kkt'", &BatchOptions::parseSolver,
                                      &nameOf<BatchOptions::Solver>)
      .value("Cholesky", BatchOptions::Solver::Cholesky)
      .value("Kkt", BatchOptions::Solver::Kkt);
  o.def(py::init<>())
      .def_readwrite("init", &BatchOptions::init, "the start: a filter run alongside (ekf, seif) or odometry alone")
      .def_readwrite("solver", &BatchOptions::solver, "cholesky (normal equations) or kkt (SparseLU, the cross-check)")
      .def("__repr__", [](py::handle s) { return reprOf(s, {"init", "solver"}); });

  py::class_<SmootherReport>(m, "SmootherReport",
                             "A smoother's last solve; costs are 0.5 chi-square (GTSAM's error()).")
      .def_readonly("init", &SmootherReport::init)
      .def_readonly("poses", &SmootherReport::poses)
      .def_readonly("landmarks", &SmootherReport::landmarks)
      .def_readonly("constraints", &SmootherReport::constraints)
      .def_readonly("converged", &SmootherReport::converged)
      .def_readonly("iterations", &SmootherReport::iterations)
      .def_readonly("initial_cost", &SmootherReport::initial_cost)
      .def_readonly("final_cost", &SmootherReport::final_cost)
      .def_readonly("costs", &SmootherReport::costs)
      .def_readonly("gradient_norm", &SmootherReport::gradient_norm)
      .def_readonly("initial_gradient_norm", &SmootherReport::initial_gradient_norm)
      .def_readonly("solve_seconds", &SmootherReport::solve_seconds)
      .def_readonly("linearize_seconds", &SmootherReport::linearize_seconds)
      .def_readonly("factorize_seconds", &SmootherReport::factorize_seconds)
      .def_readonly("step_seconds", &SmootherReport::step_seconds)
      .def_readonly("factor_nonzeros", &SmootherReport::factor_nonzeros)
      .def("__repr__", [](py::handle s) {
        return reprOf(s, {"init", "poses", "landmarks", "constraints", "converged", "iterations", "initial_cost",
                          "final_cost", "solve_seconds"});
      });
}

void bindConfig(py::module_& m) {
  bindNamedEnum<Linearization>(m, "Linearization",
                               "Where Jacobians are evaluated: Standard (newest estimates), FirstEstimates "
                               "(FEJ), Invariant (the right-invariant EKF) or ObservabilityConstrained (the OC-EKF). Strings "
                               "'standard' | 'fej' | 'invariant' | 'oc'.",
                               &parseLinearization, &linearizationName)
      .value("Standard", Linearization::Standard)
      .value("FirstEstimates", Linearization::FirstEstimates)
      .value("Invariant", Linearization::Invariant)
      .value("ObservabilityConstrained", Linearization::ObservabilityConstrained);

  py::class_<FilterConfig>(m, "FilterConfig",
                           "What every filter is built with (filters/slam_filter.hpp): the motion and sensor models "
                           "(both required: paper_filter_config(noise) builds the paper's, DatasetInfo.filter_config() "
                           "a dataset's), the start pose's sigmas, the outlier gate and the linearization.")
      .def(py::init<>())
      .def_property(
          "motion", [](const FilterConfig& c) { return mutableModel(c.motion); },
          [](FilterConfig& c, std::shared_ptr<MotionModel> p) { c.motion = std::move(p); },
          "The motion model of predict(input).")
      .def_property(
          "sensor", [](const FilterConfig& c) { return mutableModel(c.sensor); },
          [](FilterConfig& c, std::shared_ptr<MeasurementModel> p) { c.sensor = std::move(p); },
          "The sensor model of update(observations).")
      .def_readwrite("initial_pose_sigma", &FilterConfig::initial_pose_sigma,
                     "start pose standard deviations (x [m], y [m], theta [rad])")
      .def_readwrite("outlier_gate", &FilterConfig::outlier_gate,
                     "gross-outlier gate in measurement standard deviations; inf disables it")
      .def_readwrite("linearization", &FilterConfig::linearization)
      .def_readwrite("iterations", &FilterConfig::iterations, "Gauss-Newton iterations of each measurement update")
      .def("__repr__", [](py::handle s) {
        return reprOf(s, {"motion", "sensor", "initial_pose_sigma", "outlier_gate", "linearization", "iterations"});
      });
  m.def("paper_filter_config", &paperFilterConfig, py::arg("noise"),
        "A FilterConfig with the paper's models: VelocityModel(sigma_v, sigma_w, per-step) and "
        "RangeBearingModel(sigma_range, sigma_bearing).");

  py::class_<FilterStats>(m, "FilterStats", "Structure of the information matrix H (filters/slam_filter.hpp).")
      .def(py::init<>())
      .def_readonly("landmarks", &FilterStats::landmarks)
      .def_readonly("links", &FilterStats::links, "non-zero off-diagonal blocks of H (unordered pairs)")
      .def_readonly("robot_links", &FilterStats::robot_links, "landmarks linked to the robot (the active set)")
      .def_readonly("max_landmark_links", &FilterStats::max_landmark_links)
      .def_readonly("blocks_touched", &FilterStats::blocks_touched, "H blocks read or written by the last step")
      .def_readonly("information_scale", &FilterStats::information_scale,
                    "SEIF: kappa, the factor by which rho / conservative sparsification scaled its information down")
      .def("as_dict",
           [](const FilterStats& s) {
             py::dict d;
             d["landmarks"] = s.landmarks;
             d["links"] = s.links;
             d["robot_links"] = s.robot_links;
             d["max_landmark_links"] = s.max_landmark_links;
             d["blocks_touched"] = s.blocks_touched;
             d["information_scale"] = s.information_scale;
             return d;
           })
      .def("__repr__", [](py::handle s) {
        return reprOf(s, {"landmarks", "links", "robot_links", "max_landmark_links", "blocks_touched",
                          "information_scale"});
      });

  py::class_<PredictedMeasurement>(m, "PredictedMeasurement",
                                   "A landmark's predicted measurement z and innovation covariance S.")
      .def_readonly("z", &PredictedMeasurement::z)
      .def_readonly("S", &PredictedMeasurement::S)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"z", "S"}); });

  py::class_<FilterSpec>(m, "FilterSpec", "A parsed filter spec (filters/factory.hpp).")
      .def(py::init<>())
      .def_readwrite("text", &FilterSpec::text)
      .def_readwrite("name", &FilterSpec::name)
      .def_readwrite("linearization", &FilterSpec::linearization)
      .def_readwrite("iterations", &FilterSpec::iterations)
      .def_readwrite("seif", &FilterSpec::seif)
      .def_readwrite("batch", &FilterSpec::batch)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"text", "name", "linearization", "iterations", "seif"}); });
  m.def("parse_filter_spec", py::overload_cast<std::string_view, Linearization, const SeifOptions&>(&parseFilterSpec), py::arg("text"), py::arg("linearization") = Linearization::Standard,
        py::arg("seif") = SeifOptions{},
        "Parses 'name[:key=value,...]' (ekf, eif, seif, batch). Raises InvalidArgument naming what is wrong.");
  m.def("canonical_filter_spec", &canonicalFilterSpec, py::arg("spec"),
        "'name:key=value,...' with every option the filter takes: what metrics.json records; parses back "
        "to an equal spec.");
  m.def(
      "filter_options",
      [] {
        py::list rows;
        FilterSpec seif_defaults;
        seif_defaults.name = "seif";
        for (const FilterOption& o : filterOptions()) {
          py::dict row;
          row["key"] = std::string(o.key);
          row["attribute"] = [&] {
            std::string a(o.key);
            std::replace(a.begin(), a.end(), '-', '_');
            return a;
          }();
          row["filters"] = o.scope == FilterOption::Scope::Seif    ? py::make_tuple("seif")
                           : o.scope == FilterOption::Scope::Batch ? py::make_tuple("batch")
                                                                   : py::make_tuple("ekf", "eif", "seif");
          row["choices"] = std::string(o.choices);
          row["profile"] = o.kind == FilterOption::Kind::Profile;
          row["default"] = o.get(seif_defaults);
          row["help"] = std::string(o.help);
          rows.append(row);
        }
        return rows;
      },
      "The table of filter options the spec parser, the CLI's flags and metrics.json share: one dict per option "
      "(key, attribute on SeifOptions / FilterSpec, filters, choices, default, help).");
  m.def("split_filter_list", &splitFilterList, py::arg("list"),
        "Splits 'batch,ekf,seif:sparsify=eseif,beta=4' into specs.");
}

void bindSlamFilter(py::module_& m) {
  using Columns = Eigen::Matrix<double, Eigen::Dynamic, 2>;
  py::enum_<MarginalMode>(m, "MarginalMode", "How a marginal is computed (SlamFilter.marginal)")
      .value("Exact", MarginalMode::Exact, "the posterior's marginal")
      .value("Local", MarginalMode::Local, "from a blanket around the queried variables (never larger than Exact)")
      .value("Conservative", MarginalMode::Conservative,
             "an upper bound on the marginal, never smaller than Exact (the SEIF's in constant time)");

  py::class_<SlamFilter>(m, "SlamFilter",
                         "The interface of every filter (EKF, EIF, SEIF, batch MAP). Build one with make_filter().\n"
                         "State order [x, y, theta, l1x, l1y, ...], landmarks in the order they entered the map.")
      .def_property_readonly("name", &SlamFilter::name, "'ekf', 'eif', 'seif' or 'batch'")
      .def("predict", py::overload_cast<const MotionIncrement&>(&SlamFilter::predict), py::arg("increment"),
           "Motion update with an increment linearised at this filter's pose.")
      .def("predict", py::overload_cast<const MotionInput&>(&SlamFilter::predict), py::arg("input"),
           "Motion update with an input (VelocityControl, AckermannControl, OdometryIncrement) and the "
           "config's motion model.")
      .def(
          "update",
          [](SlamFilter& f, const std::vector<Observation>& z, const MeasurementModel* sensor) {
            if (sensor) f.update(z, *sensor);
            else f.update(z);
          },
          py::arg("observations"), py::arg("sensor") = nullptr,
          "Measurement update with all observations of one instant, by `sensor` (default: the config's).")
      .def(
          "step", [](SlamFilter& f, const MotionInput& u, const std::vector<Observation>& z) { f.step(u, z); },
          py::arg("input"), py::arg("observations") = std::vector<Observation>{},
          "predict(input) then update(observations): one filter cycle.")
      .def("finish", &SlamFilter::finish, py::call_guard<py::gil_scoped_release>(),
           "Call once after the last step (the batch MAP solves here; a filter does nothing).")
      .def("settle", &SlamFilter::settle, py::call_guard<py::gil_scoped_release>(),
           "Bring the stored form up to date for queries (a SEIF with deferred motion applies the "
           "controls it holds); the posterior does not change.")
      .def_property_readonly("smoother", &SlamFilter::smoother)
      .def_property_readonly("smoother_report", [](const SlamFilter& f) -> std::optional<SmootherReport> {
        if (const SmootherReport* r = f.smootherReport()) return *r;
        return std::nullopt;
      }, "A smoother's last solve (SmootherReport), None for a filter or before finish().")
      .def("smoothed_trajectory", &SlamFilter::smoothedTrajectory, "A smoother's poses after finish(); [] for a filter.")
      .def("smoothed_trajectory_covariances", &SlamFilter::smoothedTrajectoryCovariances)
      .def_property_readonly("motion_model", [](const SlamFilter& f) { return f.motionModel().describe(); },
                             "describe() of the config's motion model")
      .def_property_readonly("sensor_model", [](const SlamFilter& f) { return f.sensorModel().describe(); },
                             "describe() of the config's sensor model")
      .def(
          "predict_measurement",
          [](const SlamFilter& f, int id, const MeasurementModel* sensor, const std::optional<Mat2>& R,
             MarginalMode mode) {
            const MeasurementModel& s = sensor ? *sensor : f.sensorModel();
            return f.predictMeasurement(id, s, R ? *R : s.noise(), mode);
          },
          py::arg("id"), py::arg("sensor") = nullptr, py::arg("R") = py::none(), py::arg("mode") = MarginalMode::Exact,
          "Predicted measurement of landmark `id` and its innovation covariance S = J Sigma J^T + R "
          "over the joint marginal of pose and landmark (`mode`: MarginalMode.Exact, Local or Conservative; "
          "defaults: the config's sensor and its noise). Raises UnknownLandmark.")
      .def(
          "marginal",
          [](const SlamFilter& f, const std::vector<int>& ids, bool pose, MarginalMode mode) {
            const Marginal joint = f.marginal(ids, pose, mode);
            return py::make_tuple(joint.mean, joint.covariance);
          },
          py::arg("landmark_ids"), py::arg("pose") = true, py::arg("mode") = MarginalMode::Exact,
          "(mean, covariance) of the pose (when `pose`) and the landmarks `landmark_ids`, in that order. "
          "Exact: the posterior's marginal; Local: H inverted over a blanket around them (the SEIF's "
          "bounded by SeifOptions.blanket: constant time), never larger than Exact; Conservative: an upper "
          "bound, never smaller than Exact (the SEIF's kept in constant time). Raises UnknownLandmark.")
      .def("gate_marginal", &SlamFilter::gateMarginal,
           "The MarginalMode an Associator's gates use with this filter when AssociationOptions.marginal "
           "is None: Local in the SEIF (constant time), Exact in the EKF and EIF, and in the batch once "
           "it has solved (before, the one of the filter it starts from).")
      .def("remove_landmark", &SlamFilter::removeLandmark, py::arg("id"),
           "Takes the landmark out of the map exactly (its marginal out of the posterior).")
      .def("merge_landmarks", &SlamFilter::mergeLandmarks, py::arg("keep"), py::arg("drop"),
           "Merges `drop` into `keep` (the posterior conditioned on their equality).")
      .def("pose", &SlamFilter::pose, "(x, y, theta), heading wrapped")
      .def("pose_covariance", &SlamFilter::poseCovariance, "3x3 marginal covariance of the pose")
      .def("landmark_ids", &SlamFilter::landmarkIds, "ids in state order")
      .def("has_landmark", &SlamFilter::hasLandmark, py::arg("id"))
      .def("landmark", &SlamFilter::landmark, py::arg("id"), "(x, y); raises UnknownLandmark")
      .def("landmark_covariance", &SlamFilter::landmarkCovariance, py::arg("id"), "2x2; raises UnknownLandmark")
      .def("landmark_covariance_columns", [](const SlamFilter& f, int id) -> Columns { return f.landmarkCovarianceColumns(id); },
           py::arg("id"), "The two columns of the joint covariance of landmark `id` (n x 2).")
      .def("stats", &SlamFilter::stats, "FilterStats: the structure of H (use .as_dict() for a dict)")
      .def_property_readonly("robot_links", &SlamFilter::robotLinks)
      .def_property_readonly("blocks_touched", &SlamFilter::blocksTouched)
      .def("rejected_observations", &SlamFilter::rejectedObservations,
           "observations rejected by the gross-outlier gate so far")
      .def("mean", &SlamFilter::mean, "full state mean [x, y, theta, landmarks...] (SEIF: its current estimate)")
      .def("posterior_mean", &SlamFilter::posteriorMean, py::call_guard<py::gil_scoped_release>(),
           "the posterior's mean H^-1 b over the whole state, for a filter whose mean() is not it (the "
           "amortised SEIF: one sparse solve); None for the EKF, EIF, batch and a SEIF with mean='exact'")
      .def("covariance", &SlamFilter::covariance, py::call_guard<py::gil_scoped_release>(),
           "dense full covariance (O(N^3) for information filters)")
      .def("information_dense", &SlamFilter::information, py::call_guard<py::gil_scoped_release>(),
           "dense information matrix H as a numpy array (EKF, batch: the inverse of the covariance)")
      .def(
          "information",
          [](const SlamFilter& f) -> Eigen::SparseMatrix<double> {
            Eigen::SparseMatrix<double> H;
            {
              py::gil_scoped_release release;
              H = f.information().sparseView();
            }
            return H;
          },
          "The information matrix H as scipy.sparse.csc_matrix. SEIF: its own sparse H "
          "(sparseInformation(), stored blocks); dense filters: their dense H without its exact zeros. "
          "information_dense() gives a numpy array.")
      .def("__repr__", [](const SlamFilter& f) {
        return "<" + f.name() + " filter: " + std::to_string(f.landmarkIds().size()) + " landmarks>";
      });

  py::class_<EkfSlam, SlamFilter>(m, "EkfSlam", "EKF-SLAM with a dense covariance.")
      .def(py::init<const Pose2&, const FilterConfig&>(), py::arg("start"), py::arg("config"));
  py::class_<EifSlam, SlamFilter>(m, "EifSlam", "The exact EIF with a dense information matrix.")
      .def(py::init<const Pose2&, const FilterConfig&>(), py::arg("start"), py::arg("config"))
      .def("information_vector", &EifSlam::informationVector, "b");
  py::class_<SeifSlam, SlamFilter>(m, "SeifSlam", "The Sparse Extended Information Filter.")
      .def(py::init<const Pose2&, const FilterConfig&, const SeifOptions&>(), py::arg("start"),
           py::arg("config"), py::arg("options") = SeifOptions{})
      .def("information", &SeifSlam::sparseInformation,
           "H as scipy.sparse.csc_matrix, in the state order (SeifSlam::sparseInformation()).")
      .def("information_vector", &SeifSlam::informationVector, "b")
      .def("exact_mean", &SeifSlam::exactMean, py::call_guard<py::gil_scoped_release>(),
           "H^-1 b by sparse Cholesky, without changing the filter")
      .def("relax_mean", &SeifSlam::relaxMean, py::arg("sweeps"), "Gauss-Seidel sweeps of the mean over every variable (the landmarks over-relaxed by options.omega)")
      .def("active_landmarks", &SeifSlam::activeLandmarks, "ids of the landmarks linked to the robot")
      .def_property_readonly("options", &SeifSlam::options, py::return_value_policy::copy)
      .def("last_sparsification_residual", &SeifSlam::lastSparsificationResidual)
      .def_property_readonly("eseif_relocalizations", &SeifSlam::eseifRelocalizations)
      .def_property_readonly("eseif_deferrals", &SeifSlam::eseifDeferrals)
      .def_property_readonly("eseif_fallbacks", &SeifSlam::eseifFallbacks)
      .def_property_readonly("information_scale", &SeifSlam::informationScale,
                             "kappa: sparsify=conservative's store holds kappa H (covariances leave it times kappa)")
      .def_property_readonly("information_scalings", &SeifSlam::informationScalings,
                             "sparsifications that scaled the information down (sparsify=conservative, rho)");
  py::class_<BatchMap, SlamFilter>(m, "BatchMap", "The batch MAP smoother: estimates are final after finish().")
      .def(py::init<const Pose2&, const FilterConfig&, const BatchOptions&>(), py::arg("start"), py::arg("config"),
           py::arg("options") = BatchOptions{})
      .def_property_readonly("cost", &BatchMap::cost, "chi-square at the solution")
      .def_property_readonly("nodes", &BatchMap::nodes, "poses solved for (observation instants, the start, the end)")
      .def("trajectory_covariances", &BatchMap::trajectoryCovariances, py::call_guard<py::gil_scoped_release>(),
           "the marginal covariance of the pose after every step")
      .def_property_readonly("iterations", &BatchMap::iterations)
      .def_property_readonly("constraint_violation", &BatchMap::constraintViolation);

  m.def(
      "make_smoother",
      [](const std::string& spec, const Pose2& start, const FilterConfig& config, const BatchOptions& options) {
        return makeSmoother(parseFilterSpec(spec, config.linearization), start, config, options);
      },
      py::arg("filter"), py::arg("start"), py::arg("config"), py::arg("options") = BatchOptions{},
      "The batch MAP after the filter `filter` (a spec): the filter runs alongside, and finish() solves from its "
      "estimate (`seif run --smooth`).");
  m.def(
      "make_filter",
      [](const std::string& spec, const Pose2& start, const FilterConfig& config, const SeifOptions& seif) {
        return makeFilter(spec, start, config, seif);
      },
      py::arg("spec"), py::arg("start"), py::arg("config"),
      py::arg("seif_options") = SeifOptions{},
      "Builds a filter from its spec, 'ekf', 'eif', 'seif', 'batch', with options after a colon "
      "('seif:sparsify=eseif,linearization=fej'); unset options come from config.linearization and "
      "seif_options. Raises InvalidArgument for a bad spec.");
}

}  // namespace

void bindAssociation(py::module_& m) {
  bindNamedEnum<AssociationMethod>(m, "AssociationMethod", "'known' | 'nn' | 'jcbb' (association/association.hpp)",
                                   &parseAssociationMethod, &associationMethodName)
      .value("Known", AssociationMethod::Known)
      .value("NearestNeighbour", AssociationMethod::NearestNeighbour)
      .value("Jcbb", AssociationMethod::Jcbb);
  bindNamedEnum<ProvisionalPlace>(m, "ProvisionalPlace", "'filter' | 'held' (association/association.hpp)",
                                  &parseProvisionalPlace, &provisionalPlaceName)
      .value("Filter", ProvisionalPlace::Filter)
      .value("Held", ProvisionalPlace::Held);
  bindNamedEnum<ConfirmRule>(m, "ConfirmRule", "'count' | 'score' (association/association.hpp)", &parseConfirmRule,
                             &confirmRuleName)
      .value("Count", ConfirmRule::Count)
      .value("Score", ConfirmRule::Score);
  py::class_<AssociationOptions>(m, "AssociationOptions",
                                 "Data association's options (association/association.hpp; `seif run --association`)")
      .def(py::init<>())
      .def_readwrite("method", &AssociationOptions::method)
      .def_readwrite("accept", &AssociationOptions::accept, "chi-square probability of the accept gate")
      .def_readwrite("new_landmark", &AssociationOptions::new_landmark, "chi-square probability of the new-landmark gate")
      .def_readwrite("marginal", &AssociationOptions::marginal,
                     "MarginalMode the gates use; None: the filter's (Local in the SEIF, Exact in the others)")
      .def_readwrite("confirm", &AssociationOptions::confirm, "sightings that confirm a provisional landmark")
      .def_readwrite("window", &AssociationOptions::window, "scans it has to be confirmed in")
      .def_readwrite("confirm_rule", &AssociationOptions::confirm_rule,
                     "ConfirmRule: count (confirm sightings in window scans) or score (a track score)")
      .def_readwrite("detection_probability", &AssociationOptions::detection_probability,
                     "score: probability that a landmark in the sensor's footprint is reported")
      .def_readwrite("clutter_density", &AssociationOptions::clutter_density,
                     "score: false detections per unit of measurement space (0: estimated)")
      .def_readwrite("provisional", &AssociationOptions::provisional, "ProvisionalPlace: in the filter or held outside it")
      .def_readwrite("drop_unlabelled", &AssociationOptions::drop_unlabelled,
                     "known: drop observations without a landmark id instead of refusing them")
      .def_readwrite("merge", &AssociationOptions::merge, "chi-square probability of the correspondence test (0: never)")
      .def_readwrite("jcbb_nodes", &AssociationOptions::jcbb_nodes)
      .def_readwrite("refresh", &AssociationOptions::refresh)
      .def_readwrite("slack", &AssociationOptions::slack)
      .def("__repr__", [](py::handle s) {
        return reprOf(s, {"method", "accept", "new_landmark", "marginal", "confirm", "window", "confirm_rule", "provisional",
                          "merge"});
      });
  m.def(
      "association_options",
      [] {
        py::list rows;
        const AssociationOptions defaults;
        for (const AssociationOption& o : associationOptions()) {
          py::dict row;
          row["key"] = std::string(o.key);
          row["attribute"] = std::string(o.attribute);
          row["choices"] = std::string(o.choices);
          row["default"] = o.get(defaults);
          row["help"] = std::string(o.help);
          rows.append(row);
        }
        return rows;
      },
      "The table of association options the CLI's flags and metrics.json share: one dict per option "
      "(key: the flag; attribute: AssociationOptions' and metrics.json's name; choices; default as text; help).");
  py::class_<AssociationCounts>(m, "AssociationCounts", "What an association did, scored against Observation.truth")
      .def_readonly("observations", &AssociationCounts::observations)
      .def_readonly("scored", &AssociationCounts::scored)
      .def_readonly("correct", &AssociationCounts::correct)
      .def_readonly("wrong", &AssociationCounts::wrong)
      .def_readonly("unlabelled", &AssociationCounts::unlabelled)
      .def_readonly("unlabelled_matched", &AssociationCounts::unlabelled_matched)
      .def_readonly("in_removed_landmarks", &AssociationCounts::in_removed_landmarks)
      .def_readonly("new_landmarks", &AssociationCounts::new_landmarks)
      .def_readonly("ambiguous_dropped", &AssociationCounts::ambiguous_dropped)
      .def_readonly("unlabelled_dropped", &AssociationCounts::unlabelled_dropped)
      .def_readonly("provisional_removed", &AssociationCounts::provisional_removed)
      .def_readonly("provisional_final", &AssociationCounts::provisional_final)
      .def_readonly("merged", &AssociationCounts::merged)
      .def_readonly("jcbb_truncated", &AssociationCounts::jcbb_truncated)
      .def_readonly("landmarks_final", &AssociationCounts::landmarks_final)
      .def_readonly("spurious_landmarks", &AssociationCounts::spurious_landmarks)
      .def_readonly("duplicate_landmarks", &AssociationCounts::duplicate_landmarks)
      .def_readonly("seconds", &AssociationCounts::seconds)
      .def("__repr__", [](py::handle s) {
        return reprOf(s, {"observations", "scored", "correct", "wrong", "new_landmarks", "landmarks_final",
                          "spurious_landmarks", "duplicate_landmarks"});
      });
  py::class_<ScanDecision> decision(m, "ScanDecision", "What Associator.associate decided for one observation (last_scan)");
  py::enum_<ScanDecision::Outcome>(decision, "Outcome", "Matched, New (a landmark started) or Ambiguous (dropped)")
      .value("Matched", ScanDecision::Outcome::Matched)
      .value("New", ScanDecision::Outcome::New)
      .value("Ambiguous", ScanDecision::Outcome::Ambiguous);
  decision.def_readonly("outcome", &ScanDecision::outcome)
      .def_readonly("landmark", &ScanDecision::landmark, "Matched, New: the landmark id; Ambiguous: -1")
      .def_readonly("provisional", &ScanDecision::provisional, "the landmark is still provisional after this sighting")
      .def_readonly("applied", &ScanDecision::applied,
                    "the observation goes to the update (not when dropped, nor a held landmark's sighting)")
      .def_readonly("d2", &ScanDecision::d2,
                    "Matched: the pairing's squared Mahalanobis distance; else to the nearest landmark (inf: none)")
      .def("__repr__",
           [](py::handle d) { return reprOf(d, {"outcome", "landmark", "provisional", "applied", "d2"}); });
  py::class_<LandmarkMerge>(m, "LandmarkMerge", "Two landmarks found one (Associator.last_merges): `merged` into `kept`")
      .def_readonly("kept", &LandmarkMerge::kept)
      .def_readonly("merged", &LandmarkMerge::merged)
      .def("__repr__", [](py::handle x) { return reprOf(x, {"kept", "merged"}); });
  py::class_<Associator>(m, "Associator",
                         "Gives observations their landmark ids before an update (run_loop's associate hook)")
      .def(py::init<const AssociationOptions&>(), py::arg("options"))
      .def(
          "associate",
          [](Associator& a, SlamFilter& f, std::size_t k, std::vector<Observation> z) {
            a.associate(f, k, z);
            return z;
          },
          py::arg("filter"), py::arg("k"), py::arg("observations"),
          "The observations with their landmark ids (ambiguous ones left out); may remove provisional landmarks")
      .def("discard_scan", &Associator::discardScan,
           "The filter refused the last associate()'s observations: forget what they counted (sightings, "
           "started landmarks, tallies) and go on")
      .def("finish", [](Associator& a, SlamFilter& filter) { a.finish(filter); }, py::arg("filter"),
           "After the run: removes the landmarks still provisional (a smoother keeps them) and scores the "
           "association")
      .def("truth_of", &Associator::truthOf, py::arg("id"))
      .def("is_duplicate", &Associator::isDuplicate, py::arg("id"),
           "After finish(): landmark `id` shares its label with an older landmark (a smaller id), and its "
           "observations were counted wrong")
      .def_property_readonly("counts", &Associator::counts, py::return_value_policy::copy)
      .def_property_readonly(
          "last_scan",
          [](const Associator& a) { return std::vector<ScanDecision>(a.lastScan().begin(), a.lastScan().end()); },
          "What the last associate() decided, one ScanDecision per observation it was given, in their order "
          "(empty with known association and after a step without observations)")
      .def_property_readonly(
          "last_merges",
          [](const Associator& a) { return std::vector<LandmarkMerge>(a.lastMerges().begin(), a.lastMerges().end()); },
          "The merges the last associate() made before associating its scan, in the order made")
      .def_property_readonly("options", &Associator::options, py::return_value_policy::copy)
      .def(
          "state_bytes", [](const Associator& a) { return py::bytes(a.saveState()); },
          "Its whole state as checkpoint bytes (what a run's checkpoint carries beside the filter, "
          "under ASSOCIATOR_KEY): from_state_bytes continues it bit for bit")
      .def_static(
          "from_state_bytes",
          [](const py::bytes& data, const std::string& name) { return Associator::restoreState(std::string_view(data), name); },
          py::arg("data"), py::arg("name") = "bytes", "The associator state_bytes wrote (DataError naming `name` otherwise)");
  m.attr("ASSOCIATOR_KEY") = std::string(kAssociatorKey);
}

void bindFilters(py::module_& m) {
  bindSeifOptions(m);
  bindBatchOptions(m);
  bindConfig(m);
  bindSlamFilter(m);
  bindAssociation(m);
}

}  // namespace seif::python
