#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/robot_model.h>

namespace scanplan::collision {

/// Eq. 8 thresholds for one pair of bodies: f_C = 0 below d_low, 1 at and above d_high (m).
struct PairThresholds {
  double d_low = 0.005;
  double d_high = 0.030;
  double gamma = 1.0;
};

/// A job's pair rule, applied in order after the default pair set. Patterns: a body name, a
/// glob (`link*`, `*`), or a group (`robot`: base and links; `obstacles`). A rule matches a
/// pair when its two patterns match the two bodies in either order.
struct PairRule {
  enum class Action { kSet, kExclude, kInclude };
  std::string a;
  std::string b;
  Action action = Action::kSet;
  double d_low = -1.0;   ///< m; negative: keep the value in force
  double d_high = -1.0;  ///< m; negative: keep
  double gamma = -1.0;   ///< negative: keep
};

/// How the configuration maps see robot link meshes.
enum class LinkMeshes {
  kAuto,    ///< per link: a cylinder about its own joint axis where that stands within
            ///< piece_margin of the mesh, else its hull where that stands within
            ///< max_hull_margin, else its convex pieces where they fit piece_margin and
            ///< max_pieces, else its mesh
  kPieces,  ///< a cylinder about the joint axis as kAuto, else their convex pieces
            ///< (collision/link_standin.h), whatever their margin
  kHull,    ///< as their convex hulls: fast, conservative by each hull's margin (MapHull)
  kExact,   ///< as the meshes themselves: exact, slow for heavy meshes
};

struct ClearanceConfig {
  PairThresholds defaults;
  std::vector<PairRule> rules;
  LinkMeshes link_meshes = LinkMeshes::kAuto;
  /// kAuto: the largest margin (m) a link's hull may have to stand in for its mesh.
  double max_hull_margin = 0.002;
  /// kAuto, kPieces: the most (m) a link's convex pieces may stand outside its mesh, and how
  /// many pieces a mesh may take (collision/link_standin.h).
  double piece_margin = 0.002;
  std::size_t max_pieces = 128;
  /// A folder for the fitted pieces, one file per mesh keyed by its hash (standInKey): reused
  /// while the mesh and the settings stay, fitted again when they change. Empty: no cache.
  std::filesystem::path piece_cache;
  /// kHull: each hull simplified to at most this many vertices (collision/convex_hull.h
  /// simplifiedHull): GJK's cost grows with them, the margin shrinks.
  std::size_t hull_vertices = 32;
};

/// Which geometry a clearance query measures.
enum class Geometry {
  kExact,  ///< every body as given: validation, reports
  kMap,    ///< what the configuration maps measure: robot link meshes as hulls when
           ///< ClearanceConfig::link_meshes says so, everything else as given
};

/// A robot link with meshes and what stands in for them in the maps: its (simplified) convex
/// hull, or its convex pieces. For any body B outside the mesh, d(B, stand-in) ≤ d(B, mesh) ≤
/// d(B, stand-in) + margin: where the maps measure the stand-in (`used`) they may see a pair up
/// to `margin` closer than it is, never farther.
struct MapHull {
  int body = 0;  ///< index into Scene::bodies()
  std::size_t mesh_triangles = 0;
  std::size_t hull_vertices = 0;
  double hull_margin = 0.0;  ///< m, the hull's (collision/convex_hull.h hullMargin)
  /// The convex pieces, when the maps measure them (0: the hull or the mesh): how many, their
  /// vertices, and whether they were fitted within piece_margin and max_pieces.
  std::size_t pieces = 0;
  std::size_t piece_vertices = 0;
  bool pieces_fit = false;
  bool from_cache = false;   ///< the pieces came from ClearanceConfig::piece_cache
  double fit_seconds = 0.0;  ///< wall time fitting (or loading) the pieces
  double margin = 0.0;       ///< m, an upper bound for what the maps measure (0 for the mesh)
  bool used = false;         ///< the maps measure the hull or the pieces (else the mesh)
  /// The maps measure a cylinder about the link's own joint axis (round about it, within
  /// piece_margin: a flange), which turning that joint does not move; standin: its prism.
  bool cylinder = false;
  double cylinder_radius = 0.0;  ///< m
  double cylinder_length = 0.0;  ///< m
  /// Where `used`: what the maps measure, one closed convex mesh per hull or piece, in the
  /// link's frame (m); empty otherwise. For pictures of the stand-in over the mesh.
  std::vector<kinematics::TriangleMesh> standin;
};

/// What moves a body.
enum class BodyMotion { kWorld, kTable, kRobotLink, kScanner };

struct BodyInfo {
  std::string name;
  BodyMotion motion = BodyMotion::kWorld;
  int link = -1;  ///< robot link index 0..6, 6 for the scanner; -1 otherwise
  std::size_t shapes = 0;
  std::size_t triangles = 0;  ///< mesh triangles over all shapes
  /// The robot's own bodies: its base and links, and the scanner it carries.
  bool ridesOnTheArm() const {
    return motion == BodyMotion::kRobotLink || motion == BodyMotion::kScanner;
  }
};

struct PairInfo {
  int a = 0;
  int b = 0;
  PairThresholds thresholds;
};

namespace detail {
struct SceneGeometry;
}

/// The cell's collision scene, built once per job: FCL geometry for every body (BVH models,
/// OBBRSS, for meshes; FCL primitives for primitives) and the set of body pairs to check with
/// their thresholds (docs/design.md §4, seed §4.1). Immutable and safe to share across threads.
class Scene {
 public:
  /// Loads meshes and builds the geometry (and the hulls of robot link meshes for the maps).
  /// Throws InputError for a broken mesh or a rule that names no body.
  Scene(const kinematics::CellModel& cell, const ClearanceConfig& config);
  ~Scene();
  Scene(Scene&&) noexcept;
  Scene& operator=(Scene&&) noexcept;

  const kinematics::CellModel& cell() const { return cell_; }
  const std::vector<BodyInfo>& bodies() const { return bodies_; }
  const std::vector<PairInfo>& pairs() const { return pairs_; }
  /// True when both bodies of the pair ride on the arm (BodyInfo::ridesOnTheArm).
  bool armPair(std::size_t pair) const {
    return bodies_[static_cast<std::size_t>(pairs_[pair].a)].ridesOnTheArm() &&
           bodies_[static_cast<std::size_t>(pairs_[pair].b)].ridesOnTheArm();
  }
  /// Index of a body by name, -1 when absent.
  int bodyIndex(const std::string& name) const;

  /// World pose of every body frame for table angle θ (rad) and arm joints q (rad). A
  /// non-finite θ or q throws std::invalid_argument (so does every query built on this).
  void bodyPoses(double theta,
                 const kinematics::JointVector& q,
                 std::vector<Eigen::Isometry3d>& X_W) const;

  /// Robot links with meshes and their hulls (none for LinkMeshes::kExact), in body order.
  const std::vector<MapHull>& mapHulls() const { return map_hulls_; }

  const detail::SceneGeometry& geometry() const { return *geometry_; }

 private:
  /// InputError when the table overlaps the robot's base or a world obstacle where it stands.
  void refuseTableOverlaps() const;

  kinematics::CellModel cell_;
  std::vector<BodyInfo> bodies_;
  std::vector<PairInfo> pairs_;
  std::vector<MapHull> map_hulls_;
  std::unique_ptr<detail::SceneGeometry> geometry_;
};

}  // namespace scanplan::collision
