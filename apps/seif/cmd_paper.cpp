// seif paper: the experiment of Thrun et al. 2002, §4 (algorithm.md "What the paper
// measured"): flags -> PaperRequest -> runPaper (eval/paper.hpp) -> print, write
// OUT/results.json, OUT/table.md, OUT/figure_data/ and render the figures
// (scripts/figures/paper.py).
#include "commands.hpp"
#include "options.hpp"
#include "stop_signals.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/paper.hpp>
#include <seif/filters/factory.hpp>
#include "eval/parallel.hpp"
#include "filters/option_values.hpp"

#include <climits>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace seif::cli {
namespace {

struct PaperArgs {
  int runs = 100;
  std::uint64_t seed = 1;
  int jobs = 0;  // 0: hardware concurrency
  std::string out = "out/paper";
  std::vector<int> sweep_active;
  std::string extra;  // --filters: specs beyond the paper
  std::string path = "lawnmower";
  bool no_figures = false;
};

void paperCommand(const PaperArgs& args) {
  PaperRequest request;
  request.runs = args.runs;
  request.seed = args.seed;
  request.jobs = static_cast<unsigned>(args.jobs);
  request.options.sweep_active = args.sweep_active;
  if (!args.extra.empty()) request.options.extra = splitFilterList(args.extra);
  request.options.path = parsePaperPath(args.path);
  checkPaperRequest(request);
  requireOutputFolder(args.out);

  const WorldConfig world = paperWorld(args.seed, request.options);
  const std::size_t total = static_cast<std::size_t>(args.runs);
  std::printf("seif paper: %zu runs of the paper world (%s path, %d landmarks, %d update cycles, "
              "known data association), seeds %llu..%llu, %u threads\n",
              total, args.path.c_str(), world.landmarks, world.steps, static_cast<unsigned long long>(args.seed),
              static_cast<unsigned long long>(args.seed + total - 1), threadCount(request.jobs, total));
  std::fflush(stdout);
  PaperReport report;
  {
    const StopOnSignals stop_on_signals;  // Ctrl-C: the runs that ran are summarised and written
    request.stop = StopOnSignals::flag();
    Progress progress("seif paper");
    report = runPaper(request, [&](std::size_t done, std::size_t all) { progress(done, all); });
  }
  for (const PaperFailure& f : report.failed) {
    std::fprintf(stderr, "seif paper: run %llu failed and is left out: %s\n",
                 static_cast<unsigned long long>(f.seed - args.seed), f.error.c_str());
  }
  std::printf("%s", paperSummaryText(report).c_str());
  writePaperResults(report, args.out);
  std::printf("\nwrote %s/results.json, %s/table.md, %s/figure_data/\n", args.out.c_str(), args.out.c_str(),
              args.out.c_str());
  std::printf("figure data: the run with the median final error of the constant-time SEIF (seed %llu)\n",
              static_cast<unsigned long long>(report.runs[report.typical].seed));
  if (!args.no_figures && renderFigure("paper.py", {args.out})) {
    std::printf("figures: %s/fig1_ekf.png, fig2_seif.png, fig6_compare.png%s\n", args.out.c_str(),
                args.sweep_active.empty() ? "" : ", sweep_active.png");
  }
  if (report.interrupted) {
    std::fflush(stdout);
    throw Interrupted(interruptedText(report) + "; their results are in " + args.out);
  }
}

}  // namespace

void addPaperCommand(CLI::App& app) {
  auto args = std::make_shared<PaperArgs>();
  CLI::App* cmd = app.add_subcommand(
      "paper",
      "Reproduce the experiment of Thrun et al. 2002, section 4: runs of the paper world (50\n"
      "landmarks in the unit square, 500 update cycles, known data association), each running\n"
      "the EKF, the SEIF with exact mean and the constant-time SEIF (theta_x = 6, K = 10) on\n"
      "identical data from the true start pose. Run r uses simulator seed SEED + r; results do\n"
      "not depend on --jobs (except times).\n"
      "Final error = mean over the mapped landmarks of the squared position error after the\n"
      "last update [m^2], averaged over runs, with a 95% confidence interval (Student t); the\n"
      "table shows it in 10^-3 m^2 beside the paper's numbers, with the final number of links\n"
      "(non-zero off-diagonal blocks of the information matrix) and the median time per update.\n"
      "Writes OUT/results.json, OUT/table.md, OUT/figure_data/ and the figures fig1_ekf.png,\n"
      "fig2_seif.png, fig6_compare.png (and sweep_active.png), rendered by\n"
      "scripts/figures/paper.py with /usr/bin/python3 and matplotlib. Ctrl-C (or SIGTERM) stops\n"
      "the study: the runs under way finish, those that ran are summarised and written\n"
      "(results.json \"interrupted\": true), and the exit status is 130.");
  cmd->add_option("--runs", args->runs, "number of independent runs")
      ->transform(integerIn(1, INT_MAX))
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "simulator seed of run 0 (run r: seed + r, at most 2^64-1)")
      ->transform(seedValue())
      ->capture_default_str();
  cmd->add_option("--jobs", args->jobs, "threads (default: the number of cores)")
      ->transform(integerIn(1, INT_MAX));
  cmd->add_option("--out", args->out, "output folder")->capture_default_str();
  cmd->add_option("--filters", args->extra,
                  "also run these filters beyond the paper's (specs, e.g. batch,ekf:linearization=fej,\n"
                  "seif:sparsify=eseif,beta=4) and add a table of every filter's error against the EKF\n"
                  "and the batch MAP, with its NEES")
      ->check(filterSpecs());
  cmd->add_option("--sweep-active", args->sweep_active,
                  "also run the constant-time SEIF with each theta_x listed, e.g. 4,6,10,20")
      ->delimiter(',')
      ->transform(integerIn(options::entry(filterOptions(), "active").min,  // seif:active's range
                            options::entry(filterOptions(), "active").max));
  cmd->add_option("--path", args->path,
                  "the robot's path: lawnmower (a survey of the square, 1.75 laps) or lissajous (a\n"
                  "3:2 Lissajous curve crossing itself, 1.6 laps); docs/simulator.md")
      ->check(CLI::IsMember({"lawnmower", "lissajous"}))
      ->capture_default_str();
  cmd->add_flag("--no-figures", args->no_figures, "write the figure data but do not render the figures");
  cmd->callback([args] { paperCommand(*args); });
}

}  // namespace seif::cli
