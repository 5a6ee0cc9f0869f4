#include <scanplan/scanner/scannability.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace scanplan::scanner {

namespace {

using Eigen::Vector3d;

constexpr double kPi = 3.141592653589793;
// Rays leave a sample this far off its surface, along n, so they do not hit its own triangle.
constexpr double kSurfaceOffset = 1e-5;
// Guards memory: a box finer than this many segments is a mistaken spacing, not a request.
constexpr double kMaxSegmentsPerBox = 1e6;

// One test segment through a housing box, scanner frame S, m.
struct Segment {
  Vector3d a;
  Vector3d b;
};

// A housing box with its test segments, in the order cast.
struct HousingBox {
  Eigen::AlignedBox3d box;
  std::vector<Segment> segments;
};

// What every sample's search shares; read-only during the parallel loop.
struct Search {
  const PartOnTable& scene;
  const ScannabilitySettings& settings;
  double cos_max = 1.0;
  std::vector<double> standoffs{};  // m, in the order tried
  double shortest_standoff = 0.0;   // m
  std::vector<HousingBox> housing{};
  Eigen::AlignedBox3d part_bounds{};
  Eigen::AlignedBox3d table_bounds{};
};

bool finite(const Vector3d& v) { return v.allFinite(); }

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("classifyScannability: " + what);
}

void validate(const ScannabilitySettings& s) {
  require(s.directions >= 1 && s.rolls >= 1 && s.standoffs >= 1,
          "directions, rolls and standoffs must be >= 1");
  require(std::isfinite(s.max_incidence) && s.max_incidence >= 0.0 && s.max_incidence <= 0.5 * kPi,
          "max_incidence must be finite and in [0, pi/2] rad");
  require(std::isfinite(s.window.z_min) && std::isfinite(s.window.z_max) && s.window.z_min > 0.0 &&
              s.window.z_min <= s.window.z_max,
          "the window must have finite 0 < z_min <= z_max");
  require(!s.cameras.empty() && std::all_of(s.cameras.begin(), s.cameras.end(), finite),
          "needs at least one camera centre, all finite");
  require(std::isfinite(s.housing_spacing) && s.housing_spacing > 0.0,
          "housing_spacing must be finite and > 0");
  for (const Eigen::AlignedBox3d& box : s.housing) {
    require(!box.isEmpty() && finite(box.min()) && finite(box.max()),
            "housing boxes must be non-empty and finite");
  }
}

// Grid intervals across an extent: the fewest with spacing ≤ `spacing` (none for a flat side).
double intervals(double extent, double spacing) {
  return extent > 0.0 ? std::ceil(extent / spacing) : 0.0;
}

// Segments along each axis of `box` on a grid across the other two: the 12 edges, then the rest
// of the faces, then the inside (a surface that meets the box mostly crosses its boundary).
HousingBox housingBox(const Eigen::AlignedBox3d& box, double spacing) {
  const Vector3d size = box.sizes();
  Vector3d n;
  for (int k = 0; k < 3; ++k) n[k] = intervals(size[k], spacing);
  const double count = (n[1] + 1) * (n[2] + 1) + (n[2] + 1) * (n[0] + 1) + (n[0] + 1) * (n[1] + 1);
  require(count <= kMaxSegmentsPerBox, "housing_spacing too small for the housing boxes");
  HousingBox out{box, {}};
  std::vector<double> rank;
  for (int a = 0; a < 3; ++a) {
    if (size[a] <= 0.0) continue;  // a flat box: its other axes' segments cover it
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    for (int i = 0; i <= static_cast<int>(n[b]); ++i) {
      for (int j = 0; j <= static_cast<int>(n[c]); ++j) {
        Vector3d p = box.min();
        if (n[b] > 0) p[b] += size[b] * i / n[b];
        if (n[c] > 0) p[c] += size[c] * j / n[c];
        Vector3d q = p;
        q[a] = box.max()[a];
        out.segments.push_back({p, q});
        const bool edge_i = i == 0 || i == static_cast<int>(n[b]);
        const bool edge_j = j == 0 || j == static_cast<int>(n[c]);
        // Inside, from the middle out. The order only changes how soon a hit is found, never
        // the answer.
        const double off = std::max(std::abs(i - 0.5 * n[b]) / std::max(n[b], 1.0),
                                    std::abs(j - 0.5 * n[c]) / std::max(n[c], 1.0));
        rank.push_back(edge_i && edge_j ? -2.0 : (edge_i || edge_j ? -1.0 : off));
      }
    }
  }
  std::vector<std::size_t> order(out.segments.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t x, std::size_t y) { return rank[x] < rank[y]; });
  std::vector<Segment> sorted;
  sorted.reserve(order.size());
  for (const std::size_t k : order) sorted.push_back(out.segments[k]);
  out.segments = std::move(sorted);
  return out;
}

