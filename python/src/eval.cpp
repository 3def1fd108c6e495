// The run loop and metrics (eval/run.hpp, eval/run_dataset.hpp), statistics (eval/stats.hpp)
// and the experiments (eval/paper.hpp, eval/consistency.hpp, eval/bench.hpp). Long calls
// release the GIL; progress callbacks re-acquire it (bindings.hpp: pythonCallback).
#include "bindings.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/association_ceiling.hpp>
#include <seif/eval/bench.hpp>
#include <seif/eval/consistency.hpp>
#include <seif/eval/paper.hpp>
#include <seif/eval/run.hpp>
#include <seif/eval/run_dataset.hpp>
#include <seif/eval/stats.hpp>

#include <csignal>
#include <signal.h>

#include <atomic>
#include <exception>
#include <limits>
#include <optional>

namespace seif::python {
namespace {

// A study (consistency, bench) runs in C++ for minutes with the GIL released: Python's SIGINT
// handler, which only flags the signal for the main thread's next bytecode, would not stop
// it. While a SigintStops lives (made on the main thread), SIGINT sets its flag (the study's
// stop) instead; the handler before it is restored after, and the binding raises
// KeyboardInterrupt. On another thread a study runs to its end, as Python's Ctrl-C goes to
// the main thread.
std::atomic<std::atomic<bool>*> g_sigint_flag{nullptr};
extern "C" void flagSigint(int) {
  if (std::atomic<bool>* flag = g_sigint_flag.load()) flag->store(true, std::memory_order_relaxed);
}

class SigintStops {
 public:
  explicit SigintStops(std::atomic<bool>& flag) {
    // Only on the main thread, where Python itself takes Ctrl-C (the GIL is held here).
    const py::module_ threading = py::module_::import("threading");
    if (!threading.attr("current_thread")().is(threading.attr("main_thread")())) return;
    std::atomic<bool>* none = nullptr;
    if (!g_sigint_flag.compare_exchange_strong(none, &flag)) return;  // a study under way keeps it
    struct sigaction action {};
    action.sa_handler = flagSigint;
    sigemptyset(&action.sa_mask);
    installed_ = sigaction(SIGINT, &action, &before_) == 0;
    if (!installed_) g_sigint_flag.store(nullptr);
  }
  ~SigintStops() {
    if (!installed_) return;
    sigaction(SIGINT, &before_, nullptr);
    g_sigint_flag.store(nullptr);
  }
  SigintStops(const SigintStops&) = delete;
  SigintStops& operator=(const SigintStops&) = delete;

