#include "filters/seif_slam.hpp"
#include <seif/eval/paper.hpp>
#include <seif/eval/stats.hpp>
#include <seif/eval/consistency.hpp>

#include <seif/core/errors.hpp>
#include "filters/ekf_slam.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace seif {

std::vector<PaperFilterSpec> paperFilters(const PaperOptions& options) {
  std::vector<PaperFilterSpec> specs;
  PaperFilterSpec ekf;
  ekf.name = "ekf";
  ekf.ekf = true;
  specs.push_back(ekf);

  SeifOptions seif;
  seif.active = options.active;
  seif.relax = options.relax;
  seif.deactivate = SeifOptions::Deactivate::Weakest;  // the paper's rule
  seif.relax_order = SeifOptions::RelaxOrder::Random;  // the paper: K random landmarks

  PaperFilterSpec exact;
  exact.name = "seif_exact";
  exact.seif = seif;
  exact.seif.mean = SeifOptions::Mean::Exact;
  specs.push_back(exact);

  PaperFilterSpec amortized;
  amortized.name = "seif";
  amortized.seif = seif;
  amortized.seif.mean = SeifOptions::Mean::Amortized;
  specs.push_back(amortized);

  for (int active : options.sweep_active) {
    PaperFilterSpec s = amortized;
    s.name = "seif_active_" + std::to_string(active);
    s.seif.active = active;
    specs.push_back(s);
  }
  for (const std::string& text : options.extra) {
    PaperFilterSpec s;
    s.name = text;
    s.spec = parseFilterSpec(text);
    specs.push_back(s);
  }
  return specs;
}

WorldConfig paperWorld(std::uint64_t seed, const PaperOptions& options) {
  WorldConfig world = presetConfig(WorldPreset::Paper, options.landmarks, options.steps, seed);
  world.paper_path = options.path;
  return world;
}

double landmarkMse(const SlamFilter& filter, const std::map<int, Vec2>& truth, std::size_t* count) {
  double sum = 0.0;
  std::size_t n = 0;
  for (int id : filter.landmarkIds()) {
    const auto it = truth.find(id);
    if (it == truth.end()) continue;
    sum += (filter.landmark(id) - it->second).squaredNorm();
    ++n;
  }
  if (count) *count = n;
  return n == 0 ? std::numeric_limits<double>::quiet_NaN() : sum / static_cast<double>(n);
}

PaperRun runPaperExperiment(std::uint64_t seed, const PaperOptions& options,
                            PaperRunDetail* detail) {
  PaperRun run;
  run.seed = seed;
  const WorldConfig world = paperWorld(seed, options);
  const RobotLog log = simulate(world, &run.sim);
  Dataset data = buildDataset(log);
  run.steps = data.steps.size();

  const FilterConfig config = paperFilterConfig(data.noise.value_or(world.noise));
  const Pose2 start = startPose(data);
  const Pose2 true_end = data.groundtruth.empty()
                             ? Pose2::Zero()
                             : interpolatePose(data.groundtruth, data.steps.empty()
                                                                     ? data.start_time
                                                                     : data.steps.back().time);

  for (const PaperFilterSpec& spec : paperFilters(options)) {
    std::unique_ptr<SlamFilter> filter;
    if (spec.spec) {
      FilterSpec fs = *spec.spec;
      fs.seif.seed = seed;
      filter = makeFilter(fs, start, config);
    } else if (spec.ekf) {
      filter = std::make_unique<EkfSlam>(start, config);
    } else {
      SeifOptions o = spec.seif;
      o.seed = seed;
      filter = std::make_unique<SeifSlam>(start, config, o);
    }
    RunOutput out;
    try {
      out = runFilter(*filter, data);
    } catch (const std::exception& e) {
      throw NumericError("paper run with seed " + std::to_string(seed) + ", filter " + spec.name +
                         ": " + e.what());
    }
    PaperFilterResult r;
    r.name = spec.name;
    r.mse = landmarkMse(*filter, data.landmarks, &r.mapped);
    r.rmse = std::sqrt(r.mse);
    const std::optional<double> shape = landmarkRmse(*filter, data.landmarks, Alignment::Rigid);
    r.aligned_mse = shape ? *shape * *shape : std::numeric_limits<double>::quiet_NaN();
    r.pose_error = (filter->pose().head<2>() - true_end.head<2>()).norm();
    r.stats = out.final_stats;
    const NeesPoint nees = measureNees(*filter, true_end, data.landmarks);
    r.landmark_nees = nees.landmark;
    r.pose_nees = nees.pose;
    r.step_seconds = out.step_seconds;
    run.filters.push_back(std::move(r));
    if (detail) {
      detail->filters.push_back(std::move(filter));
      detail->outputs.push_back(std::move(out));
    }
  }
  if (detail) detail->data = std::move(data);
  return run;
}

