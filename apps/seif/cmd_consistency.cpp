// seif consistency: Monte-Carlo NEES of any set of filters on a simulator preset
// (flags -> ConsistencyOptions -> runConsistency -> print, writeConsistencyResults;
// eval/consistency.hpp).
#include "commands.hpp"
#include "options.hpp"
#include "stop_signals.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/consistency.hpp>

#include <climits>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace seif::cli {
namespace {

struct ConsistencyArgs {
  std::string preset = "paper";
  std::string path = "lawnmower";
  int landmarks = 0;
  int steps = 0;
  int runs = 50;
  std::uint64_t seed = 1;
  double clutter = 0.0;
  double detection_probability = 1.0;
  std::string filters = "batch,ekf,seif";
  int samples = 50;
  int jobs = 0;
  std::string out = "out/consistency";
  bool no_figures = false;
  bool posterior_mean = false;
  std::string dataset;           // real data: an MRCLAM folder
  std::vector<int> robots = {1, 2, 3, 4, 5};
};

void consistencyCommand(const ConsistencyArgs& args) {
  ConsistencyOptions options;
  options.world = presetConfig(parseWorldPreset(args.preset), args.landmarks, args.steps, args.seed);
  options.world.paper_path = parsePaperPath(args.path);
  options.world.clutter = args.clutter;
  options.world.detection_probability = args.detection_probability;
  options.runs = args.runs;
  options.samples = args.samples;
  options.threads = static_cast<unsigned>(args.jobs);
  options.posterior_mean = args.posterior_mean;
  for (const std::string& f : splitFilterList(args.filters)) options.filters.push_back(parseFilterSpec(f));
  if (args.dataset.empty()) checkConsistencyOptions(options);  // a usage error, before --out is made
  requireOutputFolder(args.out);
  const std::filesystem::path dir(args.out);

  if (!args.dataset.empty()) {
    options.datasets = mrclamConsistencyRuns(args.dataset, args.robots);
    checkConsistencyOptions(options);
  }
  if (!args.dataset.empty()) {
    std::printf("seif consistency: %s, robots", args.dataset.c_str());
    for (int r : args.robots) std::printf(" %d", r);
    std::printf(" (Vicon poses and surveyed landmarks the truth)\n");
  } else {
    std::printf("seif consistency: %s world%s, %d landmarks, %d steps, %d runs (seeds %llu..%llu)\n",
                args.preset.c_str(), args.preset == "paper" ? (" (" + args.path + ")").c_str() : "",
                options.world.landmarks, options.world.steps, args.runs,
                static_cast<unsigned long long>(args.seed),
                static_cast<unsigned long long>(args.seed + static_cast<std::uint64_t>(args.runs) - 1));
  }
  ConsistencyResult result;
  {
    const StopOnSignals stop_on_signals;  // Ctrl-C: the finished runs are summarised and written
    options.stop = StopOnSignals::flag();
    Progress progress("seif consistency");
    result = runConsistency(options, [&](std::size_t done, std::size_t total) { progress(done, total); });
  }
  const std::string table = consistencyTable(result);
  std::printf("\n%s", table.c_str());
  writeConsistencyResults(result, options, dir);
  std::printf("\nwrote %s/nees.json, nees.csv, table.md\n", args.out.c_str());
  if (!args.no_figures && renderFigure("consistency.py", {dir.string()})) {
    std::printf("figures: %s/nees_global.png, %s/nees_relative.png\n", args.out.c_str(), args.out.c_str());
  }
  // Runs a filter stopped in are in the table and nees.json; the exit status says so too.
  std::string stopped;
  for (const ConsistencyFilterResult& f : result.filters) {
    if (f.failed_runs.empty() || f.posterior_mean) continue;
    stopped += (stopped.empty() ? "" : "; ") + f.name + " stopped in " + std::to_string(f.failed_runs.size()) +
               " of " + std::to_string(result.runs) + " runs (first: " + f.failed_runs.front().run + ": " +
               f.failed_runs.front().error + ")";
  }
  if (result.interrupted) {
    std::fflush(stdout);
    throw Interrupted(interruptedText(result) + "; their results are in " + args.out +
                      (stopped.empty() ? "" : " (" + stopped + ")"));
  }
  if (!stopped.empty()) {
    throw NumericError("consistency: " + stopped + "; the other runs' results are in " + args.out);
  }
}

}  // namespace

