// seif bench: time per step and peak memory of each filter once its map holds N landmarks
// (issue 3, "Benchmark"): flags -> BenchRequest -> runBench (eval/bench.hpp) -> print, write
// OUT/bench.json and render OUT/bench.png (scripts/figures/bench.py).
#include "commands.hpp"
#include "options.hpp"
#include "stop_signals.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/bench.hpp>
#include "core/files.hpp"

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace seif::cli {
namespace {

struct BenchArgs {
  std::vector<std::string> filters = {"ekf", "eif", "seif"};
  std::vector<int> landmarks = {100, 1000, 10000, 100000, 1000000};
  int window = 200;
  int repeat = 3;
  std::string out = "out/bench";
  std::uint64_t world_seed = 1;
  double max_seconds = 120.0;
  double max_memory_gb = 4.0;
  bool no_figure = false;
  FilterFlags options;
  AssociationFlags association;
};

void bench(const BenchArgs& args) {
  requireOutputFolder(args.out);
  BenchRequest request;
  request.filters = args.filters;
  request.landmarks = args.landmarks;
  request.window = args.window;
  request.repeat = args.repeat;
  request.world_seed = args.world_seed;
  request.max_seconds = args.max_seconds;
  request.max_memory_gb = args.max_memory_gb;
  const FilterSpec flags = args.options.resolve();
  request.seif = flags.seif;
  request.linearization = flags.linearization;
  request.iterations = flags.iterations;
  request.association = args.association.resolve();

#if !defined(NDEBUG)
  std::printf("warning: this seif was built without NDEBUG (a debug build): times are not representative\n");
#endif
  std::printf("seif bench: corridor world (seed %llu), last %d steps timed, best of %d runs, "
              "budget %g s and %g GB per case\n",
              static_cast<unsigned long long>(args.world_seed), args.window, args.repeat,
              args.max_seconds, args.max_memory_gb);
  std::fputs(benchHeaderText().c_str(), stdout);
  request.stop = StopOnSignals::flag();  // Ctrl-C: the finished cases are written
  BenchReport report;
  {
    const StopOnSignals stop_on_signals;
    report = runBench(request, [&](const BenchRow& row) {
      std::fputs(benchRowText(row).c_str(), stdout);
      std::fflush(stdout);
    });
  }
  std::fputs(benchTargetsText(report.targets).c_str(), stdout);
  const std::filesystem::path json = std::filesystem::path(args.out) / "bench.json";
  writeFileAtomically(json, benchJson(report));
  std::printf("wrote %s\n", json.string().c_str());
  if (!args.no_figure) {
    const std::filesystem::path png = std::filesystem::path(args.out) / "bench.png";
    if (renderFigure("bench.py", {json.string(), png.string()})) std::printf("wrote %s\n", png.string().c_str());
  }
  if (report.interrupted) {
    std::fflush(stdout);
    throw Interrupted(interruptedText(report) + ": the rows above are in " + json.string());
  }
}

}  // namespace

void addBenchCommand(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Time per step and peak memory of each filter once its map holds N landmarks.\n"
      "For each (filter, N): simulate the corridor world with N landmarks (about one new\n"
      "landmark per step), run the filter over the whole corridor and time the last --window\n"
      "steps (the map then holds N - window .. N landmarks); each case runs in its own process.\n"
      "A case whose estimated memory or time (extrapolated from the smaller cases) exceeds the\n"
      "budget is skipped and the reason recorded. With --association nn|jcbb the corridor's ids\n"
      "are hidden and every scan is associated (the SEIF gates with its local marginal); its time per\n"
      "scan is reported beside the filter's step time, which excludes it. Writes OUT/bench.json and OUT/bench.png\n"
      "(rendered by scripts/figures/bench.py with /usr/bin/python3 and matplotlib). Ctrl-C (or SIGTERM)\n"
      "stops the study: the cases finished are written (bench.json \"interrupted\": true) and the\n"
      "exit status is 130.");
  cmd->add_option("--filters", args->filters, "comma-separated filters: ekf, eif, seif")
      ->delimiter(',')
      ->check(CLI::IsMember({"ekf", "eif", "seif"}))
      ->capture_default_str();
  cmd->add_option("--landmarks", args->landmarks, "comma-separated map sizes N")
      ->delimiter(',')
      ->transform(integerIn(1, 10000000))  // the simulator's bound
      ->capture_default_str();
  cmd->add_option("--window", args->window, "steps timed at the end of the corridor (at most half of them)")
      ->transform(integerIn(1, 1000000))
      ->capture_default_str();
  cmd->add_option("--repeat", args->repeat,
                  "runs per case, each in its own process; the one with the lowest median is reported")
      ->transform(integerIn(1, 100))
      ->capture_default_str();
  cmd->add_option("--out", args->out, "output folder")->capture_default_str();
  cmd->add_option("--world-seed", args->world_seed, "seed of the simulated corridor")
      ->transform(seedValue())
      ->capture_default_str();
  cmd->add_option("--max-seconds", args->max_seconds,
                  "skip a case whose estimated run time exceeds this many seconds")
      ->check(positiveFinite())
      ->capture_default_str();
  cmd->add_option("--max-memory-gb", args->max_memory_gb,
                  "skip a case whose estimated peak memory exceeds this many GB")
      ->check(positiveFinite())
      ->capture_default_str();
  cmd->add_flag("--no-figure", args->no_figure, "do not render OUT/bench.png");
  args->options.add(*cmd);
  args->association.add(*cmd, /*tuning=*/false);
  cmd->callback([args] { bench(*args); });
}

}  // namespace seif::cli