FilterSnapshot snapshotById(const SlamFilter& filter) {
  FilterSnapshot s;
  const std::vector<int>& state_ids = filter.landmarkIds();  // state order
  const Eigen::Index n_lm = static_cast<Eigen::Index>(state_ids.size());
  const Eigen::Index dim = 3 + 2 * n_lm;
  // perm[k] = state index of the k-th entry in id order.
  std::vector<Eigen::Index> slots(static_cast<std::size_t>(n_lm));
  for (Eigen::Index i = 0; i < n_lm; ++i) slots[static_cast<std::size_t>(i)] = i;
  std::sort(slots.begin(), slots.end(), [&](Eigen::Index a, Eigen::Index b) {
    return state_ids[static_cast<std::size_t>(a)] < state_ids[static_cast<std::size_t>(b)];
  });
  std::vector<Eigen::Index> perm(static_cast<std::size_t>(dim));
  for (Eigen::Index k = 0; k < 3; ++k) perm[static_cast<std::size_t>(k)] = k;
  for (Eigen::Index k = 0; k < n_lm; ++k) {
    const Eigen::Index slot = slots[static_cast<std::size_t>(k)];
    s.ids.push_back(state_ids[static_cast<std::size_t>(slot)]);
    perm[static_cast<std::size_t>(3 + 2 * k)] = 3 + 2 * slot;
    perm[static_cast<std::size_t>(4 + 2 * k)] = 4 + 2 * slot;
  }
  const Eigen::VectorXd mu = filter.mean();
  const Eigen::MatrixXd P = filter.covariance();
  const Eigen::MatrixXd H = filter.information();
  if (mu.size() != dim || P.rows() != dim || H.rows() != dim) {
    throw InvalidArgument("snapshotById: the filter's state size disagrees with its landmarks");
  }
  s.mean.resize(dim);
  s.covariance.resize(dim, dim);
  s.information.resize(dim, dim);
  for (Eigen::Index r = 0; r < dim; ++r) {
    const Eigen::Index pr = perm[static_cast<std::size_t>(r)];
    s.mean(r) = mu(pr);
    for (Eigen::Index c = 0; c < dim; ++c) {
      const Eigen::Index pc = perm[static_cast<std::size_t>(c)];
      s.covariance(r, c) = P(pr, pc);
      s.information(r, c) = H(pr, pc);
    }
  }
  // Links: non-zero off-diagonal blocks, variable 0 = robot, v >= 1 = landmark ids[v - 1].
  auto offset = [](Eigen::Index v) { return v == 0 ? Eigen::Index{0} : 3 + 2 * (v - 1); };
  auto size = [](Eigen::Index v) { return v == 0 ? Eigen::Index{3} : Eigen::Index{2}; };
  const Eigen::VectorXd d = s.information.diagonal().cwiseAbs().cwiseSqrt();
  for (Eigen::Index i = 0; i <= n_lm; ++i) {
    for (Eigen::Index j = i + 1; j <= n_lm; ++j) {
      const auto block = s.information.block(offset(i), offset(j), size(i), size(j));
      if (!(block.cwiseAbs().maxCoeff() > 0.0)) continue;
      double strength = 0.0;
      for (Eigen::Index r = 0; r < block.rows(); ++r) {
        for (Eigen::Index c = 0; c < block.cols(); ++c) {
          const double denom = d(offset(i) + r) * d(offset(j) + c);
          if (denom > 0.0) strength = std::max(strength, std::fabs(block(r, c)) / denom);
        }
      }
      FilterSnapshot::Link link;
      link.a = i == 0 ? -1 : s.ids[static_cast<std::size_t>(i - 1)];
      link.b = s.ids[static_cast<std::size_t>(j - 1)];
      link.strength = strength;
      s.links.push_back(link);
    }
  }
  return s;
}

PaperFilterSummary summarizePaperFilter(std::size_t f, const std::vector<PaperRun>& runs) {
  if (runs.empty()) throw InvalidArgument("summarizePaperFilter: no runs to summarise");
  for (const PaperRun& run : runs) {
    if (f >= run.filters.size()) {
      throw InvalidArgument("summarizePaperFilter: filter " + std::to_string(f) + " of runs with " +
                            std::to_string(run.filters.size()) + " filters (run of seed " + std::to_string(run.seed) + ")");
    }
  }
  PaperFilterSummary s;
  s.name = runs.front().filters[f].name;
  std::vector<double> us;
  for (const PaperRun& run : runs) {
    const PaperFilterResult& r = run.filters[f];
    s.seeds.push_back(run.seed);
    s.mse.push_back(r.mse);
    s.rmse.push_back(r.rmse);
    s.aligned_mse.push_back(r.aligned_mse);
    s.links.push_back(static_cast<double>(r.stats.links));
    s.mapped.push_back(static_cast<double>(r.mapped));
    s.robot_links.push_back(static_cast<double>(r.stats.robot_links));
    s.pose_error.push_back(r.pose_error);
    s.landmark_nees.push_back(r.landmark_nees);
    s.pose_nees.push_back(r.pose_nees);
    s.diff_to_ekf.push_back(r.mse - run.filters[0].mse);
    for (double t : r.step_seconds) us.push_back(1e6 * t);
  }
  s.error = summarize(s.mse);
  s.rms = summarize(s.rmse);
  s.aligned_error = summarize(s.aligned_mse);
  s.link = summarize(s.links);
  s.map = summarize(s.mapped);
  s.diff = summarize(s.diff_to_ekf);
  s.pose = summarize(s.pose_error);
  s.nees = summarize(s.landmark_nees);
  s.nees_pose = summarize(s.pose_nees);
  std::vector<double> ekf_mse, ratios;
  for (const PaperRun& run : runs) ekf_mse.push_back(run.filters[0].mse);
  const PairedRatio to_ekf = pairedRatio(s.mse, ekf_mse);
  s.ratio = to_ekf.ratio;
  s.ratio_ci95 = to_ekf.ci95;
  for (std::size_t r = 0; r < runs.size(); ++r) ratios.push_back(s.mse[r] / ekf_mse[r]);
  s.ratio_median = median(std::move(ratios));
  std::vector<double> ekf_aligned;
  for (const PaperRun& run : runs) ekf_aligned.push_back(run.filters[0].aligned_mse);
  s.aligned_ratio = pairedRatio(s.aligned_mse, ekf_aligned).ratio;
  s.us_mean = sampleMean(us);
  s.us_median = median(std::move(us));
  return s;
}


}  // namespace seif
