#include <seif/core/angles.hpp>
#include <seif/core/errors.hpp>
#include <seif/eval/consistency.hpp>
#include "eval/parallel.hpp"
#include <seif/eval/run.hpp>
#include <seif/eval/run_loop.hpp>
#include "core/files.hpp"
#include <seif/io/event_source.hpp>
#include <seif/io/mrclam.hpp>

#include "filters/landmark_book.hpp"
#include "json_fields.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace seif {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr NeesPoint kNoNees{kNaN, kNaN, kNaN, kNaN};

/// Landmark `k` of the state order (landmarkIds()[k]): the filter's own, or `mean`'s.
Vec2 landmarkEstimate(const SlamFilter& filter, const Eigen::VectorXd* mean, std::size_t k) {
  const int slot = static_cast<int>(k);
  return mean ? Vec2(mean->segment<2>(StateLayout::landmark(slot))) : filter.landmark(filter.landmarkIds()[k]);
}

/// e^T P^-1 e, NaN when P is not positive definite (a filter that lost its covariance).
template <int N>
double nees(const Eigen::Matrix<double, N, 1>& e, const Eigen::Matrix<double, N, N>& P) {
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(P);
  if (llt.info() != Eigen::Success) return kNaN;
  return e.dot(llt.solve(e));
}

/// What one estimate of one filter gave in one run.
struct EstimateRun {
  std::vector<NeesPoint> nees;  // per sample
  double mse = kNaN, mse_aligned = kNaN, rmse = kNaN, rmse_aligned = kNaN;
};

/// What one filter gave in one run: its own estimate and, when asked for and different, its
/// posterior's mean (ConsistencyOptions::posterior_mean).
struct FilterRun {
  EstimateRun own;
  std::optional<EstimateRun> posterior;
  double seconds = 0.0;
  std::optional<std::string> failure;  // the NumericError it stopped with; its figures NaN
};

std::vector<std::size_t> sampleSteps(std::size_t steps, int samples) {
  std::vector<std::size_t> at;
  const std::size_t n = std::min<std::size_t>(static_cast<std::size_t>(samples), steps);
  for (std::size_t i = 1; i <= n; ++i) at.push_back((i * steps) / n);  // ends at `steps`
  at.erase(std::unique(at.begin(), at.end()), at.end());
  return at;
}

/// Measures the NEES after each sample step: during the run for a filter, after finish()
/// (the last sample) for a smoother, whose estimates before it are only its initial guess.
class NeesSampler : public RunObserver {
 public:
  NeesSampler(const Dataset& data, const std::vector<std::size_t>& samples, bool posterior, FilterRun& out)
      : data_(data), samples_(samples), posterior_(posterior), out_(out) {}
  void afterUpdate(const SlamFilter& filter, const Step& step, std::size_t k, double seconds) override {
    out_.seconds += seconds;
    if (next_ >= samples_.size() || samples_[next_] != k + 1) return;
    if (k + 1 == data_.steps.size()) return;  // the last sample: after finish()
    if (!filter.smoother()) measure(filter, step.time);
    ++next_;
  }
  void onFinish(const SlamFilter& filter, double seconds) override {
    out_.seconds += seconds;
    if (next_ < samples_.size() && samples_[next_] == data_.steps.size()) measure(filter, data_.steps.back().time);
  }

 private:
  void measure(const SlamFilter& filter, double time) {
    const Pose2 truth = interpolatePose(data_.groundtruth, time);
    out_.own.nees[next_] = measureNees(filter, truth, data_.landmarks);
    if (!posterior_) return;
    if (const std::optional<Eigen::VectorXd> mean = filter.posteriorMean()) {
      if (!out_.posterior) out_.posterior = EstimateRun{std::vector<NeesPoint>(samples_.size(), kNoNees)};
      out_.posterior->nees[next_] = measureNees(filter, truth, data_.landmarks, &*mean);
    }
  }
  const Dataset& data_;
  const std::vector<std::size_t>& samples_;
  const bool posterior_;
  FilterRun& out_;
  std::size_t next_ = 0;
};

