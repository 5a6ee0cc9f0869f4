#pragma once

namespace scanplan::cli {

/// Exit codes, stable for scripts.
enum class ExitCode : int {
  kOk = 0,
  kInternal = 1,   ///< a bug: please report
  kUsage = 2,      ///< bad command line
  kInput = 3,      ///< bad job, robot or mesh file, or a bad value
  kNoPlan = 4,     ///< the input is valid but no feasible plan / pose exists
};

/// The whole command-line application; main() only forwards to it.
int run(int argc, char** argv);

}  // namespace scanplan::cli
