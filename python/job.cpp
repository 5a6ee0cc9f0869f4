// Job files as the pipeline's problem: load_job(), Job and Problem.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <scanplan/config/job.h>
#include <scanplan/config/to_problem.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/pipeline/problem.h>

#include "python/arrays.h"
#include "python/bindings.h"
#include "python/objects.h"

namespace py = pybind11;

namespace scanplan::python {

namespace {

// `--set` texts of `overrides`: a dict (key → value: a string as written, anything else as
// JSON, which is YAML flow: True → true, [1, 2] → [1, 2]) or a list of "key=value" strings.
std::vector<std::string> overrideTexts(const py::object& overrides) {
  std::vector<std::string> texts;
  if (overrides.is_none()) return texts;
  if (!py::isinstance<py::dict>(overrides)) return overrides.cast<std::vector<std::string>>();
  const py::object dumps = py::module_::import("json").attr("dumps");
  for (const auto& [key, value] : overrides.cast<py::dict>()) {
    const std::string text = py::isinstance<py::str>(value) ? value.cast<std::string>()
                                                            : dumps(value).cast<std::string>();
    texts.push_back(py::str(key).cast<std::string>() + "=" + text);
  }
  return texts;
}

Job loadJob(const std::filesystem::path& file, const py::object& overrides) {
  return Job{
      std::make_shared<const config::JobSpec>(config::loadJob(file, overrideTexts(overrides)))};
}

Problem problemOf(const Job& job) {
  return Problem{std::make_shared<pipeline::ScanProblem>(config::toProblem(*job.spec)), job.spec};
}

// True keeps (or, for a problem that had none, cannot make) an optional stage; False drops it.
template <class T>
void setStage(std::optional<T>& stage, bool on, const char* name) {
  if (!on) {
    stage.reset();
  } else if (!stage) {
    throw InputError(std::string(name) +
                     ": the job turned it off; turn it on in the job (or with overrides) instead");
  }
}

void bindProblem(py::module_& m) {
  py::class_<Problem>(m, "Problem",
                      "The pipeline's problem (pipeline::ScanProblem), SI: the cell, the part, "
                      "the scan path request, the constraints and every stage's settings. "
                      "Values set here are checked when it is planned (InputError).")
      .def_property(
          "name", [](const Problem& p) { return p.problem->name; },
          [](Problem& p, const std::string& name) { p.problem->name = name; })
      .def_property(
          "planner", [](const Problem& p) { return p.problem->planning.method; },
          [](Problem& p, const std::string& method) { p.problem->planning.method = method; },
          "The planner: 'ray', 'dp' or 'ompl'.")
      .def_property(
          "refine", [](const Problem& p) { return p.problem->planning.refine; },
          [](Problem& p, bool on) { p.problem->planning.refine = on; },
          "NLopt refinement of each candidate path.")
      .def_property(
          "validate", [](const Problem& p) { return p.problem->validation.has_value(); },
          [](Problem& p, bool on) { setStage(p.problem->validation, on, "validate"); },
          "Validate the planned motion (limits, speeds, continuous collision check).")
      .def_property(
          "simulate", [](const Problem& p) { return p.problem->simulation.has_value(); },
          [](Problem& p, bool on) { setStage(p.problem->simulation, on, "simulate"); },
          "Simulate the scanner along the motion (cloud, coverage).")
      .def_property(
          "map_angle_step", [](const Problem& p) { return p.problem->map.angle_step; },
          [](Problem& p, double v) { p.problem->map.angle_step = v; },
          "rad: the configuration maps' table-angle step (map.angle_step_deg).")
      .def_property(
          "ray_horizon", [](const Problem& p) { return p.problem->planning.planners.ray.horizon; },
          [](Problem& p, int v) { p.problem->planning.planners.ray.horizon = v; },
          "Samples each ray holds its acceleration (planner.ray.horizon).")
      .def_property(
          "ray_cost_to_go",
          [](const Problem& p) { return p.problem->planning.planners.ray.cost_to_go; },
          [](Problem& p, bool v) { p.problem->planning.planners.ray.cost_to_go = v; },
          "Score each ray's end by a cost-to-go; False: the paper's plain rays.")
      .def_property(
          "k_omega", [](const Problem& p) { return p.problem->planning.objective.k_omega; },
          [](Problem& p, double v) { p.problem->planning.objective.k_omega = v; },
          "s²/rad²: the weight of the table's speed in J (Eq. 9).")
      .def_property(
          "k_alpha", [](const Problem& p) { return p.problem->planning.objective.k_alpha; },
          [](Problem& p, double v) { p.problem->planning.objective.k_alpha = v; },
          "s⁴/rad²: the weight of the table's acceleration in J (Eq. 9).")
      .def_property(
          "time_limit",
          [](const Problem& p) { return p.problem->planning.termination.time_limit_s; },
          [](Problem& p, double v) { p.problem->planning.termination.time_limit_s = v; },
          "s: each planner run's wall-clock budget (per branch); 0: none.")
      .def_property_readonly(
          "auto_scan", [](const Problem& p) { return p.problem->auto_scan.has_value(); },
          "The passes are planned by the automatic scan (scan.auto).")
      .def_property_readonly(
          "part_vertices",
          [](const Problem& p) { return matrixOf<double>(p.problem->part.vertices, p.problem); },
          "(V, 3) float64: the part mesh's vertices, part frame, m.")
      .def_property_readonly(
          "part_triangles",
          [](const Problem& p) { return matrixOf<int>(p.problem->part.triangles, p.problem); },
          "(F, 3) int32: the part mesh's triangles, vertex indices.");
}

}  // namespace

void bindJob(py::module_& m) {
  py::class_<Job>(m, "Job", "A job file, read and checked (config::JobSpec).")
      .def_property_readonly("name", [](const Job& j) { return j.spec->name; })
      .def_property_readonly("source", [](const Job& j) { return j.spec->source; })
      .def("problem", &problemOf,
           "The job as the pipeline's problem (config::toProblem), SI; a new one each call.");
  bindProblem(m);
  m.def("load_job", &loadJob, py::arg("path"), py::arg("overrides") = py::none(),
        "Reads and checks a job file. `overrides`: a dict {key: value} or a list of "
        "'key=value' strings, as `scanplan plan --set` (e.g. {'simulation.enabled': False}). "
        "Raises InputError naming the file, the key and the value.");
}

}  // namespace scanplan::python