/// The final landmark errors of `out`'s estimate: the filter's own, or `mean` (state order).
void measureErrors(const SlamFilter& filter, const std::map<int, Vec2>& truth, const Eigen::VectorXd* mean,
                   EstimateRun& out) {
  std::vector<Vec2> est, ref;
  const std::vector<int>& ids = filter.landmarkIds();
  for (std::size_t k = 0; k < ids.size(); ++k) {
    if (const auto it = truth.find(ids[k]); it != truth.end()) {
      est.push_back(landmarkEstimate(filter, mean, k));
      ref.push_back(it->second);
    }
  }
  if (est.empty()) return;
  out.rmse = alignedRmse(est, ref, Alignment::None);
  out.rmse_aligned = alignedRmse(est, ref, Alignment::Rigid);
  out.mse = out.rmse * out.rmse;
  out.mse_aligned = out.rmse_aligned * out.rmse_aligned;
}

/// One filter over one run's data; nothing when `stop` stopped it before its last step.
std::optional<FilterRun> runOne(const FilterSpec& spec, const Dataset& data, const FilterConfig& config,
                                const Pose2& start, const std::vector<std::size_t>& samples, std::uint64_t seed,
                                bool posterior, const std::atomic<bool>* stop) {
  FilterSpec s = spec;
  s.seif.seed = seed;  // a SEIF's random relaxation varies with the run like the data
  std::unique_ptr<SlamFilter> filter = makeFilter(s, start, config);
  FilterRun out;
  out.own.nees.assign(samples.size(), kNoNees);
  NeesSampler sampler(data, samples, posterior, out);
  RunLoopOptions loop;
  loop.stop = stop;
  if (runLoop(*filter, data, {&sampler}, loop) < data.steps.size()) return std::nullopt;
  measureErrors(*filter, data.landmarks, nullptr, out.own);
  if (out.posterior) {
    const std::optional<Eigen::VectorXd> mean = filter->posteriorMean();
    if (mean) measureErrors(*filter, data.landmarks, &*mean, *out.posterior);
  }
  return out;
}

/// Mean of the finite values; NaN when there are none.
double finiteMean(const std::vector<double>& xs) {
  double sum = 0.0;
  std::size_t n = 0;
  for (double x : xs) {
    if (std::isfinite(x)) {
      sum += x;
      ++n;
    }
  }
  return n == 0 ? kNaN : sum / static_cast<double>(n);
}

NeesPoint meanPoint(const std::vector<NeesPoint>& points) {
  std::vector<double> a, b, c, d;
  for (const NeesPoint& p : points) {
    a.push_back(p.pose);
    b.push_back(p.landmark);
    c.push_back(p.pose_relative);
    d.push_back(p.landmark_relative);
  }
  return {finiteMean(a), finiteMean(b), finiteMean(c), finiteMean(d)};
}

}  // namespace

NeesPoint measureNees(const SlamFilter& filter, const Pose2& true_pose, const std::map<int, Vec2>& truth,
                      const Eigen::VectorXd* mean) {
  NeesPoint p = kNoNees;
  const std::vector<int>& ids = filter.landmarkIds();
  const Eigen::Index state = StateLayout::size(static_cast<int>(ids.size()));
  if (mean && mean->size() != state) {
    throw InvalidArgument("measureNees: a mean of " + std::to_string(mean->size()) + " values for a state of " +
                          std::to_string(state));
  }
  auto landmark = [&](std::size_t k) { return landmarkEstimate(filter, mean, k); };
  const Pose2 x = mean ? Pose2(mean->head<3>()) : filter.pose();
  Vec3 e = x - true_pose;
  e(2) = wrapAngle(e(2));
  const Mat3 Pxx = filter.poseCovariance();
  p.pose = nees<3>(e, Pxx);

  std::vector<double> global;
  for (std::size_t k = 0; k < ids.size(); ++k) {
    if (const auto it = truth.find(ids[k]); it != truth.end()) {
      global.push_back(nees<2>(landmark(k) - it->second, filter.landmarkCovariance(ids[k])));
    }
  }
  p.landmark = finiteMean(global);

  // The frame of the first landmark mapped (state slot 0): its two covariance columns give
  // every cross-covariance the relative errors need.
  if (ids.size() < 2 || truth.find(ids[0]) == truth.end()) return p;
  const int anchor = ids[0];
  const Vec2 m0 = landmark(0), m0_true = truth.at(anchor);
  const Eigen::Matrix<double, Eigen::Dynamic, 2> c0 = filter.landmarkCovarianceColumns(anchor);
  const Mat2 S00 = c0.middleRows<2>(3);
  // Pose: (p - m0, theta) = A [x; m0] with A = [I2 0 -I2; 0 0 1 0 0].
  Eigen::Matrix<double, 3, 5> A = Eigen::Matrix<double, 3, 5>::Zero();
  A.leftCols<3>().setIdentity();
  A.block<2, 2>(0, 3) = -Mat2::Identity();
  Eigen::Matrix<double, 5, 5> J = Eigen::Matrix<double, 5, 5>::Zero();
  J.topLeftCorner<3, 3>() = Pxx;
  J.block<3, 2>(0, 3) = c0.topRows<3>();
  J.block<2, 3>(3, 0) = c0.topRows<3>().transpose();
  J.bottomRightCorner<2, 2>() = S00;
  Vec3 er;
  er.head<2>() = (x.head<2>() - m0) - (true_pose.head<2>() - m0_true);
  er(2) = e(2);
  p.pose_relative = nees<3>(er, Mat3(A * J * A.transpose()));
  std::vector<double> relative;
  for (std::size_t k = 1; k < ids.size(); ++k) {
    const auto it = truth.find(ids[k]);
    if (it == truth.end()) continue;
    const Eigen::Index i = 3 + 2 * static_cast<Eigen::Index>(k);
    const Mat2 Si0 = c0.middleRows<2>(i);
    const Mat2 P = filter.landmarkCovariance(ids[k]) + S00 - Si0 - Si0.transpose();
    const Vec2 er_i = (landmark(k) - m0) - (it->second - m0_true);
    relative.push_back(nees<2>(er_i, P));
  }
  p.landmark_relative = finiteMean(relative);
  return p;
}

