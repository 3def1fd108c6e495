// seif._core: the pybind11 module under the Python package seif (python/seif/__init__.py).
#include "bindings.hpp"

#include <seif/core/version.hpp>

namespace seif::python {

std::string reprOf(py::handle self, std::initializer_list<const char*> fields) {
  std::string out = py::str(py::type::handle_of(self).attr("__name__")).cast<std::string>() + "(";
  bool first = true;
  for (const char* f : fields) {
    if (!first) out += ", ";
    first = false;
    out += std::string(f) + "=" + py::repr(self.attr(f)).cast<std::string>();
  }
  return out + ")";
}

}  // namespace seif::python

PYBIND11_MODULE(_core, m) {
  namespace sp = seif::python;
  m.doc() =
      "C++ core of seif: SLAM with Sparse Extended Information Filters (EKF, EIF, SEIF, batch "
      "MAP). Import the package `seif`, which re-exports everything here.";
  m.attr("__version__") = seif::kVersion;
  sp::bindErrors(m);
  sp::bindCore(m);
  sp::bindFilters(m);
  sp::bindIo(m);
  sp::bindEval(m);
  sp::bindCheckpoints(m);
  sp::bindRunLoop(m);
}
