// plan() and Plan: pipeline::planScan() with its results as NumPy arrays and dicts, SI.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/pipeline/certificate.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/planner/validation.h>

#include "cli/commands/plan_folder.h"

#include "python/arrays.h"
#include "python/bindings.h"
#include "python/objects.h"
#include "python/run.h"

namespace py = pybind11;

namespace scanplan::python {

namespace {

// Runs `call(problem, options, report)` on a worker thread with `problem` carrying the run's
// cancel flag (the caller's copy of the problem, for this run only).
template <class Call>
auto runPipeline(pipeline::ScanProblem& problem,
                 const pipeline::PlanOptions& options,
                 const py::object& progress,
                 Call&& call) {
  decltype(call(problem, options, ReportFn{})) result;
  try {
    runInterruptibly(
        [&](const std::atomic<bool>& cancel, const ReportFn& report) {
          problem.planning.termination.cancel = &cancel;
          result = call(problem, options, report);
        },
        progress);
  } catch (...) {
    problem.planning.termination.cancel = nullptr;
    throw;
  }
  problem.planning.termination.cancel = nullptr;
  return result;
}

Plan plan(const Problem& problem,
          const std::optional<std::string>& planner,
          const py::object& progress,
          bool compare,
          int setups) {
  if (setups != 1 && setups != 2) {
    throw InputError("setups: " + std::to_string(setups) + " is not 1 or 2");
  }
  Plan out;
  out.start = std::chrono::steady_clock::now();
  out.job = problem.job;
  auto planned = std::make_shared<pipeline::ScanProblem>(*problem.problem);
  pipeline::PlanOptions options;
  if (planner) options.method = *planner;
  options.compare = compare;
  auto result = std::make_shared<const pipeline::ScanPlan>(
      runPipeline(*planned, options, progress,
                  [](const pipeline::ScanProblem& p, const pipeline::PlanOptions& o,
                     const ReportFn& report) { return pipeline::planScan(p, o, report); }));
  if (setups == 2 && result->trajectory &&
      result->status != pipeline::ScanStatus::kInvalidTrajectory) {
    out.second = std::make_shared<const pipeline::SecondSetupPlan>(runPipeline(
        *planned, options, progress,
        [&](const pipeline::ScanProblem& p, const pipeline::PlanOptions& o,
            const ReportFn& report) { return pipeline::planSecondSetup(p, *result, o, report); }));
  }
  out.plan = std::move(result);
  out.problem = std::move(planned);
  return out;
}

// The second setup's plan as a Plan of its own (sharing the first's), None without one.
py::object secondSetupOf(const Plan& p) {
  if (!p.second || !p.second->setup) return py::none();
  Plan second;
  second.plan = std::shared_ptr<const pipeline::ScanPlan>(p.second, &p.second->plan);
  second.problem = std::shared_ptr<const pipeline::ScanProblem>(p.second, &*p.second->problem);
  second.job = p.job;
  second.start = p.start;
  return py::cast(second);
}

// The setups: None with one; else the second setup's turn, gain, status and the coverage of both.
py::object setupsOf(const Plan& p) {
  if (!p.second) return py::none();
  const pipeline::SecondSetupPlan& s = *p.second;
  py::dict d;
  if (!s.setup) {
    d["status"] = "not_planned";
    d["reason"] = s.why_not;
    return d;
  }
  d["turn"] = s.setup->turn;
  d["gain"] = s.setup->gain;
  d["status"] = pipeline::scanStatusName(s.plan.status);
  if (s.combined) {
    py::dict c;
    c["area_fraction"] = s.combined->area_fraction;
    c["scannable_fraction"] = s.combined->scannable_fraction;
    c["covered_of_scannable"] = s.combined->covered_of_scannable;
    d["combined"] = c;
  }
  return d;
}

// Plan.write(dir): the files `scanplan plan -o DIR` writes, published atomically; returns the
// summary lines from the plan on.
std::string writePlan(const Plan& p, const std::filesystem::path& dir) {
  if (!p.job) throw InputError("write: this plan has no job to write (plan the job's problem)");
  const py::gil_scoped_release release;
  return cli::publishPlanFolder(dir, {*p.job, *p.problem, *p.plan, p.second.get(), p.start},
                                "write(dir)")
      .summary;
}

// (N, 8): t, table angle, j1..j6 of every trajectory sample (s, rad); None without one.
py::object trajectoryOf(const Plan& p) {
  if (!p.plan->trajectory) return py::none();
  const auto& samples = p.plan->trajectory->trajectory.samples;
  py::array_t<double> out({static_cast<py::ssize_t>(samples.size()), py::ssize_t{8}});
  auto a = out.mutable_unchecked<2>();
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const auto i = static_cast<py::ssize_t>(k);
    a(i, 0) = samples[k].t;
    a(i, 1) = samples[k].theta;
    for (int j = 0; j < 6; ++j) a(i, j + 2) = samples[k].q[j];
  }
  return out;
}

// (N, 4, 4): the target scanner pose of every trajectory sample, part frame, m.
py::object scannerPosesOf(const Plan& p) {
  if (!p.plan->trajectory) return py::none();
  const auto& samples = p.plan->trajectory->trajectory.samples;
  py::array_t<double> out(
      {static_cast<py::ssize_t>(samples.size()), py::ssize_t{4}, py::ssize_t{4}});
  auto a = out.mutable_unchecked<3>();
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Eigen::Matrix4d& m = samples[k].X_PS.matrix();
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) a(static_cast<py::ssize_t>(k), r, c) = m(r, c);
  }
  return out;
}

