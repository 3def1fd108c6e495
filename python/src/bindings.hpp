#pragma once
// Shared pieces of the pybind11 module seif._core: one bind* function per source file
// (module.cpp calls them in order), the enum helper and the progress-callback adapters.
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace seif::python {

namespace py = pybind11;

void bindErrors(py::module_& m);      // errors.cpp
void bindCore(py::module_& m);        // core.cpp: types, models, dataset vocabulary
void bindFilters(py::module_& m);     // filters.cpp
void bindIo(py::module_& m);          // io.cpp: readers, simulator, result files
void bindEval(py::module_& m);        // eval.cpp: run loop, metrics, experiments
void bindCheckpoints(py::module_& m); // checkpoint.cpp: save, load, pickling
void bindRunLoop(py::module_& m);     // run_loop.cpp: run_loop, RunObserver

/// A C++ enum bound as a Python enum that is also constructible from, and implicitly
/// converted from, the library's lower-case name ("per-step", "fej", ...): every argument
/// of that type takes either form. `parse` throws std::invalid_argument for a bad name.
template <typename E, typename Parse, typename Name>
py::enum_<E> bindNamedEnum(py::handle scope, const char* name, const char* doc, Parse parse, Name to_name) {
  py::enum_<E> e(scope, name, doc);
  e.def(py::init([parse](const std::string& s) { return parse(s); }), py::arg("name"),
        "The value named by the library's string (e.g. as the CLI takes it).");
  e.def_property_readonly("text", [to_name](E v) { return std::string(to_name(v)); },
                          "The library's name of the value.");
  py::implicitly_convertible<py::str, E>();
  return e;
}

/// Progress callbacks for calls that release the GIL. The callback (None: none) is held by
/// a shared_ptr, so the library may copy the std::function without touching Python reference
/// counts; each call re-acquires the GIL (it may come from a worker thread). Create it with
/// the GIL held and let it die with the GIL held (outside the released block).
template <typename... Args>
std::function<void(Args...)> pythonCallback(const py::object& f) {
  if (f.is_none()) return {};
  auto fn = std::make_shared<py::object>(f);
  return [fn](Args... args) {
    py::gil_scoped_acquire gil;
    (*fn)(args...);
  };
}

/// "Name(field=value, ...)" for __repr__ of plain records.
std::string reprOf(py::handle self, std::initializer_list<const char*> fields);

}  // namespace seif::python