 private:
  struct sigaction before_ {};
  bool installed_ = false;
};

/// Raises KeyboardInterrupt(message) carrying what the stopped study finished as `.result`.
[[noreturn]] void raiseInterrupted(const std::string& message, const py::object& result) {
  const py::object error = py::reinterpret_steal<py::object>(PyObject_CallFunction(PyExc_KeyboardInterrupt, "s", message.c_str()));
  if (!error) throw py::error_already_set();
  error.attr("result") = result;
  PyErr_SetObject(PyExc_KeyboardInterrupt, error.ptr());
  throw py::error_already_set();
}

/// (n, 4) array [t, x, y, theta] of a list of TimedPose.
Eigen::MatrixXd poseArray(const std::vector<TimedPose>& poses) {
  Eigen::MatrixXd a(static_cast<Eigen::Index>(poses.size()), 4);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    a.row(static_cast<Eigen::Index>(i)) << poses[i].time, poses[i].pose.transpose();
  }
  return a;
}

void bindRun(py::module_& m) {
  py::class_<AssociationRecord>(m, "AssociationRecord",
                                "One observation offered to the associator and its decision (a row of associations.csv)")
      .def_readonly("step", &AssociationRecord::step, "the step whose update it was offered to (0-based)")
      .def_readonly("index", &AssociationRecord::index, "its place among that step's observations")
      .def_readonly("z", &AssociationRecord::z)
      .def_readonly("truth", &AssociationRecord::truth, "the data's id, hidden from the filter (-1: none)")
      .def_readonly("decision", &AssociationRecord::decision)
      .def("__repr__", [](py::handle x) { return reprOf(x, {"step", "index", "truth", "decision"}); });
  py::class_<MergeRecord>(m, "MergeRecord", "A merge of two landmarks and the step whose association made it")
      .def_readonly("step", &MergeRecord::step)
      .def_readonly("merge", &MergeRecord::merge)
      .def("__repr__", [](py::handle x) { return reprOf(x, {"step", "merge"}); });
  py::enum_<AssociationVerdict>(m, "AssociationVerdict", "A recorded observation's verdict against the truth")
      .value("Unscored", AssociationVerdict::Unscored)
      .value("Correct", AssociationVerdict::Correct)
      .value("Wrong", AssociationVerdict::Wrong)
      .value("Duplicate", AssociationVerdict::Duplicate);
  py::class_<RunOutput>(m, "RunOutput",
                        "What a run produced (eval/run.hpp). List attributes are copied on access; "
                        "trajectory_array() etc. give numpy arrays.")
      .def_readonly("steps", &RunOutput::steps)
      .def_readonly("trajectory", &RunOutput::trajectory, py::return_value_policy::copy, "start pose, then the pose after every step")
      .def_readonly("filter_trajectory", &RunOutput::filter_trajectory, py::return_value_policy::copy,
                    "a smoother's: the estimates while streaming, before finish() smoothed them")
      .def_readonly("step_seconds", &RunOutput::step_seconds)
      .def_readonly("pose_covariances", &RunOutput::pose_covariances, py::return_value_policy::copy)
      .def_readonly("seconds", &RunOutput::seconds)
      .def_readonly("final_stats", &RunOutput::final_stats)
      .def_readonly("max_robot_links", &RunOutput::max_robot_links)
      .def_readonly("max_blocks_touched", &RunOutput::max_blocks_touched)
      .def_readonly("rejected_observations", &RunOutput::rejected_observations)
      .def_readonly("interrupted", &RunOutput::interrupted,
                    "stopped before its last step (Ctrl-C in run_dataset): everything here covers `steps`")
      .def_readonly("dead_reckoning", &RunOutput::dead_reckoning, py::return_value_policy::copy)
      .def_readonly("groundtruth", &RunOutput::groundtruth, py::return_value_policy::copy)
      .def_readonly("gps", &RunOutput::gps, py::return_value_policy::copy)
      .def_readonly("dropped", &RunOutput::dropped)
      .def_readonly("associations", &RunOutput::associations, py::return_value_policy::copy,
                    "with an associator that is not known: every observation offered to it (AssociationRecord)")
      .def_readonly("merges", &RunOutput::merges, py::return_value_policy::copy, "every merge it made (MergeRecord)")
      .def_readonly("associations_from", &RunOutput::associations_from,
                    "the first step `associations` covers (0 but after a resume from an old checkpoint)")
      .def("trajectory_array", [](const RunOutput& o) { return poseArray(o.trajectory); }, "(n, 4): t, x, y, theta")
      .def("dead_reckoning_array", [](const RunOutput& o) { return poseArray(o.dead_reckoning); })
      .def("groundtruth_array", [](const RunOutput& o) { return poseArray(o.groundtruth); })
      .def("gps_array",
           [](const RunOutput& o) {
             Eigen::MatrixXd a(static_cast<Eigen::Index>(o.gps.size()), 3);
             for (std::size_t i = 0; i < o.gps.size(); ++i) {
               a.row(static_cast<Eigen::Index>(i)) << o.gps[i].time, o.gps[i].position.transpose();
             }
             return a;
           },
           "(n, 3): t, x, y");

  py::class_<RunErrors>(m, "RunErrors", "Errors of a run against ground truth / GPS [m]; None when not measurable.")
      .def_readonly("ate", &RunErrors::ate)
      .def_readonly("dead_reckoning_ate", &RunErrors::dead_reckoning_ate)
      .def_readonly("landmark", &RunErrors::landmark)
      .def_readonly("ate_unaligned", &RunErrors::ate_unaligned)
      .def_readonly("dead_reckoning_ate_unaligned", &RunErrors::dead_reckoning_ate_unaligned)
      .def_readonly("landmark_unaligned", &RunErrors::landmark_unaligned)
      .def_readonly("gps", &RunErrors::gps)
      .def_readonly("dead_reckoning_gps", &RunErrors::dead_reckoning_gps)
      .def_readonly("gps_median", &RunErrors::gps_median)
      .def_readonly("gps_without_jumps", &RunErrors::gps_without_jumps)
      .def_readonly("gps_jumps", &RunErrors::gps_jumps)
      .def_readonly("gps_fixes", &RunErrors::gps_fixes)
      .def("__repr__", [](py::handle s) {
        return reprOf(s, {"ate", "dead_reckoning_ate", "landmark", "ate_unaligned", "dead_reckoning_ate_unaligned",
                          "landmark_unaligned", "gps", "dead_reckoning_gps", "gps_median", "gps_fixes",
                          "gps_without_jumps", "gps_jumps"});
      });

  py::class_<RunRequest>(m, "RunRequest", "`seif run` as a request (eval/run_dataset.hpp).")
      .def(py::init([](const std::filesystem::path& dataset, const std::string& filter) {
             RunRequest r;
             r.dataset = dataset;
             r.filter = filter;
             return r;
           }),
           py::arg("dataset") = std::filesystem::path{}, py::arg("filter") = "seif")
      .def_readwrite("dataset", &RunRequest::dataset)
      .def_readwrite("format", &RunRequest::format)
      .def_readwrite("dataset_options", &RunRequest::dataset_options)
      .def_readwrite("filter", &RunRequest::filter, "filter spec, e.g. 'seif:sparsify=eseif'")
      .def_readwrite("outlier_gate", &RunRequest::outlier_gate)
      .def_readwrite("seif", &RunRequest::seif, "SeifOptions (spec options override them)")
      .def_readwrite("batch", &RunRequest::batch, "BatchOptions of the batch and of smooth (spec options override them)")
      .def_readwrite("smooth", &RunRequest::smooth, "run the filter, then the batch MAP from its estimate")
      .def_readwrite("association", &RunRequest::association, "AssociationOptions (method known: the data's ids)")
      .def_readwrite("linearization", &RunRequest::linearization, "default linearization (the spec's overrides it)")
      .def_readwrite("iterations", &RunRequest::iterations, "default iterations (the spec's overrides it)")
      .def_readwrite("map_covariances", &RunRequest::map_covariances)
      .def_readwrite("trajectory_covariances", &RunRequest::trajectory_covariances)
      .def_readwrite("checkpoint_every", &RunRequest::checkpoint_every,
                     "save the filter and the run so far to `checkpoint` after every N steps (0: only when "
                     "the run is interrupted)")
      .def_readwrite("checkpoint", &RunRequest::checkpoint, "the checkpoint file (replaced atomically each time)")
      .def_readwrite("resume", &RunRequest::resume,
                     "resume the run saved in this checkpoint (same dataset): the outputs equal those of the "
                     "run never interrupted")
      .def_readwrite("command_line", &RunRequest::command_line, "recorded in metrics.json")
      .def("__repr__", [](py::handle s) {
        return reprOf(s, {"dataset", "format", "dataset_options", "filter", "outlier_gate", "seif", "map_covariances",
                          "trajectory_covariances"});
      });

  py::class_<AssociationCeilingOptions>(m, "AssociationCeilingOptions",
                                        "association_ceiling()'s gate (d²) and node bound per scan")
      .def(py::init<>())
      .def_readwrite("gate", &AssociationCeilingOptions::gate)
      .def_readwrite("max_nodes", &AssociationCeilingOptions::max_nodes);
  py::class_<AssociationCeiling>(m, "AssociationCeiling",
                                 "The labelled observations the true map seen from the true pose associates right: "
                                 "individually (most likely landmark) and jointly (the scan's most likely one-to-one "
                                 "assignment)")
      .def_readonly("observations", &AssociationCeiling::observations)
      .def_readonly("individual", &AssociationCeiling::individual)
      .def_readonly("joint", &AssociationCeiling::joint)
      .def_readonly("scans", &AssociationCeiling::scans)
      .def_readonly("joint_truncated", &AssociationCeiling::joint_truncated)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"observations", "individual", "joint", "scans"}); });
  m.def(
      "association_ceiling",
      [](EventSource& source, const MeasurementModel& sensor, const AssociationCeilingOptions& options) {
        py::gil_scoped_release release;
        return associationCeiling(source, sensor, options);
      },
      py::arg("source"), py::arg("sensor"), py::arg("options") = AssociationCeilingOptions{},
      "Reads the source to its end; how many labelled observations the true map seen from the true pose "
      "associates right (None without ground-truth poses or landmarks).");

  py::class_<RunReport>(m, "RunReport", "What run_dataset() measured.")
      .def_readonly("info", &RunReport::info)
      .def_readonly("output", &RunReport::output)
      .def_readonly("errors", &RunReport::errors)
      .def_readonly("landmarks", &RunReport::landmarks)
      .def_readonly("smoother", &RunReport::smoother, py::return_value_policy::copy, "SmootherReport of a batch or smooth run, else None")
      .def_readonly("association", &RunReport::association, py::return_value_policy::copy, "AssociationCounts of an nn or jcbb run, else None")
      .def_readonly("association_ceiling", &RunReport::association_ceiling, py::return_value_policy::copy,
                    "AssociationCeiling of an nn or jcbb run on data with ground truth, else None")
      .def_readonly("filter_errors", &RunReport::filter_errors, py::return_value_policy::copy, "smooth: the filter's errors before the batch")
      .def_readonly("filter_map_distance", &RunReport::filter_map_distance,
                    "smooth: RMS distance of the filter's map from the batch's [m]")
      .def_readonly("filter_trajectory_distance", &RunReport::filter_trajectory_distance, py::return_value_policy::copy,
                    "with smooth: [RMS, median] distance of the filter's position from the batch's at every pose [m]")
      .def_readonly("filter_covariance_ratio", &RunReport::filter_covariance_ratio, py::return_value_policy::copy,
                    "with smooth: trace(filter's landmark covariance) / trace(batch's) over the landmarks, "
                    "[median, 10th, 90th percentile]; below 1 the filter claims too little variance")
      .def_readonly("seconds_wall", &RunReport::seconds_wall)
      .def_readonly("seconds_outputs", &RunReport::seconds_outputs);

  m.def(
      "run_dataset",
      [](RunRequest request, const std::filesystem::path& out, const py::object& progress) {
        // Ctrl-C: Python's C handler only flags the signal; the flag is read here at each
        // progress report (or KeyboardInterrupt comes out of the progress callback). The run then stops
        // whole - outputs and any checkpoint written - and KeyboardInterrupt is raised after.
        std::atomic<bool> stop{false};
        std::optional<py::error_already_set> interrupt;
        const std::function<void(double)> callback = [&](double fraction) {
          py::gil_scoped_acquire gil;
          try {
            if (!progress.is_none()) progress(fraction);
            if (PyErr_CheckSignals() != 0) throw py::error_already_set();
          } catch (py::error_already_set& e) {
            if (!e.matches(PyExc_KeyboardInterrupt)) throw;
            if (!interrupt) interrupt.emplace(std::move(e));
            stop.store(true, std::memory_order_relaxed);
          }
        };
        request.stop = &stop;
        RunReport report;
        std::exception_ptr failure;
        {
          py::gil_scoped_release release;
          try {
            report = runDataset(request, out, callback);
          } catch (...) {
            failure = std::current_exception();  // released below, with the GIL held
          }
        }
        if (interrupt) {  // whatever the stopped run threw after (Interrupted: nothing to write)
          interrupt->restore();
          throw py::error_already_set();
        }
        if (failure) std::rethrow_exception(failure);
        if (report.output.failure) std::rethrow_exception(report.output.failure);  // the outputs are written
        return report;
      },
      py::arg("request"), py::arg("out_dir"), py::arg("progress") = py::none(),
      "`seif run` as one call: writes trajectory.tum, dead_reckoning.tum, map.csv, metrics.json into "
      "out_dir (which must exist) and returns a RunReport. progress(fraction) is called during the run. "
      "Raises DataError, NumericError, InvalidArgument; a failure after the first step raises once the "
      "outputs of the steps before it are written (metrics.json \"failure\"). Ctrl-C (read at each progress report, every 1024 steps) stops the run: the "
      "outputs so far are written (metrics.json \"interrupted\": true; with request.checkpoint a checkpoint "
      "to resume from), then KeyboardInterrupt is raised.");

  m.def("run_summary", &runSummary, py::arg("request"), py::arg("report"), py::arg("out_dir"),
        "The report `seif run` prints after run_dataset: the filter, models and noise with their sources, "
        "the errors against each reference, timing, smoothing and association figures, and what was written.");
  m.def(
      "run_filter",
      [](SlamFilter& filter, const Dataset& data, const py::object& progress) {
        const auto callback = pythonCallback<std::size_t, std::size_t>(progress);
        py::gil_scoped_release release;
        return runFilter(filter, data, callback);
      },
      py::arg("filter"), py::arg("dataset"), py::arg("progress") = py::none(),
      "Runs every step of an in-memory Dataset through `filter` (then finish()); progress(done, total).");
  m.def(
      "run_filter",
      [](SlamFilter& filter, EventSource& source, const py::object& progress, bool pose_covariances,
         Associator* associator) {
        const auto callback = pythonCallback<double>(progress);
        RunOutput out;
        {
          py::gil_scoped_release release;
          out = runFilter(filter, source, callback, pose_covariances, {}, nullptr, associator);
        }
        if (out.failure) std::rethrow_exception(out.failure);  // the filter holds the steps before it
        return out;
      },
      py::arg("filter"), py::arg("source"), py::arg("progress") = py::none(), py::arg("pose_covariances") = false,
      py::arg("associator") = nullptr,
      "Streams an EventSource through `filter` (built with source.info's models); progress(fraction). "
      "With `associator` the observations get their landmark ids from it (then its finish() runs) and the "
      "output records them (associations, merges). A failure raises its error; `filter` then holds the steps "
      "before it.");
  m.def("merged_into", &mergedInto, py::arg("id"), py::arg("merges"),
        "The landmark that holds landmark `id`'s observations after `merges`, `id` itself when never merged.");
  m.def(
      "association_verdicts",
      [](const RunOutput& out, const SlamFilter& filter, const Associator& associator) {
        std::vector<int> final_landmark;
        std::vector<AssociationVerdict> verdicts = associationVerdicts(out, filter, associator, &final_landmark);
        return py::make_tuple(verdicts, final_landmark);
      },
      py::arg("output"), py::arg("filter"), py::arg("associator"),
      "After a run with `associator` (its finish() done): (each record's AssociationVerdict, each record's "
      "landmark at the end, -1 when dropped or removed). Correct sums to its counts.correct, Wrong and "
      "Duplicate to counts.wrong.");
  m.def("write_associations_csv", &writeAssociationsCsv, py::arg("file"), py::arg("output"), py::arg("filter"),
        py::arg("associator"), "associations.csv, as `seif run` writes it.");

  m.def("start_pose", &startPose, py::arg("dataset"), "Ground truth at the first step's time, else the origin.");
  m.def("dead_reckoning", &deadReckoning, py::arg("dataset"), py::arg("start"), py::arg("motion"),
        "The controls integrated alone from `start`, at runFilter's stamps.");

  py::enum_<Alignment>(m, "Alignment", "Unaligned (C++ None): as estimated; Rigid: after the best rigid 2-D alignment.")
      .value("Unaligned", Alignment::None)
      .value("Rigid", Alignment::Rigid);
  m.def(
      "aligned_rmse",
      [](const std::vector<Vec2>& est, const std::vector<Vec2>& truth, Alignment a) {
        return alignedRmse(est, truth, a);
      },
      py::arg("estimate"), py::arg("truth"), py::arg("alignment") = Alignment::Rigid);
  m.def("ate_rmse", &ateRmse, py::arg("estimate"), py::arg("groundtruth"), py::arg("alignment") = Alignment::None,
        "Absolute trajectory error [m]; None without ground truth.");
  m.def("landmark_rmse", &landmarkRmse, py::arg("filter"), py::arg("truth"), py::arg("alignment") = Alignment::None,
        "RMS landmark error [m] of the filter's map against {id: (x, y)}.");
  m.def(
      "gps_rmse",
      [](const std::vector<TimedPose>& trajectory, const std::vector<GpsFix>& gps) {
        std::size_t compared = 0;
        std::optional<double> median;
        const auto rmse = gpsRmse(trajectory, gps, &compared, &median);
        return py::make_tuple(rmse, compared, median);
      },
      py::arg("trajectory"), py::arg("gps"), "(rmse, fixes compared, median) after rigid alignment.");
  m.def("gps_jumps", &gpsJumps, py::arg("gps"), py::arg("max_speed") = kGpsJumpSpeed,
        "For each fix, whether it is a jump: the speed it implies from each neighbour exceeds max_speed [m/s].");
  m.def("evaluate_run", &evaluateRun, py::arg("filter"), py::arg("info"), py::arg("output"));
  m.def("seif_options_json", &seifOptionsJson, py::arg("options"));
}