// `count` standoffs evenly over [z_min, z_max] (the ends included when count ≥ 2), those nearest
// the middle first: the middle of the window is where the head is designed to measure.
std::vector<double> standoffs(const LaserWindow& w, int count) {
  const double mid = 0.5 * (w.z_min + w.z_max);
  if (count == 1) return {mid};
  std::vector<double> out;
  for (int j = 0; j < count; ++j) out.push_back(w.z_min + (w.z_max - w.z_min) * j / (count - 1));
  std::stable_sort(out.begin(), out.end(),
                   [mid](double x, double y) { return std::abs(x - mid) < std::abs(y - mid); });
  return out;
}

// Direction k of `count` on the cap of half-angle acos(cos_max) about n: a Fibonacci spiral,
// uniform in cos θ (so in area), k = 0 on the axis and the last on the rim.
Vector3d capDirection(const Vector3d& n, double cos_max, int k, int count) {
  if (count == 1 || k == 0) return n;
  const double golden_angle = kPi * (3.0 - std::sqrt(5.0));
  const double cos_t = 1.0 - (1.0 - cos_max) * k / (count - 1);
  const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
  const Vector3d t1 = n.unitOrthogonal();
  const Vector3d t2 = n.cross(t1);
  const double phi = golden_angle * k;
  return (cos_t * n + sin_t * (std::cos(phi) * t1 + std::sin(phi) * t2)).normalized();
}

// R_RS for the laser ray d (p → scanner) turned by ψ about it: z_S = −d, and at ψ = 0 x_S is R's
// z off d (the camera above the laser), R's x when d is vertical.
Eigen::Matrix3d headRotation(const Vector3d& d, double psi) {
  Vector3d x0 = Vector3d::UnitZ() - d.z() * d;
  if (x0.norm() < 1e-6) x0 = Vector3d::UnitX() - d.x() * d;
  x0.normalize();
  const Vector3d x = std::cos(psi) * x0 + std::sin(psi) * d.cross(x0);
  const Vector3d z = -d;
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = z.cross(x);
  R.col(2) = z;
  return R;
}

// How far the laser ray can travel from the sample along d before meeting anything, m
// (infinity when nothing within the window's far end).
double laserReach(const AreaSample& s, const Vector3d& d, const Search& search) {
  const Vector3d start = s.p + kSurfaceOffset * s.n;
  const auto hit = search.scene.cast(start, d, 2e-5, search.settings.window.z_max);
  return hit ? hit->distance : std::numeric_limits<double>::infinity();
}

// Some camera sees the sample from the head at X_RS within the incidence limit.
bool cameraSees(const AreaSample& s, const Eigen::Isometry3d& X_RS, const Search& search) {
  for (const Vector3d& c_S : search.settings.cameras) {
    const Vector3d C = X_RS * c_S;
    const Vector3d v = C - s.p;
    const double length = v.norm();
    // A hair of slack: a camera exactly on the limit counts.
    if (length <= 0.0 || s.n.dot(v) < search.cos_max * length - 1e-12) continue;
    if (search.scene.clear(s.p + kSurfaceOffset * s.n, C)) return true;
  }
  return false;
}

