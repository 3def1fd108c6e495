// Checkpoints from Python (filters/checkpoint.hpp): save_checkpoint / load / bytes, and
// pickling of every filter that can be saved (python/seif/__init__.py sets __reduce__).
#include "bindings.hpp"

#include <seif/eval/run.hpp>
#include <seif/filters/checkpoint.hpp>

namespace seif::python {

namespace {

/// The extras' values: bytes for the binary ones a run writes (its outputs, its associator, its association records),
/// whatever their content; str for others that are UTF-8 text, bytes for the rest.
py::dict valuesToPython(const std::map<std::string, std::string>& values) {
  py::dict out;
  for (const auto& [key, value] : values) {
    if (key == kRunOutputKey || key == kAssociatorKey || key == kRunAssociationsKey) {
      out[py::str(key)] = py::bytes(value);
      continue;
    }
    PyObject* text = PyUnicode_DecodeUTF8(value.data(), static_cast<Py_ssize_t>(value.size()), "strict");
    if (text != nullptr) {
      out[py::str(key)] = py::reinterpret_steal<py::object>(text);
    } else {
      PyErr_Clear();
      out[py::str(key)] = py::bytes(value);
    }
  }
  return out;
}

}  // namespace

void bindCheckpoints(py::module_& m) {
  m.def(
      "save_checkpoint",
      [](const SlamFilter& filter, const std::filesystem::path& path, std::uint64_t steps_consumed,
         const std::map<std::string, std::string>& values) {
        saveCheckpoint(filter, path, CheckpointExtras{steps_consumed, values});
      },
      py::arg("filter"), py::arg("path"), py::arg("steps_consumed") = 0,
      py::arg("values") = std::map<std::string, std::string>{},
      "Writes the filter's whole state (means, information store, active set, first estimates,\n"
      "counters, random state, models) to a versioned binary checkpoint, atomically. A loaded\n"
      "filter continues bit-identically. The batch MAP cannot be saved (InvalidArgument).");
  m.def(
      "load",
      [](const std::filesystem::path& path) { return load(path); }, py::arg("path"),
      "The filter saved in the checkpoint `path` (DataError, naming the file, for anything else).");
  m.def(
      "load_checkpoint",
      [](const std::filesystem::path& path) {
        CheckpointExtras extras;
        std::unique_ptr<SlamFilter> filter = load(path, &extras);
        return py::make_tuple(std::move(filter), extras.steps_consumed, valuesToPython(extras.values));
      },
      py::arg("path"),
      "(filter, steps_consumed, values): a checkpoint with the run position saved beside it; a value\n"
      "that is text is a str, one that is binary (a run's outputs, its associator) bytes.");
  m.def(
      "checkpoint_bytes", [](const SlamFilter& filter) { return py::bytes(saveToBytes(filter)); },
      py::arg("filter"), "The checkpoint of `filter` as bytes (what pickling stores).");
  m.def(
      "load_bytes",
      [](const py::bytes& bytes, const std::string& name) {
        return loadFromBytes(std::string_view(bytes), name);
      },
      py::arg("data"), py::arg("name") = "bytes", "The filter in checkpoint bytes (checkpoint_bytes).");
}

}  // namespace seif::python
