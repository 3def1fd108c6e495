// seif run: one filter over one dataset of any format (flags -> RunRequest -> runDataset).
#include <seif/core/errors.hpp>
#include "commands.hpp"
#include "options.hpp"
#include "stop_signals.hpp"

#include <seif/eval/run_dataset.hpp>

#include <cmath>
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
  request.stop = StopOnSignals::flag();
  // Flags that do not apply are noted, not refused: the run is what was asked without them.
  // (A resumed run's filter and association are its checkpoint's.)
  if (request.resume.empty()) {
    std::vector<std::string> notes = args.options.ignoredBy(args.filter, args.smooth);
    if (request.association.method == AssociationMethod::Known) {
      for (std::string& n : args.association.ignoredByKnown()) notes.push_back(std::move(n));
    }
    for (const std::string& n : notes) std::fprintf(stderr, "seif run: note: %s\n", n.c_str());
  }
  RunReport r;
  {
    const StopOnSignals stop_on_signals;
    Progress progress("seif run " + args.filter);
    r = runDataset(request, args.out, [&](double f) { progress(f); });
  }
  const RunOutput& out = r.output;
  std::fputs(runSummary(request, r, args.out).c_str(), stdout);
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
      "dataset has it, else null); OUT/gps.csv with GPS fixes, OUT/groundtruth.tum and\n"
      "OUT/landmarks_groundtruth.csv with ground truth; with --association nn or jcbb,\n"
      "OUT/associations.csv (each observation's landmark and its verdict against the data's\n"
      "ids). Noise: a --sigma-* flag, else the file's, else the format's\n"
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
