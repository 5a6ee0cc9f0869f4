#include "cli/app.h"

int main(int argc, char** argv) { return scanplan::cli::run(argc, argv); }