std::vector<ConsistencyDataset> mrclamConsistencyRuns(const std::filesystem::path& folder,
                                                      const std::vector<int>& robots) {
  std::vector<ConsistencyDataset> out;
  for (int robot : robots) {
    if (robot < 1 || robot > 5) throw InvalidArgument("consistency: MRCLAM robot " + std::to_string(robot) + " is not in 1..5");
    if (std::count(robots.begin(), robots.end(), robot) > 1) {  // one run counted twice is not two runs
      throw InvalidArgument("consistency: MRCLAM robot " + std::to_string(robot) + " listed twice");
    }
    DatasetOptions o;
    o.robot = robot;
    const std::unique_ptr<EventSource> source = openDataset(folder, DatasetFormat::Mrclam, o);
    ConsistencyDataset d;
    d.name = folder.filename().string() + " robot " + std::to_string(robot);
    d.data = buildDataset(readMrclam(folder, robot));
    d.config.motion = source->info().motion;
    d.config.sensor = source->info().sensor;
    if (d.data.groundtruth.empty() || d.data.landmarks.empty()) {
      throw DataError(folder.string(), 0, "robot " + std::to_string(robot) + " has no ground truth to measure NEES against");
    }
    out.push_back(std::move(d));
  }
  return out;
}

void checkConsistencyOptions(const ConsistencyOptions& options) {
  const bool real = !options.datasets.empty();
  if (!real && options.runs < 1) throw InvalidArgument("consistency: runs must be >= 1");
  if (options.samples < 1) throw InvalidArgument("consistency: samples must be >= 1");
  if (options.filters.empty()) throw InvalidArgument("consistency: no filter given");
  for (const ConsistencyDataset& d : options.datasets) {  // NEES needs steps and the truth
    if (d.data.steps.empty()) throw InvalidArgument("consistency: dataset '" + d.name + "' holds no step");
    if (d.data.groundtruth.empty() || d.data.landmarks.empty()) {
      throw InvalidArgument("consistency: dataset '" + d.name + "' has no ground truth to measure NEES against");
    }
    if (!d.config.motion || !d.config.sensor) {
      throw InvalidArgument("consistency: dataset '" + d.name + "' has no motion or sensor model in its config");
    }
  }
  if (!real && options.world.seed > std::numeric_limits<std::uint64_t>::max() - static_cast<std::uint64_t>(options.runs - 1)) {
    throw InvalidArgument("consistency: seed + runs - 1 must be at most " +
                          std::to_string(std::numeric_limits<std::uint64_t>::max()) + " (the seeds would wrap)");
  }
}

