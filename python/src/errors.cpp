// The Python exception hierarchy of seif and the ONE translator from C++ exceptions:
//   seif.Error                      base of every error the library reports
//     seif.DataError                seif::DataError (malformed input: "file:line: what"),
//                                   with .file and .line
//     seif.NumericError             seif::NumericError (a numerical failure in a filter)
//     seif.InvalidArgument          seif::InvalidArgument, seif::ModelError (also a ValueError)
//     seif.UnknownLandmark          seif::UnknownLandmark (a landmark id not in the map; also a LookupError)
// str(exception) is the C++ what() unchanged. Anything else keeps pybind11's default
// translation (std::runtime_error -> RuntimeError, ...).
#include "bindings.hpp"

#include <seif/core/errors.hpp>

#include <cstring>
#include <stdexcept>

namespace seif::python {
namespace {

// Strong references owned by the module (never freed: the module lives until exit).
PyObject* g_error = nullptr;
PyObject* g_data_error = nullptr;
PyObject* g_numeric_error = nullptr;
PyObject* g_invalid_argument = nullptr;
PyObject* g_unknown_landmark = nullptr;

PyObject* newException(py::module_& m, const char* name, py::tuple bases, const char* doc) {
  const std::string qualified = "seif." + std::string(name);
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (!type) throw py::error_already_set();
  m.add_object(name, py::handle(type));  // the module takes its own reference; we keep ours
  return type;
}

/// Raises `type` with message `what`; `attrs` are set on the instance. The message is UTF-8
/// decoded with bytes that are not (a path's, say) shown as \xNN escapes.
void raise(PyObject* type, const char* what, std::initializer_list<std::pair<const char*, py::object>> attrs = {}) {
  py::object message = py::reinterpret_steal<py::object>(
      PyUnicode_DecodeUTF8(what, static_cast<Py_ssize_t>(std::strlen(what)), "backslashreplace"));
  if (!message) throw py::error_already_set();
  py::object instance = py::reinterpret_steal<py::object>(PyObject_CallOneArg(type, message.ptr()));
  if (!instance) throw py::error_already_set();
  for (const auto& [name, value] : attrs) instance.attr(name) = value;
  PyErr_SetObject(type, instance.ptr());
}

/// The one translator: C++ exception (seif::Error and its subclasses) -> seif.Error
/// subclass, message unchanged.
void translate(std::exception_ptr p) {
  try {
    std::rethrow_exception(p);
  } catch (const DataError& e) {
    // The file as os.fsdecode gives it: a path that is not UTF-8 round-trips (os.fsencode).
    py::object file = py::reinterpret_steal<py::object>(
        PyUnicode_DecodeFSDefaultAndSize(e.file().data(), static_cast<Py_ssize_t>(e.file().size())));
    if (!file) throw py::error_already_set();
    raise(g_data_error, e.what(), {{"file", file}, {"line", py::int_(e.line())}});
  } catch (const NumericError& e) {
    raise(g_numeric_error, e.what());
  } catch (const InvalidArgument& e) {  // ModelError included
    raise(g_invalid_argument, e.what());
  } catch (const UnknownLandmark& e) {
    raise(g_unknown_landmark, e.what(), {{"id", py::int_(e.id())}});
  } catch (const Error& e) {
    raise(g_error, e.what());
  } catch (const std::invalid_argument& e) {  // from pybind11's own argument conversions
    raise(g_invalid_argument, e.what());
  }
}

}  // namespace

void bindErrors(py::module_& m) {
  g_error = newException(m, "Error", py::make_tuple(py::handle(PyExc_Exception)),
                         "Base of every error the seif library reports; str() is the C++ message.");
  const auto base = py::handle(g_error);
  g_data_error = newException(
      m, "DataError", py::make_tuple(base),
      "Malformed input (seif::DataError): the message reads 'file:line: what is wrong'; the "
      "attributes `file` (str) and `line` (int, 0 when the error has no line) name the place.");
  g_numeric_error = newException(
      m, "NumericError", py::make_tuple(base),
      "A numerical failure inside a filter (seif::NumericError), naming the step and landmark.");
  g_invalid_argument = newException(
      m, "InvalidArgument", py::make_tuple(base, py::handle(PyExc_ValueError)),
      "An invalid argument (seif::InvalidArgument, seif::ModelError): a bad filter spec, "
      "option name, model parameter or input type. Also a ValueError.");
  g_unknown_landmark = newException(
      m, "UnknownLandmark", py::make_tuple(base, py::handle(PyExc_LookupError)),
      "A landmark id that is not in the filter's map (seif::UnknownLandmark; attribute `id`). Also a LookupError.");
  py::register_exception_translator(&translate);
}

}  // namespace seif::python
