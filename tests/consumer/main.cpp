// Uses the installed scanplan: loads a job file (scanplan::config), plans it with planScan()
// (scanplan::pipeline) and checks the result: planned, validated, one joint vector per path
// sample, and FK of each lands the flange on the path (the 7-DOF chain). Run: consumer JOB.
#include <algorithm>
#include <cstdio>
#include <exception>

#include <scanplan/config/to_problem.h>
#include <scanplan/pipeline/plan_scan.h>

int main(int argc, char** argv) {
  if (argc != 2) return std::fprintf(stderr, "usage: consumer JOB\n"), 2;
  try {
    using namespace scanplan;
    const config::JobSpec job = config::loadJob(argv[1], {"simulation.enabled=false"});
    const pipeline::ScanProblem problem = config::toProblem(job);
    const pipeline::ScanPlan plan = pipeline::planScan(problem);
    if (!plan.planned()) return std::fprintf(stderr, "no plan: %s\n", plan.reason.c_str()), 1;
    const auto& samples = plan.trajectory->trajectory.samples;
    const auto& path = plan.prepared->path.path.samples;
    double error_max = 0.0;  // m
    for (std::size_t k = 0; k < samples.size() && k < path.size(); ++k) {
      const auto X_BF = problem.cell.robot.fk(samples[k].q);
      const auto want = problem.cell.flangeTarget(samples[k].theta, path[k].X_PS);
      error_max = std::max(error_max, (X_BF.matrix() - want.matrix()).norm());
    }
    const bool ok = plan.validation && plan.validation->valid && samples.size() == path.size() &&
                    error_max < 1e-6;
    std::printf("job %s: %s, %zu samples on %s, J = %.3f s, validation %s, max FK error %.1e\n",
                job.name.c_str(), ok ? "planned" : "WRONG", samples.size(),
                plan.prepared->map.branches[plan.choice.chosen.result.branch].words().c_str(),
                plan.choice.terms.total, plan.validation->valid ? "valid" : "INVALID", error_max);
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 1;
  }
}