py::dict objectiveOf(const Plan& p) {
  const planner::ObjectiveTerms& t = p.plan->choice.terms;
  py::dict d;
  d["J"] = t.total;
  d["f"] = t.cost_f;
  d["omega"] = t.cost_omega;
  d["alpha"] = t.cost_alpha;
  d["min_f"] = t.min_f;
  d["max_abs_omega"] = t.max_abs_omega;
  d["max_abs_alpha"] = t.max_abs_alpha;
  return d;
}

py::object finiteOrNone(double v) {
  return std::isfinite(v) ? py::object(py::float_(v)) : py::none();
}

py::object validationOf(const Plan& p) {
  if (!p.plan->validation) return py::none();
  const planner::ValidationReport& v = *p.plan->validation;
  py::list violations;
  for (const planner::Violation& x : v.violations) {
    py::dict d;
    d["kind"] = planner::kindName(x.kind);
    d["what"] = x.what;
    d["t"] = x.t;
    d["t_start"] = x.t_start;
    d["t_end"] = x.t_end;
    d["value"] = x.value;
    d["limit"] = x.limit;
    d["note"] = x.note;
    violations.append(d);
  }
  py::dict d;
  d["valid"] = v.valid;
  d["violations"] = violations;
  d["min_distance"] = finiteOrNone(v.min_distance);
  d["min_distance_pair"] = v.min_distance_pair;
  d["min_distance_t"] = v.min_distance_t;
  d["min_cell_distance"] = finiteOrNone(v.min_cell_distance);
  d["min_cell_distance_pair"] = v.min_cell_distance_pair;
  d["min_cell_distance_t"] = v.min_cell_distance_t;
  d["min_self_distance"] = finiteOrNone(v.min_self_distance);
  d["min_self_distance_pair"] = v.min_self_distance_pair;
  d["min_self_distance_t"] = v.min_self_distance_t;
  d["proven_clearance"] = finiteOrNone(v.proven_clearance);
  d["poses"] = v.samples;
  return d;
}

py::object coverageOf(const Plan& p) {
  if (!p.plan->simulation) return py::none();
  const pipeline::SimulationRun& s = *p.plan->simulation;
  py::dict d;
  d["area_fraction"] = s.area.covered_fraction;
  d["faces_table_fraction"] = s.faces_table_fraction;
  d["points"] = s.cloud.points.size();
  d["profiles"] = s.frames;
  d["point_spacing"] = s.point_spacing;
  if (const auto& c = p.plan->certificate) {
    d["scannable_fraction"] = c->scannable_fraction;
    d["covered_of_scannable"] = c->covered_of_scannable;
    py::dict classes;
    for (std::size_t k = 0; k < pipeline::kCoverageClasses; ++k)
      classes[pipeline::coverageClassName(static_cast<pipeline::CoverageClass>(k))] =
          c->fraction[k];
    d["classes"] = classes;
  }
  return d;
}

