#include <scanplan/collision/scene.h>

#include <fnmatch.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <set>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include <scanplan/collision/chain_levers.h>
#include <scanplan/collision/convex_hull.h>
#include <scanplan/collision/fcl_geometry.h>
#include <scanplan/collision/link_standin.h>
#include <scanplan/collision/map_links.h>
#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::collision {
namespace {

// The cylinder margin is measured as the pieces' is (StandInOptions::tolerance).
constexpr double kCylinderTolerance = 2.5e-4;  // m

bool matches(const std::string& pattern, const BodyInfo& body) {
  if (pattern == "robot") return body.motion == BodyMotion::kRobotLink;
  if (pattern == "obstacles") {
    return (body.motion == BodyMotion::kWorld || body.motion == BodyMotion::kTable) &&
           body.name != "table" && body.name != "part";
  }
  return fnmatch(pattern.c_str(), body.name.c_str(), 0) == 0;
}

// Which rigid group a body belongs to for the default pair set: bodies of one group never move
// relative to each other (seed §4.1). The robot base is fixed in the world.
int rigidGroup(const BodyInfo& body) {
  switch (body.motion) {
    case BodyMotion::kWorld:
      return -1;
    case BodyMotion::kTable:
      return -2;
    case BodyMotion::kRobotLink:
      return body.link == 0 ? -1 : body.link;
    case BodyMotion::kScanner:
      return 6;
  }
  return -3;
}

bool pairByDefault(const BodyInfo& a, const BodyInfo& b) {
  const int ga = rigidGroup(a), gb = rigidGroup(b);
  if (ga == gb) return false;
  const bool a_arm = a.link >= 1, b_arm = b.link >= 1;  // the base (link 0) stays put
  if (!a_arm && !b_arm) {
    // Neither moves with the arm. What the table carries (the part, table-carried fixtures)
    // turns past what stands in the world (the robot base, world obstacles): such a pair
    // depends on θ alone. The table itself turns about its own axis, into no new space.
    const auto carried = [](const BodyInfo& body) {
      return body.motion == BodyMotion::kTable && body.name != "table";
    };
    return (carried(a) && gb == -1) || (carried(b) && ga == -1);
  }
  if (a.link >= 0 && b.link >= 0 && std::abs(a.link - b.link) <= 1) return false;  // consecutive
  return true;
}

// Two bodies that can move relative to one another: of different rigid groups, apart from the
// table and what stands in the world (the table turns about its own axis, into no new space; an
// overlap at rest is refused by Scene::refuseTableOverlaps). Only such pairs are candidates, so
// that thousands of obstacles standing still cost nothing among themselves.
bool canMoveApart(const BodyInfo& a, const BodyInfo& b) {
  const int ga = rigidGroup(a), gb = rigidGroup(b);
  if (ga == gb) return false;
  const auto table = [](const BodyInfo& body) {
    return body.motion == BodyMotion::kTable && body.name == "table";
  };
  return !((table(a) && gb == -1) || (table(b) && ga == -1));
}

// A pair checked or not, and its thresholds.
struct Candidate {
  int a, b;
  bool enabled;
  PairThresholds t;
};

int bodyNamed(const std::vector<BodyInfo>& bodies, const std::string& name) {
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (bodies[i].name == name && bodies[i].motion == BodyMotion::kRobotLink) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

// Applies one rule to every candidate pair it matches; a rule that matches none is an input
// error.
void applyRule(const PairRule& rule,
               const std::vector<BodyInfo>& bodies,
               std::vector<Candidate>& candidates) {
  bool any = false;
  for (Candidate& cand : candidates) {
    const BodyInfo& A = bodies[static_cast<std::size_t>(cand.a)];
    const BodyInfo& B = bodies[static_cast<std::size_t>(cand.b)];
    if (!((matches(rule.a, A) && matches(rule.b, B)) ||
          (matches(rule.a, B) && matches(rule.b, A)))) {
      continue;
    }
    any = true;
    if (rule.action == PairRule::Action::kExclude) cand.enabled = false;
    if (rule.action == PairRule::Action::kInclude) cand.enabled = true;
    if (rule.d_low >= 0.0) cand.t.d_low = rule.d_low;
    if (rule.d_high >= 0.0) cand.t.d_high = rule.d_high;
    if (rule.gamma > 0.0) cand.t.gamma = rule.gamma;
  }
  if (!any) {
    throw InputError("constraints.clearance.pairs: rule [" + rule.a + ", " + rule.b +
                     "] matches no pair of bodies that can move relative to one another: "
                     "expected body names, globs, 'robot' or 'obstacles'");
  }
}

// The pairs to check: default pairs less the robot's allowed collisions, then the job's rules
// in order (a rule may include an allowed pair again).
std::vector<PairInfo> selectPairs(const std::vector<BodyInfo>& bodies,
                                  const ClearanceConfig& config,
                                  const std::vector<std::array<std::string, 2>>& allowed) {
  const int n = static_cast<int>(bodies.size());
  std::vector<Candidate> candidates;  // in the order of the pairs a < b
  for (int a = 0; a < n; ++a) {
    const BodyInfo& A = bodies[static_cast<std::size_t>(a)];
    for (int b = a + 1; b < n; ++b) {
      const BodyInfo& B = bodies[static_cast<std::size_t>(b)];
      if (canMoveApart(A, B)) candidates.push_back({a, b, pairByDefault(A, B), config.defaults});
    }
  }
  // Allowed pairs by exact name (not as rule patterns: a link may be named `robot` or hold glob
  // characters). A link without geometry is no body here: nothing to leave out.
  for (const auto& [name_a, name_b] : allowed) {
    int a = bodyNamed(bodies, name_a), b = bodyNamed(bodies, name_b);
    if (a < 0 || b < 0 || a == b) continue;
    if (a > b) std::swap(a, b);
    const auto it = std::lower_bound(candidates.begin(), candidates.end(), std::pair{a, b},
                                     [](const Candidate& c, const std::pair<int, int>& p) {
                                       return std::pair{c.a, c.b} < p;
                                     });
    if (it != candidates.end() && it->a == a && it->b == b) it->enabled = false;
  }
  for (const PairRule& rule : config.rules) applyRule(rule, bodies, candidates);
  std::vector<PairInfo> pairs;
  for (const Candidate& c : candidates) {
    if (!c.enabled) continue;
    if (!(c.t.d_low < c.t.d_high)) {
      throw InputError("constraints.clearance: pair " + bodies[static_cast<std::size_t>(c.a)].name +
                       " ↔ " + bodies[static_cast<std::size_t>(c.b)].name + ": d_low " +
                       std::to_string(toMm(c.t.d_low)) + " mm is not below d_high " +
                       std::to_string(toMm(c.t.d_high)) + " mm: expected d_low < d_high");
    }
    pairs.push_back({c.a, c.b, c.t});
  }
  return pairs;
}

// A convex shape's mesh (shape frame) in its body's frame.
kinematics::TriangleMesh inBody(const detail::CollisionShape& shape,
                                kinematics::TriangleMesh mesh) {
  for (Eigen::Vector3d& v : mesh.vertices) v = shape.X_BG * v;
  return mesh;
}

// A robot link as the maps measure it: each mesh shape replaced by its convex hull, simplified
// to at most `max_vertices` (a flat mesh, which has none, stays). `info` sums the meshes' triangles
// and hull vertices and takes the largest margin.
detail::BodyGeometry hullBody(const detail::BodyGeometry& body,
                              std::size_t max_vertices,
                              MapHull& info,
                              std::vector<kinematics::TriangleMesh>& meshes) {
  detail::BodyGeometry out;
  for (const detail::CollisionShape& shape : body.shapes) {
    const auto* model = dynamic_cast<const detail::MeshModel*>(shape.geometry.get());
    std::optional<kinematics::TriangleMesh> hull;
    kinematics::TriangleMesh mesh;
    if (model) {
      mesh = detail::meshOf(*model);
      hull = convexHull(mesh);
      if (hull) hull = simplifiedHull(*hull, max_vertices);
    }
    if (!hull) {
      out.shapes.push_back(shape);
      continue;
    }
    info.mesh_triangles += mesh.triangles.size();
    info.hull_vertices += hull->vertices.size();
    info.hull_margin = std::max(info.hull_margin, hullMargin(*hull, mesh).margin);
    out.shapes.push_back(detail::makeHullShape(shape, *hull));
    meshes.push_back(inBody(shape, *hull));
  }
  return out;
}

// A mesh's convex pieces: from the cache when it holds them for this mesh and these settings,
// else fitted (and written there).
StandIn piecesOf(const kinematics::TriangleMesh& mesh,
                 const ClearanceConfig& config,
                 MapHull& info) {
  StandInOptions options;
  options.margin = config.piece_margin;
  options.max_pieces = config.max_pieces;
  const std::string key = standInKey(mesh, options);
  const std::filesystem::path file =
      config.piece_cache.empty() ? std::filesystem::path() : config.piece_cache / (key + ".pieces");
  if (!file.empty()) {
    if (auto cached = loadStandIn(file, key)) {
      info.from_cache = true;
      return std::move(*cached);
    }
  }
  StandIn fitted = fitStandIn(mesh, options);
  if (!file.empty()) saveStandIn(file, key, fitted);
  return fitted;
}

// A robot link as convex pieces: each mesh shape's pieces, and its hulls (`hulls`, which hold
// every piece) as the gate a query passes first. Shapes that are not meshes stay.
detail::BodyGeometry piecesBody(const detail::BodyGeometry& body,
                                const detail::BodyGeometry& hulls,
                                const ClearanceConfig& config,
                                MapHull& info) {
  const auto start = std::chrono::steady_clock::now();
  detail::BodyGeometry out;
  info.pieces_fit = true;
  info.margin = 0.0;
  for (const detail::CollisionShape& shape : body.shapes) {
    const auto* model = dynamic_cast<const detail::MeshModel*>(shape.geometry.get());
    if (!model) {
      out.shapes.push_back(shape);
      continue;
    }
    const StandIn standin = piecesOf(detail::meshOf(*model), config, info);
    for (const kinematics::TriangleMesh& piece : standin.pieces) {
      out.shapes.push_back(detail::makeHullShape(shape, piece));
      info.standin.push_back(inBody(shape, piece));
    }
    info.pieces += standin.pieces.size();
    info.piece_vertices += standin.vertices;
    info.pieces_fit = info.pieces_fit && standin.fits;
    info.margin = std::max(info.margin, standin.margin);
  }
  out.gate = hulls.shapes;
  info.fit_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

// A line in a link's frame: a point on it and its unit direction.
struct Axis {
  Eigen::Vector3d o, u;
};

// The axis link k turns about (detail::ownJointAxis, as ChainLevers sees it); none for the base.
std::optional<Axis> ownAxis(const kinematics::RobotModel& robot, int k) {
  if (k < 1 || k > kinematics::kNumJoints) return std::nullopt;
  const auto [o, u] = detail::ownJointAxis(robot, k);
  return Axis{o, u};
}

// A link of one mesh that is round about its own joint's axis within piece_margin (a flange),
// as that cylinder: into `out`, true. Turning the joint does not move it, and its distances
// are closed forms against primitives, GJK on a cylinder against polytopes.
bool cylinderBody(const detail::BodyGeometry& body,
                  const Axis& axis,
                  const ClearanceConfig& config,
                  MapHull& info,
                  detail::BodyGeometry& out) {
  if (body.shapes.size() != 1) return false;
  const detail::CollisionShape& shape = body.shapes.front();
  const auto* model = dynamic_cast<const detail::MeshModel*>(shape.geometry.get());
  if (!model) return false;
  const Eigen::Isometry3d X_GB = shape.X_BG.inverse();
  const auto c = axisCylinder(detail::meshOf(*model), X_GB * axis.o, X_GB.linear() * axis.u,
                              kCylinderTolerance, config.piece_margin);
  if (!c || !(c->margin <= config.piece_margin)) return false;
  kinematics::Shape cylinder;
  cylinder.geometry = kinematics::Cylinder{c->radius, c->length};
  cylinder.X_BG = shape.X_BG * c->X_MC;
  out.shapes = {detail::makeCollisionShape(cylinder)};
  info.used = info.cylinder = true;
  info.margin = c->margin;
  info.cylinder_radius = c->radius;
  info.cylinder_length = c->length;
  info.standin = {inBody(shape, c->prism)};
  return true;
}

// What the maps measure for robot link `i` under the config: a cylinder about its joint's axis,
// its hull, its pieces or its mesh.
void chooseMapBody(const ClearanceConfig& config,
                   const std::optional<Axis>& axis,
                   detail::SceneGeometry& geometry,
                   MapHull& info) {
  const auto i = static_cast<std::size_t>(info.body);
  std::vector<kinematics::TriangleMesh> hull_meshes;
  detail::BodyGeometry hulls =
      hullBody(geometry.bodies[i], config.hull_vertices, info, hull_meshes);
  if (info.mesh_triangles == 0) return;
  detail::BodyGeometry round;
  if (axis && config.link_meshes != LinkMeshes::kHull &&
      cylinderBody(geometry.bodies[i], *axis, config, info, round)) {
    geometry.map_bodies[i] = std::move(round);
    return;
  }
  info.margin = info.hull_margin;
  if (config.link_meshes == LinkMeshes::kHull ||
      (config.link_meshes == LinkMeshes::kAuto && info.hull_margin <= config.max_hull_margin)) {
    info.used = true;
    info.standin = std::move(hull_meshes);
    geometry.map_bodies[i] = std::move(hulls);
    return;
  }
  detail::BodyGeometry pieces = piecesBody(geometry.bodies[i], hulls, config, info);
  info.used = config.link_meshes == LinkMeshes::kPieces || info.pieces_fit;
  if (info.used) {
    geometry.map_bodies[i] = std::move(pieces);
  } else {
    info.margin = 0.0;  // the mesh itself
    info.standin.clear();
  }
}

}  // namespace

Scene::Scene(const kinematics::CellModel& cell, const ClearanceConfig& config)
    : cell_(cell), geometry_(std::make_unique<detail::SceneGeometry>()) {
  const auto add = [&](std::string name, BodyMotion motion, int link,
                       const std::vector<kinematics::Shape>& shapes) {
    if (shapes.empty()) return;
    detail::BodyGeometry body;
    BodyInfo info{std::move(name), motion, link, shapes.size(), 0};
    for (const kinematics::Shape& shape : shapes) {
      body.shapes.push_back(detail::makeCollisionShape(shape));
      info.triangles += body.shapes.back().triangles;
    }
    if (bodyIndex(info.name) >= 0) {
      throw InputError("collision scene: two bodies are named '" + info.name +
                       "': expected unique names (robot links, scanner, table, part, obstacles)");
    }
    bodies_.push_back(std::move(info));
    geometry_->bodies.push_back(std::move(body));
  };

  const auto& robot = cell.robot.definition();
  for (int k = 0; k <= kinematics::kNumJoints; ++k) {
    const auto& link = robot.links[static_cast<std::size_t>(k)];
    const std::string fallback = k == 0 ? std::string("base") : "link" + std::to_string(k);
    add(link.name.empty() ? fallback : link.name, BodyMotion::kRobotLink, k, link.shapes);
  }
  add("scanner", BodyMotion::kScanner, 6, cell.scanner.body);

  kinematics::Shape table_shape;
  table_shape.geometry = kinematics::Cylinder{cell.table.radius, cell.table.height};
  table_shape.X_BG.translation() << 0.0, 0.0, -0.5 * cell.table.height;  // top at z = 0
  add("table", BodyMotion::kTable, -1, {table_shape});

  kinematics::Shape part_shape;
  part_shape.geometry = cell.part.mesh;
  part_shape.X_BG = cell.part.X_RP;
  add("part", BodyMotion::kTable, -1, {part_shape});

  for (const kinematics::Obstacle& o : cell.obstacles) {
    add(o.name, o.carrier == kinematics::Carrier::kTable ? BodyMotion::kTable : BodyMotion::kWorld,
        -1, o.shapes);
  }

  pairs_ = selectPairs(bodies_, config, cell.robot.definition().allowed_collisions);
  refuseTableOverlaps();

  geometry_->map_bodies = geometry_->bodies;
  if (config.link_meshes == LinkMeshes::kExact) return;
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    if (bodies_[i].motion != BodyMotion::kRobotLink) continue;
    MapHull info;
    info.body = static_cast<int>(i);
    chooseMapBody(config, ownAxis(cell.robot, bodies_[i].link), *geometry_, info);
    if (info.mesh_triangles > 0) map_hulls_.push_back(info);
  }
}

std::vector<MapHull> robotMapLinks(const kinematics::RobotModel& robot,
                                   const ClearanceConfig& config,
                                   const std::function<void(std::size_t, std::size_t)>& progress) {
  std::vector<MapHull> out;
  if (config.link_meshes == LinkMeshes::kExact) return out;
  detail::SceneGeometry geometry;
  for (const kinematics::Link& link : robot.definition().links) {
    detail::BodyGeometry body;
    for (const kinematics::Shape& shape : link.shapes)
      body.shapes.push_back(detail::makeCollisionShape(shape));
    geometry.bodies.push_back(std::move(body));
  }
  geometry.map_bodies = geometry.bodies;
  for (std::size_t i = 0; i < geometry.bodies.size(); ++i) {
    MapHull info;
    info.body = static_cast<int>(i);
    chooseMapBody(config, ownAxis(robot, static_cast<int>(i)), geometry, info);
    if (info.mesh_triangles > 0) out.push_back(info);
    if (progress) progress(i + 1, geometry.bodies.size());
  }
  return out;
}

Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

int Scene::bodyIndex(const std::string& name) const {
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    if (bodies_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

void Scene::bodyPoses(double theta,
                      const kinematics::JointVector& q,
                      std::vector<Eigen::Isometry3d>& X_W) const {
  // Always on (a few comparisons per pose): a NaN or infinite pose would reach FCL, whose GJK
  // asserts abort the process; callers validate their input, this keeps a slip from crashing.
  if (!std::isfinite(theta) || !q.allFinite()) {
    throw std::invalid_argument("collision::Scene: non-finite table angle or joint value");
  }
  X_W.resize(bodies_.size());
  const auto frames = cell_.robot.linkFrames(q);
  const Eigen::Isometry3d X_WR = cell_.table.X_WR(theta);
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    const BodyInfo& body = bodies_[i];
    switch (body.motion) {
      case BodyMotion::kWorld:
        X_W[i].setIdentity();
        break;
      case BodyMotion::kTable:
        X_W[i] = X_WR;
        break;
      case BodyMotion::kRobotLink:
        X_W[i] = cell_.X_WB * frames[static_cast<std::size_t>(body.link)];
        break;
      case BodyMotion::kScanner:
        X_W[i] = cell_.X_WB * frames[6] * cell_.scanner.X_FS;
        break;
    }
  }
}

// The table turns about its own axis into no new space, so no motion pair measures it against
// what stands still (the robot's base, world obstacles): an overlap there is a cell that cannot
// be built, refused here rather than planned and validated as clear.
void Scene::refuseTableOverlaps() const {
  const int table = bodyIndex("table");
  if (table < 0) return;
  std::vector<Eigen::Isometry3d> X_W;
  bodyPoses(0.0, kinematics::JointVector::Zero(), X_W);
  const auto t = static_cast<std::size_t>(table);
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    const BodyInfo& b = bodies_[i];
    const bool base = b.motion == BodyMotion::kRobotLink && b.link == 0;
    if (!base && b.motion != BodyMotion::kWorld) continue;
    const detail::ShapeDistance d = detail::bodyDistance(
        geometry_->bodies[t], X_W[t], geometry_->bodies[i], X_W[i], 1e-3, false, false);
    if (!d.penetrating) continue;
    throw InputError(
        base ? fmt::format("the table (table.axis, table.radius_mm, table.height_mm) overlaps "
                           "the robot's base '{}': expected the table clear of the robot; move "
                           "table.axis away from the robot or make the table smaller",
                           b.name)
             : fmt::format("the table (table.axis, table.radius_mm, table.height_mm) overlaps "
                           "the obstacle '{}', which stands in the world: expected the table to "
                           "turn clear of it; move the obstacle, or carry it on the table "
                           "(carrier: table)",
                           b.name));
  }
}

}  // namespace scanplan::collision