ConsistencyResult runConsistency(const ConsistencyOptions& options,
                                 const std::function<void(std::size_t, std::size_t)>& progress) {
  checkConsistencyOptions(options);
  const bool real = !options.datasets.empty();
  const std::size_t runs = real ? options.datasets.size() : static_cast<std::size_t>(options.runs);
  const std::size_t nf = options.filters.size();
  std::vector<std::vector<FilterRun>> results(runs);  // [run][filter]
  std::vector<std::size_t> steps_of_run(runs, 0);
  std::vector<char> finished(runs, 0);  // every filter ran the whole run (not stopped)
  const auto runName = [&](std::size_t r) {
    return real ? options.datasets[r].name : "seed " + std::to_string(options.world.seed + r);
  };
  auto runFilters = [&](std::size_t r) {
    WorldConfig world = options.world;
    world.seed = options.world.seed + r;
    const Dataset data = real ? Dataset() : buildDataset(simulate(world));
    const Dataset& run_data = real ? options.datasets[r].data : data;
    const FilterConfig config = real ? options.datasets[r].config : paperFilterConfig(data.noise.value_or(world.noise));
    const Pose2 start = startPose(run_data);
    const std::vector<std::size_t> samples = sampleSteps(run_data.steps.size(), options.samples);
    steps_of_run[r] = run_data.steps.size();
    for (const FilterSpec& spec : options.filters) {
      try {
        if (stopRequested(options.stop)) return;  // left out: results[r] is not read
        std::optional<FilterRun> run =
            runOne(spec, run_data, config, start, samples, world.seed, options.posterior_mean, options.stop);
        if (!run) return;
        results[r].push_back(std::move(*run));
      } catch (const Error& e) {
        // A step failed (the run loop's NumericError or ModelError: the filter diverged, or
        // its estimate put a landmark where no sighting can be predicted): this run's
        // figures are NaN, the study goes on. Anything else stops the study.
        const bool step_failed = dynamic_cast<const NumericError*>(&e) != nullptr ||
                                 dynamic_cast<const ModelError*>(&e) != nullptr;
        if (!step_failed) throw NumericError("consistency: " + runName(r) + ", filter " + spec.text + ": " + e.what());
        FilterRun failed;  // summarise() reads a stopped run as NaN throughout
        failed.failure = e.what();
        results[r].push_back(std::move(failed));
      } catch (const std::exception& e) {
        throw NumericError("consistency: " + runName(r) + ", filter " + spec.text + ": " + e.what());
      }
    }
    finished[r] = 1;
  };
  parallelFor(runs, options.threads, runFilters, progress, options.stop);  // stopped: the runs not started are left out

  std::vector<std::size_t> kept;  // the runs summarised
  for (std::size_t r = 0; r < runs; ++r) {
    if (finished[r]) kept.push_back(r);
  }
  if (kept.empty()) throw Interrupted("consistency: stopped before any run finished");

  ConsistencyResult result;
  result.runs = static_cast<int>(kept.size());
  result.runs_requested = static_cast<int>(runs);
  result.interrupted = kept.size() < runs;
  for (const std::size_t r : kept) result.run_names.push_back(runName(r));
  result.steps = steps_of_run[kept.front()];
  for (const std::size_t r : kept) {  // real runs: sampled at the same fractions
    if (real) break;
    if (steps_of_run[r] != result.steps) {
      throw NumericError("consistency: runs differ in their number of steps (" + std::to_string(result.steps) +
                         " and " + std::to_string(steps_of_run[r]) + ")");
    }
  }
  result.sample_steps = sampleSteps(result.steps, options.samples);
  result.pose_band = neesBand95(kept.size(), 3);
  result.landmark_band = neesBand95(kept.size(), 2);
  // One row per filter and estimate: its own, then its posterior mean's where measured
  // (every run of a filter has one or none: it depends on the spec alone).
  auto summarise = [&](std::size_t f, bool posterior) {
    ConsistencyFilterResult fr;
    fr.name = options.filters[f].text + (posterior ? " [posterior mean]" : "");
    fr.spec = f;
    fr.posterior_mean = posterior;
    // A stopped run measured nothing: NaN throughout (finiteMean() leaves it out).
    const EstimateRun stopped{std::vector<NeesPoint>(result.sample_steps.size(), kNoNees)};
    auto estimate = [&](std::size_t r) -> const EstimateRun& {
      if (results[r][f].failure) return stopped;
      return posterior ? *results[r][f].posterior : results[r][f].own;
    };
    for (std::size_t s = 0; s < result.sample_steps.size(); ++s) {
      std::vector<NeesPoint> at;
      for (const std::size_t r : kept) at.push_back(estimate(r).nees[s]);
      fr.nees.push_back(meanPoint(at));
    }
    fr.nees_final = fr.nees.back();
    std::vector<double> mse, mse_aligned, rmse, rmse_aligned;
    for (const std::size_t r : kept) {
      const EstimateRun& run = estimate(r);
      fr.landmark_nees_runs.push_back(run.nees.back().landmark);
      mse.push_back(run.mse);
      mse_aligned.push_back(run.mse_aligned);
      rmse.push_back(run.rmse);
      rmse_aligned.push_back(run.rmse_aligned);
      fr.seconds += results[r][f].seconds;
      if (results[r][f].failure) fr.failed_runs.push_back({runName(r), *results[r][f].failure});
    }
    fr.mse_final = finiteMean(mse);
    fr.mse_aligned_final = finiteMean(mse_aligned);
    fr.mse_runs = mse;
    fr.mse_aligned_runs = mse_aligned;
    fr.error_final = finiteMean(rmse);
    fr.error_aligned_final = finiteMean(rmse_aligned);
    result.filters.push_back(std::move(fr));
  };
  for (std::size_t f = 0; f < nf; ++f) {
    summarise(f, false);
    // Whether it has a posterior-mean row: from its runs that completed (it depends on the
    // spec alone).
    std::optional<bool> posterior;
    for (const std::size_t r : kept) {
      if (results[r][f].failure) continue;
      if (!posterior) posterior = results[r][f].posterior.has_value();
      if (results[r][f].posterior.has_value() != *posterior) {
        throw NumericError("consistency: filter " + options.filters[f].text +
                           " gave a posterior mean in some runs and not in others");
      }
    }
    if (posterior.value_or(false)) summarise(f, true);
  }
  return result;
}

