#pragma once

namespace scanplan::cli {

/// Exit codes, stable for scripts (docs/commands.md "Exit codes").
enum class ExitCode : int {
  kOk = 0,
  kInternal = 1,  ///< a bug: please report
  kUsage = 2,     ///< bad command line
  kNoPlan = 3,    ///< the input is valid but no feasible plan / pose exists
  kInput = 4,     ///< bad job, robot or mesh file, or a bad value
  kStop = 5,      ///< watch: the motion must stop now (--stop-distance-mm)
};

}  // namespace scanplan::cli
