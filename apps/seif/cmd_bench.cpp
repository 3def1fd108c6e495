// seif bench: time per step and peak memory of each filter once its map holds N landmarks
// (issue 3, "Benchmark"): flags -> BenchRequest -> runBench (eval/bench.hpp) -> print, write
// OUT/bench.json and render OUT/bench.png (scripts/figures/bench.py).
#include "commands.hpp"
#include "options.hpp"

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

void printHeader() {
  std::printf("%-6s %9s %9s %6s %12s %12s %10s %10s %10s\n", "filter", "N", "mapped", "steps",
              "median us", "p90 us", "peak MB", "filter MB", "B/landmark");
}

void printRow(const BenchMeasurement& m) {
  const double per = m.filter_peak_mb * 1024.0 * 1024.0 / static_cast<double>(std::max<std::size_t>(1, m.map_last));
  std::printf("%-6s %9d %9zu %6zu %12.1f %12.1f %10.1f %10.1f %10.0f", m.filter.c_str(), m.landmarks,
              m.map_last, m.steps, m.us_per_step_median, m.us_per_step_p90, m.peak_rss_mb,
              m.filter_peak_mb, per);
  if (m.association != "known") {
    const double correct = m.association_scored == 0 ? 0.0 : 100.0 * double(m.association_correct) / double(m.association_scored);
    std::printf("   %s: %.1f us/scan median, %.1f p90 over %zu scans; %.1f %% correct", m.association.c_str(),
                m.us_association_per_scan_median, m.us_association_per_scan_p90, m.scans, correct);
  }
  std::printf("\n");
  std::fflush(stdout);
}

void printSkipped(const std::string& filter, int n, const std::string& why) {
  std::printf("%-6s %9d   skipped: %s\n", filter.c_str(), n, why.c_str());
  std::fflush(stdout);
}

void printTargets(const BenchTargets& t) {
  if (const auto& g = t.seif_growth) {
    std::printf("SEIF median at N=%d / at N=%d: %.1f / %.1f us = %.2fx (target <= 1.5x): %s\n", g->to_landmarks,
                g->from_landmarks, g->to_us, g->from_us, g->ratio, g->met ? "met" : "NOT met");
  }
  if (const auto& g = t.seif_association_growth) {
    std::printf("SEIF association per scan at N=%d / at N=%d: %.1f / %.1f us = %.2fx (target <= 1.5x): %s\n",
                g->to_landmarks, g->from_landmarks, g->to_us, g->from_us, g->ratio, g->met ? "met" : "NOT met");
  }
  if (const auto& s = t.ekf_over_seif) {
    std::printf("EKF / SEIF median at N=%d: %.1f / %.1f us = %.0fx (target >= 100x): %s\n", s->landmarks,
                s->ekf_us, s->seif_us, s->ratio, s->met ? "met" : "NOT met");
  }
  if (!t.seif_bytes_per_landmark.empty()) {
    std::printf("SEIF memory per landmark (filter peak / mapped):");
    for (const auto& [n, bytes] : t.seif_bytes_per_landmark) std::printf(" %.0f B at N=%d;", bytes, n);
    std::printf("\n");
  }
}

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
  printHeader();
  const BenchReport report = runBench(request, [&](const BenchRow& row) {
    if (row.measurement) {
      printRow(*row.measurement);
    } else {
      printSkipped(row.filter, row.landmarks, row.skipped);
    }
  });
  printTargets(report.targets);
  const std::filesystem::path json = std::filesystem::path(args.out) / "bench.json";
  writeFileAtomically(json, benchJson(report));
  std::printf("wrote %s\n", json.string().c_str());
  if (args.no_figure) return;
  const std::filesystem::path png = std::filesystem::path(args.out) / "bench.png";
  if (renderFigure("bench.py", {json.string(), png.string()})) std::printf("wrote %s\n", png.string().c_str());
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
      "(rendered by scripts/figures/bench.py with /usr/bin/python3 and matplotlib).");
  cmd->add_option("--filters", args->filters, "comma-separated filters: ekf, eif, seif")
      ->delimiter(',')
      ->check(CLI::IsMember({"ekf", "eif", "seif"}))
      ->capture_default_str();
  cmd->add_option("--landmarks", args->landmarks, "comma-separated map sizes N")
      ->delimiter(',')
      ->transform(integerIn(1, 100000000))
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