const ConsistencyFilterResult* batchReference(const ConsistencyResult& result) {
  for (const ConsistencyFilterResult& f : result.filters) {
    if (f.name == "batch" || f.name.rfind("batch:", 0) == 0) return &f;
  }
  return nullptr;
}

namespace {

nlohmann::json finiteArray(const std::vector<double>& xs) {
  nlohmann::json a = nlohmann::json::array();
  for (double x : xs) a.push_back(finiteOrNull(x));
  return a;
}

nlohmann::json ratioJson(const std::vector<double>& x, const std::vector<double>* y) {
  if (!y) return nullptr;
  const PairedRatio r = pairedRatio(x, *y);
  return {{"ratio", finiteOrNull(r.ratio)}, {"ci95", finiteOrNull(r.ci95)}, {"pairs", r.pairs}};
}

/// The runs named in one line: consecutive seeds as a range ("seeds 1..1274, seed 1276"),
/// other names as they are; past ten groups, how many more.
std::string runList(const std::vector<std::string>& names) {
  std::vector<std::string> groups;
  const auto seedOf = [](const std::string& name) -> std::optional<std::uint64_t> {
    if (name.rfind("seed ", 0) != 0) return std::nullopt;
    return std::stoull(name.substr(5));
  };
  for (std::size_t i = 0; i < names.size();) {
    const std::optional<std::uint64_t> first = seedOf(names[i]);
    std::size_t j = i + 1;
    while (first && j < names.size() && seedOf(names[j]) == *first + (j - i)) ++j;
    groups.push_back(j - i > 1 ? "seeds " + std::to_string(*first) + ".." + std::to_string(*first + (j - i - 1))
                               : names[i]);
    i = j;
  }
  constexpr std::size_t kShown = 10;
  std::string out;
  for (std::size_t g = 0; g < std::min(groups.size(), kShown); ++g) out += (g == 0 ? "" : ", ") + groups[g];
  if (groups.size() > kShown) out += " and " + std::to_string(groups.size() - kShown) + " more";
  return out;
}

}  // namespace

