#pragma once
// The scannability certificate after the simulation (docs/design.md §11): every area sample of the
// part is covered by the simulated cloud, or it says why not — scannable but missed, facing the
// table, occluded, no standoff fits the housing, or out of the arm's reach. The reasons come
// from the automatic scan's classification of its (coarser) evaluation samples: a sample not
// covered takes the class of the nearest evaluation sample.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <scanplan/pipeline/auto_scan.h>
#include <scanplan/scanner/area_coverage.h>

namespace scanplan::pipeline {

enum class CoverageClass : std::uint8_t {
  kCovered = 0,
  kMissed = 1,      ///< scannable, not covered
  kFacesTable = 2,  ///< faces the table or lies on it
  kOccluded = 3,    ///< no free line of sight for the laser and a camera within the incidence limit
  kNoStandoff = 4,  ///< no standoff in the depth window fits the housing
  kOutOfReach = 5,  ///< every pass that sees it is out of the arm's reach
};
inline constexpr std::size_t kCoverageClasses = 6;
/// "covered", "scannable_not_covered", "faces_table", "occluded", "no_standoff", "out_of_reach".
const char* coverageClassName(CoverageClass c);
/// The same in words for pictures and legends: "covered", "scannable, not covered", "faces the
/// table", "occluded", "no standoff fits the housing", "out of the arm's reach".
const char* coverageClassWords(CoverageClass c);
/// The class's colour in every picture (sRGB; Okabe-Ito, colour-blind safe): covered green,
/// missed orange, faces the table grey, occluded blue, no standoff purple, out of reach
/// vermilion.
std::array<std::uint8_t, 3> coverageClassColour(CoverageClass c);

struct Certificate {
  std::vector<CoverageClass> classes;               ///< per area sample
  std::array<double, kCoverageClasses> fraction{};  ///< of the area, per class
  double scannable_fraction = 0.0;    ///< covered or missed: the area some reachable pass sees
  double covered_of_scannable = 0.0;  ///< covered / scannable
};

/// Coverage of the scannable area against program time: after t[k] s, fraction[k] of the
/// scannable area (Certificate::scannable_fraction) has a point within the point spacing.
/// Ascending; at most 401 points (every 1/400 of the final coverage, and the end).
struct CoverageCurve {
  std::vector<double> t;         ///< s of program time
  std::vector<double> fraction;  ///< of the scannable area, non-decreasing
  /// The first time the curve reaches `share` of the scannable area; nullopt when it never does.
  std::optional<double> timeTo(double share) const;
};

/// The curve of `covered` (made with point times: AreaCoverage::first_time) over the samples
/// `certificate` calls scannable. Empty without first_time or scannable samples.
CoverageCurve coverageCurve(const Certificate& certificate, const scanner::AreaCoverage& covered);

/// The certificate of `sampling` (part frame) covered as `covered` says, with the reasons of
/// `report` (whose sampling is in the part frame too). Precondition: report.classes not empty.
Certificate certify(const scanner::AreaSampling& sampling,
                    const scanner::AreaCoverage& covered,
                    const AutoScanReport& report);

}  // namespace scanplan::pipeline
