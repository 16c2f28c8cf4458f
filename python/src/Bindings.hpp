#pragma once
// One function per area of the module `rovermap` (python/src/Module.cpp calls them in order).

#include <pybind11/pybind11.h>

namespace rovermap::python {

namespace py = pybind11;

/// register() and its result.
void BindRegistration(py::module_& m);
/// read_points(), Camera, Frame and Sequence.
void BindIo(py::module_& m);
/// ElevationMap.
void BindElevationMap(py::module_& m);
/// Mapper and FrameResult.
void BindMapper(py::module_& m);
/// The submodule rovermap.eval.
void BindEval(py::module_& m);

}  // namespace rovermap::python