// A field of every cloud point, viewed in place: (M, 3) for vectors, (M,) for scalars. `field`
// gives the field's first value in a point.
template <class T, class Field>
py::object cloudField(const Plan& p, Field field, int columns) {
  if (!p.plan->simulation) return py::none();
  const auto& points = p.plan->simulation->cloud.points;
  const auto m = static_cast<py::ssize_t>(points.size());
  std::vector<py::ssize_t> shape{m}, strides{static_cast<py::ssize_t>(sizeof(scanner::CloudPoint))};
  if (columns > 1) {
    shape.push_back(columns);
    strides.push_back(static_cast<py::ssize_t>(sizeof(T)));
  }
  if (points.empty()) return py::array_t<T>(shape);
  return viewOf<T>(field(points.front()), shape, strides, p.plan);
}

py::object mapsOf(const Plan& p) {
  const planner::ConfigMap& map = p.plan->prepared->map;
  return viewOf<float>(
      map.f.data(),
      {static_cast<py::ssize_t>(map.branches.size()), static_cast<py::ssize_t>(map.angles.size()),
       static_cast<py::ssize_t>(map.times.size())},
      {static_cast<py::ssize_t>(map.cellsPerBranch() * sizeof(float)),
       static_cast<py::ssize_t>(map.times.size() * sizeof(float)),
       static_cast<py::ssize_t>(sizeof(float))},
      p.plan);
}

void bindPlanArrays(py::class_<Plan>& c) {
  c.def_property_readonly("trajectory", &trajectoryOf,
                          "(N, 8) float64: t, table angle, j1..j6 per sample (s, rad; the table "
                          "angle unwrapped); None without a trajectory.")
      .def_property_readonly(
          "scanner_poses", &scannerPosesOf,
          "(N, 4, 4) float64: the target scanner pose per sample, part frame, m.")
      .def_property_readonly("maps", &mapsOf,
                             "(branches, angles, samples) float32: the configuration maps' f "
                             "(Eq. 6), a view of the plan's own buffer.")
      .def_property_readonly(
          "map_angles",
          [](const Plan& p) { return py::array_t<double>(py::cast(p.plan->prepared->map.angles)); },
          "(angles,) table angles of the maps, rad.")
      .def_property_readonly(
          "map_times",
          [](const Plan& p) { return py::array_t<double>(py::cast(p.plan->prepared->map.times)); },
          "(samples,) times of the maps, s.")
      .def_property_readonly(
          "map_branches",
          [](const Plan& p) {
            py::list names;
            for (const auto& b : p.plan->prepared->map.branches) names.append(b.words());
            return names;
          },
          "The IK branch of each map, in V+ words.")
      .def_property_readonly(
          "cloud",
          [](const Plan& p) {
            return cloudField<double>(
                p, [](const scanner::CloudPoint& point) { return point.p_P.data(); }, 3);
          },
          "(M, 3) float64: the simulated points, part frame, m (a view); None without simulation.")
      .def_property_readonly(
          "cloud_normals",
          [](const Plan& p) {
            return cloudField<double>(
                p, [](const scanner::CloudPoint& point) { return point.n_P.data(); }, 3);
          },
          "(M, 3) float64: each point's surface normal, towards the laser.")
      .def_property_readonly(
          "cloud_incidence",
          [](const Plan& p) {
            return cloudField<double>(
                p, [](const scanner::CloudPoint& point) { return &point.incidence; }, 1);
          },
          "(M,) float64: the angle between the laser ray and the normal, rad.")
      .def_property_readonly(
          "cloud_times",
          [](const Plan& p) {
            return cloudField<double>(
                p, [](const scanner::CloudPoint& point) { return &point.t; }, 1);
          },
          "(M,) float64: each point's acquisition time, s.");
}

}  // namespace