bool insideTable(const Vector3d& p, const TableTop& table) {
  return p.z() <= 0.0 && p.z() >= -table.height &&
         p.head<2>().squaredNorm() <= table.radius * table.radius;
}

// Inside the part: straight up from p the first part hit is a back face (its winding normal
// points up, along the ray).
bool insidePart(const Vector3d& p, const PartOnTable& scene) {
  const auto hit = scene.cast(p, Vector3d::UnitZ());
  if (!hit || !scene.onPart(*hit)) return false;
  const kinematics::TriangleMesh& m = scene.part();
  const Eigen::Vector3i& f = m.triangles[hit->triangle];
  const Vector3d& a = m.vertices[static_cast<std::size_t>(f[0])];
  const Vector3d normal = (m.vertices[static_cast<std::size_t>(f[1])] - a)
                              .cross(m.vertices[static_cast<std::size_t>(f[2])] - a);
  return normal.z() > 0.0;
}

// The box placed at X_RS meets the part or the table (see the header for what can slip through).
bool boxMeetsScene(const HousingBox& h,
                   const Eigen::Isometry3d& X_RS,
                   const PartOnTable& scene,
                   const Eigen::AlignedBox3d& part_bounds,
                   const Eigen::AlignedBox3d& table_bounds) {
  Eigen::AlignedBox3d placed;
  for (int k = 0; k < 8; ++k) {
    placed.extend(X_RS * h.box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k)));
  }
  // Far from both bodies' bounds: no ray can hit.
  if (!placed.intersects(part_bounds) && !placed.intersects(table_bounds)) {
    return false;
  }
  for (const Segment& seg : h.segments) {
    const Vector3d a = X_RS * seg.a;
    const Vector3d d = X_RS.linear() * (seg.b - seg.a);
    if (scene.cast(a, d, 0.0, d.norm())) return true;
  }
  const Vector3d centre = X_RS * h.box.center();
  return insideTable(centre, scene.table()) || insidePart(centre, scene);
}

bool housingFits(const Eigen::Isometry3d& X_RS, const Search& search) {
  return std::none_of(search.housing.begin(), search.housing.end(), [&](const HousingBox& h) {
    return boxMeetsScene(h, X_RS, search.scene, search.part_bounds, search.table_bounds);
  });
}

// Steps 2–5 of the header for one sample that does not face the table.
SampleClass classifySample(const AreaSample& s, const Search& search, Eigen::Isometry3d& witness) {
  const ScannabilitySettings& st = search.settings;
  bool seen = false;
  for (int k = 0; k < st.directions; ++k) {
    const Vector3d d = capDirection(s.n, search.cos_max, k, st.directions);
    // The laser segment does not depend on the roll: one cast gives every standoff's answer.
    const double reach = laserReach(s, d, search);
    if (reach <= search.shortest_standoff) continue;
    for (int j = 0; j < st.rolls; ++j) {
      Eigen::Isometry3d X_RS = Eigen::Isometry3d::Identity();
      X_RS.linear() = headRotation(d, 2.0 * kPi * j / st.rolls);
      for (const double standoff : search.standoffs) {
        if (standoff >= reach) continue;
        X_RS.translation() = s.p + standoff * d;
        if (!cameraSees(s, X_RS, search)) continue;
        seen = true;
        if (housingFits(X_RS, search)) {
          witness = X_RS;
          return SampleClass::kScannable;
        }
      }
    }
  }
  return seen ? SampleClass::kNoStandoff : SampleClass::kOccluded;
}

