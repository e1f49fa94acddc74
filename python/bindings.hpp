#pragma once
// What the binding files of the Python module share (python/*.cpp). The module wraps the C++
// libraries; it computes nothing itself: each function converts its arguments, calls the library
// without the GIL where the work is long, and converts the result. Errors are the library's own
// exceptions, translated by pybind11 (std::invalid_argument -> ValueError, std::runtime_error ->
// RuntimeError, std::bad_alloc -> MemoryError) or by module.cpp, with the messages the command
// line prints after "confpack CMD: error: ".
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>
#include <vector>

#include "analysis/analyze.hpp"
#include "core/packing.hpp"

namespace confpack::python {

namespace py = pybind11;
using namespace pybind11::literals;

/// A packing held by Python (confpack.Packing): the C++ packing, never changed after construction
/// (the numpy views of its grains rely on it), and the file it was read from, which the messages
/// about it name as the command line does.
struct PyPacking {
  core::Packing packing;
  std::string source;  ///< the path as given to read_packing; empty for a packing made in memory
};

/// A copy of `values` as a one-dimensional numpy array.
template <class T>
py::array_t<T> toArray(const std::vector<T>& values) {
  return py::array_t<T>(static_cast<py::ssize_t>(values.size()), values.data());
}

/// The profiles of an analysis as {file stem: {column: array}}, with the names of the CSV files
/// and columns that `confpack run` and `confpack analyze` write (analysis::writeProfiles).
py::dict profiles(const analysis::Analysis& a);

void bindPacking(py::module_& m);
void bindRun(py::module_& m);
void bindStudy(py::module_& m);

}  // namespace confpack::python
