// confpack._confpack: the extension module under the Python package confpack (python/confpack/),
// which adds the dictionaries and the study tables around it.
#include <filesystem>

#include "core/build_info.hpp"
#include "core/interrupt.hpp"
#include "python/bindings.hpp"

PYBIND11_MODULE(_confpack, m) {
  using namespace confpack;
  namespace py = pybind11;
  m.doc() = "confpack's C++ library: packings, deposition, compaction with nscd or Bullet, analysis, sweeps";
  m.attr("__version__") = core::version();
  m.attr("__revision__") = core::sourceRevision();
  // The library's stop request is a KeyboardInterrupt in Python, as Ctrl-C is; the module itself
  // stops long work on Python's own signal check (run.cpp), never installing the library's handlers.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const core::Interrupted& e) {
      PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
    } catch (const std::filesystem::filesystem_error& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    }
  });
  python::bindPacking(m);
  python::bindRun(m);
  python::bindStudy(m);
}
