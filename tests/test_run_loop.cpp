// The run loop (eval/run_loop.hpp): observers see every step in order, a run through the
// loop is runFilter's run, start_step resumes a run at the step it stopped, the association
// hook sees the predicted filter and decides what the update gets; and the experiments'
// thread pool (eval/parallel.hpp).
#include <seif/core/errors.hpp>
#include "eval/parallel.hpp"
#include <seif/eval/run.hpp>
#include <seif/eval/run_loop.hpp>
#include <seif/filters/factory.hpp>
#include "io/robot_log_source.hpp"
#include <seif/sim/world.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using namespace seif;

/// Everything the hooks were called with, in order.
class Recorder : public RunObserver {
 public:
  std::vector<std::string> calls;
  std::vector<std::size_t> steps;  // k of every afterUpdate
  std::vector<TimedPose> poses;    // the start pose, then after every update
  std::vector<Step> seen;          // the steps updated
  double start_time = -1.0;

  void onStart(const SlamFilter& f, double time) override {
    calls.push_back("start");
    start_time = time;
    poses.push_back({time, f.pose()});
  }
  void afterPredict(const SlamFilter&, const Step&, std::size_t k, double) override {
    calls.push_back("predict " + std::to_string(k));
  }
  void afterUpdate(const SlamFilter& f, const Step& step, std::size_t k, double seconds) override {
    calls.push_back("update " + std::to_string(k));
    EXPECT_GE(seconds, 0.0);
    steps.push_back(k);
    poses.push_back({step.time, f.pose()});
    seen.push_back(step);
  }
  void onStop(const SlamFilter&, std::size_t consumed) override { calls.push_back("stop " + std::to_string(consumed)); }
  void onFinish(const SlamFilter&, double) override { calls.push_back("finish"); }
  void onGroundTruth(const TimedPose& pose) override { last_groundtruth = pose.time; }
  double last_groundtruth = -1.0;  // the stamp of the last ground-truth pose handed on
};

/// Asks the run to stop from inside it, after the update of step `at`.
class StopAfter : public RunObserver {
 public:
  StopAfter(std::atomic<bool>& stop, std::size_t at) : stop_(stop), at_(at) {}
  void afterUpdate(const SlamFilter&, const Step&, std::size_t k, double) override {
    if (k == at_) stop_.store(true);
  }

 private:
  std::atomic<bool>& stop_;
  std::size_t at_;
};

struct World {
  RobotLog log;
  Dataset data;
  explicit World(std::uint64_t seed) : log(simulate(presetConfig(WorldPreset::Paper, 20, 120, seed))), data(buildDataset(log)) {}
  std::unique_ptr<SlamFilter> filter(const std::string& name) const {
    FilterConfig config = paperFilterConfig(data.noise.value_or(NoiseModel{}));
    return makeFilter(name, startPose(data), config);
  }
};

/// A filter with the models of a streamed source, from its start pose.
std::unique_ptr<SlamFilter> streamedFilter(const std::string& name, const EventSource& source) {
  FilterConfig config;
  config.motion = source.info().motion;
  config.sensor = source.info().sensor;
  return makeFilter(name, source.info().start_pose, config);
}

RunLoopOptions resumingAt(std::size_t step) {
  RunLoopOptions options;
  options.start_step = step;
  return options;
}

void expectSamePoses(const std::vector<TimedPose>& a, const std::vector<TimedPose>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].time, b[k].time) << "pose " << k;
    ASSERT_EQ(a[k].pose, b[k].pose) << "pose " << k;  // bit for bit
  }
}

