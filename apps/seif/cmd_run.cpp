// seif run: one filter over one dataset of any format (flags -> RunRequest -> runDataset).
#include <seif/core/errors.hpp>
#include "commands.hpp"
#include "options.hpp"

#include <seif/eval/run_dataset.hpp>

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>

namespace seif::cli {
namespace {

struct RunArgs {
  std::string dataset;
  std::string format = "auto";
  int robot = 1;
  std::string filter = "seif";
  std::string out = "out/run";
  NoiseFlags noise;
  FilterFlags options;
  double outlier_gate = FilterConfig{}.outlier_gate;
  std::string map_covariance = "exact";
  std::string trajectory_covariance = "off";
  std::size_t checkpoint_every = 0;
  std::string checkpoint;
  std::string resume;
  bool smooth = false;
  AssociationFlags association;
  std::string command_line;
};

// Ctrl-C (SIGINT) or SIGTERM during a run stops it after the step it is in, and the outputs so
// far are written. The handler stays for more of them (`timeout` and process managers send
// one to the process and one to its group); Ctrl-\ (SIGQUIT) still ends the process at once.
std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void requestStop(int) { g_stop.store(true, std::memory_order_relaxed); }

/// Installs requestStop() for SIGINT and SIGTERM while it lives, and restores what was there.
/// A signal the shell ignores (a background job's SIGINT, nohup) stays ignored.
class StopOnSignals {
 public:
  using Handler = void (*)(int);
  StopOnSignals() : int_(install(SIGINT)), term_(install(SIGTERM)) {}
  ~StopOnSignals() {
    std::signal(SIGINT, int_);
    std::signal(SIGTERM, term_);
  }
  StopOnSignals(const StopOnSignals&) = delete;
  StopOnSignals& operator=(const StopOnSignals&) = delete;

