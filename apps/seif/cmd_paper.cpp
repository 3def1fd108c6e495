// seif paper: the experiment of Thrun et al. 2002, §4 (algorithm.md "What the paper
// measured"). Many independent runs of the paper world, each running the EKF, the SEIF
// with exact mean and the constant-time SEIF on identical data (eval/paper.hpp), summarised
// with 95 % confidence intervals (eval/stats.hpp) beside the paper's numbers. Writes
// OUT/results.json, OUT/table.md, OUT/figure_data/ and the figures (scripts/figures/paper.py).
#include "commands.hpp"
#include "options.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/paper.hpp>
#include <seif/eval/stats.hpp>
#include <seif/filters/information_ops.hpp>
#include <seif/io/atomic_file.hpp>

#include <algorithm>
#include <atomic>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace seif::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* kErrorDefinition =
    "final error = mean over the mapped landmarks of the squared landmark position error "
    "|estimate - truth|^2 after the last update [m^2], averaged over runs; 95% CI = "
    "t(0.975, n-1) * s / sqrt(n) over the runs' values";
constexpr const char* kTimeDefinition =
    "wall time of one filter cycle (motion update + measurement update, incl. mean recovery "
    "and sparsification), median over every step of every run";

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

/// The paper's numbers (WAFR 2002, §4 table), and the journal version's for the sweep.
struct PaperReference {
  const char* label;
  double error;  // [m^2]
  double error_ci95;
  double links;
  double links_ci95;
  const char* complexity_paper;
  const char* complexity_here;
};

PaperReference reference(const std::string& name) {
  if (name == "ekf") return {"EKF", 5.54e-3, 0.67e-3, 1275, 0, "O(N^2)", "O(N^2)"};
  if (name == "seif_exact") {
    return {"SEIF with exact μ", 4.75e-3, 0.67e-3, 549, 1.60, "O(N^3)", "sparse solve"};
  }
  return {"SEIF (constant time)", 6.35e-3, 0.67e-3, 549, 1.59, "O(1)", "O(1)"};
}

/// The journal version (IJRR 2004), N = 50: error and time relative to the EKF.
std::optional<double> journalErrorRatio(int active) {
  if (active == 6) return 0.0800 / 0.0526;
  if (active == 10) return 0.0584 / 0.0526;
  return std::nullopt;
}

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

std::string plusMinus(double mean, double ci, const char* format) {
  return fmt(format, mean) + " ± " + fmt(format, ci);
}

/// A table kept as strings, printed aligned for the terminal and as Markdown.
struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;

  static std::size_t width(const std::string& s) {  // UTF-8 code points
    std::size_t n = 0;
    for (unsigned char c : s) n += (c & 0xC0) != 0x80;
    return n;
  }
  std::string text() const {
    std::vector<std::size_t> w(header.size(), 0);
    for (std::size_t c = 0; c < header.size(); ++c) w[c] = width(header[c]);
    for (const auto& row : rows)
      for (std::size_t c = 0; c < row.size(); ++c) w[c] = std::max(w[c], width(row[c]));
    std::string out;
    auto line = [&](const std::vector<std::string>& cells) {
      for (std::size_t c = 0; c < cells.size(); ++c) {
        out += (c ? " | " : "") + cells[c] + std::string(w[c] - width(cells[c]), ' ');
      }
      while (!out.empty() && out.back() == ' ') out.pop_back();
      out += "\n";
    };
    line(header);
    for (std::size_t c = 0; c < header.size(); ++c) out += (c ? "-+-" : "") + std::string(w[c], '-');
    out += "\n";
    for (const auto& row : rows) line(row);
    return out;
  }
  std::string markdown() const {
    std::string out = "|";
    for (const auto& h : header) out += " " + h + " |";
    out += "\n|";
    for (std::size_t c = 0; c < header.size(); ++c) out += c == 0 ? "---|" : "---:|";
    out += "\n";
    for (const auto& row : rows) {
      out += "|";
      for (const auto& cell : row) out += " " + cell + " |";
      out += "\n";
    }
    return out;
  }
};