TEST(RunLoop, ObserversSeeEveryStepInOrder) {
  const World w(3);
  auto filter = w.filter("seif");
  Recorder a, b;
  const std::size_t run = runLoop(*filter, w.data, {&a, &b});
  const std::size_t n = w.data.steps.size();
  ASSERT_GT(n, 10u);
  EXPECT_EQ(run, n);
  ASSERT_EQ(a.calls.size(), 2 * n + 2);
  EXPECT_EQ(a.calls.front(), "start");
  for (std::size_t k = 0; k < n; ++k) {
    EXPECT_EQ(a.calls[1 + 2 * k], "predict " + std::to_string(k));
    EXPECT_EQ(a.calls[2 + 2 * k], "update " + std::to_string(k));
  }
  EXPECT_EQ(a.calls.back(), "finish");
  EXPECT_EQ(a.calls, b.calls);
  EXPECT_EQ(a.start_time, w.data.start_time);
}

TEST(RunLoop, InMemoryAndStreamedRunsAreRunFiltersRuns) {
  const World w(4);
  for (const char* name : {"ekf", "seif"}) {
    auto looped = w.filter(name);
    Recorder in_memory;
    runLoop(*looped, w.data, {&in_memory});
    auto reference = w.filter(name);
    const RunOutput out = runFilter(*reference, w.data);
    expectSamePoses(in_memory.poses, out.trajectory);
    EXPECT_EQ(looped->landmarkIds(), reference->landmarkIds());

    RobotLogSource source(w.log, w.data.noise.value_or(NoiseModel{}));
    auto streamed = streamedFilter(name, source);
    Recorder stream;
    StepAssembler steps;
    runLoop(*streamed, source, steps, {&stream});
    RobotLogSource again(w.log, w.data.noise.value_or(NoiseModel{}));
    auto streamed_reference = streamedFilter(name, again);
    const RunOutput streamed_out = runFilter(*streamed_reference, again);
    expectSamePoses(stream.poses, streamed_out.trajectory);
    EXPECT_EQ(streamed->mean(), streamed_reference->mean()) << name;
  }
}

TEST(RunLoop, StartStepSkipsTheFirstStepsAndResumesWhereARunStopped) {
  const World w(5);
  const std::size_t n = w.data.steps.size(), k = n / 3;
  auto whole = w.filter("seif");
  Recorder all;
  runLoop(*whole, w.data, {&all});

  // In memory: the first k steps, then the rest with start_step = k on the same filter.
  Dataset head = w.data;
  head.steps.resize(k);
  auto resumed = w.filter("seif");
  runLoop(*resumed, head, {});
  Recorder rest;
  EXPECT_EQ(runLoop(*resumed, w.data, {&rest}, resumingAt(k)), n - k);
  EXPECT_EQ(rest.start_time, w.data.steps[k - 1].time);
  ASSERT_EQ(rest.steps.size(), n - k);
  EXPECT_EQ(rest.steps.front(), k);
  expectSamePoses(rest.poses, std::vector<TimedPose>(all.poses.begin() + static_cast<std::ptrdiff_t>(k), all.poses.end()));
  EXPECT_EQ(resumed->mean(), whole->mean());

  // Streamed: the assembler still makes the skipped steps, the filter never sees them.
  RobotLogSource source(w.log, w.data.noise.value_or(NoiseModel{}));
  auto streamed = streamedFilter("seif", source);
  runLoop(*streamed, head, {});
  Recorder streamed_rest;
  StepAssembler steps;
  EXPECT_EQ(runLoop(*streamed, source, steps, {&streamed_rest}, resumingAt(k)), n - k);
  EXPECT_EQ(streamed_rest.steps, rest.steps);
  expectSamePoses(streamed_rest.poses, rest.poses);

  // Skipping everything runs nothing.
  auto untouched = w.filter("seif");
  Recorder none;
  EXPECT_EQ(runLoop(*untouched, w.data, {&none}, resumingAt(n + 5)), 0u);
  EXPECT_EQ(untouched->landmarkIds().size(), 0u);
  EXPECT_EQ(none.calls, (std::vector<std::string>{"start", "finish"}));
}