void addConsistencyCommand(CLI::App& app) {
  auto args = std::make_shared<ConsistencyArgs>();
  CLI::App* cmd = app.add_subcommand(
      "consistency",
      "Monte-Carlo consistency of filters on a simulator preset: R runs (run r: seed SEED + r),\n"
      "every filter on the same data from the true start pose. For each it measures the NEES\n"
      "(normalised estimation error squared: e^T P^-1 e with the filter's own covariance P) of the\n"
      "pose (3 dof) and of each landmark (2 dof, averaged over the map), against time, in the\n"
      "global frame and relative to the first landmark the filter mapped, and the final landmark\n"
      "error (unaligned and after rigid alignment). A consistent filter's mean NEES lies in the\n"
      "chi-square 95% band for R runs; above it, the filter is more confident than its error.\n"
      "Filters are --filter names with options: ekf, eif, seif, batch (the MAP smoother over every\n"
      "pose and landmark, the reference), e.g. seif:sparsify=eseif,linearization=fej.\n"
      "Writes OUT/nees.json, OUT/nees.csv, OUT/table.md and the figures nees_global.png and\n"
      "nees_relative.png (scripts/figures/consistency.py, /usr/bin/python3 with matplotlib).\n"
      "A filter that stops in a run (a numerical failure: it diverged) is listed under the table and\n"
      "in nees.json, its figures are those of its other runs, and the exit status is 2.\n"
      "Ctrl-C (or SIGTERM) stops the study: the runs every filter finished are summarised and\n"
      "written (nees.json \"interrupted\", \"run_names\"), and the exit status is 130.");
  cmd->add_option("--preset", args->preset, "simulator world: paper, uniform, corridor or park")
      ->check(CLI::IsMember({"paper", "uniform", "corridor", "park"}))
      ->capture_default_str();
  cmd->add_option("--path", args->path, "the paper world's path: lawnmower or lissajous")
      ->check(CLI::IsMember({"lawnmower", "lissajous"}))
      ->capture_default_str();
  cmd->add_option("--landmarks", args->landmarks, "landmarks N (default: the preset's)")
      ->transform(integerIn(1, INT_MAX));
  cmd->add_option("--steps", args->steps, "steps T (default: the preset's)")->transform(integerIn(1, INT_MAX));
  cmd->add_option("--runs", args->runs, "Monte-Carlo runs R")->transform(integerIn(1, INT_MAX))->capture_default_str();
  cmd->add_option("--seed", args->seed, "simulator seed of run 0 (run r: seed + r)")
      ->transform(seedValue())
      ->capture_default_str();
  addDetectionFlags(*cmd, args->clutter, args->detection_probability);
  cmd->add_option("--filters", args->filters,
                  "comma-separated filter specs; options continue a spec: ekf,seif:sparsify=eseif,beta=4")
      ->check(filterSpecs())
      ->capture_default_str();
  cmd->add_option("--samples", args->samples, "points of the NEES-against-time series")
      ->transform(integerIn(1, INT_MAX))
      ->capture_default_str();
  cmd->add_option("--jobs", args->jobs, "threads (default: the number of cores)")->transform(integerIn(1, INT_MAX));
  cmd->add_option("--out", args->out, "output folder")->capture_default_str();
  cmd->add_flag("--no-figures", args->no_figures, "write the data but do not render the figures");
  cmd->add_flag("--posterior-mean", args->posterior_mean,
                "also measure, for each filter whose mean is not its posterior's (the amortised SEIF), its\n"
                "covariances with the posterior's mean H^-1 b: a row '<spec> [posterior mean]' after its own\n"
                "(one sparse solve per sample; the filter is not changed)");
  cmd->add_option("--dataset", args->dataset,
                  "real data instead of the simulator: an MRCLAM folder, one run per robot (--robots),\n"
                  "its ground truth (Vicon poses, surveyed landmarks) the reference")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--robots", args->robots, "MRCLAM robots of --dataset")
      ->delimiter(',')
      ->check(CLI::Range(1, 5))
      ->capture_default_str();
  cmd->callback([args, cmd] {
    // The simulator's flags and --dataset's exclude each other: one of them would be ignored.
    if (!args->dataset.empty()) {
      for (const char* flag :
           {"--preset", "--path", "--landmarks", "--steps", "--runs", "--seed", "--clutter", "--detection-probability"}) {
        if (cmd->count(flag) > 0) {
          throw InvalidArgument(std::string(flag) + " sets the simulated world: with --dataset the runs are the data's "
                                "robots (leave it out)");
        }
      }
    } else if (cmd->count("--robots") > 0) {
      throw InvalidArgument("--robots chooses the robots of --dataset: give --dataset, or leave it out");
    }
    consistencyCommand(*args);
  });
}

}  // namespace seif::cli