void bindStats(py::module_& m) {
  py::class_<Summary>(m, "Summary", "Summary of a sample (eval/stats.hpp).")
      .def_readonly("n", &Summary::n)
      .def_readonly("mean", &Summary::mean)
      .def_readonly("sd", &Summary::sd)
      .def_readonly("ci95", &Summary::ci95)
      .def_readonly("min", &Summary::min)
      .def_readonly("max", &Summary::max)
      .def_readonly("median", &Summary::median)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"n", "mean", "sd", "ci95", "min", "max", "median"}); });
  py::class_<Band>(m, "Band", "A [lo, hi] band.")
      .def_readonly("lo", &Band::lo)
      .def_readonly("hi", &Band::hi)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"lo", "hi"}); });
  py::class_<PairedRatio>(m, "PairedRatio", "mean(x) / mean(y) over paired runs and its 95 % half-width.")
      .def_readonly("ratio", &PairedRatio::ratio)
      .def_readonly("ci95", &PairedRatio::ci95, "half-width of the 95 % interval (delta method)")
      .def_readonly("pairs", &PairedRatio::pairs, "pairs where both values are finite")
      .def("__repr__", [](py::handle s) { return reprOf(s, {"ratio", "ci95", "pairs"}); });
  m.def("summarize", [](const std::vector<double>& xs) { return summarize(xs); }, py::arg("xs"));
  m.def(
      "paired_ratio",
      [](const std::vector<std::optional<double>>& x, const std::vector<std::optional<double>>& y) {
        auto values = [](const std::vector<std::optional<double>>& v) {  // None (JSON null): a stopped run
          std::vector<double> out;
          for (const auto& e : v) out.push_back(e.value_or(std::numeric_limits<double>::quiet_NaN()));
          return out;
        };
        return pairedRatio(values(x), values(y));
      },
      py::arg("x"), py::arg("y"),
      "mean(x) / mean(y) over the pairs where both are finite (None and NaN: a stopped run), with the "
      "half-width of its 95 % interval (delta method over the residuals x_i - R y_i), e.g. two filters' "
      "mse_runs of one study or of nees.json.");
  m.def("ci95_half_width", [](const std::vector<double>& xs) { return ci95HalfWidth(xs); }, py::arg("xs"));
  m.def("student_t_quantile", &studentTQuantile, py::arg("p"), py::arg("dof"));
  m.def("chi_square_quantile", &chiSquareQuantile, py::arg("p"), py::arg("dof"));
  m.def("chi_square_cdf", &chiSquareCdf, py::arg("x"), py::arg("dof"));
  m.def("nees_band95", &neesBand95, py::arg("samples"), py::arg("dof"),
        "95 % band of the mean of `samples` NEES values of `dof` degrees of freedom.");
}