TEST(RunLoop, AStopEndsTheRunBeforeItsNextStepAndStillFinishesIt) {
  const World w(7);
  const std::size_t n = w.data.steps.size(), k = n / 2;
  auto whole = w.filter("seif");
  Recorder all;
  runLoop(*whole, w.data, {&all});
  EXPECT_EQ(std::count_if(all.calls.begin(), all.calls.end(), [](const std::string& c) { return c.starts_with("stop"); }),
            0);  // no stop asked: none reported
  const std::vector<TimedPose> first_k(all.poses.begin(), all.poses.begin() + static_cast<std::ptrdiff_t>(k + 1));
  const std::vector<std::string> ending = {"update " + std::to_string(k - 1), "stop " + std::to_string(k), "finish"};

  // In memory: asked during step k - 1, the loop stops before step k.
  std::atomic<bool> stop{false};
  StopAfter stopper(stop, k - 1);
  RunLoopOptions options;
  options.stop = &stop;
  auto stopped = w.filter("seif");
  Recorder in_memory;
  EXPECT_EQ(runLoop(*stopped, w.data, {&stopper, &in_memory}, options), k);
  ASSERT_GE(in_memory.calls.size(), 3u);
  EXPECT_EQ(std::vector<std::string>(in_memory.calls.end() - 3, in_memory.calls.end()), ending);
  expectSamePoses(in_memory.poses, first_k);

  // Streamed: the same, and nothing the stream carries after the last step run is handed on.
  stop.store(false);
  RobotLogSource source(w.log, w.data.noise.value_or(NoiseModel{}));
  auto streamed = streamedFilter("seif", source);
  Recorder stream;
  StepAssembler steps;
  EXPECT_EQ(runLoop(*streamed, source, steps, {&stopper, &stream}, options), k);
  EXPECT_EQ(std::vector<std::string>(stream.calls.end() - 3, stream.calls.end()), ending);
  expectSamePoses(stream.poses, in_memory.poses);
  EXPECT_GE(stream.last_groundtruth, w.data.steps[k - 2].time);
  EXPECT_LE(stream.last_groundtruth, w.data.steps[k - 1].time);

  // Asked before the run: it starts, stops at once and finishes, in memory and streamed.
  for (const bool in_mem : {true, false}) {
    stop.store(true);
    auto untouched = w.filter("seif");
    Recorder none;
    RobotLogSource again(w.log, w.data.noise.value_or(NoiseModel{}));
    StepAssembler fresh;
    EXPECT_EQ(in_mem ? runLoop(*untouched, w.data, {&none}, options) : runLoop(*untouched, again, fresh, {&none}, options),
              0u);
    EXPECT_EQ(none.calls, (std::vector<std::string>{"start", "stop 0", "finish"})) << (in_mem ? "in memory" : "streamed");
    EXPECT_EQ(untouched->landmarkIds().size(), 0u);
  }
}

TEST(RunLoop, TheAssociationHookSeesThePredictionAndRewritesTheUpdatesObservations) {
  const World w(6);
  // Keeping the observations as they are changes nothing.
  auto plain = w.filter("ekf");
  runLoop(*plain, w.data, {});
  auto kept = w.filter("ekf");
  std::size_t calls = 0;
  RunLoopOptions keep;
  keep.associate = [&](const SlamFilter&, const Step& step, std::size_t k, std::vector<Observation>& z) {
    EXPECT_EQ(k, calls++);
    EXPECT_EQ(z.size(), step.observations.size());
  };
  runLoop(*kept, w.data, {}, keep);
  EXPECT_EQ(calls, w.data.steps.size());
  EXPECT_EQ(kept->mean(), plain->mean());

  // The hook runs after predict: it sees the predicted pose. Dropping every observation
  // leaves the map empty.
  class PredictedPose : public RunObserver {
   public:
    Pose2 pose = Pose2::Zero();
    void afterPredict(const SlamFilter& f, const Step&, std::size_t, double) override { pose = f.pose(); }
  } predicted;
  auto blind = w.filter("ekf");
  RunLoopOptions drop;
  drop.associate = [&](const SlamFilter& f, const Step&, std::size_t, std::vector<Observation>& z) {
    EXPECT_EQ(f.pose(), predicted.pose);
    z.clear();
  };
  runLoop(*blind, w.data, {&predicted}, drop);
  EXPECT_TRUE(blind->landmarkIds().empty());
  EXPECT_FALSE(plain->landmarkIds().empty());
}

