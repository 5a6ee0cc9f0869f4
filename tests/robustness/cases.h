#pragma once
// The robustness catalogue: hand-written cases by class (cases.cpp) and the cases generated from
// the job's key list (generated.cpp). tests/robustness/README.md says how to add one.

#include <initializer_list>
#include <string>
#include <vector>

#include "tests/robustness/runner.h"

namespace scanplan::robustness {

std::vector<Case> reportedCases();    // the problems first reported against the CLI
std::vector<Case> fileCases();        // truncated, garbage, special and misplaced files
std::vector<Case> pathCases();        // unicode and odd paths, output folders
std::vector<Case> commandCases();     // every command's own arguments
std::vector<Case> generatedCases();   // every numeric key of the job × hostile values
std::vector<Case> modelLimitCases();  // users' files, unmodelled input, estimates, causes

/// Helpers shared by the case files (defined in cases.cpp).
Case meshFileCase(const std::string& name, InputFile file, std::vector<int> exits = {4});
// The cases of several groups, in order.
std::vector<Case> concat(std::initializer_list<std::vector<Case>> parts);
Case trajectoryFileCase(const std::string& name, InputFile file, std::vector<int> exits = {4});
std::string trajectoryCell(std::string csv, int column, const std::string& value);
const std::string& offText();
const std::string& plyText();
std::string aliasBombText();
std::string nestedText(int depth);

/// Every case, in a stable order.
std::vector<Case> allCases();

}  // namespace scanplan::robustness
