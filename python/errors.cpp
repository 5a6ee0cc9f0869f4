#include <pybind11/pybind11.h>

#include <scanplan/kinematics/error.h>

#include "python/bindings.h"

namespace py = pybind11;

namespace scanplan::python {

void bindErrors(py::module_& m) {
  py::register_exception<InputError>(m, "InputError", PyExc_ValueError).doc() =
      "Bad input: a job, robot or mesh file, or a value. The message names the file, the key, the "
      "value and what was expected, as the scanplan command prints it.";
}

}  // namespace scanplan::python