void bindPaper(py::module_& m) {
  py::class_<PaperOptions>(m, "PaperOptions", "What the paper's experiment varies (eval/paper.hpp).")
      .def(py::init<>())
      .def_readwrite("landmarks", &PaperOptions::landmarks)
      .def_readwrite("steps", &PaperOptions::steps)
      .def_readwrite("active", &PaperOptions::active)
      .def_readwrite("relax", &PaperOptions::relax)
      .def_readwrite("path", &PaperOptions::path)
      .def_readwrite("sweep_active", &PaperOptions::sweep_active)
      .def_readwrite("extra", &PaperOptions::extra)
      .def("__repr__", [](py::handle s) {
        return reprOf(s, {"landmarks", "steps", "active", "relax", "path", "sweep_active", "extra"});
      });
  py::class_<PaperFilterSpec>(m, "PaperFilterSpec")
      .def_readonly("name", &PaperFilterSpec::name)
      .def_readonly("ekf", &PaperFilterSpec::ekf)
      .def_readonly("seif", &PaperFilterSpec::seif)
      .def_readonly("spec", &PaperFilterSpec::spec, py::return_value_policy::copy);
  m.def("paper_filters", &paperFilters, py::arg("options") = PaperOptions{});
  m.def("paper_world", &paperWorld, py::arg("seed"), py::arg("options") = PaperOptions{},
        "The simulator configuration of the paper's run with seed `seed`.");
  m.def(
      "landmark_mse",
      [](const SlamFilter& f, const std::map<int, Vec2>& truth) {
        std::size_t count = 0;
        const double mse = landmarkMse(f, truth, &count);
        return py::make_tuple(mse, count);
      },
      py::arg("filter"), py::arg("truth"), "(mean squared landmark error [m^2], landmarks averaged).");

  py::class_<PaperFilterResult>(m, "PaperFilterResult")
      .def_readonly("name", &PaperFilterResult::name)
      .def_readonly("mse", &PaperFilterResult::mse)
      .def_readonly("rmse", &PaperFilterResult::rmse)
      .def_readonly("aligned_mse", &PaperFilterResult::aligned_mse)
      .def_readonly("pose_error", &PaperFilterResult::pose_error)
      .def_readonly("mapped", &PaperFilterResult::mapped)
      .def_readonly("stats", &PaperFilterResult::stats)
      .def_readonly("step_seconds", &PaperFilterResult::step_seconds)
      .def_readonly("landmark_nees", &PaperFilterResult::landmark_nees)
      .def_readonly("pose_nees", &PaperFilterResult::pose_nees)
      .def("__repr__", [](py::handle s) {
        return reprOf(s, {"name", "mse", "aligned_mse", "pose_error", "mapped", "landmark_nees", "pose_nees"});
      });
  py::class_<PaperRun>(m, "PaperRun")
      .def_readonly("seed", &PaperRun::seed)
      .def_readonly("steps", &PaperRun::steps)
      .def_readonly("sim", &PaperRun::sim)
      .def_readonly("filters", &PaperRun::filters, py::return_value_policy::copy);
  py::class_<PaperFilterSummary>(m, "PaperFilterSummary")
      .def_readonly("name", &PaperFilterSummary::name)
      .def_readonly("seeds", &PaperFilterSummary::seeds)
      .def_readonly("mse", &PaperFilterSummary::mse)
      .def_readonly("rmse", &PaperFilterSummary::rmse)
      .def_readonly("aligned_mse", &PaperFilterSummary::aligned_mse)
      .def_readonly("links", &PaperFilterSummary::links, py::return_value_policy::copy)
      .def_readonly("mapped", &PaperFilterSummary::mapped)
      .def_readonly("robot_links", &PaperFilterSummary::robot_links)
      .def_readonly("pose_error", &PaperFilterSummary::pose_error)
      .def_readonly("landmark_nees", &PaperFilterSummary::landmark_nees)
      .def_readonly("pose_nees", &PaperFilterSummary::pose_nees)
      .def_readonly("diff_to_ekf", &PaperFilterSummary::diff_to_ekf)
      .def_readonly("error", &PaperFilterSummary::error)
      .def_readonly("rms", &PaperFilterSummary::rms)
      .def_readonly("aligned_error", &PaperFilterSummary::aligned_error)
      .def_readonly("link", &PaperFilterSummary::link)
      .def_readonly("map", &PaperFilterSummary::map)
      .def_readonly("diff", &PaperFilterSummary::diff)
      .def_readonly("pose", &PaperFilterSummary::pose)
      .def_readonly("nees", &PaperFilterSummary::nees)
      .def_readonly("nees_pose", &PaperFilterSummary::nees_pose)
      .def_readonly("us_median", &PaperFilterSummary::us_median)
      .def_readonly("us_mean", &PaperFilterSummary::us_mean)
      .def_readonly("ratio", &PaperFilterSummary::ratio)
      .def_readonly("ratio_ci95", &PaperFilterSummary::ratio_ci95)
      .def_readonly("ratio_median", &PaperFilterSummary::ratio_median)
      .def_readonly("aligned_ratio", &PaperFilterSummary::aligned_ratio);
  m.def("summarize_paper_filter", &summarizePaperFilter, py::arg("filter_index"), py::arg("runs"),
        "Summary of filter `filter_index` (paper_filters() order; 0 = the EKF) over runs.");

  py::class_<PaperRunDetail>(m, "PaperRunDetail", "The data and the filters of one paper run, kept for figures.")
      .def_readonly("data", &PaperRunDetail::data)
      .def_property_readonly(
          "filters",
          [](py::object self) {
            py::list out;
            for (const auto& f : self.cast<PaperRunDetail&>().filters) {
              out.append(py::cast(f.get(), py::return_value_policy::reference_internal, self));
            }
            return out;
          },
          "the filters in paper_filters() order (alive as long as this object)")
      .def_readonly("outputs", &PaperRunDetail::outputs, py::return_value_policy::copy);
  m.def(
      "run_paper_experiment",
      [](std::uint64_t seed, const PaperOptions& options) {
        py::gil_scoped_release release;
        return runPaperExperiment(seed, options);
      },
      py::arg("seed"), py::arg("options") = PaperOptions{},
      "One run of the paper's experiment (EKF, SEIF with exact mean, constant-time SEIF, ... on one simulated "
      "world). Deterministic in (seed, options) except step times.");
  m.def(
      "run_paper_experiment_detail",
      [](std::uint64_t seed, const PaperOptions& options) {
        auto detail = std::make_unique<PaperRunDetail>();
        PaperRun run;
        {
          py::gil_scoped_release release;
          run = runPaperExperiment(seed, options, detail.get());
        }
        return py::make_tuple(std::move(run), std::move(detail));
      },
      py::arg("seed"), py::arg("options") = PaperOptions{}, "run_paper_experiment() and its detail: (run, detail).");

  py::class_<PaperRequest>(m, "PaperRequest", "`seif paper` as one call (eval/paper.hpp): runs, seed, jobs, options.")
      .def(py::init<>())
      .def_readwrite("runs", &PaperRequest::runs)
      .def_readwrite("seed", &PaperRequest::seed, "run r uses simulator seed seed + r")
      .def_readwrite("jobs", &PaperRequest::jobs, "threads; 0: the number of cores (results do not depend on it)")
      .def_readwrite("options", &PaperRequest::options)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"runs", "seed", "jobs", "options"}); });
  py::class_<PaperFailure>(m, "PaperFailure")
      .def_readonly("seed", &PaperFailure::seed)
      .def_readonly("error", &PaperFailure::error);
  py::class_<PaperReport>(m, "PaperReport", "What run_paper() measured; write_paper_results() writes it as `seif paper` does.")
      .def_readonly("request", &PaperReport::request)
      .def_readonly("jobs", &PaperReport::jobs)
      .def_readonly("world", &PaperReport::world)
      .def_readonly("specs", &PaperReport::specs, py::return_value_policy::copy)
      .def_readonly("runs", &PaperReport::runs, py::return_value_policy::copy)
      .def_readonly("failed", &PaperReport::failed, py::return_value_policy::copy)
      .def_readonly("interrupted", &PaperReport::interrupted, "stopped before every run had started")
      .def_readonly("summaries", &PaperReport::summaries, py::return_value_policy::copy)
      .def_readonly("typical", &PaperReport::typical, "index into runs of the figures' run")
      .def("summary_text", &paperSummaryText, "what `seif paper` prints")
      .def("write", &writePaperResults, py::arg("dir"), py::call_guard<py::gil_scoped_release>(),
           "writes DIR/results.json, DIR/table.md and DIR/figure_data/ as `seif paper` does");
  m.def(
      "run_paper",
      [](PaperRequest request, const py::object& progress) {
        const auto callback = pythonCallback<std::size_t, std::size_t>(progress);
        std::atomic<bool> stop{false};
        request.stop = &stop;
        std::unique_ptr<PaperReport> report;
        std::optional<std::string> none_ran;
        {
          const SigintStops sigint(stop);
          py::gil_scoped_release release;
          try {
            report = std::make_unique<PaperReport>(runPaper(request, callback));
          } catch (const Interrupted& e) {  // stopped before any run succeeded
            none_ran = e.what();
          }
        }
        if (none_ran) raiseInterrupted(*none_ran, py::none());
        if (report->interrupted) {
          const std::string what = interruptedText(*report) + " (their report: .result)";
          raiseInterrupted(what, py::cast(std::move(report)));
        }
        return report;
      },
      py::arg("request"), py::arg("progress") = py::none(),
      "`seif paper` as one call: request.runs runs of the paper world on worker threads, summarised; "
      "progress(done, total) counts runs. Ctrl-C (SIGINT) stops it: no run starts after it, and "
      "KeyboardInterrupt is raised with the report of the runs that ran as its .result.");

  py::class_<FilterSnapshot::Link>(m, "SnapshotLink")
      .def_readonly("a", &FilterSnapshot::Link::a)
      .def_readonly("b", &FilterSnapshot::Link::b)
      .def_readonly("strength", &FilterSnapshot::Link::strength);
  py::class_<FilterSnapshot>(m, "FilterSnapshot", "A filter's state with landmarks ordered by id (for figures).")
      .def_readonly("ids", &FilterSnapshot::ids)
      .def_readonly("mean", &FilterSnapshot::mean)
      .def_readonly("covariance", &FilterSnapshot::covariance)
      .def_readonly("information", &FilterSnapshot::information)
      .def_readonly("links", &FilterSnapshot::links, py::return_value_policy::copy);
  m.def("snapshot_by_id", &snapshotById, py::arg("filter"), py::call_guard<py::gil_scoped_release>());
}

