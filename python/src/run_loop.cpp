// The run loop from Python (eval/run_loop.hpp): RunObserver subclasses in Python watch a run
// of any filter over an in-memory Dataset or streamed from an EventSource; RunLoopOptions.start_step skips steps (resume),
// `associate` may rewrite a step's observations between predict and update, and `stop`
// ends the run early but whole.
#include "bindings.hpp"

#include <seif/core/errors.hpp>
#include <seif/eval/run_loop.hpp>
#include <seif/eval/step_assembler.hpp>

#include <atomic>
#include <functional>
#include <optional>

namespace seif::python {

namespace {

/// Forwards each hook to the Python subclass's method of the same name, when it has one.
/// The step goes as a copy: an observer may keep it after the hook (the filter is the caller's).
class PyRunObserver : public RunObserver {
 public:
  using RunObserver::RunObserver;
  void onStart(const SlamFilter& filter, double time) override {
    PYBIND11_OVERRIDE_NAME(void, RunObserver, "on_start", onStart, std::cref(filter), time);
  }
  void afterPredict(const SlamFilter& filter, const Step& step, std::size_t k, double seconds) override {
    PYBIND11_OVERRIDE_NAME(void, RunObserver, "after_predict", afterPredict, std::cref(filter), Step(step), k,
                           seconds);
  }
  void afterUpdate(const SlamFilter& filter, const Step& step, std::size_t k, double seconds) override {
    PYBIND11_OVERRIDE_NAME(void, RunObserver, "after_update", afterUpdate, std::cref(filter), Step(step), k,
                           seconds);
  }
  void onStop(const SlamFilter& filter, std::size_t steps) override {
    PYBIND11_OVERRIDE_NAME(void, RunObserver, "on_stop", onStop, std::cref(filter), steps);
  }
  void onFinish(const SlamFilter& filter, double seconds) override {
    PYBIND11_OVERRIDE_NAME(void, RunObserver, "on_finish", onFinish, std::cref(filter), seconds);
  }
  void onGroundTruth(const TimedPose& pose) override {
    PYBIND11_OVERRIDE_NAME(void, RunObserver, "on_ground_truth", onGroundTruth, pose);
  }
  void onGps(const GpsFix& fix) override { PYBIND11_OVERRIDE_NAME(void, RunObserver, "on_gps", onGps, fix); }
};

/// Asks `stop()` after every step (and before the first) and raises the loop's flag when it
/// says so.
class StopWhen : public RunObserver {
 public:
  StopWhen(std::function<bool()> stop, std::atomic<bool>& flag) : stop_(std::move(stop)), flag_(flag) { ask(); }
  void afterUpdate(const SlamFilter&, const Step&, std::size_t, double) override { ask(); }

 private:
  void ask() {
    bool stop = false;
    try {
      stop = stop_();
    } catch (const py::cast_error&) {  // pybind11's message names no hook
      throw InvalidArgument("run_loop: stop() must return True or False");
    }
    if (stop) flag_.store(true, std::memory_order_relaxed);
  }
  std::function<bool()> stop_;
  std::atomic<bool>& flag_;
};

using PyAssociate = std::function<std::vector<Observation>(SlamFilter&, const Step&, std::size_t, std::vector<Observation>)>;

/// run_loop's options and observers from its Python arguments, then `loop(observers, options)`.
template <typename Loop>
std::size_t runWith(std::vector<RunObserver*> observers, std::size_t start_step, const PyAssociate& associate,
                    const std::function<bool()>& stop, Loop&& loop) {
  for (std::size_t i = 0; i < observers.size(); ++i) {
    if (observers[i] == nullptr) throw InvalidArgument("run_loop: observers[" + std::to_string(i) + "] is None");
  }
  RunLoopOptions options;
  options.start_step = start_step;
  std::atomic<bool> stopping{false};
  std::optional<StopWhen> stop_when;
  if (stop) {
    stop_when.emplace(stop, stopping);
    observers.push_back(&*stop_when);
    options.stop = &stopping;
  }
  if (associate) {
    options.associate = [&](SlamFilter& f, const Step& step, std::size_t k, std::vector<Observation>& z) {
      try {
        z = associate(f, step, k, z);
      } catch (const py::cast_error&) {  // pybind11's message names no hook
        throw InvalidArgument("run_loop: associate(filter, step, k, observations) must return a list of Observation");
      }
    };
  }
  return loop(observers, options);
}

}  // namespace

void bindRunLoop(py::module_& m) {
  py::class_<RunObserver, PyRunObserver>(m, "RunObserver",
                                         "Subclass and override on_start(filter, time), after_predict(filter, step, "
                                         "k, seconds), after_update(filter, step, k, seconds), on_stop(filter, "
                                         "steps) (run_loop's stop ended the run with steps left), on_finish(filter, "
                                         "seconds), and for a streamed run on_ground_truth(pose) and on_gps(fix); "
                                         "pass instances to run_loop().")
      .def(py::init<>())
      .def("on_start", &RunObserver::onStart)
      .def("after_predict", &RunObserver::afterPredict)
      .def("after_update", &RunObserver::afterUpdate)
      .def("on_stop", &RunObserver::onStop)
      .def("on_finish", &RunObserver::onFinish)
      .def("on_ground_truth", &RunObserver::onGroundTruth)
      .def("on_gps", &RunObserver::onGps);
  m.def(
      "run_loop",
      [](SlamFilter& filter, const Dataset& data, std::vector<RunObserver*> observers, std::size_t start_step,
         const PyAssociate& associate, const std::function<bool()>& stop) {
        return runWith(std::move(observers), start_step, associate, stop,
                       [&](const std::vector<RunObserver*>& o, const RunLoopOptions& options) {
                         return runLoop(filter, data, o, options);
                       });
      },
      py::arg("filter"), py::arg("data"), py::arg("observers") = std::vector<RunObserver*>{},
      py::arg("start_step") = 0, py::arg("associate") = nullptr, py::arg("stop") = nullptr,
      "The one run loop over an in-memory Dataset, or streamed from an EventSource (open_dataset; "
      "its ground truth and GPS go to on_ground_truth / on_gps as they come): predict, (associate,) "
      "update for every step from start_step, the observers' hooks after each, then finish(). "
      "`associate(filter, step, k, observations)` returns the observations the update gets. `stop()` "
      "is asked before the first step and after every step: True ends the run there (on_stop, then "
      "finish() and on_finish). Returns the steps run.");
  m.def(
      "run_loop",
      [](SlamFilter& filter, EventSource& source, std::vector<RunObserver*> observers, std::size_t start_step,
         const PyAssociate& associate, const std::function<bool()>& stop) {
        StepAssembler steps;
        return runWith(std::move(observers), start_step, associate, stop,
                       [&](const std::vector<RunObserver*>& o, const RunLoopOptions& options) {
                         return runLoop(filter, source, steps, o, options);
                       });
      },
      py::arg("filter"), py::arg("source"), py::arg("observers") = std::vector<RunObserver*>{},
      py::arg("start_step") = 0, py::arg("associate") = nullptr, py::arg("stop") = nullptr);
}

}  // namespace seif::python
