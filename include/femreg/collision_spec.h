// femreg/collision_spec.h - what a scene says about collision (docs/theory/contact.md): the object
// pairs, the penalty and the rigid obstacles with their keyframed poses (their triangle
// surfaces are read by ReadTriangleSurface, femreg/io.h, or given in memory). femreg/collision.h
// detects and penalizes the contacts a spec describes.
#ifndef FEMREG_COLLISION_SPEC_H_
#define FEMREG_COLLISION_SPEC_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "femreg/field_table.h"
#include "femreg/io.h"  // ReadTriangleSurface, which obstacle meshes are read with
#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {

// A rigid pose at a frame; frames between keyframes interpolate (translation linearly,
// rotation by slerp), before the first / after the last hold it.
struct ObstacleKeyframe {
  int frame = 0;
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();  // axis * angle (rad)
};

struct ObstacleSpec {
  enum class Kind { kPlane, kBox, kMesh };
  // A mesh obstacle's triangle surface in memory, as ReadTriangleSurface reads a file's.
  struct Surface {
    Vertices vertices;
    Triangles triangles;
  };
  std::string name;
  Kind kind = Kind::kPlane;
  // Plane (in the obstacle frame): the solid side is behind `normal`.
  Eigen::Vector3d plane_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d plane_normal = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d box_size = Eigen::Vector3d::Ones();  // box centred at the obstacle origin
  std::string mesh_path;  // triangle surface (OBJ, ASCII or binary STL), outward normals
  // The surface given in memory instead (outward normals), used in place of mesh_path when
  // set: a program's own obstacle needs no file. A scene names a file, so WriteScene refuses
  // an obstacle with one (femreg/scene.h).
  std::optional<Surface> surface;
  double scale = 1.0;     // applied to the mesh's coordinates (the file's or `surface`'s)
  std::vector<std::string> objects;  // objects it collides with; empty = all
  std::vector<ObstacleKeyframe> keyframes;  // empty = identity pose
  std::optional<double> friction = std::nullopt;  // Coulomb coefficient against it; unset: CollisionSpec::friction
};

// An obstacle's own values beside its name, geometry (plane, box or mesh), objects and
// keyframes, which are read and written by hand.
template <>
struct OptionFields<ObstacleSpec> {
  static constexpr const char* kSection = "collision.obstacles";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = ObstacleSpec;
    v(&S::scale, FieldInfo("scale").Above(0).Doc("applied to the mesh file's coordinates"));
    v(&S::friction, FieldInfo("friction").AtLeast(0).Doc("Coulomb coefficient against it (unset: the collision's)"));
  }
};

// A pair of objects that may touch, with its own friction coefficient (unset: the collision's).
struct CollisionPair {
  std::string first, second;  // object names
  std::optional<double> friction = std::nullopt;  // its own coefficient; unset: the collision's
  bool operator==(const CollisionPair& o) const {
    return first == o.first && second == o.second && friction == o.friction;
  }
};

// A pair's own value beside its objects: {objects: [a, b], friction: mu}.
template <>
struct OptionFields<CollisionPair> {
  static constexpr const char* kSection = "collision.pairs";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    v(&CollisionPair::friction, FieldInfo("friction").AtLeast(0).Doc("Coulomb coefficient of the pair (unset: the collision's)"));
  }
};

struct CollisionSpec {
  std::vector<CollisionPair> pairs;  // object pairs; empty: every pair
  double stiffness = 1.0e4;  // k (N/m) per contact
  double distance = 0.002;   // D (m): contacts are detected within it; not a standoff
  // Registration: the penetration (m) a contact may keep. The contact multipliers are
  // updated between outer iterations (augmented Lagrangian), and a frame does not stop while
  // a contact is deeper than this, up to solver.max_outer_iterations.
  double tolerance = 2.0e-4;
  bool augmented = true;  // false: the bare penalty, zero at contact (penetration F / k)
  std::vector<ObstacleSpec> obstacles;
  // Coulomb friction (docs/theory/contact.md#friction): the coefficient mu of every pair and
  // obstacle (0: frictionless; a pair's and an obstacle's own override it), and the slip (m)
  // below which a contact sticks, where the friction force ramps up to mu times the normal
  // force.
  double friction = 0.0;
  double friction_slip = 1.0e-4;
  // The table's ranges (the pairs and obstacles are checked where they are read).
  bool IsValid(std::string* error) const;
};

// The scene's `collision:` keys; `pairs` (with their own friction) and `obstacles` are lists
// of entries, read and written by hand.
template <>
struct OptionFields<CollisionSpec> {
  static constexpr const char* kSection = "collision";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = CollisionSpec;
    v(&S::stiffness, FieldInfo("stiffness").Above(0).Doc("k (N/m) per contact"));
    v(&S::distance, FieldInfo("distance").Above(0).Doc("D (m): contacts are detected within it"));
    v(&S::tolerance, FieldInfo("tolerance").Above(0).Doc("registration: the penetration (m) a contact may keep"));
    v(&S::augmented, FieldInfo("augmented").Doc("augmented Lagrangian; false: the bare penalty"));
    v(&S::friction, FieldInfo("friction").AtLeast(0).Doc("Coulomb coefficient of every pair and obstacle"));
    v(&S::friction_slip, FieldInfo("friction_slip").Above(0).Doc("slip (m) below which a contact sticks"));
  }
};

// The resultant of the contact forces (N) between an object and another object or an obstacle,
// normal and friction parts together.
struct ContactForce {
  int object = 0;   // the object it acts on
  int other = 0;    // the other object (> object), or -1 - i for obstacle i
  int contacts = 0; // contacts carrying a normal force
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d friction = Eigen::Vector3d::Zero();  // the friction part of `force`
  bool obstacle() const { return other < 0; }
};

// The pose of a keyframed obstacle at `frame`.
Eigen::Isometry3d ObstaclePose(const std::vector<ObstacleKeyframe>& keyframes, double frame);

}  // namespace femreg

#endif  // FEMREG_COLLISION_SPEC_H_
