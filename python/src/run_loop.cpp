// The run loop from Python (eval/run_loop.hpp): RunObserver subclasses in Python watch a run
// of any filter over an in-memory Dataset; RunLoopOptions.start_step skips steps (resume)
// and `associate` may rewrite a step's observations between predict and update.
#include "bindings.hpp"

#include <seif/eval/run_loop.hpp>

namespace seif::python {

namespace {

/// Forwards each hook to the Python subclass's method of the same name, when it has one.
class PyRunObserver : public RunObserver {
 public:
  using RunObserver::RunObserver;
  void onStart(const SlamFilter& filter, double time) override {
    PYBIND11_OVERRIDE_NAME(void, RunObserver, "on_start", onStart, std::cref(filter), time);
  }
  void afterPredict(const SlamFilter& filter, const Step& step, std::size_t k, double seconds) override {
    PYBIND11_OVERRIDE_NAME(void, RunObserver, "after_predict", afterPredict, std::cref(filter), std::cref(step), k,
                           seconds);
  }
  void afterUpdate(const SlamFilter& filter, const Step& step, std::size_t k, double seconds) override {
    PYBIND11_OVERRIDE_NAME(void, RunObserver, "after_update", afterUpdate, std::cref(filter), std::cref(step), k,
                           seconds);
  }
  void onFinish(const SlamFilter& filter, double seconds) override {
    PYBIND11_OVERRIDE_NAME(void, RunObserver, "on_finish", onFinish, std::cref(filter), seconds);
  }
};

}  // namespace

void bindRunLoop(py::module_& m) {
  py::class_<RunObserver, PyRunObserver>(m, "RunObserver",
                                         "Subclass and override on_start(filter, time), after_predict(filter, step, "
                                         "k, seconds), after_update(filter, step, k, seconds), on_finish(filter, "
                                         "seconds); pass instances to run_loop().")
      .def(py::init<>())
      .def("on_start", &RunObserver::onStart)
      .def("after_predict", &RunObserver::afterPredict)
      .def("after_update", &RunObserver::afterUpdate)
      .def("on_finish", &RunObserver::onFinish);
  m.def(
      "run_loop",
      [](SlamFilter& filter, const Dataset& data, const std::vector<RunObserver*>& observers, std::size_t start_step,
         const std::function<std::vector<Observation>(SlamFilter&, const Step&, std::size_t,
                                                      std::vector<Observation>)>& associate) {
        RunLoopOptions options;
        options.start_step = start_step;
        if (associate) {
          options.associate = [&](SlamFilter& f, const Step& step, std::size_t k, std::vector<Observation>& z) {
            z = associate(f, step, k, z);
          };
        }
        return runLoop(filter, data, observers, options);
      },
      py::arg("filter"), py::arg("data"), py::arg("observers") = std::vector<RunObserver*>{},
      py::arg("start_step") = 0, py::arg("associate") = nullptr,
      "The one run loop over an in-memory Dataset: predict, (associate,) update for every step from "
      "start_step, the observers' hooks after each, then finish(). `associate(filter, step, k, "
      "observations)` returns the observations the update gets. Returns the steps run.");
}

}  // namespace seif::python
