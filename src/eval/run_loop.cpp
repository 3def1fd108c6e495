// The run loop (include/seif/eval/run_loop.hpp): the only code that calls a filter's
// predict and update for a run.
#include <seif/core/errors.hpp>
#include <seif/eval/run_loop.hpp>

#include "core/binary_archive.hpp"
#include "eval/parallel.hpp"

#include <chrono>
#include <cmath>
#include <sstream>
#include <string>
#include <variant>

namespace seif {

void StepDigest::bytes(const void* data, std::size_t n) {
  hash_ = fnv1a64(std::string_view(static_cast<const char*>(data), n), hash_);
}

void StepDigest::add(const Step& step) {
  value(step.time);
  value(static_cast<std::uint64_t>(step.u.index()));
  std::visit(
      [this](const auto& u) {
        using U = std::decay_t<decltype(u)>;
        if constexpr (std::is_same_v<U, VelocityControl>) {
          value(u.v), value(u.w), value(u.dt);
        } else if constexpr (std::is_same_v<U, AckermannControl>) {
          value(u.speed), value(u.steering), value(u.dt);
        } else {
          bytes(u.delta.data(), sizeof(double) * 3);
          bytes(u.covariance.data(), sizeof(double) * 9);
        }
      },
      step.u);
  value(static_cast<std::uint64_t>(step.observations.size()));
  for (const Observation& z : step.observations) {
    value(z.landmark), value(z.truth);
    bytes(z.z.data(), sizeof(double) * 2);
    value(static_cast<std::uint64_t>(z.noise ? 1 : 0));
    if (z.noise) bytes(z.noise->data(), sizeof(double) * 4);
  }
}

namespace {

using Clock = std::chrono::steady_clock;
double secondsBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

/// One filter cycle: predict, the association hook, update; timed and observed.
void runStep(SlamFilter& filter, const Step& step, std::size_t k, const std::vector<RunObserver*>& observers,
             const RunLoopOptions& options) {
  double seconds = 0.0;
  try {
    const auto t0 = Clock::now();
    filter.predict(step.u);
    const auto t1 = Clock::now();
    seconds = secondsBetween(t0, t1);
    for (RunObserver* o : observers) o->afterPredict(filter, step, k, seconds);
    if (options.associate) {
      // Held work the association's queries would otherwise do first is the filter's.
      const auto t_settle = Clock::now();
      if (!step.observations.empty()) filter.settle();
      seconds += secondsBetween(t_settle, Clock::now());
      std::vector<Observation> observations = step.observations;
      options.associate(filter, step, k, observations);
      const auto t2 = Clock::now();
      filter.update(observations);
      seconds += secondsBetween(t2, Clock::now());
    } else {
      const auto t2 = Clock::now();
      filter.update(step.observations);
      seconds += secondsBetween(t2, Clock::now());
    }
  } catch (const Interrupted&) {
    throw;
  } catch (const Error& e) {  // seif's own: named with the step, its kind kept; anything else passes as it is
    std::ostringstream msg;
    msg << filter.name() << ": step " << k << " (t = ";
    if (std::abs(step.time) < 1e12) msg << std::fixed;  // else in exponent form, not 300 digits
    msg << step.time << "): " << e.what();
    if (dynamic_cast<const NumericError*>(&e) != nullptr) throw NumericError(msg.str());
    throw ModelError(msg.str());  // what the filter or a model cannot do with this step's data
  }
  for (RunObserver* o : observers) o->afterUpdate(filter, step, k, seconds);
}

/// RunLoopOptions::skipped_digest against the steps skipped, `skipped` of them.
void checkSkipped(const RunLoopOptions& options, std::size_t skipped) {
  if (!options.skipped_digest || !options.digest) return;
  if (skipped < options.start_step) {
    throw InvalidArgument("resume: the data holds " + std::to_string(skipped) + " steps, but the checkpoint consumed " +
                          std::to_string(options.start_step) + ": it is not the data the checkpoint was written from");
  }
  if (options.digest->value() != *options.skipped_digest) {
    throw InvalidArgument("resume: the data's first " + std::to_string(skipped) +
                          " steps differ from those the checkpoint consumed: it is not the data the checkpoint was "
                          "written from (changed since?)");
  }
}

void stopRun(SlamFilter& filter, const std::vector<RunObserver*>& observers, std::size_t consumed) {
  for (RunObserver* o : observers) o->onStop(filter, consumed);
}

void finishRun(SlamFilter& filter, const std::vector<RunObserver*>& observers) {
  const auto t0 = Clock::now();
  filter.finish();  // a smoother's solve
  const double seconds = secondsBetween(t0, Clock::now());
  for (RunObserver* o : observers) o->onFinish(filter, seconds);
}

}  // namespace

std::size_t runLoop(SlamFilter& filter, const Dataset& data, const std::vector<RunObserver*>& observers,
                    const RunLoopOptions& options) {
  const std::size_t first = std::min(options.start_step, data.steps.size());
  const double start_time = first == 0 ? data.start_time : data.steps[first - 1].time;
  for (RunObserver* o : observers) o->onStart(filter, start_time);
  std::size_t k = first;
  for (; k < data.steps.size(); ++k) {
    if (stopRequested(options.stop)) {
      stopRun(filter, observers, k);
      break;
    }
    // A Dataset built in memory has not been through a reader's checks of its stamps.
    const double before = k == 0 ? data.start_time : data.steps[k - 1].time;
    if (!std::isfinite(data.steps[k].time) || data.steps[k].time < before) {
      std::ostringstream msg;
      msg << "dataset: step " << k << "'s time " << data.steps[k].time << " is not finite or goes back in time (from "
          << before << ")";
      throw InvalidArgument(msg.str());
    }
    runStep(filter, data.steps[k], k, observers, options);
  }
  finishRun(filter, observers);
  return k - first;
}

std::size_t runLoop(SlamFilter& filter, EventSource& source, StepAssembler& steps,
                    const std::vector<RunObserver*>& observers, const RunLoopOptions& options) {
  std::vector<TimedPose> groundtruth;
  std::vector<GpsFix> gps;
  // Hands what the stream carried besides steps to the observers, as it came.
  auto handOn = [&] {
    for (const TimedPose& p : groundtruth)
      for (RunObserver* o : observers) o->onGroundTruth(p);
    for (const GpsFix& g : gps)
      for (RunObserver* o : observers) o->onGps(g);
    groundtruth.clear();
    gps.clear();
  };
  Step step;
  std::size_t k = 0, run = 0;
  double last_time = 0.0;  // time of the last skipped step
  while (steps.next(source, step, &groundtruth, &gps)) {
    if (k >= options.start_step && stopRequested(options.stop)) {
      // What the stream carried with the step not run (ground truth, GPS) is not handed on.
      if (run == 0) {
        checkSkipped(options, k);
        for (RunObserver* o : observers) o->onStart(filter, k == 0 ? steps.startTime() : last_time);
      }
      stopRun(filter, observers, k);
      finishRun(filter, observers);
      return run;
    }
    handOn();
    if (k < options.start_step) {
      if (options.digest) options.digest->add(step);
      last_time = step.time;
      ++k;
      continue;
    }
    if (run == 0) {
      checkSkipped(options, k);
      const double start_time = k == 0 ? steps.startTime() : last_time;
      for (RunObserver* o : observers) o->onStart(filter, start_time);
    }
    if (options.digest) options.digest->add(step);
    runStep(filter, step, k, observers, options);
    ++k;
    ++run;
  }
  handOn();
  if (run == 0) checkSkipped(options, k);
  finishRun(filter, observers);
  return run;
}

}  // namespace seif