void bindPlan(py::module_& m) {
  py::class_<Plan> c(m, "Plan", "A plan (pipeline::ScanPlan) and its results, SI.");
  c.def_property_readonly(
       "status", [](const Plan& p) { return pipeline::scanStatusName(p.plan->status); },
       "'planned', 'no_path', 'no_executable_path' or 'invalid_trajectory'.")
      .def_property_readonly(
          "reason", [](const Plan& p) { return p.plan->reason; },
          "Why it is not planned (empty when planned).")
      .def_property_readonly("planned", [](const Plan& p) { return p.plan->planned(); })
      .def_property_readonly("objective", &objectiveOf,
                             "J of the final path (s) and its terms f, omega, alpha (Eq. 9).")
      .def_property_readonly(
          "dp_gap", [](const Plan& p) { return p.plan->choice.dpGap(); },
          "(J - J_dp) / J_dp against the exact DP on the chosen branch; None without DP.")
      .def_property_readonly("branch",
                             [](const Plan& p) -> py::object {
                               if (!p.plan->choice.solved()) return py::none();
                               const auto b = p.plan->choice.chosen.result.branch;
                               return py::str(p.plan->prepared->map.branches[b].words());
                             })
      .def_property_readonly("validation", &validationOf,
                             "valid, violations, the closest approaches (m, s) and where.")
      .def_property_readonly("coverage", &coverageOf,
                             "The simulation's coverage: area fraction, points, and with the "
                             "automatic scan the certificate's shares.")
      .def_property_readonly(
          "program",
          [](const Plan& p) {
            py::dict d;
            d["total"] = p.plan->program.total;
            d["scanning"] = p.plan->program.scanning;
            d["moving"] = p.plan->program.moving;
            d["moves"] = p.plan->program.moves;
            d["backed_off_moves"] = p.plan->program.detours;
            d["passes_table_held"] = p.plan->program.held;
            d["table_held_J"] = p.plan->program.held_cost;
            const auto& by = p.plan->program.moving_by_axis;
            d["moves_set_by_axis"] = py::array_t<double>(by.size(), by.data());
            return d;
          },
          "The program's time (s): total, scanning and moving between passes; moves, "
          "backed_off_moves, passes_table_held, table_held_J (s); moves_set_by_axis (7,): s of the "
          "moves set by each "
          "axis's limit "
          "(table, j1..j6).")
      .def_property_readonly("setups", &setupsOf,
                             "With setups=2: the second setup's turn, gain (share of the area "
                             "that faced the table), status and the coverage of both; else None.")
      .def_property_readonly("second_setup", &secondSetupOf,
                             "With setups=2: the second setup's Plan (the part turned over), or "
                             "None when there is none.")
      .def("write", &writePlan, py::arg("dir"),
           "Writes the files `scanplan plan -o DIR` writes (trajectory, programs, report.json, "
           "figures, cloud, replay; setup2/ with two setups), published atomically: DIR holds "
           "the old files or the new, never a mix. Refused when DIR is, holds or lies inside an "
           "input of the job. job.yaml is the job as loaded, with its overrides. Returns the "
           "summary lines the command prints from the plan on.");
  bindPlanArrays(c);
  m.def("plan", &plan, py::arg("problem"), py::arg("planner") = py::none(),
        py::arg("progress") = py::none(), py::arg("compare") = false, py::arg("setups") = 1,
        "Plans `problem` (pipeline::planScan: path, maps, table path, trajectory, validation, "
        "simulation). `planner`: 'ray', 'dp' or 'ompl' (default: the problem's). `progress`: "
        "None or a callable(stage, fraction), called on this thread. Releases the GIL; Ctrl-C "
        "cancels it and raises KeyboardInterrupt. `setups`: 2 also plans a second setup, the "
        "part turned onto another face it rests on (needs the automatic scan and the "
        "simulation; see Plan.setups, Plan.second_setup). 'No plan' is a status, not an "
        "exception; bad input raises InputError.");
}

}  // namespace scanplan::python