std::string consistencyJson(const ConsistencyResult& result, const ConsistencyOptions& options) {
  const ConsistencyFilterResult* reference = batchReference(result);
  nlohmann::json filters = nlohmann::json::array();
  for (std::size_t i = 0; i < result.filters.size(); ++i) {
    const ConsistencyFilterResult& f = result.filters[i];
    nlohmann::json series = {{"pose", nlohmann::json::array()},
                             {"landmark", nlohmann::json::array()},
                             {"pose_relative", nlohmann::json::array()},
                             {"landmark_relative", nlohmann::json::array()}};
    nlohmann::json failures = nlohmann::json::array();
    for (const ConsistencyFailure& x : f.failed_runs) failures.push_back({{"run", x.run}, {"error", x.error}});
    for (const NeesPoint& p : f.nees) {
      series["pose"].push_back(finiteOrNull(p.pose));
      series["landmark"].push_back(finiteOrNull(p.landmark));
      series["pose_relative"].push_back(finiteOrNull(p.pose_relative));
      series["landmark_relative"].push_back(finiteOrNull(p.landmark_relative));
    }
    filters.push_back({{"name", f.name},
                       // the SEIF's seed is each run's simulator seed
                       {"filter_spec", f.spec < options.filters.size() ? canonicalFilterSpec(options.filters[f.spec]) : f.name},
                       {"estimate", f.posterior_mean ? "posterior_mean" : "own"},
                       {"pose_nees_final", finiteOrNull(f.nees_final.pose)},
                       {"landmark_nees_final", finiteOrNull(f.nees_final.landmark)},
                       {"pose_nees_relative_final", finiteOrNull(f.nees_final.pose_relative)},
                       {"landmark_nees_relative_final", finiteOrNull(f.nees_final.landmark_relative)},
                       {"error_final", finiteOrNull(f.error_final)},
                       {"error_aligned_final", finiteOrNull(f.error_aligned_final)},
                       {"mse_final", finiteOrNull(f.mse_final)},
                       {"mse_aligned_final", finiteOrNull(f.mse_aligned_final)},
                       {"mse_runs", finiteArray(f.mse_runs)},
                       {"mse_aligned_runs", finiteArray(f.mse_aligned_runs)},
                       {"mse_ratio_to_batch", ratioJson(f.mse_runs, reference ? &reference->mse_runs : nullptr)},
                       {"mse_aligned_ratio_to_batch",
                        ratioJson(f.mse_aligned_runs, reference ? &reference->mse_aligned_runs : nullptr)},
                       {"seconds", f.seconds},
                       {"nees", series},
                       {"failed_runs", failures}});
  }
  const WorldConfig& w = options.world;
  nlohmann::json datasets = nlohmann::json::array();
  for (const ConsistencyDataset& d : options.datasets) datasets.push_back(d.name);
  nlohmann::json j = {
      {"runs", result.runs},
      {"runs_requested", result.runs_requested},
      {"interrupted", result.interrupted},
      {"run_names", result.run_names},
      {"steps", result.steps},
      {"world",
       {{"preset", std::string(worldPresetName(w.preset))},
        {"path", w.preset == WorldPreset::Paper ? nlohmann::json(std::string(paperPathName(w.paper_path)))
                                                : nlohmann::json(nullptr)},
        {"landmarks", w.landmarks},
        {"steps", w.steps},
        {"seed_first", w.seed},
        {"seed_last", w.seed + static_cast<std::uint64_t>(result.runs_requested) - 1}}},
      {"band95",
       {{"pose", {result.pose_band.lo, result.pose_band.hi}},
        {"landmark", {result.landmark_band.lo, result.landmark_band.hi}}}},
      {"sample_steps", result.sample_steps},
      {"filters", filters}};
  if (!datasets.empty()) j["datasets"] = datasets;
  return j.dump(2);
}

std::string interruptedText(const ConsistencyResult& result) {
  return "consistency interrupted: " + std::to_string(result.runs) + " of " + std::to_string(result.runs_requested) +
         " runs finished";
}

std::string consistencyCsv(const ConsistencyResult& r) {
  std::ostringstream csv;
  csv.precision(10);
  csv << "filter,step,pose,landmark,pose_relative,landmark_relative\n";
  // What was not measured (no landmark in view, a stopped run) is an empty cell, as
  // nees.json's null.
  const auto cell = [&csv](double v) -> std::ostringstream& {
    csv << ',';
    if (std::isfinite(v)) csv << v;
    return csv;
  };
  for (const ConsistencyFilterResult& f : r.filters) {
    for (std::size_t s = 0; s < r.sample_steps.size(); ++s) {
      const NeesPoint& p = f.nees[s];
      csv << '"' << f.name << "\"," << r.sample_steps[s];
      cell(p.pose);
      cell(p.landmark);
      cell(p.pose_relative);
      cell(p.landmark_relative) << '\n';
    }
  }
  return csv.str();
}

