#include <scanplan/pipeline/certificate.h>

#include <algorithm>
#include <cmath>

#include <scanplan/scanner/scan_passes.h>

namespace scanplan::pipeline {

namespace {

CoverageClass fromSample(scanner::SampleClass c) {
  switch (c) {
    case scanner::SampleClass::kScannable:
      return CoverageClass::kMissed;
    case scanner::SampleClass::kFacesTable:
      return CoverageClass::kFacesTable;
    case scanner::SampleClass::kOccluded:
      return CoverageClass::kOccluded;
    case scanner::SampleClass::kNoStandoff:
      return CoverageClass::kNoStandoff;
    case scanner::SampleClass::kOutOfReach:
      return CoverageClass::kOutOfReach;
  }
  return CoverageClass::kMissed;
}

}  // namespace

const char* coverageClassName(CoverageClass c) {
  static constexpr const char* kNames[kCoverageClasses] = {
      "covered", "scannable_not_covered", "faces_table", "occluded", "no_standoff", "out_of_reach"};
  return kNames[static_cast<std::size_t>(c)];
}

const char* coverageClassWords(CoverageClass c) {
  static constexpr const char* kWords[kCoverageClasses] = {
      "covered",  "scannable, not covered",       "faces the table",
      "occluded", "no standoff fits the housing", "out of the arm's reach"};
  return kWords[static_cast<std::size_t>(c)];
}

std::array<std::uint8_t, 3> coverageClassColour(CoverageClass c) {
  static constexpr std::array<std::array<std::uint8_t, 3>, kCoverageClasses> kColours{{
      {0, 158, 115},    // covered: green
      {230, 159, 0},    // scannable, not covered: orange
      {150, 150, 150},  // faces the table: grey
      {0, 114, 178},    // occluded: blue
      {204, 121, 167},  // no standoff fits the housing: purple
      {213, 94, 0},     // out of reach: vermilion
  }};
  return kColours[static_cast<std::size_t>(c)];
}

Certificate certify(const scanner::AreaSampling& sampling,
                    const scanner::AreaCoverage& covered,
                    const AutoScanReport& report) {
  Certificate out;
  out.classes.resize(sampling.samples.size(), CoverageClass::kCovered);
  const scanner::SampleIndex index(report.sampling);
  std::array<std::size_t, kCoverageClasses> count{};
  for (std::size_t i = 0; i < sampling.samples.size(); ++i) {
    if (!covered.covered[i])
      out.classes[i] = fromSample(report.classes[index.nearest(sampling.samples[i].p)]);
    ++count[static_cast<std::size_t>(out.classes[i])];
  }
  const double n = std::max<double>(1.0, static_cast<double>(sampling.samples.size()));
  for (std::size_t c = 0; c < kCoverageClasses; ++c)
    out.fraction[c] = static_cast<double>(count[c]) / n;
  out.scannable_fraction = out.fraction[0] + out.fraction[1];
  out.covered_of_scannable =
      out.scannable_fraction > 0.0 ? out.fraction[0] / out.scannable_fraction : 0.0;
  return out;
}

std::optional<double> CoverageCurve::timeTo(double share) const {
  for (std::size_t k = 0; k < t.size(); ++k)
    if (fraction[k] >= share - 1e-12) return t[k];
  return std::nullopt;
}

CoverageCurve coverageCurve(const Certificate& certificate, const scanner::AreaCoverage& covered) {
  CoverageCurve curve;
  if (covered.first_time.size() != certificate.classes.size()) return curve;
  std::vector<double> first;
  std::size_t scannable = 0;
  for (std::size_t i = 0; i < certificate.classes.size(); ++i) {
    const CoverageClass c = certificate.classes[i];
    if (c != CoverageClass::kCovered && c != CoverageClass::kMissed) continue;
    ++scannable;
    if (std::isfinite(covered.first_time[i])) first.push_back(covered.first_time[i]);
  }
  if (scannable == 0 || first.empty()) return curve;
  std::sort(first.begin(), first.end());
  constexpr std::size_t kPoints = 400;
  const double n = static_cast<double>(scannable);
  for (std::size_t k = 1; k <= kPoints; ++k) {
    const std::size_t i = std::max<std::size_t>(1, first.size() * k / kPoints) - 1;
    if (!curve.t.empty() && first[i] <= curve.t.back()) {
      curve.fraction.back() = static_cast<double>(i + 1) / n;
      continue;
    }
    curve.t.push_back(first[i]);
    curve.fraction.push_back(static_cast<double>(i + 1) / n);
  }
  return curve;
}

}  // namespace scanplan::pipeline