 private:
  static Handler install(int signal) {
    const Handler before = std::signal(signal, requestStop);
    if (before == SIG_IGN) std::signal(signal, SIG_IGN);
    return before;
  }
  Handler int_;
  Handler term_;
};

std::string metres(const std::optional<double>& v) {
  if (!v) return "n/a";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4f", *v);
  return buf;
}

void run(const RunArgs& args) {
  requireOutputFolder(args.out);  // before any work: a bad --out fails at once
  RunRequest request;
  request.dataset = args.dataset;
  request.format = parseDatasetFormat(args.format);
  request.dataset_options = args.noise.resolve();
  request.dataset_options.robot = args.robot;
  request.filter = args.filter;
  request.outlier_gate = args.outlier_gate;
  const FilterSpec flags = args.options.resolve();
  request.seif = flags.seif;
  request.linearization = flags.linearization;
  request.iterations = flags.iterations;
  request.batch = flags.batch;
  request.smooth = args.smooth;
  request.association = args.association.resolve();
  request.map_covariances = args.map_covariance == "exact";
  request.trajectory_covariances = args.trajectory_covariance == "on";
  request.checkpoint_every = args.checkpoint_every;
  request.checkpoint = args.checkpoint;
  request.resume = args.resume;
  if (request.checkpoint_every > 0 && request.checkpoint.empty()) {
    throw InvalidArgument("--checkpoint-every needs --checkpoint FILE");
  }
  request.command_line = args.command_line;
  request.stop = &g_stop;
  RunReport r;
  {
    const StopOnSignals stop_on_signals;
    Progress progress("seif run " + args.filter);
    r = runDataset(request, args.out, [&](double f) { progress(f); });
  }
  const RunOutput& out = r.output;
  if (!args.resume.empty()) std::printf("resumed from %s\n", args.resume.c_str());
  std::printf("%s on %s (%s): %zu steps, %zu landmarks, %.1f us/step\n", r.filter.c_str(),
              args.dataset.c_str(), r.info.format.c_str(), out.steps, r.landmarks,
              out.steps == 0 ? 0.0 : 1e6 * out.seconds / static_cast<double>(out.steps));
  std::printf("  motion: %s\n  sensor: %s\n", r.info.motion->describe().c_str(), r.info.sensor->describe().c_str());
  for (const NoiseSetting& n : r.info.noise) {
    std::printf("  noise %-15s %-10g %-14s (%s)\n", n.name.c_str(), n.value, n.unit.c_str(), n.source.c_str());
  }
  std::printf("  start pose (%.3f, %.3f, %.3f): %s\n", r.info.start_pose.x(), r.info.start_pose.y(),
              r.info.start_pose.z(), r.info.start_pose_source.c_str());
  const RunErrors& e = r.errors;
  if (r.info.has_groundtruth || !r.info.landmarks.empty()) {
    std::printf("  aligned:   landmark RMSE %s m | ATE %s m | dead-reckoning ATE %s m\n",
                metres(e.landmark).c_str(), metres(e.ate).c_str(), metres(e.dead_reckoning_ate).c_str());
    std::printf("  unaligned: landmark RMSE %s m | ATE %s m | dead-reckoning ATE %s m | links %zu\n",
                metres(e.landmark_unaligned).c_str(), metres(e.ate_unaligned).c_str(),
                metres(e.dead_reckoning_ate_unaligned).c_str(), out.final_stats.links);
  }
  if (r.info.has_gps) {
    std::printf("  GPS (%zu fixes, aligned): trajectory RMSE %s m (median %s m; %s m without the %zu that jump) | "
                "dead reckoning %s m\n",
                e.gps_fixes, metres(e.gps).c_str(), metres(e.gps_median).c_str(),
                metres(e.gps_without_jumps).c_str(), e.gps_jumps, metres(e.dead_reckoning_gps).c_str());
  }
  const double kappa = out.final_stats.information_scale;
  if (kappa > kForgottenInformationScale) {
    std::printf("  warning: information scaled down %.3g times (seif:rho, sparsify=conservative): the first "
                "steps, and the start prior, now weigh less than 1/%.0g of the newest\n",
                kappa, kForgottenInformationScale);
  } else if (kappa != 1.0) {
    std::printf("  information scaled down %.3g times (seif:rho, sparsify=conservative)\n", kappa);
  }
  std::printf("  time: filter %.2f s | read and filter %.2f s | trajectory and map with covariances %.2f s\n",
              out.seconds, r.seconds_wall, r.seconds_outputs);
  for (const auto& [reason, count] : out.dropped) {
    if (count > 0) std::printf("  dropped %zu records: %s\n", count, reason.c_str());
  }
  if (r.smoother) {
    const SmootherReport& b = *r.smoother;
    std::printf("  batch from %s: %d poses, %d landmarks, %d constraints; 0.5 chi2 %.6g -> %.6g in %d iterations, "
                "%.3f s (linearise %.3f, factorise %.3f, solve %.3f); |gradient| %.3g (from %.3g)\n",
                b.init.c_str(), b.poses, b.landmarks, b.constraints, b.initial_cost, b.final_cost, b.iterations,
                b.solve_seconds, b.linearize_seconds, b.factorize_seconds, b.step_seconds, b.gradient_norm,
                b.initial_gradient_norm);
    if (!b.converged) {
      std::printf("  WARNING: the batch stopped at its iteration limit without converging (from %s: try another --init)\n",
                  b.init.c_str());
    }
  }
  if (r.filter_errors) {
    const RunErrors& f = *r.filter_errors;
    std::printf("  the filter before smoothing: landmark RMSE %s m | ATE %s m | GPS RMSE %s m | map %s m from the batch's\n",
                metres(f.landmark).c_str(), metres(f.ate).c_str(), metres(f.gps).c_str(),
                metres(r.filter_map_distance).c_str());
    if (r.filter_trajectory_distance) {
      const Vec2& d = *r.filter_trajectory_distance;
      std::printf("  the filter's trajectory from the batch's: RMS %s m, median %s m\n", metres(d(0)).c_str(),
                  metres(d(1)).c_str());
    }
  }
  const std::string association(associationMethodName(r.association_options.method));  // a resumed run's: the checkpoint's
  if (r.association && association == "known") {
    std::printf("  association known: %zu observations, %zu without a landmark id dropped\n", r.association->observations,
                r.association->unlabelled_dropped);
  } else if (r.association) {
    const AssociationCounts& a = *r.association;
    std::printf("  association %s: %zu observations; %zu of %zu with a truth id correct (%.2f %%), %zu wrong; "
                "%zu without one (%zu matched to a labelled landmark)\n",
                association.c_str(), a.observations, a.correct, a.scored,
                a.scored == 0 ? 0.0 : 100.0 * double(a.correct) / double(a.scored), a.wrong, a.unlabelled,
                a.unlabelled_matched);
    std::printf("    %zu landmarks started, %zu provisional removed, %zu merged, %zu ambiguous dropped; %zu landmarks at "
                "the end (%zu spurious, %zu duplicates); %.2f s associating%s\n",
                a.new_landmarks, a.provisional_removed, a.merged, a.ambiguous_dropped, a.landmarks_final, a.spurious_landmarks,
                a.duplicate_landmarks, a.seconds,
                a.jcbb_truncated > 0 ? (", " + std::to_string(a.jcbb_truncated) + " JCBB searches truncated").c_str() : "");
    if (const auto& c = r.association_ceiling; c && c->observations > 0) {
      std::printf("    ceiling (the true map seen from the true pose): %.2f %% individually, %.2f %% jointly of %zu "
                  "labelled observations; this run %.2f %% of them\n",
                  100.0 * double(c->individual) / double(c->observations),
                  100.0 * double(c->joint) / double(c->observations), c->observations,
                  100.0 * double(a.correct) / double(c->observations));
    }
  }
  if (out.rejected_observations > 0) {
    std::printf("  rejected %zu gross outlier observation%s (beyond %g sigma of the measurement noise)\n",
                out.rejected_observations, out.rejected_observations == 1 ? "" : "s", args.outlier_gate);
  }
  std::printf("  wrote %s/{trajectory.tum,dead_reckoning.tum,map.csv,metrics.json%s}\n", args.out.c_str(),
              r.filter_errors ? ",trajectory_filter.tum,map_filter.csv" : "");
  if (out.failure) {  // its one line on stderr follows (exit status 2)
    std::printf("  the run failed at step %zu: the outputs above cover the steps before it\n", out.steps);
    std::fflush(stdout);
    std::rethrow_exception(out.failure);
  }
  if (out.interrupted) {
    std::fflush(stdout);
    std::string what = "run interrupted after " + std::to_string(out.steps) + " steps: the outputs above cover them";
    if (!args.checkpoint.empty()) {
      what += "; checkpoint saved: go on with --resume " + args.checkpoint + " (and the same --dataset and its options)";
    }
    throw Interrupted(what);
  }
}

}  // namespace

void addRunCommand(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "Run a SLAM filter over a dataset: an MRCLAM folder (real, or from `seif simulate`), a\n"
      "Victoria Park folder, an iSAM/GTSAM text file or a g2o 2-D file (--format auto tells\n"
      "them apart). The data are streamed: memory is the filter's, not the log's.\n"
      "Writes OUT/trajectory.tum (TUM: t x y z qx qy qz qw), OUT/dead_reckoning.tum (the\n"
      "controls alone), OUT/map.csv (id,x,y and the 2x2\n"
      "covariance) and OUT/metrics.json (models and noise with their sources, timing, links,\n"
      "landmark RMSE and ATE against ground truth, GPS RMSE against GPS fixes, each when the\n"
      "dataset has it, else null). Noise: a --sigma-* flag, else the file's, else the format's\n"
      "documented default; the console lists every value and where it came from.");
  cmd->add_option("--dataset", args->dataset, "dataset folder or file")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("--format", args->format, "auto, mrclam, victoria-park, isam or g2o")
      ->check(CLI::IsMember({"auto", "mrclam", "victoria-park", "isam", "g2o"}))
      ->capture_default_str();
  cmd->add_option("--robot", args->robot, "MRCLAM: robot number in the dataset")
      ->transform(integerIn(1, 5))
      ->capture_default_str();
  cmd->add_option("--filter", args->filter,
                  "ekf (dense covariance), eif (dense information), seif, or batch (the MAP smoother\n"
                  "over every pose and landmark: the reference), with options after a colon, e.g.\n"
                  "seif:sparsify=eseif,linearization=fej; " + filterSpecHelp())
      ->check(filterSpecs())
      ->capture_default_str();
  cmd->add_option("--out", args->out, "output folder")->capture_default_str();
  cmd->add_option("--outlier-gate", args->outlier_gate,
                  "reject an observation whose innovation exceeds this many measurement standard "
                  "deviations (a gross outlier; counted in metrics.json rejected_observations); "
                  "'inf' disables the gate")
      ->check([](const std::string& s) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(s, v) || !(v > 0.0)) return "must be > 0 (or inf), found " + s;
        return {};
      })
      ->capture_default_str();
  cmd->add_option("--map-covariance", args->map_covariance,
                  "exact: map.csv carries each landmark's exact marginal covariance (for the SEIF, "
                  "one sparse factorisation of H at the end: at 10^6 landmarks it needs more memory "
                  "than the filter); none: id,x,y only")
      ->check(CLI::IsMember({"exact", "none"}))
      ->capture_default_str();
  cmd->add_option("--trajectory-covariance", args->trajectory_covariance,
                  "on: write trajectory_cov.csv, the pose covariance after every step (EKF: a read;\n"
                  "EIF: a solve, O(N^2); SEIF: one sparse factorisation per step - minutes on Victoria\n"
                  "Park - or O(1) with seif:covariance=local, smaller than the marginal; batch: the\n"
                  "smoother's marginals by selected inversion); off: no file")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();
  cmd->add_option("--checkpoint-every", args->checkpoint_every,
                  "save the filter and the run so far to --checkpoint after every N steps (0: only\n"
                  "when the run is interrupted)")
      ->transform(integerIn(0, 1000000000))
      ->capture_default_str();
  cmd->add_option("--checkpoint", args->checkpoint,
                  "the checkpoint file (binary, versioned; replaced atomically each time; docs/checkpoints.md).\n"
                  "Ctrl-C (or SIGTERM) stops a run after the step it is in, writes the outputs so far and,\n"
                  "with --checkpoint, a checkpoint there to --resume from; exit status 130")
      ->check(nonEmptyPath());
  cmd->add_option("--resume", args->resume,
                  "resume the run saved in this checkpoint (same --dataset, --robot, --detections and\n"
                  "noise flags): the filter and the association are the checkpoint's, the steps it\n"
                  "consumed are skipped, and the outputs equal those of the uninterrupted run")
      ->check(nonEmptyPath());
  cmd->add_flag("--smooth", args->smooth,
                 "after the filter, the batch MAP from the filter's estimate (the batch's flags below\n"
                 "set its solver): the smoothed trajectory and map are the outputs, the filter's are written\n"
                 "beside them (trajectory_filter.tum, map_filter.csv) and compared in metrics.json\n"
                 "(filter_before_smoothing: errors, distance from the batch map, and the ratio of the\n"
                 "filter's landmark covariances to the batch's: below 1 it claims too little variance)");
  args->association.add(*cmd);
  args->noise.add(*cmd);
  args->options.add(*cmd, /*batch=*/true);
  cmd->callback([args] {
    args->command_line = commandLine();
    run(*args);
  });
}

}  // namespace seif::cli