std::string consistencyTable(const ConsistencyResult& result) {
  const ConsistencyFilterResult* reference = batchReference(result);
  std::ostringstream t;
  t << std::fixed;
  t << "| filter | pose NEES | landmark NEES | rel. pose NEES | rel. landmark NEES | landmark RMSE [m] | aligned [m] |";
  if (reference) t << " MSE / batch | aligned MSE / batch |";
  t << "\n|---|---:|---:|---:|---:|---:|---:|" << (reference ? "---:|---:|" : "") << "\n";
  auto cell = [&](double v, int digits) {
    std::ostringstream c;
    if (std::isfinite(v)) {
      c << std::fixed << std::setprecision(digits) << v;
    } else {
      c << "-";
    }
    return c.str();
  };
  for (const ConsistencyFilterResult& f : result.filters) {
    t << "| " << f.name << " | " << cell(f.nees_final.pose, 2) << " | " << cell(f.nees_final.landmark, 2) << " | "
      << cell(f.nees_final.pose_relative, 2) << " | " << cell(f.nees_final.landmark_relative, 2) << " | "
      << cell(f.error_final, 4) << " | " << cell(f.error_aligned_final, 4) << " |";
    if (reference) {
      // The ratio of the means over the runs both completed, and its 95 % half-width (none
      // on the reference's own row).
      auto ratio = [&](const std::vector<double>& x, const std::vector<double>& y) {
        const PairedRatio r = pairedRatio(x, y);
        const bool interval = &f != reference && r.pairs >= 2 && std::isfinite(r.ratio);
        return cell(r.ratio, 2) + (interval ? " ± " + cell(r.ci95, 2) : "");
      };
      t << " " << ratio(f.mse_runs, reference->mse_runs) << " | "
        << ratio(f.mse_aligned_runs, reference->mse_aligned_runs) << " |";
    }
    t << "\n";
  }
  if (result.interrupted) {
    t << "\nInterrupted: " << result.runs << " of " << result.runs_requested
      << " runs finished; the figures are theirs (" << runList(result.run_names) << ").\n";
  }
  t << "\nNEES: mean over " << result.runs << " runs after step " << result.steps << "; 95 % band for "
    << result.runs << " runs: pose [" << cell(result.pose_band.lo, 2) << ", " << cell(result.pose_band.hi, 2)
    << "] (3 dof), landmark [" << cell(result.landmark_band.lo, 2) << ", " << cell(result.landmark_band.hi, 2)
    << "] (2 dof, each landmark's NEES averaged over the map first).\n";
  if (reference) {
    t << "MSE / batch: the ratio of the mean squared landmark errors over the runs both completed, ± the half-width "
         "of its 95 % interval (delta method over the paired runs).\n";
  }
  for (const ConsistencyFilterResult& f : result.filters) {
    if (f.failed_runs.empty() || f.posterior_mean) continue;
    t << "\n" << f.name << " stopped in " << f.failed_runs.size() << " of " << result.runs << " runs"
      << (f.failed_runs.size() < static_cast<std::size_t>(result.runs) ? "; its figures are those of the others:\n"
                                                                       : ":\n");
    for (const ConsistencyFailure& x : f.failed_runs) t << "- " << x.run << ": " << x.error << "\n";
  }
  if (std::any_of(result.filters.begin(), result.filters.end(), [](const auto& f) { return f.posterior_mean; })) {
    t << "[posterior mean]: the filter's own covariances with the mean H^-1 b of its information in place of its "
         "own (amortised) mean.\n";
  }
  return t.str();
}

void writeConsistencyResults(const ConsistencyResult& result, const ConsistencyOptions& options,
                             const std::filesystem::path& dir) {
  writeFileAtomically(dir / "nees.json", consistencyJson(result, options) + "\n");
  writeFileAtomically(dir / "nees.csv", consistencyCsv(result));
  writeFileAtomically(dir / "table.md", consistencyTable(result));
}

}  // namespace seif