TEST(RunLoop, AFailureInsideAStepNamesTheFilterTheStepAndItsTime) {
  const World w(7);
  auto filter = w.filter("seif");
  RunLoopOptions options;
  options.associate = [](const SlamFilter&, const Step&, std::size_t k, std::vector<Observation>&) {
    if (k == 3) throw InvalidArgument("no match");
  };
  try {
    runLoop(*filter, w.data, {}, options);
    FAIL() << "no exception";
  } catch (const NumericError& e) {
    FAIL() << "a step's bad data is not a numerical failure: " << e.what();
  } catch (const ModelError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(filter->name() + ": step 3 (t = ", 0), 0u) << what;
    EXPECT_NE(what.find("): no match"), std::string::npos) << what;
  }
  // A numerical failure keeps its kind.
  options.associate = [](const SlamFilter&, const Step&, std::size_t k, std::vector<Observation>&) {
    if (k == 2) throw NumericError("singular");
  };
  auto numeric = w.filter("seif");
  try {
    runLoop(*numeric, w.data, {}, options);
    FAIL() << "no exception";
  } catch (const NumericError& e) {
    EXPECT_NE(std::string(e.what()).find(": step 2 (t = "), std::string::npos) << e.what();
  }
  // A caller's own exception passes as it is (its type is the caller's to catch).
  struct Mine : std::runtime_error {
    using std::runtime_error::runtime_error;
  };
  options.associate = [](const SlamFilter&, const Step&, std::size_t k, std::vector<Observation>&) {
    if (k == 3) throw Mine("mine");
  };
  auto again = w.filter("seif");
  EXPECT_THROW(runLoop(*again, w.data, {}, options), Mine);
}

// Once the stop flag is set no task starts: with one thread, the three tasks before it ran.
TEST(Parallel, NoTaskStartsOnceStopped) {
  std::atomic<bool> stop{false};
  std::vector<int> ran;
  parallelFor(10, 1, [&](std::size_t i) { ran.push_back(static_cast<int>(i)); },
              [&](std::size_t done, std::size_t) {
                if (done == 3) stop = true;
              },
              &stop);
  EXPECT_EQ(ran, (std::vector<int>{0, 1, 2}));
  EXPECT_TRUE(stopRequested(&stop));
  EXPECT_FALSE(stopRequested(nullptr));
}

TEST(Parallel, RunsEveryTaskOnceAndRethrowsTheFirstFailure) {
  std::vector<std::atomic<int>> hits(50);
  std::size_t last_done = 0;
  parallelFor(hits.size(), 3, [&](std::size_t i) { ++hits[i]; },
              [&](std::size_t done, std::size_t total) {
                EXPECT_EQ(done, last_done + 1);
                EXPECT_EQ(total, hits.size());
                last_done = done;
              });
  for (const auto& h : hits) EXPECT_EQ(h.load(), 1);
  EXPECT_EQ(last_done, hits.size());
  EXPECT_THROW(parallelFor(10, 2, [](std::size_t i) {
                 if (i == 4) throw std::runtime_error("task 4");
               }),
               std::runtime_error);
  // A `done` that throws (a Python progress callback) is a failure like a task's, on any thread.
  for (unsigned threads : {1u, 2u, 4u}) {
    EXPECT_THROW(parallelFor(10, threads, [](std::size_t) {},
                             [](std::size_t finished, std::size_t) {
                               if (finished == 3) throw std::runtime_error("done 3");
                             }),
                 std::runtime_error)
        << threads << " threads";
  }
  EXPECT_EQ(threadCount(8, 3), 3u);
  EXPECT_EQ(threadCount(2, 0), 1u);
  EXPECT_GE(threadCount(0, 100), 1u);
}

}  // namespace