void bindConsistency(py::module_& m) {
  py::class_<ConsistencyDataset>(m, "ConsistencyDataset", "One real run of the NEES study: data with ground truth.")
      .def(py::init<>())
      .def_readwrite("name", &ConsistencyDataset::name)
      .def_readwrite("data", &ConsistencyDataset::data)
      .def_readwrite("config", &ConsistencyDataset::config);
  m.def("mrclam_consistency_runs", &mrclamConsistencyRuns, py::arg("folder"), py::arg("robots"),
        "The MRCLAM robots of `folder` as runs of the NEES study (Vicon poses, surveyed landmarks).");
  py::class_<ConsistencyOptions>(m, "ConsistencyOptions", "The Monte-Carlo NEES study (eval/consistency.hpp).")
      .def(py::init<>())
      .def_readwrite("world", &ConsistencyOptions::world)
      .def_readwrite("datasets", &ConsistencyOptions::datasets, py::return_value_policy::copy, "real runs (then world and runs are unused)")
      .def_readwrite("runs", &ConsistencyOptions::runs)
      .def_readwrite("filters", &ConsistencyOptions::filters, py::return_value_policy::copy, "list of FilterSpec (parse_filter_spec)")
      .def_readwrite("samples", &ConsistencyOptions::samples)
      .def_readwrite("threads", &ConsistencyOptions::threads, "0: the number of cores")
      .def_readwrite("posterior_mean", &ConsistencyOptions::posterior_mean,
                     "also measure each filter whose mean is not its posterior's (the amortised SEIF) with "
                     "the posterior's mean H^-1 b: a result of its own after the filter's");
  py::class_<NeesPoint>(m, "NeesPoint")
      .def_readonly("pose", &NeesPoint::pose)
      .def_readonly("landmark", &NeesPoint::landmark)
      .def_readonly("pose_relative", &NeesPoint::pose_relative)
      .def_readonly("landmark_relative", &NeesPoint::landmark_relative)
      .def("__repr__", [](py::handle s) { return reprOf(s, {"pose", "landmark", "pose_relative", "landmark_relative"}); });
  py::class_<ConsistencyFailure>(m, "ConsistencyFailure")
      .def_readonly("run", &ConsistencyFailure::run, "'seed 6', or the dataset's name")
      .def_readonly("error", &ConsistencyFailure::error)
      .def("__repr__", [](const ConsistencyFailure& f) { return "ConsistencyFailure(" + f.run + ": " + f.error + ")"; });
  py::class_<ConsistencyFilterResult>(m, "ConsistencyFilterResult")
      .def_readonly("name", &ConsistencyFilterResult::name)
      .def_readonly("spec", &ConsistencyFilterResult::spec, "its index in ConsistencyOptions.filters")
      .def_readonly("posterior_mean", &ConsistencyFilterResult::posterior_mean,
                    "the figures of the posterior's mean H^-1 b, not the filter's own estimate")
      .def_readonly("nees", &ConsistencyFilterResult::nees, py::return_value_policy::copy)
      .def_readonly("nees_final", &ConsistencyFilterResult::nees_final)
      .def_readonly("landmark_nees_runs", &ConsistencyFilterResult::landmark_nees_runs)
      .def_readonly("error_final", &ConsistencyFilterResult::error_final)
      .def_readonly("error_aligned_final", &ConsistencyFilterResult::error_aligned_final)
      .def_readonly("mse_final", &ConsistencyFilterResult::mse_final)
      .def_readonly("mse_aligned_final", &ConsistencyFilterResult::mse_aligned_final)
      .def_readonly("mse_runs", &ConsistencyFilterResult::mse_runs, "mean squared landmark error of each run (NaN: stopped)")
      .def_readonly("mse_aligned_runs", &ConsistencyFilterResult::mse_aligned_runs)
      .def_readonly("seconds", &ConsistencyFilterResult::seconds)
      .def_readonly("failed_runs", &ConsistencyFilterResult::failed_runs, py::return_value_policy::copy,
                    "runs it stopped in (a numerical failure), left out of its figures");
  py::class_<ConsistencyResult>(m, "ConsistencyResult")
      .def_readonly("runs", &ConsistencyResult::runs, "the runs summarised")
      .def_readonly("interrupted", &ConsistencyResult::interrupted, "stopped before every run finished")
      .def_readonly("runs_requested", &ConsistencyResult::runs_requested)
      .def_readonly("run_names", &ConsistencyResult::run_names, "the runs summarised: 'seed 6', or the dataset's")
      .def_readonly("steps", &ConsistencyResult::steps)
      .def_readonly("pose_band", &ConsistencyResult::pose_band)
      .def_readonly("landmark_band", &ConsistencyResult::landmark_band)
      .def_readonly("sample_steps", &ConsistencyResult::sample_steps)
      .def_readonly("filters", &ConsistencyResult::filters, py::return_value_policy::copy);
  m.def(
      "run_consistency",
      [](ConsistencyOptions options, const py::object& progress) {
        const auto callback = pythonCallback<std::size_t, std::size_t>(progress);
        std::atomic<bool> stop{false};
        options.stop = &stop;
        ConsistencyResult result;
        std::optional<std::string> none_finished;
        {
          const SigintStops sigint(stop);
          py::gil_scoped_release release;
          try {
            result = runConsistency(options, callback);
          } catch (const Interrupted& e) {  // stopped before any run finished
            none_finished = e.what();
          }
        }
        if (none_finished) raiseInterrupted(*none_finished, py::none());
        if (result.interrupted) {
          raiseInterrupted(interruptedText(result) + " (their result: .result)", py::cast(result));
        }
        return result;
      },
      py::arg("options"), py::arg("progress") = py::none(),
      "Runs the NEES study on worker threads; progress(done, total) counts runs. Ctrl-C (SIGINT) stops "
      "it: the runs under way stop after their step, and KeyboardInterrupt is raised with the runs every "
      "filter finished as its .result (a ConsistencyResult, interrupted=True; None when none had).");
  m.def(
      "measure_nees",
      [](const SlamFilter& filter, const Pose2& true_pose, const std::map<int, Vec2>& truth,
         std::optional<Eigen::VectorXd> mean) {
        return measureNees(filter, true_pose, truth, mean ? &*mean : nullptr);
      },
      py::arg("filter"), py::arg("true_pose"), py::arg("truth"), py::arg("mean") = py::none(),
      "NEES of the filter now against the truth: its own estimate, or `mean` (the whole state, e.g. "
      "filter.posterior_mean()) with its covariances");
  m.def("consistency_json", &consistencyJson, py::arg("result"), py::arg("options"));
  m.def("consistency_table", &consistencyTable, py::arg("result"));
  m.def("consistency_csv", &consistencyCsv, py::arg("result"),
        "nees.csv of `seif consistency`: one row per sampled step, each filter's NEES and band.");
  m.def("write_consistency_results", &writeConsistencyResults, py::arg("result"), py::arg("options"), py::arg("dir"),
        "Writes dir/nees.json, nees.csv and table.md, as `seif consistency` does (figures: "
        "scripts/figures/consistency.py dir).");
}

