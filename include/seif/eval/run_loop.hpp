#pragma once
// The run loop: the one place that turns a run's steps into filter calls (predict, then
// update, step after step, then finish). Everything else about a run - its trajectory,
// timing, dead reckoning, covariances, progress, an experiment's measurements - watches
// the loop through RunObserver hooks. Steps come from an in-memory Dataset or are
// assembled from an EventSource (StepAssembler) without holding the log in memory.
//
// Two seams for what comes later: RunLoopOptions::associate may rewrite a step's
// observations between predict and update (data association), and
// RunLoopOptions::start_step skips the first steps of the source without calling the
// filter (a run resumed from a checkpoint saved after step start_step - 1). A third,
// RunLoopOptions::stop, ends a run early but whole (Ctrl-C in `seif run`): the filter is
// finished and observed as after a last step, so what was run is kept.
#include <seif/core/dataset.hpp>
#include <seif/eval/step_assembler.hpp>
#include <seif/filters/slam_filter.hpp>
#include <seif/io/event_source.hpp>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

namespace seif {

/// Hooks into a run; each does nothing unless overridden. Called in the order the
/// observers were given. `k` counts the source's steps from 0 (skipped ones included).
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  /// Before the first step run: the filter at its start, and the time of its pose (the
  /// dataset's start time, or the time of the last skipped step).
  virtual void onStart(const SlamFilter& /*filter*/, double /*time*/) {}
  /// After the predict of step k; `seconds` is the predict's wall time.
  virtual void afterPredict(const SlamFilter& /*filter*/, const Step& /*step*/, std::size_t /*k*/,
                            double /*seconds*/) {}
  /// After the update of step k; `seconds` is the wall time of the step's filter calls
  /// (predict + update, without the observers and the association hook).
  virtual void afterUpdate(const SlamFilter& /*filter*/, const Step& /*step*/, std::size_t /*k*/,
                           double /*seconds*/) {}
  /// The run was stopped (RunLoopOptions::stop) with steps left: after the last step run and
  /// before finish(). `steps` counts the source's steps consumed (skipped ones included):
  /// a run resumed with start_step = steps goes on where this one stopped.
  virtual void onStop(const SlamFilter& /*filter*/, std::size_t /*steps*/) {}
  /// After the last step and the filter's finish(); `seconds` is finish()'s wall time.
  virtual void onFinish(const SlamFilter& /*filter*/, double /*seconds*/) {}
  /// Streamed runs: the ground truth and GPS fixes the stream carries, as they come
  /// (before the step they precede; skipped steps' too).
  virtual void onGroundTruth(const TimedPose& /*pose*/) {}
  virtual void onGps(const GpsFix& /*fix*/) {}
};

/// A running digest (FNV-1a 64) of the steps a run took from its source, bit for bit: each
/// step's time, control and observations as the source gave them (before association). A
/// run's checkpoint records it, and a resumed run checks the steps it skips against it.
class StepDigest {
 public:
  void add(const Step& step);
  std::uint64_t value() const { return hash_; }

 private:
  void bytes(const void* data, std::size_t n);
  template <typename T>
  void value(const T& v) {
    bytes(&v, sizeof v);
  }
  std::uint64_t hash_ = 0xcbf29ce484222325ULL;  // FNV-1a's offset basis
};

/// Between predict and update of step k: may rewrite `observations` (initially the step's)
/// before the filter's update sees them, e.g. to associate them with the map (an Associator,
/// association/association.hpp, which may also take provisional landmarks out of the filter).
using AssociateHook = std::function<void(SlamFilter& filter, const Step& step, std::size_t k,
                                         std::vector<Observation>& observations)>;

struct RunLoopOptions {
  /// Steps 0 .. start_step - 1 are taken from the source but not run and not observed.
  std::size_t start_step = 0;
  /// Data association between predict and update; none: the step's observations as they are.
  AssociateHook associate;
  /// Read before each step to run: once true (set from any thread, a signal handler or an
  /// observer), the run ends there - onStop, then finish() and onFinish as after a last step.
  /// Null: the run goes to the end of its steps.
  const std::atomic<bool>* stop = nullptr;
  /// Streamed runs: every step taken from the source, skipped or run, is added to it before
  /// it runs (a checkpoint saved after step k - 1 records the digest of steps 0 .. k - 1).
  StepDigest* digest = nullptr;
  /// With start_step and digest: the digest the skipped steps must have (the checkpoint's).
  /// Other steps, or fewer than start_step, are an InvalidArgument before any step runs:
  /// the data is not the data the checkpoint consumed.
  std::optional<std::uint64_t> skipped_digest;
};

/// Runs the steps of `data` from options.start_step through `filter` (until options.stop),
/// then finish().
/// A seif::Error inside a step (the filter's or the association hook's) is rethrown as
/// "<filter name>: step k (t = <time>): <what>", its kind kept: a NumericError as a
/// NumericError (the filter failed numerically), any other as a ModelError (what the filter
/// or a model cannot do with the step's data: an observation without an id under known
/// association, a degenerate sighting); Interrupted and any other exception (a caller's
/// own, a Python error from a hook) pass unchanged. Returns the steps run.
std::size_t runLoop(SlamFilter& filter, const Dataset& data, const std::vector<RunObserver*>& observers,
                    const RunLoopOptions& options = {});

/// The same over the steps `steps` assembles from `source` (a fresh assembler for a whole
/// run). onStart comes with the first step run, so a stream without steps calls none of
/// the step hooks; onFinish and finish() always come.
std::size_t runLoop(SlamFilter& filter, EventSource& source, StepAssembler& steps,
                    const std::vector<RunObserver*>& observers, const RunLoopOptions& options = {});

}  // namespace seif