nlohmann::json matrixJson(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (Eigen::Index c = 0; c < m.cols(); ++c) row.push_back(m(r, c));
    rows.push_back(std::move(row));
  }
  return rows;
}

/// The data of one filter of run 0 for scripts/figures/paper.py.
nlohmann::json figureData(const SlamFilter& filter, const RunOutput& out, const Dataset& data,
                          std::uint64_t seed, const std::string& name) {
  const FilterSnapshot snap = snapshotById(filter);
  nlohmann::json j;
  j["filter"] = name;
  j["seed"] = seed;
  j["order"] = "state [x, y, theta, then landmarks by ascending id]";
  j["ids"] = snap.ids;
  j["ids_state_order"] = filter.landmarkIds();
  nlohmann::json truth = nlohmann::json::array();
  for (const auto& [id, p] : data.landmarks) truth.push_back({{"id", id}, {"x", p.x()}, {"y", p.y()}});
  j["true_landmarks"] = truth;
  nlohmann::json est = nlohmann::json::array();
  for (std::size_t k = 0; k < snap.ids.size(); ++k) {
    const Eigen::Index i = 3 + 2 * static_cast<Eigen::Index>(k);
    const Mat2 P = snap.covariance.block<2, 2>(i, i);
    est.push_back({{"id", snap.ids[k]},
                   {"x", snap.mean(i)},
                   {"y", snap.mean(i + 1)},
                   {"cov", {{P(0, 0), P(0, 1)}, {P(1, 0), P(1, 1)}}}});
  }
  j["landmarks"] = est;
  auto path = [](const std::vector<TimedPose>& track) {
    nlohmann::json p = nlohmann::json::array();
    for (const TimedPose& tp : track) p.push_back({tp.time, tp.pose.x(), tp.pose.y(), tp.pose.z()});
    return p;
  };
  j["true_path"] = path(data.groundtruth);
  j["path"] = path(out.trajectory);
  const Pose2 x = filter.pose();
  const Mat3 Px = snap.covariance.topLeftCorner<3, 3>();
  j["pose"] = {x.x(), x.y(), x.z()};
  j["pose_cov"] = matrixJson(Px);
  j["covariance"] = matrixJson(snap.covariance);
  j["information"] = matrixJson(snap.information);
  nlohmann::json robot = nlohmann::json::array(), between = nlohmann::json::array();
  for (const FilterSnapshot::Link& l : snap.links) {
    if (l.a < 0) {
      robot.push_back({{"id", l.b}, {"strength", l.strength}});
    } else {
      between.push_back({{"a", l.a}, {"b", l.b}, {"strength", l.strength}});
    }
  }
  j["robot_links"] = robot;
  j["landmark_links"] = between;
  j["links"] = snap.links.size();
  j["stats"] = toJson(filter.stats());
  return j;
}