void bindBench(py::module_& m) {
  py::class_<BenchCase>(m, "BenchCase", "One (filter, N) of the scaling benchmark (eval/bench.hpp).")
      .def(py::init<>())
      .def_readwrite("filter", &BenchCase::filter)
      .def_readwrite("landmarks", &BenchCase::landmarks)
      .def_readwrite("window", &BenchCase::window)
      .def_readwrite("seed", &BenchCase::seed)
      .def_readwrite("seif", &BenchCase::seif)
      .def_readwrite("linearization", &BenchCase::linearization)
      .def_readwrite("iterations", &BenchCase::iterations)
      .def_readwrite("association", &BenchCase::association, "known, or nn/jcbb with the corridor's ids hidden");
  py::class_<BenchMeasurement>(m, "BenchMeasurement", "Times in microseconds, memory in MiB.")
      .def_readonly("filter", &BenchMeasurement::filter)
      .def_readonly("landmarks", &BenchMeasurement::landmarks)
      .def_readonly("steps", &BenchMeasurement::steps)
      .def_readonly("steps_run", &BenchMeasurement::steps_run)
      .def_readonly("map_first", &BenchMeasurement::map_first)
      .def_readonly("map_last", &BenchMeasurement::map_last)
      .def_readonly("us_per_step_median", &BenchMeasurement::us_per_step_median)
      .def_readonly("us_per_step_p90", &BenchMeasurement::us_per_step_p90)
      .def_readonly("us_per_step_mean", &BenchMeasurement::us_per_step_mean)
      .def_readonly("us_per_step_max", &BenchMeasurement::us_per_step_max)
      .def_readonly("observations_per_step", &BenchMeasurement::observations_per_step)
      .def_readonly("sim_seconds", &BenchMeasurement::sim_seconds)
      .def_readonly("run_seconds", &BenchMeasurement::run_seconds)
      .def_readonly("max_blocks_touched", &BenchMeasurement::max_blocks_touched)
      .def_readonly("max_robot_links", &BenchMeasurement::max_robot_links)
      .def_readonly("peak_rss_mb", &BenchMeasurement::peak_rss_mb)
      .def_readonly("base_rss_mb", &BenchMeasurement::base_rss_mb)
      .def_readonly("sim_peak_mb", &BenchMeasurement::sim_peak_mb)
      .def_readonly("data_rss_mb", &BenchMeasurement::data_rss_mb)
      .def_readonly("filter_peak_mb", &BenchMeasurement::filter_peak_mb)
      .def_readonly("filter_final_mb", &BenchMeasurement::filter_final_mb)
      .def_readonly("peak_reset", &BenchMeasurement::peak_reset)
      .def_readonly("association", &BenchMeasurement::association)
      .def_readonly("scans", &BenchMeasurement::scans)
      .def_readonly("us_association_per_scan_median", &BenchMeasurement::us_association_per_scan_median)
      .def_readonly("us_association_per_scan_p90", &BenchMeasurement::us_association_per_scan_p90)
      .def_readonly("us_association_per_scan_max", &BenchMeasurement::us_association_per_scan_max)
      .def_readonly("association_scored", &BenchMeasurement::association_scored)
      .def_readonly("association_correct", &BenchMeasurement::association_correct)
      .def_readonly("landmarks_final", &BenchMeasurement::landmarks_final);
  m.def("run_bench_case", &runBenchCase, py::arg("case"), py::call_guard<py::gil_scoped_release>(),
        "Measures one case in this process (the Python interpreter's memory counts in the RSS figures).");
  m.def("quantile", &quantile, py::arg("values"), py::arg("q"));
  py::class_<ProcessMemory>(m, "ProcessMemory")
      .def_readonly("rss_mb", &ProcessMemory::rss_mb)
      .def_readonly("peak_mb", &ProcessMemory::peak_mb);
  m.def("process_memory", &processMemory);
  m.def("step_cost_exponent", &stepCostExponent, py::arg("filter"));
  m.def("dense_matrix_bytes", &denseMatrixBytes, py::arg("filter"), py::arg("landmarks"));
  py::class_<BenchPoint>(m, "BenchPoint")
      .def(py::init<>())
      .def_readwrite("landmarks", &BenchPoint::landmarks)
      .def_readwrite("seconds_per_step", &BenchPoint::seconds_per_step)
      .def_readwrite("filter_bytes", &BenchPoint::filter_bytes)
      .def_readwrite("data_bytes", &BenchPoint::data_bytes)
      .def_readwrite("steps", &BenchPoint::steps);
  py::class_<BenchEstimate>(m, "BenchEstimate")
      .def_readonly("exponent", &BenchEstimate::exponent)
      .def_readonly("seconds_per_step", &BenchEstimate::seconds_per_step)
      .def_readonly("build_seconds", &BenchEstimate::build_seconds)
      .def_readonly("bytes", &BenchEstimate::bytes)
      .def_readonly("matrix_bytes", &BenchEstimate::matrix_bytes);
  m.def(
      "estimate_bench_case",
      [](const std::string& filter, int landmarks, double steps, const std::vector<BenchPoint>& measured) {
        return estimateBenchCase(filter, landmarks, steps, measured);
      },
      py::arg("filter"), py::arg("landmarks"), py::arg("steps"), py::arg("measured"));

  // The whole study: `seif bench` as one call.
  py::class_<BenchRequest>(m, "BenchRequest", "`seif bench` as one call (run_bench); the CLI's defaults.")
      .def(py::init<>())
      .def_readwrite("filters", &BenchRequest::filters, py::return_value_policy::copy)
      .def_readwrite("landmarks", &BenchRequest::landmarks, py::return_value_policy::copy)
      .def_readwrite("window", &BenchRequest::window)
      .def_readwrite("repeat", &BenchRequest::repeat, "runs per case, each in its own forked child; the lowest median is reported")
      .def_readwrite("world_seed", &BenchRequest::world_seed)
      .def_readwrite("max_seconds", &BenchRequest::max_seconds, "time budget of all runs of one case")
      .def_readwrite("max_memory_gb", &BenchRequest::max_memory_gb, "memory budget of one case")
      .def_readwrite("linearization", &BenchRequest::linearization)
      .def_readwrite("iterations", &BenchRequest::iterations)
      .def_readwrite("seif", &BenchRequest::seif)
      .def_readwrite("association", &BenchRequest::association);
  py::class_<BenchRow>(m, "BenchRow", "One (filter, N) of the study: measured, or skipped with the reason.")
      .def_readonly("filter", &BenchRow::filter)
      .def_readonly("landmarks", &BenchRow::landmarks)
      .def_readonly("measurement", &BenchRow::measurement, py::return_value_policy::copy)
      .def_readonly("repeat_medians", &BenchRow::repeat_medians, py::return_value_policy::copy)
      .def_readonly("estimate", &BenchRow::estimate, py::return_value_policy::copy)
      .def_readonly("skipped", &BenchRow::skipped)
      .def("__repr__", [](const BenchRow& r) {
        return "BenchRow(" + r.filter + ", " + std::to_string(r.landmarks) +
               (r.measurement ? ", " + std::to_string(r.measurement->us_per_step_median) + " us/step" : ", skipped: " + r.skipped) + ")";
      });
  py::class_<BenchTargets::Growth>(m, "BenchGrowth")
      .def_readonly("from_landmarks", &BenchTargets::Growth::from_landmarks)
      .def_readonly("to_landmarks", &BenchTargets::Growth::to_landmarks)
      .def_readonly("from_us", &BenchTargets::Growth::from_us)
      .def_readonly("to_us", &BenchTargets::Growth::to_us)
      .def_readonly("ratio", &BenchTargets::Growth::ratio)
      .def_readonly("met", &BenchTargets::Growth::met);
  py::class_<BenchTargets::Speedup>(m, "BenchSpeedup")
      .def_readonly("landmarks", &BenchTargets::Speedup::landmarks)
      .def_readonly("ekf_us", &BenchTargets::Speedup::ekf_us)
      .def_readonly("seif_us", &BenchTargets::Speedup::seif_us)
      .def_readonly("ratio", &BenchTargets::Speedup::ratio)
      .def_readonly("met", &BenchTargets::Speedup::met);
  py::class_<BenchTargets>(m, "BenchTargets")
      .def_readonly("seif_growth", &BenchTargets::seif_growth, py::return_value_policy::copy)
      .def_readonly("seif_association_growth", &BenchTargets::seif_association_growth, py::return_value_policy::copy)
      .def_readonly("ekf_over_seif", &BenchTargets::ekf_over_seif, py::return_value_policy::copy)
      .def_readonly("seif_bytes_per_landmark", &BenchTargets::seif_bytes_per_landmark, py::return_value_policy::copy);
  py::class_<BenchReport>(m, "BenchReport")
      .def_readonly("request", &BenchReport::request, py::return_value_policy::copy)
      .def_readonly("rows", &BenchReport::rows, py::return_value_policy::copy)
      .def_readonly("calibration", &BenchReport::calibration, py::return_value_policy::copy)
      .def_readonly("targets", &BenchReport::targets, py::return_value_policy::copy)
      .def_readonly("interrupted", &BenchReport::interrupted, "stopped before every case was run")
      .def("json", [](const BenchReport& r) { return benchJson(r); }, "bench.json of `seif bench`")
      .def("summary_text", &benchSummaryText, "the table `seif bench` prints (its rows and targets)");
  m.def(
      "run_bench",
      [](BenchRequest request, const py::object& row_done) {
        const auto callback = pythonCallback<const BenchRow&>(row_done);
        std::atomic<bool> stop{false};
        request.stop = &stop;
        BenchReport report;
        {
          const SigintStops sigint(stop);
          py::gil_scoped_release release;
          report = runBench(request, callback);
        }
        if (report.interrupted) {
          raiseInterrupted(interruptedText(report) + " (the report: .result)", py::cast(report));
        }
        return report;
      },
      py::arg("request"), py::arg("row_done") = py::none(),
      "`seif bench` as one call: every (filter, N) measured in forked children; row_done(row) follows "
      "each case, measured or skipped. Returns a BenchReport (.json() is bench.json). Ctrl-C (SIGINT) "
      "stops the study before its next case and raises KeyboardInterrupt with the cases finished as its "
      ".result (a BenchReport, interrupted=True).");
  m.def("bench_json", &benchJson, py::arg("report"));
}

}  // namespace

void bindEval(py::module_& m) {
  bindRun(m);
  bindStats(m);
  bindPaper(m);
  bindConsistency(m);
  bindBench(m);
}

}  // namespace seif::python
