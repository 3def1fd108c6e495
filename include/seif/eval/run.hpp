#pragma once
// Runs a filter over a dataset and measures it: runFilter() is the run loop (run_loop.hpp)
// with the observers that record a RunOutput, behind `seif run` and `seif paper`. A dataset
// comes either in memory (Dataset: the simulator's worlds) or as a stream of events
// (EventSource: every reader); StepAssembler (step_assembler.hpp) turns events into filter
// steps, and the run never holds the observations of more than one step.
#include <seif/association/association.hpp>
#include <seif/filters/slam_filter.hpp>
#include <seif/core/dataset.hpp>
#include <seif/io/event_source.hpp>
#include <seif/eval/step_assembler.hpp>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <optional>
#include <vector>

namespace seif {

/// One observation of a run with unknown association and what the associator made of it
/// (Associator::lastScan()): a row of `seif run`'s associations.csv.
struct AssociationRecord {
  std::size_t step = 0;   ///< the step whose update it was offered to (0-based)
  std::size_t index = 0;  ///< its place among that step's observations, as the data gave them
  Vec2 z = Vec2::Zero();  ///< the measurement
  int truth = kUnknownLandmark;  ///< the data's id, hidden from the filter: for scoring only
  ScanDecision decision;
};

/// A merge of two landmarks (Associator::lastMerges()) and the step whose association made it.
struct MergeRecord {
  std::size_t step = 0;
  LandmarkMerge merge;
};

struct RunOutput {
  std::size_t steps = 0;
  std::vector<TimedPose> trajectory;  ///< the start pose, then the pose after every step
  /// A smoother's: the trajectory of its estimates while streaming (the filter it runs
  /// alongside), which finish() replaced in `trajectory` by the smoothed one.
  std::vector<TimedPose> filter_trajectory;
  std::vector<double> step_seconds;   ///< wall time of every step (predict + update)
  /// The pose covariance beside every trajectory pose, when asked for (runFilter's
  /// pose_covariances): the filter's poseCovariance() after each step (its cost: see
  /// SlamFilter), or a smoother's marginals after finish().
  std::vector<Mat3> pose_covariances;
  double seconds = 0.0;               ///< sum of step_seconds
  FilterStats final_stats;
  std::size_t max_robot_links = 0;     ///< over all steps
  std::size_t max_blocks_touched = 0;  ///< over all steps
  std::size_t rejected_observations = 0;  ///< by the gross-outlier gate (OutlierGate)
  /// Stopped before its last step (RunLoopOptions::stop, Ctrl-C in `seif run`): everything
  /// here covers the `steps` run.
  bool interrupted = false;
  /// The error that ended a streamed run before its end (a step's numerical failure, a bad
  /// line further in the stream); null when it ran to the end or was stopped. Everything
  /// here then covers the `steps` run before it; the filter holds the state after them
  /// (and, when the update failed, that step's motion).
  std::exception_ptr failure;
  // Streamed runs only (runFilter over an EventSource): what the stream carried besides
  // controls and observations, and the controls integrated alone. All O(steps).
  std::vector<TimedPose> dead_reckoning;  ///< the start pose, then after every step
  std::vector<TimedPose> groundtruth;
  std::vector<GpsFix> gps;
  std::map<std::string, std::size_t> dropped;  ///< by the source and the assembler, by reason
  // Streamed runs with an associator that is not `known`: every observation offered to it,
  // in order, and every merge it made. O(observations).
  std::vector<AssociationRecord> associations;
  std::vector<MergeRecord> merges;
  /// The first step `associations` covers: 0, except in a run resumed from a checkpoint
  /// written before runs recorded them (then the step it resumed at).
  std::size_t associations_from = 0;
};

/// Where landmark `id` ended up after `merges` (each `merged` into its `kept`, in order):
/// the landmark that holds its observations now, `id` itself when it was never merged.
int mergedInto(int id, const std::vector<MergeRecord>& merges);

/// A recorded observation's verdict against the truth, as AssociationCounts scores it.
enum class AssociationVerdict {
  Unscored,   ///< dropped, without a truth id, or in a landmark that is not in the map at the end
  Correct,    ///< in the landmark labelled with its truth, which is not a duplicate
  Wrong,      ///< in a landmark labelled with another truth (or with none)
  Duplicate,  ///< in a landmark labelled with its truth, but a younger copy (scored wrong)
};
std::string_view associationVerdictName(AssociationVerdict v);  ///< "" | "correct" | "wrong" | "duplicate"

/// Each of `out.associations`' verdicts, once the run is over and `associator.finish()` has
/// labelled the map in `filter`: their sum over Correct is AssociationCounts::correct, over
/// Wrong and Duplicate AssociationCounts::wrong. `final_landmark` receives each one's landmark
/// at the end (kUnknownLandmark when dropped or removed).
std::vector<AssociationVerdict> associationVerdicts(const RunOutput& out, const SlamFilter& filter,
                                                    const Associator& associator,
                                                    std::vector<int>* final_landmark = nullptr);

/// associations.csv: header "step,time,index,z0,z1,truth,outcome,landmark,d2,provisional,applied,
/// final_landmark,label,verdict", one row per recorded observation (z0, z1: range [m] and
/// bearing [rad] for the range-bearing sensor; truth, landmark, final_landmark and label empty
/// when none; d2 "inf" when no landmark was in reach). Written atomically.
void writeAssociationsCsv(const std::filesystem::path& file, const RunOutput& out, const SlamFilter& filter,
                          const Associator& associator);

/// Checkpoints of a streamed run (`seif run --checkpoint-every N --checkpoint FILE`): after
/// every `every` steps the filter and the run so far are saved to `path` (atomically, the
/// previous one replaced), with `values` recorded beside them (the dataset, the spec).
/// A run stopped early (runFilter's `stop`) saves one where it stopped, whatever `every`.
/// The extras key under which a run's checkpoint carries its outputs so far (binary; the
/// associator's is kAssociatorKey).
inline constexpr std::string_view kRunOutputKey = "run-output";
/// The extras key of the digest of the steps a run's checkpoint consumed (StepDigest, decimal).
inline constexpr std::string_view kStepsDigestKey = "steps-digest";
/// The extras key of a run's association records so far (RunOutput::associations and
/// merges; binary), in the checkpoints of runs with an associator that is not `known`.
inline constexpr std::string_view kRunAssociationsKey = "run-associations";

struct RunCheckpointing {
  std::size_t every = 0;  ///< 0: never periodically (only where a stopped run stops)
  std::filesystem::path path;
  std::map<std::string, std::string> values;
};

/// A run resumed from a checkpoint (`seif run --resume FILE`): the steps it had consumed
/// and its outputs so far; the filter comes from the same checkpoint (seif::load).
struct RunResume {
  std::size_t steps = 0;
  RunOutput output;
  /// The run's associator (Associator::saveState, under kAssociatorKey), empty when the run
  /// had none: runFilter continues with Associator::restoreState of it.
  std::string associator;
  /// The digest of the steps it consumed (kStepsDigestKey): runFilter refuses a source whose
  /// first `steps` steps have another (InvalidArgument in RunOutput::failure). None in
  /// checkpoints written before it: not checked.
  std::optional<std::uint64_t> steps_digest;
};

/// The run state a checkpoint carries (RunCheckpointing), from the extras load() returns.
/// Throws DataError naming `checkpoint` when they hold no run or a damaged one.
RunResume runResumeFrom(const std::map<std::string, std::string>& values, std::size_t steps,
                        const std::string& checkpoint);

/// Streams `source` through `filter`, whose config must hold the source's models (the
/// filter is built from info()). `progress(fraction)` is called now and then.
/// A failure inside a step (a NumericError naming the step and its time) or of the stream
/// (a DataError naming the file and line) ends the run there: it is returned in
/// RunOutput::failure, with everything else covering the steps before it.
/// With `resume`, the first resume->steps steps of the source are skipped (the filter is
/// the checkpoint's) and the outputs continue resume->output: a resumed run ends with the
/// same outputs, bit for bit, as the run that was never interrupted (timings aside).
/// With `associator`, it gives the observations their landmark ids before each update
/// (and its finish() is called after the run); checkpoints carry its state, and a resumed
/// run needs the one its checkpoint carried (RunResume::associator; InvalidArgument when
/// the checkpoint has one and none is given, or the other way round). Once `*stop` is true the run ends before its
/// next step, as if that were the end of the data (RunOutput::interrupted), and with a
/// checkpoint path saves a checkpoint there to resume from.
RunOutput runFilter(SlamFilter& filter, EventSource& source,
                    const std::function<void(double)>& progress = {}, bool pose_covariances = false,
                    const RunCheckpointing& checkpointing = {}, const RunResume* resume = nullptr,
                    Associator* associator = nullptr, const std::atomic<bool>* stop = nullptr);

/// The pose the filter starts from: the ground truth at the first step's time when the
/// dataset has ground truth, else the origin.
Pose2 startPose(const Dataset& data);

/// Runs every step of `data` through `filter`. `progress(done, total)` is called now and then.
/// A failure inside a step is rethrown as NumericError naming the step and its time.
RunOutput runFilter(SlamFilter& filter, const Dataset& data,
                    const std::function<void(std::size_t, std::size_t)>& progress = {});

/// Integrates the controls alone from `start` (dead reckoning), at the same stamps as runFilter.
std::vector<TimedPose> deadReckoning(const Dataset& data, const Pose2& start, const MotionModel& motion);

/// Whether an error is measured in the ground truth's frame as it is (the filters start at
/// the true pose) or after the rigid 2-D motion that best aligns estimate and truth
/// (least squares, Horn/Umeyama without scale), as the TUM benchmark and evo define ATE.
enum class Alignment { None, Rigid };

/// RMS of |R p_i + t - q_i| over point pairs, with (R, t) = identity or the best rigid fit;
/// `residuals` receives each |R p_i + t - q_i| when given.
double alignedRmse(const std::vector<Vec2>& estimate, const std::vector<Vec2>& truth,
                   Alignment alignment, std::vector<double>* residuals = nullptr);

/// Absolute trajectory error: RMS position error against the ground truth interpolated at
/// the estimate's stamps (stamps outside the ground truth's span are skipped).
/// nullopt without ground truth.
std::optional<double> ateRmse(const std::vector<TimedPose>& estimate,
                              const std::vector<TimedPose>& groundtruth,
                              Alignment alignment = Alignment::None);

/// RMS landmark position error of the filter's map against the true positions of the
/// landmarks it mapped. nullopt without ground truth or mapped landmarks.
std::optional<double> landmarkRmse(const SlamFilter& filter, const std::map<int, Vec2>& truth,
                                   Alignment alignment = Alignment::None);

}  // namespace seif