void paperCommand(const PaperArgs& args) {
  // Run r uses seed SEED + r: the last one must not wrap past 2^64 - 1.
  if (args.seed > UINT64_MAX - static_cast<std::uint64_t>(args.runs - 1)) {
    throw InvalidArgument("--seed + --runs - 1 must be at most " + std::to_string(UINT64_MAX) +
                                ", found " + std::to_string(args.seed) + " + " + std::to_string(args.runs) +
                                " - 1");
  }
  requireOutputFolder(args.out);
  PaperOptions options;
  options.sweep_active = args.sweep_active;
  if (!args.extra.empty()) options.extra = splitFilterList(args.extra);
  options.path = parsePaperPath(args.path);
  const std::vector<PaperFilterSpec> specs = paperFilters(options);
  const WorldConfig world = paperWorld(args.seed, options);
  const std::size_t total = static_cast<std::size_t>(args.runs);
  unsigned jobs = args.jobs > 0 ? static_cast<unsigned>(args.jobs) : std::thread::hardware_concurrency();
  jobs = std::max(1u, std::min<unsigned>(jobs, static_cast<unsigned>(total)));

  std::printf("seif paper: %zu runs of the paper world (%s path, %d landmarks, %d update cycles, "
              "known data association), seeds %llu..%llu, %u threads\n",
              total, args.path.c_str(), world.landmarks, world.steps, static_cast<unsigned long long>(args.seed),
              static_cast<unsigned long long>(args.seed + total - 1), jobs);
  std::fflush(stdout);

  // Each run is independent and stored by index: the results do not depend on --jobs.
  std::vector<std::optional<PaperRun>> results(total);
  std::vector<std::string> failures(total);
  std::atomic<std::size_t> next{0};
  std::size_t done = 0;
  std::mutex mutex;
  {
    Progress progress("seif paper");
    auto worker = [&] {
      for (;;) {
        const std::size_t r = next.fetch_add(1);
        if (r >= total) return;
        try {
          results[r] = runPaperExperiment(args.seed + r, options);
        } catch (const std::exception& e) {
          failures[r] = e.what();
        }
        const std::lock_guard<std::mutex> lock(mutex);
        progress(++done, total);
      }
    };
    std::vector<std::thread> threads;
    for (unsigned t = 1; t < jobs; ++t) threads.emplace_back(worker);
    worker();
    for (std::thread& t : threads) t.join();
  }

  std::vector<PaperRun> runs;
  nlohmann::json failed = nlohmann::json::array();
  for (std::size_t r = 0; r < total; ++r) {
    if (results[r]) {
      runs.push_back(std::move(*results[r]));
    } else {
      failed.push_back({{"seed", args.seed + r}, {"error", failures[r]}});
      std::fprintf(stderr, "seif paper: run %zu failed and is left out: %s\n", r, failures[r].c_str());
    }
  }
  if (runs.empty()) throw NumericError("every run failed");

  std::vector<PaperFilterSummary> sums;
  for (std::size_t f = 0; f < specs.size(); ++f) sums.push_back(summarizePaperFilter(f, runs));
  const PaperFilterSummary& ekf = sums[0];
  const std::size_t n_runs = runs.size();
  const int N = world.landmarks;

  // EKF: the information matrix is dense, so links = n(n+1)/2 for n mapped landmarks.
  std::size_t all_mapped = 0, ekf_full = 0, ekf_dense = 0;
  double ekf_links_all_min = 1e300, ekf_links_all_max = 0;
  for (const PaperRun& run : runs) {
    const PaperFilterResult& e = run.filters[0];
    if (e.stats.links == e.mapped * (e.mapped + 1) / 2) ++ekf_dense;
    if (e.mapped == static_cast<std::size_t>(N)) {
      ++all_mapped;
      const double l = static_cast<double>(e.stats.links);
      ekf_links_all_min = std::min(ekf_links_all_min, l);
      ekf_links_all_max = std::max(ekf_links_all_max, l);
      if (e.stats.links == static_cast<std::size_t>(N * (N + 1) / 2)) ++ekf_full;
    }
  }

  // ---- the table ----
  Table table;
  table.header = {"filter", "runs", "final error (95% CI) [10^-3 m^2]", "paper", "error / EKF (95% CI)",
                  "paper", "final links (95% CI)", "paper", "µs per update (median)", "complexity"};
  for (std::size_t f = 0; f < 3; ++f) {
    const PaperFilterSummary& s = sums[f];
    const PaperReference ref = reference(s.name);
    table.rows.push_back({
        ref.label,
        std::to_string(s.error.n),
        plusMinus(1e3 * s.error.mean, 1e3 * s.error.ci95, "%.2f"),
        plusMinus(1e3 * ref.error, 1e3 * ref.error_ci95, "%.2f"),
        f == 0 ? std::string("1") : plusMinus(s.ratio, s.ratio_ci95, "%.3f"),
        fmt("%.3f", ref.error / 5.54e-3),
        plusMinus(s.link.mean, s.link.ci95, "%.1f"),
        ref.links_ci95 > 0 ? fmt("%.0f", ref.links) + " ± " + fmt("%.2f", ref.links_ci95)
                           : fmt("%.0f", ref.links),
        fmt("%.1f", s.us_median),
        std::string(ref.complexity_here) +
            (std::string(ref.complexity_here) != ref.complexity_paper
                 ? std::string(" (paper: ") + ref.complexity_paper + ")"
                 : std::string()),
    });
  }

  std::ostringstream notes;
  notes << "Final error: mean over the mapped landmarks of the squared position error after the "
           "last update [m^2], averaged over runs (shown in 10^-3 m^2); 95% CI = t(0.975, n-1) "
           "s / sqrt(n). The paper does not define its error; this definition matches the "
           "magnitude of its table. Same data for all filters in a run.\n";
  notes << "RMS landmark error [m] (sqrt of each run's value, averaged):";
  for (std::size_t f = 0; f < 3; ++f) {
    notes << (f ? ", " : " ") << sums[f].name << " " << fmt("%.4f", sums[f].rms.mean) << " ± "
          << fmt("%.4f", sums[f].rms.ci95);
  }
  notes << "\n";
  notes << "Aligned error (the map's shape error): the final error after the best rigid 2-D "
           "alignment of each map to the truth, i.e. with the whole map's offset and rotation "
           "removed [10^-3 m^2]:";
  for (std::size_t f = 0; f < 3; ++f) {
    notes << (f ? ", " : " ") << sums[f].name << " " << fmt("%.3f", 1e3 * sums[f].aligned_error.mean)
          << " ± " << fmt("%.3f", 1e3 * sums[f].aligned_error.ci95);
    if (f > 0) notes << " (" << fmt("%.2f", sums[f].aligned_ratio) << " × EKF)";
  }
  notes << "\n";
  notes << "Paired difference to the EKF, same runs [10^-3 m^2]:";
  for (std::size_t f = 1; f < 3; ++f) {
    notes << (f > 1 ? ", " : " ") << sums[f].name << " " << fmt("%+.3f", 1e3 * sums[f].diff.mean)
          << " ± " << fmt("%.3f", 1e3 * sums[f].diff.ci95);
  }
  notes << "\n";
  notes << "Error / EKF with 95% CI (paired, delta method):";
  for (std::size_t f = 1; f < 3; ++f) {
    notes << (f > 1 ? ", " : " ") << sums[f].name << " " << fmt("%.3f", sums[f].ratio) << " ± "
          << fmt("%.3f", sums[f].ratio_ci95) << " (median of per-run ratios "
          << fmt("%.3f", sums[f].ratio_median) << ")";
  }
  notes << "\n";
  notes << "Per-run error [10^-3 m^2] median / max:";
  for (std::size_t f = 0; f < 3; ++f) {
    notes << (f ? ", " : " ") << sums[f].name << " " << fmt("%.2f", 1e3 * sums[f].error.median)
          << " / " << fmt("%.2f", 1e3 * sums[f].error.max);
  }
  notes << "\n";
  notes << "Mapped landmarks: " << fmt("%.2f", ekf.map.mean) << " of " << N << " on average (min "
        << fmt("%.0f", ekf.map.min) << "); " << all_mapped << " of " << n_runs << " runs mapped all "
        << N << ".\n";
  notes << "EKF links = n(n+1)/2 for its n mapped landmarks in " << ekf_dense << " of " << n_runs
        << " runs; in the " << all_mapped << " runs with all " << N << " mapped: ";
  if (all_mapped > 0) {
    notes << (ekf_links_all_min == ekf_links_all_max
                  ? fmt("%.0f", ekf_links_all_min)
                  : fmt("%.0f", ekf_links_all_min) + ".." + fmt("%.0f", ekf_links_all_max))
          << " (paper: 1275).\n";
  } else {
    notes << "none.\n";
  }
  notes << "SEIF links / EKF links: exact " << fmt("%.3f", sums[1].link.mean / ekf.link.mean)
        << ", constant time " << fmt("%.3f", sums[2].link.mean / ekf.link.mean)
        << " (paper: 549 / 1275 = 0.431).\n";
  notes << "Time per update: " << kTimeDefinition << "; measured with " << jobs
        << " runs in parallel.\n";

  // ---- the sweep ----
  Table sweep;
  nlohmann::json sweep_json = nlohmann::json::array();
  if (!args.sweep_active.empty()) {
    sweep.header = {"theta_x (active)", "runs", "final error (95% CI) [10^-3 m^2]", "error / EKF (95% CI)",
                    "journal", "final links (95% CI)", "µs per update (median)", "time / EKF"};
    for (std::size_t k = 0; k < args.sweep_active.size(); ++k) {
      const PaperFilterSummary& s = sums[3 + k];
      const int active = args.sweep_active[k];
      const auto journal = journalErrorRatio(active);
      sweep.rows.push_back({std::to_string(active), std::to_string(s.error.n),
                            plusMinus(1e3 * s.error.mean, 1e3 * s.error.ci95, "%.2f"),
                            plusMinus(s.ratio, s.ratio_ci95, "%.3f"),
                            journal ? fmt("%.3f", *journal) : std::string("-"),
                            plusMinus(s.link.mean, s.link.ci95, "%.1f"), fmt("%.1f", s.us_median),
                            fmt("%.3f", s.us_median / ekf.us_median)});
      sweep_json.push_back({{"active", active},
                            {"runs", s.error.n},
                            {"error_mean", s.error.mean},
                            {"error_ci95", s.error.ci95},
                            {"error_ratio_to_ekf", s.ratio},
                            {"error_ratio_to_ekf_ci95", s.ratio_ci95},
                            {"error_ratio_to_ekf_median_per_run", s.ratio_median},
                            {"journal_error_ratio_to_ekf", journal ? nlohmann::json(*journal) : nlohmann::json()},
                            {"rms_mean", s.rms.mean},
                            {"rms_ci95", s.rms.ci95},
                            {"links_mean", s.link.mean},
                            {"links_ci95", s.link.ci95},
                            {"us_per_update_median", s.us_median},
                            {"time_ratio_to_ekf", s.us_median / ekf.us_median}});
    }
  }

  std::printf("\n%s\n%s", table.text().c_str(), notes.str().c_str());
  if (!args.sweep_active.empty()) {
    std::printf("\nConstant-time SEIF against theta_x (K = %d; the journal version, N = 50: error / "
                "EKF 1.521 at theta_x = 6, 1.110 at 10, the latter at 1/6 of the EKF's time):\n%s",
                options.relax, sweep.text().c_str());
  }

  // ---- beyond the paper: every filter's error with its NEES, against the EKF and the batch MAP ----
  Table beyond;
  std::size_t batch_index = sums.size();
  for (std::size_t f = 0; f < specs.size(); ++f) {
    if (specs[f].spec && specs[f].spec->name == "batch") batch_index = f;
  }
  const bool with_batch = batch_index < sums.size();
  beyond.header = {"filter", "final error [10^-3 m^2]", "error / EKF", "aligned / EKF"};
  if (with_batch) beyond.header.insert(beyond.header.end(), {"error / batch", "aligned / batch"});
  beyond.header.insert(beyond.header.end(), {"landmark NEES mean (median)", "pose NEES mean (median)", "µs per update"});
  if (!options.extra.empty()) {
    for (std::size_t f = 0; f < sums.size(); ++f) {
      if (f >= 3 && !specs[f].spec) continue;  // the sweep has its own table
      const PaperFilterSummary& s = sums[f];
      std::vector<std::string> row = {s.name, plusMinus(1e3 * s.error.mean, 1e3 * s.error.ci95, "%.2f"),
                                      fmt("%.3f", s.ratio), fmt("%.3f", s.aligned_ratio)};
      if (with_batch) {
        const PaperFilterSummary& b = sums[batch_index];
        row.push_back(fmt("%.2f", s.error.mean / b.error.mean));
        row.push_back(fmt("%.2f", s.aligned_error.mean / b.aligned_error.mean));
      }
      row.push_back(fmt("%.1f", s.nees.mean) + " (" + fmt("%.1f", s.nees.median) + ")");
      row.push_back(fmt("%.1f", s.nees_pose.mean) + " (" + fmt("%.1f", s.nees_pose.median) + ")");
      row.push_back(fmt("%.1f", s.us_median));
      beyond.rows.push_back(std::move(row));
    }
    std::printf("\nBeyond the paper, same runs (NEES: e^T P^-1 e with the filter's own covariance after the "
                "last update; a consistent filter has 2 per landmark, 3 for the pose):\n%s",
                beyond.text().c_str());
  }

  // ---- results.json ----
  const fs::path dir(args.out);
  fs::create_directories(dir);
  nlohmann::json setup = {
      {"experiment", "Thrun et al. 2002 (WAFR), section 4: EKF vs SEIF with exact mean vs constant-time SEIF"},
      {"runs", total},
      {"runs_ok", n_runs},
      {"seed", args.seed},
      {"seeds", "run r uses simulator seed " + std::to_string(args.seed) + " + r"},
      {"jobs", jobs},
      {"world", "paper"},
      {"landmarks", world.landmarks},
      {"steps", world.steps},
      {"filter_steps", runs.front().steps},
      {"noise", toJson(world.noise)},
      {"noise_variances", {{"v", world.noise.sigma_v * world.noise.sigma_v},
                           {"w", world.noise.sigma_w * world.noise.sigma_w},
                           {"range", world.noise.sigma_range * world.noise.sigma_range},
                           {"bearing", world.noise.sigma_bearing * world.noise.sigma_bearing}}},
      {"filter_noise", "the world's true noise"},
      {"sensor_range", world.sensor_range},
      {"dt", world.dt},
      {"speed", world.speed},
      {"path", args.path},
      {"path_description",
       options.path == PaperPath::Lissajous
           ? "3:2 Lissajous curve x = 0.5 + 0.4 sin 3u, y = 0.5 + 0.4 sin 2u in the unit square (docs/simulator.md)"
           : "closed lawnmower loop: 6 lanes 0.1 from the border, corners of radius 0.04, return leg along "
             "the bottom (docs/simulator.md)"},
      {"data_association", "known"},
      {"start", "every filter starts at the true start pose with initial pose sigma 1e-3"},
      {"theta_x", options.active},
      {"K", options.relax},
      {"theta_y", "not bounded separately (bounding the active set bounds the links per landmark)"},
      {"deactivate", "weakest normalised link to the robot (the paper's rule)"},
      {"mean_rules",
       {{"ekf", "EKF mean (dense covariance)"},
        {"seif_exact", "exact mean: sparse Cholesky solve of H mu = b after every measurement update"},
        {"seif", "amortised coordinate descent (paper eq. 42): robot and active landmarks jointly, "
                 "and K random landmarks per step, relaxed " +
                     std::string(specs[2].seif.recovery == SeifOptions::Recovery::BeforeMeasurement
                                     ? "before the measurement update (the book's order)"
                                     : "after the measurement update")}}},
      {"error_definition", kErrorDefinition},
      {"error_unit", "m^2"},
      {"rms_definition", "sqrt of a run's final error [m], averaged over runs"},
      {"links_definition", "non-zero off-diagonal blocks of the information matrix after the last update"},
      {"time_definition", kTimeDefinition},
      {"time_unit", "microseconds"},
      {"sweep_active", args.sweep_active},
      {"paper", {{"ekf", {{"error_mean", 5.54e-3}, {"error_ci95", 0.67e-3}, {"links", 1275}}},
                 {"seif_exact", {{"error_mean", 4.75e-3}, {"error_ci95", 0.67e-3}, {"links_mean", 549}, {"links_ci95", 1.60}}},
                 {"seif", {{"error_mean", 6.35e-3}, {"error_ci95", 0.67e-3}, {"links_mean", 549}, {"links_ci95", 1.59}}}}},
  };
  nlohmann::json filters = nlohmann::json::array();
  for (std::size_t f = 0; f < sums.size(); ++f) {
    const PaperFilterSummary& s = sums[f];
    const PaperFilterSpec& spec = specs[f];
    nlohmann::json per_run = nlohmann::json::array();
    for (std::size_t r = 0; r < s.mse.size(); ++r) {
      per_run.push_back({{"seed", s.seeds[r]},
                         {"error", s.mse[r]},
                         {"rms", s.rmse[r]},
                         {"aligned_error", s.aligned_mse[r]},
                         {"links", s.links[r]},
                         {"mapped", s.mapped[r]},
                         {"pose_error", s.pose_error[r]},
                         {"landmark_nees", s.landmark_nees[r]},
                         {"pose_nees", s.pose_nees[r]}});
    }
    nlohmann::json j = {
        {"name", s.name},
        {"runs", s.error.n},
        {"error_mean", s.error.mean},
        {"error_ci95", s.error.ci95},
        {"error_sd", s.error.sd},
        {"error_median", s.error.median},
        {"error_max", s.error.max},
        {"error_ratio_to_ekf", s.ratio},
        {"error_ratio_to_ekf_ci95", s.ratio_ci95},
        {"error_ratio_to_ekf_median_per_run", s.ratio_median},
        {"error_diff_to_ekf_mean", s.diff.mean},
        {"error_diff_to_ekf_ci95", s.diff.ci95},
        {"rms_mean", s.rms.mean},
        {"rms_ci95", s.rms.ci95},
        {"aligned_error_mean", s.aligned_error.mean},
        {"aligned_error_ci95", s.aligned_error.ci95},
        {"aligned_error_ratio_to_ekf", s.aligned_ratio},
        {"links_mean", s.link.mean},
        {"links_ci95", s.link.ci95},
        {"links_min", s.link.min},
        {"links_max", s.link.max},
        {"mapped_mean", s.map.mean},
        {"mapped_min", s.map.min},
        {"pose_error_mean", s.pose.mean},
        {"landmark_nees_mean", s.nees.mean},
        {"landmark_nees_median", s.nees.median},
        {"pose_nees_mean", s.nees_pose.mean},
        {"pose_nees_median", s.nees_pose.median},
        {"us_per_update_median", s.us_median},
        {"us_per_update_mean", s.us_mean},
        {"per_run", per_run},
    };
    if (spec.spec) {
      j["spec"] = spec.spec->text;
    } else if (spec.ekf) {
      j["mean_rule"] = "ekf";
      j["runs_all_landmarks_mapped"] = all_mapped;
      j["runs_links_full_graph"] = ekf_dense;
      if (all_mapped > 0) {
        j["links_when_all_mapped_min"] = ekf_links_all_min;
        j["links_when_all_mapped_max"] = ekf_links_all_max;
      }
    } else {
      j["seif"] = toJson(spec.seif);
      j["seif"].erase("seed");
      j["seif"]["seed"] = "the run's simulator seed";
    }
    if (f < 3) {
      const PaperReference ref = reference(s.name);
      j["label"] = ref.label;
      j["complexity"] = ref.complexity_here;
      j["paper"] = {{"error_mean", ref.error},
                    {"error_ci95", ref.error_ci95},
                    {"error_ratio_to_ekf", ref.error / 5.54e-3},
                    {"links_mean", ref.links},
                    {"links_ci95", ref.links_ci95},
                    {"complexity", ref.complexity_paper}};
    }
    filters.push_back(std::move(j));
  }
  nlohmann::json results_json = {{"setup", setup}, {"filters", filters}};
  if (!args.sweep_active.empty()) results_json["sweep_active"] = sweep_json;
  if (!failed.empty()) results_json["failed_runs"] = failed;
  writeJson((dir / "results.json").string(), results_json);

  // ---- table.md ----
  {
    std::ostringstream md;
    md << "# The paper's experiment (Thrun et al. 2002, §4), reproduced\n\n";
    md << "`seif paper --runs " << total << " --seed " << args.seed << "`: " << n_runs
       << " runs of the paper world (" << args.path << " path, " << world.landmarks << " landmarks, " << world.steps
       << " update cycles, known data association), simulator seeds " << args.seed << ".."
       << args.seed + total - 1 << "; theta_x = " << options.active << ", K = " << options.relax
       << ". The paper's numbers beside ours.\n\n";
    md << table.markdown() << "\n";
    std::string n = notes.str();
    std::string bulleted = "- ";
    for (std::size_t i = 0; i < n.size(); ++i) {  // one note per line -> one bullet
      bulleted += n[i];
      if (n[i] == '\n' && i + 1 < n.size()) bulleted += "- ";
    }
    md << bulleted;
    if (!args.sweep_active.empty()) {
      md << "\n## Constant-time SEIF against theta_x (the journal version's study)\n\n";
      md << "K = " << options.relax << ". The journal version (IJRR 2004, N = 50) reports error / EKF = "
            "1.521 at theta_x = 6 and 1.110 at theta_x = 10, the latter at 1/6 of the EKF's time "
            "per update.\n\n";
      md << sweep.markdown();
    }
    if (!options.extra.empty()) {
      md << "\n## Beyond the paper: reference, consistency and exactly sparse variants\n\n"
            "The same runs. NEES = e^T P^-1 e with the filter's own covariance after the last update "
            "(a consistent filter: 2 per landmark, 3 for the pose); mean and median over runs.\n\n";
      md << beyond.markdown();
    }
    if (!failed.empty()) md << "\n" << failed.size() << " run(s) failed and are left out (results.json: failed_runs).\n";
    writeFileAtomically(dir / "table.md", md.str());
  }

  // ---- figures ----
  // The figures show one typical run, chosen by a rule fixed in advance: the run whose
  // constant-time SEIF has the median final error (the lower median for an even count).
  // It is simulated and filtered again (deterministic) with the filters kept for the data.
  std::vector<std::size_t> order(runs.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return runs[a].filters[2].mse < runs[b].filters[2].mse;
  });
  const PaperRun& typical = runs[order[(order.size() - 1) / 2]];
  PaperOptions figure_options = options;
  figure_options.sweep_active.clear();
  PaperRunDetail detail;
  runPaperExperiment(typical.seed, figure_options, &detail);
  const std::string selection = "the run with the median final error of the constant-time SEIF (seed " +
                                std::to_string(typical.seed) + ")";
  for (std::size_t f = 0; f < 3; ++f) {
    nlohmann::json j = figureData(*detail.filters[f], detail.outputs[f], detail.data, typical.seed, specs[f].name);
    j["selection"] = selection;
    j["final_error"] = typical.filters[f].mse;
    writeJson((dir / "figure_data" / (specs[f].name + ".json")).string(), j);
  }
  std::printf("\nwrote %s/results.json, %s/table.md, %s/figure_data/\n", args.out.c_str(),
              args.out.c_str(), args.out.c_str());
  std::printf("figure data: %s\n", selection.c_str());
  if (!args.no_figures) {
    if (renderFigure("paper.py", {dir.string()})) {
      std::printf("figures: %s/fig1_ekf.png, fig2_seif.png, fig6_compare.png%s\n", args.out.c_str(),
                  args.sweep_active.empty() ? "" : ", sweep_active.png");
    }
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
      "scripts/figures/paper.py with /usr/bin/python3 and matplotlib.");
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
      ->transform(integerIn(1, kMaxLocalLandmarks - 1));
  cmd->add_option("--path", args->path,
                  "the robot's path: lawnmower (a survey of the square, 1.75 laps) or lissajous (a\n"
                  "3:2 Lissajous curve crossing itself, 1.6 laps); docs/simulator.md")
      ->check(CLI::IsMember({"lawnmower", "lissajous"}))
      ->capture_default_str();
  cmd->add_flag("--no-figures", args->no_figures, "write the figure data but do not render the figures");
  cmd->callback([args] { paperCommand(*args); });
}

}  // namespace seif::cli
