#include <seif/core/errors.hpp>
#include <seif/eval/run.hpp>
#include <seif/eval/run_loop.hpp>

#include "eval/parallel.hpp"
#include "run_checkpoint.hpp"
#include <seif/models/odometry_model.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

namespace seif {

Pose2 startPose(const Dataset& data) {
  if (data.groundtruth.empty()) return Pose2::Zero();
  return interpolatePose(data.groundtruth, data.start_time);
}

namespace {

/// Records a run into RunOutput: the trajectory (the start pose, then the pose after each
/// step, checked finite), step times, the largest link counts, and at the end a smoother's
/// smoothed trajectory and the filter's final statistics.
class OutputRecorder : public RunObserver {
 public:
  /// `resumed`: `out` already holds the run up to the start (a checkpoint's).
  explicit OutputRecorder(RunOutput& out, bool resumed = false) : out_(out), resumed_(resumed) {}
  void onStart(const SlamFilter& filter, double time) override {
    if (!resumed_) out_.trajectory.push_back({time, filter.pose()});
  }
  void afterUpdate(const SlamFilter& filter, const Step& step, std::size_t k, double seconds) override {
    out_.step_seconds.push_back(seconds);
    out_.seconds += seconds;
    const Pose2 x = filter.pose();
    if (!x.allFinite()) {
      std::ostringstream msg;
      msg << filter.name() << ": the pose estimate is not finite after step " << k;
      throw NumericError(msg.str());
    }
    out_.trajectory.push_back({step.time, x});
    out_.max_robot_links = std::max(out_.max_robot_links, filter.robotLinks());
    out_.max_blocks_touched = std::max(out_.max_blocks_touched, filter.blocksTouched());
    ++out_.steps;
  }
  void onFinish(const SlamFilter& filter, double seconds) override {
    out_.seconds += seconds;  // a smoother's solve: part of its time
    // A smoother's trajectory is the smoothed one, known only now.
    const std::vector<Pose2> smoothed = filter.smoothedTrajectory();
    if (!smoothed.empty()) {
      if (smoothed.size() != out_.trajectory.size()) {
        throw NumericError(filter.name() + ": the smoothed trajectory has " + std::to_string(smoothed.size()) +
                           " poses for " + std::to_string(out_.trajectory.size()) + " steps");
      }
      out_.filter_trajectory = out_.trajectory;
      for (std::size_t k = 0; k < smoothed.size(); ++k) out_.trajectory[k].pose = smoothed[k];
      if (!out_.pose_covariances.empty()) out_.pose_covariances = filter.smoothedTrajectoryCovariances();
    }
    out_.final_stats = filter.stats();
    out_.rejected_observations = filter.rejectedObservations();
    out_.max_robot_links = std::max(out_.max_robot_links, out_.final_stats.robot_links);
  }
  void onStop(const SlamFilter&, std::size_t) override { out_.interrupted = true; }
  void onGroundTruth(const TimedPose& pose) override { out_.groundtruth.push_back(pose); }
  void onGps(const GpsFix& fix) override { out_.gps.push_back(fix); }

 private:
  RunOutput& out_;
  bool resumed_;
};

/// The filter's pose covariance at the start and after every step.
class PoseCovarianceRecorder : public RunObserver {
 public:
  PoseCovarianceRecorder(std::vector<Mat3>& covariances, bool resumed) : covariances_(covariances), resumed_(resumed) {}
  void onStart(const SlamFilter& filter, double) override {
    if (!resumed_) covariances_.push_back(filter.poseCovariance());
  }
  void afterUpdate(const SlamFilter& filter, const Step&, std::size_t, double) override {
    covariances_.push_back(filter.poseCovariance());
  }

 private:
  std::vector<Mat3>& covariances_;
  bool resumed_;
};

/// The controls integrated alone from the filter's start pose, at the steps' stamps.
class DeadReckoningRecorder : public RunObserver {
 public:
  DeadReckoningRecorder(const MotionModel& motion, std::vector<TimedPose>& track) : motion_(motion), track_(track) {}
  void onStart(const SlamFilter& filter, double time) override {
    if (!track_.empty()) {  // resumed: the track so far is the checkpoint's
      pose_ = track_.back().pose;
      return;
    }
    pose_ = filter.pose();
    track_.push_back({time, pose_});
  }
  void afterUpdate(const SlamFilter&, const Step& step, std::size_t, double) override {
    pose_ = motion_.apply(pose_, step.u);
    track_.push_back({step.time, pose_});
  }

 private:
  const MotionModel& motion_;
  std::vector<TimedPose>& track_;
  Pose2 pose_ = Pose2::Zero();
};

/// Calls `report` after every `every`-th step and after the step numbered `last`.
class ProgressReporter : public RunObserver {
 public:
  ProgressReporter(std::size_t every, std::size_t last, std::function<void(std::size_t)> report)
      : every_(every), last_(last), report_(std::move(report)) {}
  void afterUpdate(const SlamFilter&, const Step&, std::size_t k, double) override {
    if (k % every_ == 0 || k == last_) report_(k);
  }

