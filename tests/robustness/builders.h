#pragma once
// Makers of a case's input files (tests/robustness/README.md). Sources are written with the
// prefixes of a case's command line: "@src/…" the repository, "@fix/…" the shared fixtures.

#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "tests/robustness/runner.h"

namespace scanplan::robustness {

// The fixtures the cases read ("@fix/…": built once by the fixture test; "@src/…": the tree).
inline const std::string kLight = "@fix/light.yaml";
inline const std::string kTrajectory = "@fix/plan/trajectory.csv";
inline const std::string kProgram = "@fix/plan/programs/scan.v2";
inline const std::string kStl = "@src/data/parts/demo_housing.stl";
inline const std::string kRobot = "@src/data/robots/viper_s650.yaml";

/// "@src/x" → the repository's x, "@fix/x" → fixtureDir()/x; anything else as it is.
std::string expand(const std::string& text);

/// A file with exactly these bytes.
InputFile text(const std::string& name, std::string content);
/// A copy of `source` (with @src/@fix).
InputFile copyOf(const std::string& name, const std::string& source);
/// The first `fraction` of `source`'s bytes (0.5: half).
InputFile truncated(const std::string& name, const std::string& source, double fraction);
/// `bytes` seeded pseudo-random bytes.
InputFile garbage(const std::string& name, std::size_t bytes, unsigned seed = 17);
/// `source`'s text passed through `change`.
InputFile transformed(const std::string& name,
                      const std::string& source,
                      std::function<std::string(std::string)> change);
/// A FIFO nobody writes to, an empty folder, a symbolic link.
InputFile fifo(const std::string& name);
InputFile folder(const std::string& name);
InputFile symlinkTo(const std::string& name, const std::string& target);
/// A folder nobody may write to (0555; the case runs as nobody when root).
InputFile readOnlyFolder(const std::string& name);

/// KEY=VALUE edits of a job: the key as `--set` writes it (`scan.paths[0].height_mm`), the value
/// YAML text (`.nan`, `[1, 2]`, `{a: 1}`).
using Edits = std::vector<std::pair<std::string, std::string>>;
/// fix/light.yaml (the lightened demo) with `edits`.
InputFile jobWith(const std::string& name, const Edits& edits);
/// fix/resolved.yaml (every key written out, robot inline) with `edits`.
InputFile resolvedWith(const std::string& name, const Edits& edits);
/// A robot file: data/robots/viper_s650.yaml with `edits`.
InputFile robotWith(const std::string& name, const Edits& edits);
/// fix/light.yaml's text with `extra` appended (duplicate keys and other things a YAML tree
/// cannot hold).
InputFile jobAppended(const std::string& name, const std::string& extra);

/// The numeric leaves of fix/resolved.yaml, one per key (a list's first element stands for its
/// elements, the first robot link shape for the others): ("robot.dh[0].a_mm", "75"), ….
std::vector<std::pair<std::string, std::string>> numericKeys();
/// Keys whose value is a list of numbers ("table.eccentricity_mm").
std::vector<std::string> numericListKeys();

}  // namespace scanplan::robustness
