#pragma once
// The Python module's parts (module.cpp puts them together): each binds one area of the library.

#include <pybind11/pybind11.h>

namespace scanplan::python {

/// scanplan.InputError (a ValueError) for scanplan::InputError, with the library's message.
void bindErrors(pybind11::module_& m);
/// load_job(), Job and Problem: job files as the pipeline's problem (config/, pipeline/problem.h).
void bindJob(pybind11::module_& m);
/// plan() and Plan: pipeline::planScan() with NumPy views of its results.
void bindPlan(pybind11::module_& m);
/// load_robot() and Robot: forward and inverse kinematics.
void bindRobot(pybind11::module_& m);

}  // namespace scanplan::python
