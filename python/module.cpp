// The Python module `scanplan`: the library's pipeline in process, SI units, NumPy arrays
// (docs/python.md).
#include <pybind11/pybind11.h>

#include "python/bindings.h"

PYBIND11_MODULE(scanplan, m) {
  m.doc() =
      "scanplan: scanning path planning for a 6-axis arm with a laser line scanner and a rotary "
      "table. The same library the scanplan command runs, in SI units (m, rad, s), with NumPy "
      "arrays in and out. See docs/python.md.";
  scanplan::python::bindErrors(m);
  scanplan::python::bindJob(m);
  scanplan::python::bindRobot(m);
  scanplan::python::bindPlan(m);
}
