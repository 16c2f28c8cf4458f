// `import rovermap`: the compiled part (rovermap._rovermap); python/rovermap/__init__.py
// re-exports it.
#include <pybind11/pybind11.h>

#include <exception>
#include <filesystem>

#include "config/ConfigError.hpp"
#include "io/IoError.hpp"
#include "python/src/Bindings.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_rovermap, m) {
  m.doc() =
      "rovermap: Zhang's iterative point matching, the mapping pipeline (registered trajectory, "
      "DEM, OctoMap, drift report) and the trajectory and DEM metrics, on numpy arrays";
  m.attr("__version__") = ROVERMAP_VERSION;  // the CMake project's, as rovermapConfigVersion
  // Errors carry over as the commands report them: a bad key or value is a ValueError naming
  // the key (the commands' usage error), a file that cannot be read or written an OSError
  // naming the file. std::invalid_argument is pybind11's ValueError already.
  py::register_exception_translator([](std::exception_ptr error) {
    try {
      if (error) std::rethrow_exception(error);
    } catch (const rovermap::config::ConfigError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const rovermap::io::IoError& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    } catch (const std::filesystem::filesystem_error& e) {
      PyErr_SetString(PyExc_OSError, e.what());  // what() names the path
    }
  });
  rovermap::python::BindRegistration(m);
  rovermap::python::BindIo(m);
  rovermap::python::BindElevationMap(m);
  rovermap::python::BindMapper(m);
  rovermap::python::BindEval(m);
}
