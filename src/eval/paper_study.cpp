// The paper's Monte-Carlo study as one call (runPaper in include/seif/eval/paper.hpp).
#include <seif/core/errors.hpp>
#include <seif/eval/paper.hpp>
#include "eval/parallel.hpp"
#include "filters/information_ops.hpp"

#include <algorithm>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

namespace seif {

void checkPaperRequest(const PaperRequest& request) {
  if (request.runs < 1) throw InvalidArgument("paper: runs must be >= 1");
  // Each SEIF's theta_x within the range its spec's `active` takes, K not negative: every
  // run would fail otherwise.
  const PaperOptions& o = request.options;
  const auto checkActive = [](int active, const char* what) {
    if (active < 1 || active > kMaxLocalLandmarks - 1) {
      throw InvalidArgument(std::string("paper: ") + what + " must be in [1, " + std::to_string(kMaxLocalLandmarks - 1) +
                            "], found " + std::to_string(active));
    }
  };
  checkActive(o.active, "active");
  for (int a : o.sweep_active) checkActive(a, "each of sweep_active");
  if (o.relax < 0) throw InvalidArgument("paper: relax must be >= 0, found " + std::to_string(o.relax));
  // Run r uses seed SEED + r: the last one must not wrap past 2^64 - 1.
  if (request.seed > UINT64_MAX - static_cast<std::uint64_t>(request.runs - 1)) {
    throw InvalidArgument("paper: seed + runs - 1 (--seed, --runs) must be at most " + std::to_string(UINT64_MAX) + ", found " +
                                std::to_string(request.seed) + " + " + std::to_string(request.runs) + " - 1");
  }
}

PaperReport runPaper(const PaperRequest& request, const std::function<void(std::size_t, std::size_t)>& progress) {
  checkPaperRequest(request);
  PaperReport report;
  report.request = request;
  report.request.stop = nullptr;  // the request's flag need not outlive the call
  report.specs = paperFilters(request.options);
  report.world = paperWorld(request.seed, request.options);
  const std::size_t total = static_cast<std::size_t>(request.runs);
  report.jobs = threadCount(request.jobs, total);

  // Each run is independent and stored by index: the results do not depend on the threads.
  std::vector<std::optional<PaperRun>> results(total);
  std::vector<std::string> failures(total);
  std::vector<char> ran(total, 0);  // not all when stopped: no run starts after the stop
  parallelFor(
      total, report.jobs,
      [&](std::size_t r) {
        ran[r] = 1;
        try {
          results[r] = runPaperExperiment(request.seed + r, request.options);
        } catch (const std::exception& e) {
          failures[r] = e.what();
        }
      },
      progress, request.stop);
  for (std::size_t r = 0; r < total; ++r) {
    if (!ran[r]) {
      report.interrupted = true;
    } else if (results[r]) {
      report.runs.push_back(std::move(*results[r]));
    } else {
      report.failed.push_back({request.seed + r, failures[r]});
    }
  }
  if (report.runs.empty() && report.interrupted) throw Interrupted("paper: stopped before any run succeeded");
  if (report.runs.empty()) throw NumericError("every run failed");
  for (std::size_t f = 0; f < report.specs.size(); ++f) {
    report.summaries.push_back(summarizePaperFilter(f, report.runs));
  }

  std::vector<std::size_t> order(report.runs.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return report.runs[a].filters[2].mse < report.runs[b].filters[2].mse;
  });
  report.typical = order[(order.size() - 1) / 2];
  PaperOptions figure_options = request.options;
  figure_options.sweep_active.clear();
  runPaperExperiment(report.runs[report.typical].seed, figure_options, &report.typical_detail);
  return report;
}

}  // namespace seif