// The part's and the table's bounds, padded by 1 mm: the tessellation and Embree's float
// coordinates stray a little.
void sceneBounds(const PartOnTable& scene, Eigen::AlignedBox3d& part, Eigen::AlignedBox3d& table) {
  const Vector3d pad = Vector3d::Constant(1e-3);
  part = scene.part().bounds();
  part.extend(part.min() - pad).extend(part.max() + pad);
  const TableTop& top = scene.table();
  table = Eigen::AlignedBox3d(Vector3d(-top.radius, -top.radius, -top.height),
                              Vector3d(top.radius, top.radius, 0.0));
  table.extend(table.min() - pad).extend(table.max() + pad);
}

Search makeSearch(const PartOnTable& scene, const ScannabilitySettings& settings) {
  Search search{scene, settings};
  search.cos_max = std::cos(settings.max_incidence);
  search.standoffs = standoffs(settings.window, settings.standoffs);
  search.shortest_standoff = *std::min_element(search.standoffs.begin(), search.standoffs.end());
  for (const Eigen::AlignedBox3d& box : settings.housing) {
    search.housing.push_back(housingBox(box, settings.housing_spacing));
  }
  sceneBounds(scene, search.part_bounds, search.table_bounds);
  return search;
}

}  // namespace

const char* sampleClassName(SampleClass c) {
  switch (c) {
    case SampleClass::kScannable:
      return "scannable";
    case SampleClass::kFacesTable:
      return "faces_table";
    case SampleClass::kOccluded:
      return "occluded";
    case SampleClass::kNoStandoff:
      return "no_standoff";
    case SampleClass::kOutOfReach:
      return "out_of_reach";
  }
  return "unknown";
}

std::vector<SampleClass> classifyScannability(const AreaSampling& sampling,
                                              const PartOnTable& scene,
                                              const ScannabilitySettings& settings,
                                              std::vector<Eigen::Isometry3d>* witnesses) {
  validate(settings);
  std::vector<Eigen::Isometry3d> poses(witnesses ? sampling.samples.size() : 0,
                                       Eigen::Isometry3d::Identity());
  const Search search = makeSearch(scene, settings);
  const std::vector<std::uint8_t> faces = facesTable(sampling, Eigen::Isometry3d::Identity(),
                                                     settings.max_incidence, settings.window.z_max);
  std::vector<SampleClass> out(sampling.samples.size(), SampleClass::kFacesTable);
  // Samples differ widely in cost (one pose or all of them): small chunks balance the threads.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.size(), 8),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        Eigen::Isometry3d witness = Eigen::Isometry3d::Identity();
                        if (!faces[i])
                          out[i] = classifySample(sampling.samples[i], search, witness);
                        if (witnesses) poses[i] = witness;
                      }
                    });
  if (witnesses) *witnesses = std::move(poses);
  return out;
}

struct HousingCheck::Impl {
  const PartOnTable& scene;
  std::vector<HousingBox> boxes;
  Eigen::AlignedBox3d part_bounds, table_bounds;
};

HousingCheck::HousingCheck(const PartOnTable& scene,
                           const std::vector<Eigen::AlignedBox3d>& housing,
                           double spacing)
    : impl_(std::make_unique<Impl>(Impl{scene, {}, {}, {}})) {
  require(std::isfinite(spacing) && spacing > 0.0, "housing spacing must be finite and > 0");
  for (const Eigen::AlignedBox3d& box : housing) {
    require(!box.isEmpty() && finite(box.min()) && finite(box.max()),
            "housing boxes must be non-empty and finite");
    impl_->boxes.push_back(housingBox(box, spacing));
  }
  sceneBounds(scene, impl_->part_bounds, impl_->table_bounds);
}

HousingCheck::~HousingCheck() = default;

bool HousingCheck::fits(const Eigen::Isometry3d& X_RS) const {
  return std::none_of(impl_->boxes.begin(), impl_->boxes.end(), [&](const HousingBox& h) {
    return boxMeetsScene(h, X_RS, impl_->scene, impl_->part_bounds, impl_->table_bounds);
  });
}

}  // namespace scanplan::scanner
