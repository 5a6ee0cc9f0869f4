// Uses the installed scanplan: loads a job (scanplan::config), builds its cell and checks
// FK(IK(X)) = X on one flange pose of the job's robot. Run: consumer JOB.
#include <algorithm>
#include <cstdio>
#include <exception>

#include "cli/config/job.h"
#include "kinematics/cell.h"

int main(int argc, char** argv) {
  if (argc != 2) return std::fprintf(stderr, "usage: consumer JOB\n"), 2;
  try {
    using namespace scanplan;
    const cli::JobSpec job = cli::loadJob(argv[1]);
    const kinematics::CellModel cell = cli::buildCell(job);
    kinematics::JointVector q;
    q << 0.1, -0.6, 1.5, 0.2, 0.7, 0.3;  // rad
    const Eigen::Isometry3d X_BF = cell.robot.fk(q);
    const auto solutions = cell.robot.ik(X_BF);
    double error_max = 0.0;
    for (const kinematics::IkSolution& s : solutions) {
      error_max = std::max(error_max, (cell.robot.fk(s.q).matrix() - X_BF.matrix()).norm());
    }
    std::printf("job %s: robot %s, flange at (%.4f, %.4f, %.4f) m, %zu IK solutions, "
                "max |FK(IK(X)) - X| = %.1e\n",
                job.name.c_str(), cell.robot.name().c_str(), X_BF.translation().x(),
                X_BF.translation().y(), X_BF.translation().z(), solutions.size(), error_max);
    return solutions.empty() || error_max > 1e-9 ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 1;
  }
}
