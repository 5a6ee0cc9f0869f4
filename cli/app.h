#pragma once

#include "cli/io/exit_code.h"

namespace scanplan::cli {

/// The whole command-line application; main() only forwards to it.
int run(int argc, char** argv);

}  // namespace scanplan::cli
