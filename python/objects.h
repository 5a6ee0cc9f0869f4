#pragma once
// The objects the module hands to Python: each holds the library's data by shared_ptr, so NumPy
// views of it outlive neither it nor one another.

#include <chrono>
#include <memory>

#include <scanplan/config/job.h>
#include <scanplan/kinematics/robot_model.h>
#include <scanplan/pipeline/plan_scan.h>
#include <scanplan/pipeline/setups.h>

namespace scanplan::python {

struct Job {
  std::shared_ptr<const config::JobSpec> spec;
};

struct Problem {
  std::shared_ptr<pipeline::ScanProblem> problem;
  std::shared_ptr<const config::JobSpec> job;  ///< the job it came from
};

struct Plan {
  std::shared_ptr<const pipeline::ScanPlan> plan;
  std::shared_ptr<const pipeline::ScanProblem> problem;     ///< a copy, as planned
  std::shared_ptr<const config::JobSpec> job;               ///< the job the problem came from
  std::shared_ptr<const pipeline::SecondSetupPlan> second;  ///< with setups=2
  std::chrono::steady_clock::time_point start;              ///< when plan() began
};

struct Robot {
  std::shared_ptr<const kinematics::RobotModel> model;
};

}  // namespace scanplan::python
