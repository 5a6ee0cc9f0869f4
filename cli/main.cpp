#include "cli/app.h"
#include "cli/io/output.h"

int main(int argc, char** argv) {
  scanplan::cli::installInterruptHandler();  // before any thread starts
  return scanplan::cli::run(argc, argv);
}