 private:
  std::size_t every_, last_;
  std::function<void(std::size_t)> report_;
};

/// After a failure inside a step's observers, some records hold that step and others not:
/// each is cut to the steps every one of them holds.
void keepCompleteSteps(RunOutput& out, bool pose_covariances) {
  std::size_t poses = std::min(out.trajectory.size(), out.dead_reckoning.size());
  if (pose_covariances) poses = std::min(poses, out.pose_covariances.size());
  out.steps = poses == 0 ? 0 : std::min(out.steps, poses - 1);
  out.trajectory.resize(std::min(out.trajectory.size(), out.steps + 1));
  out.dead_reckoning.resize(std::min(out.dead_reckoning.size(), out.steps + 1));
  if (pose_covariances) out.pose_covariances.resize(std::min(out.pose_covariances.size(), out.steps + 1));
  out.step_seconds.resize(std::min(out.step_seconds.size(), out.steps));
  // The failed step's observations went to no update; its merges stay (they are in the filter).
  const auto first_failed = std::find_if(out.associations.begin(), out.associations.end(),
                                         [&](const AssociationRecord& r) { return r.step >= out.steps; });
  out.associations.erase(first_failed, out.associations.end());
  out.seconds = 0.0;
  for (double t : out.step_seconds) out.seconds += t;
}

}  // namespace

RunOutput runFilter(SlamFilter& filter, const Dataset& data,
                    const std::function<void(std::size_t, std::size_t)>& progress) {
  RunOutput out;
  const std::size_t total = data.steps.size();
  out.trajectory.reserve(total + 1);
  out.step_seconds.reserve(total);
  OutputRecorder recorder(out);
  ProgressReporter reporter(std::max<std::size_t>(1, total / 100), total - 1,
                            [&](std::size_t k) { progress(k + 1, total); });
  std::vector<RunObserver*> observers = {&recorder};
  if (progress) observers.push_back(&reporter);
  runLoop(filter, data, observers);
  return out;
}

RunOutput runFilter(SlamFilter& filter, EventSource& source, const std::function<void(double)>& progress,
                    bool pose_covariances, const RunCheckpointing& checkpointing, const RunResume* resume,
                    Associator* associator, const std::atomic<bool>* stop) {
  RunOutput out;
  if (resume) out = resume->output;
  StepAssembler steps;
  OutputRecorder recorder(out, resume != nullptr);
  PoseCovarianceRecorder covariances(out.pose_covariances, resume != nullptr);
  DeadReckoningRecorder dead_reckoning(*source.info().motion, out.dead_reckoning);
  ProgressReporter reporter(1024, SIZE_MAX, [&](std::size_t) { progress(source.progress()); });
  std::vector<RunObserver*> observers = {&recorder};
  if (pose_covariances) observers.push_back(&covariances);
  observers.push_back(&dead_reckoning);
  if (progress) observers.push_back(&reporter);
  if (resume && !resume->associator.empty() && associator == nullptr) {
    throw InvalidArgument("resume: the checkpoint carries an associator; the run needs it "
                          "(Associator::restoreState of RunResume::associator)");
  }
  if (resume && resume->associator.empty() && associator && associator->options().method != AssociationMethod::Known) {
    throw InvalidArgument("resume: the checkpoint was written by a run without association");
  }
  StepDigest digest;
  CheckpointWriter checkpoints(checkpointing, out, associator, &digest);
  if (!checkpointing.path.empty()) observers.push_back(&checkpoints);
  RunLoopOptions options;
  options.stop = stop;
  if (!checkpointing.path.empty() || resume) options.digest = &digest;  // only checkpoints read it
  if (resume) {
    options.start_step = resume->steps;
    options.skipped_digest = resume->steps_digest;
  }
  if (associator) {
    const bool record = associator->options().method != AssociationMethod::Known;
    options.associate = [associator, record, &out](SlamFilter& f, const Step&, std::size_t k, std::vector<Observation>& z) {
      if (!record) {
        associator->associate(f, k, z);
        return;
      }
      // Each observation as offered (the associator hides its id, kept as the truth), then
      // what became of it.
      const std::size_t first = out.associations.size();
      for (std::size_t i = 0; i < z.size(); ++i) {
        const int truth = z[i].truth != kUnknownLandmark ? z[i].truth : z[i].landmark;
        out.associations.push_back({k, i, z[i].z, truth < 0 ? kUnknownLandmark : truth, {}});
      }
      associator->associate(f, k, z);
      for (const LandmarkMerge& m : associator->lastMerges()) out.merges.push_back({k, m});
      const std::span<const ScanDecision> decisions = associator->lastScan();
      for (std::size_t i = 0; i < decisions.size() && first + i < out.associations.size(); ++i) {
        out.associations[first + i].decision = decisions[i];
      }
    };
  }
  std::size_t consumed = options.start_step;  // the stream's steps behind the filter
  try {
    consumed += runLoop(filter, source, steps, observers, options);
  } catch (const Error&) {  // what ran before it is kept (RunOutput::failure)
    out.failure = std::current_exception();
    keepCompleteSteps(out, pose_covariances);
    out.final_stats = filter.stats();
    out.rejected_observations = filter.rejectedObservations();
  }
  if (associator) {
    try {
      // A stopped run leaves its provisional landmarks in the map: their removal can be slow
      // (docs/association.md).
      associator->finish(filter, stop);
    } catch (const Error&) {
      if (!out.failure) throw;  // else the run's own failure is the one reported
    }
    // A stop after the last step, before or during those removals: the run is interrupted
    // there, and its checkpoint (the state the removals stopped in) finishes them when resumed.
    const bool kept = associator->counts().provisional_final > 0 && !filter.smoother();
    if (!out.failure && !out.interrupted && kept && stopRequested(stop)) {
      out.interrupted = true;
      if (!checkpointing.path.empty()) checkpoints.onStop(filter, consumed);
    }
  }
  if (progress) progress(1.0);
  out.dropped = source.dropped();
  if (steps.droppedBeforeFirstControl() > 0) out.dropped["before_first_control"] += steps.droppedBeforeFirstControl();
  return out;
}

std::vector<TimedPose> deadReckoning(const Dataset& data, const Pose2& start, const MotionModel& motion) {
  std::vector<TimedPose> track;
  track.reserve(data.steps.size() + 1);
  Pose2 x = start;
  track.push_back({data.start_time, x});
  for (const Step& step : data.steps) {
    x = motion.apply(x, step.u);
    track.push_back({step.time, x});
  }
  return track;
}

double alignedRmse(const std::vector<Vec2>& estimate, const std::vector<Vec2>& truth,
                   Alignment alignment, std::vector<double>* residuals) {
  const std::size_t n = estimate.size();
  if (n == 0 || n != truth.size()) throw InvalidArgument("alignedRmse: point sets differ in size");
  Eigen::Matrix2d R = Eigen::Matrix2d::Identity();
  Vec2 t = Vec2::Zero();
  if (alignment == Alignment::Rigid && n >= 2) {
    Vec2 ce = Vec2::Zero(), ct = Vec2::Zero();
    for (std::size_t i = 0; i < n; ++i) {
      ce += estimate[i];
      ct += truth[i];
    }
    ce /= static_cast<double>(n);
    ct /= static_cast<double>(n);
    // The rotation angle maximising sum (q_i - ct)^T R (p_i - ce), in closed form in 2-D.
    double sxx = 0.0, sxy = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2 p = estimate[i] - ce, q = truth[i] - ct;
      sxx += p.dot(q);
      sxy += p.x() * q.y() - p.y() * q.x();
    }
    const double angle = std::atan2(sxy, sxx);
    R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
    t = ct - R * ce;
  }
  double sum = 0.0;
  if (residuals) residuals->clear();
  for (std::size_t i = 0; i < n; ++i) {
    const double e2 = (R * estimate[i] + t - truth[i]).squaredNorm();
    sum += e2;
    if (residuals) residuals->push_back(std::sqrt(e2));
  }
  return std::sqrt(sum / static_cast<double>(n));
}

std::optional<double> ateRmse(const std::vector<TimedPose>& estimate,
                              const std::vector<TimedPose>& groundtruth, Alignment alignment) {
  if (groundtruth.empty()) return std::nullopt;
  const double t0 = groundtruth.front().time, t1 = groundtruth.back().time;
  std::vector<Vec2> est, truth;
  for (const TimedPose& p : estimate) {
    if (p.time < t0 || p.time > t1) continue;
    est.push_back(p.pose.head<2>());
    truth.push_back(interpolatePose(groundtruth, p.time).head<2>());
  }
  if (est.empty()) return std::nullopt;
  return alignedRmse(est, truth, alignment);
}

std::optional<double> landmarkRmse(const SlamFilter& filter, const std::map<int, Vec2>& truth,
                                   Alignment alignment) {
  std::vector<Vec2> est, ref;
  for (int id : filter.landmarkIds()) {
    const auto it = truth.find(id);
    if (it == truth.end()) continue;
    est.push_back(filter.landmark(id));
    ref.push_back(it->second);
  }
  if (est.empty()) return std::nullopt;
  return alignedRmse(est, ref, alignment);
}

}  // namespace seif
