#include "pipeline/certificate.h"

#include "scanner/scan_passes.h"

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

}  // namespace scanplan::pipeline
