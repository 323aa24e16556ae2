// femreg/collision.h - contacts between objects and with rigid obstacles (seed Section 5):
// exact triangle-triangle closest points, an AABB hierarchy over each surface, a broad and a
// coarse-to-fine narrow phase, and the penalty E = 1/2 k delta^2 of seed eq. 15.
//
// Sign conventions. A contact ties a point p_a on a surface triangle of object a (a
// barycentric combination of its 3 vertices) to a point p_b on object b or on an obstacle.
// n is the unit contact normal, pointing from b towards a (the direction that separates
// them), held fixed between detections. The signed gap is g = n . (p_a - p_b): it equals the
// distance |p_a - p_b| while the surfaces have not crossed and is negative once they have
// (p_a inside b). With D > 0 the proximity threshold, the penetration is delta = D - g; the
// contact is active while delta > 0 and its energy is E = 1/2 k delta^2, whose force on p_a
// is f_a = -dE/dp_a = k delta n (away from b): seed eq. 15 with its delta = d - D = -delta.
// "Deepest penetration" below is max delta; delta < D means the surfaces have not crossed.
#ifndef FEMREG_COLLISION_H_
#define FEMREG_COLLISION_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "femreg/forward.h"
#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {

// ---------------------------------------------------------------------------------------
// Exact closest-point queries.

// Closest point of triangle (a, b, c) to p; *barycentric (may be null) gets its weights.
Eigen::Vector3d TriangleClosestPoint(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                       const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                       Eigen::Vector3d* barycentric = nullptr);

// Closest points p0 + s (p1 - p0) and q0 + t (q1 - q0) of two segments, s, t in [0, 1];
// parallel and degenerate (point-like) segments included. Returns the distance.
double ClosestSegmentSegment(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                             const Eigen::Vector3d& q0, const Eigen::Vector3d& q1, double* s,
                             double* t);

struct TrianglePairDistance {
  double distance = 0.0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero(), q = Eigen::Vector3d::Zero();  // on T1, on T2
  Eigen::Vector3d bary_p = Eigen::Vector3d(1, 0, 0), bary_q = Eigen::Vector3d(1, 0, 0);
  bool intersecting = false;  // the triangles cut each other (distance 0, p = q on the cut)
};

// Closest points of two triangles t1[0..2], t2[0..2]: an edge of one through the other's
// face (intersection), else the best of the 6 vertex-face and 9 edge-edge pairs; coplanar,
// parallel and touching triangles included.
TrianglePairDistance TriangleTriangleDistance(const Eigen::Vector3d* t1, const Eigen::Vector3d* t2);

// ---------------------------------------------------------------------------------------
// AABB hierarchy over the triangles of a surface.

class AabbTree {
 public:
  struct Node {
    Eigen::AlignedBox3d box;
    int left = -1, right = -1;  // children (both -1 at a leaf)
    int triangle = -1;          // leaf: the triangle (row of the triangle list)
  };

  // Top-down build (median split on the longest axis of the centroids). x: #V by 3,
  // triangles: #F by 3 rows of x. Call again after a topology change.
  void Build(const Vertices& x, const Triangles& triangles);
  // Recomputes the boxes bottom-up for moved vertices (same topology).
  void Refit(const Vertices& x);
  // Triangle pairs (this, other) whose boxes come within `margin` of each other, found by
  // descending both trees from the roots (coarse to fine).
  void Overlapping(const AabbTree& other, double margin,
                   std::vector<std::pair<int, int>>* pairs) const;
  // Triangles whose box comes within `margin` of `box`.
  void Overlapping(const Eigen::AlignedBox3d& box, double margin, std::vector<int>* triangles) const;

  bool empty() const { return nodes_.empty(); }
  int num_nodes() const { return static_cast<int>(nodes_.size()); }
  const Eigen::AlignedBox3d& bounds() const { return nodes_.front().box; }
  const std::vector<Node>& nodes() const { return nodes_; }
  const Triangles& triangles() const { return triangles_; }

 private:
  int BuildRange(const Vertices& x, std::vector<int>* order, int begin, int end);
  std::vector<Node> nodes_;  // children after their parent, so a reverse sweep refits
  Triangles triangles_;
};

// ---------------------------------------------------------------------------------------
// Scene description.

// A rigid pose at a frame; frames between keyframes interpolate (translation linearly,
// rotation by slerp), before the first / after the last hold it.
struct ObstacleKeyframe {
  int frame = 0;
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();  // axis * angle (rad)
};

struct ObstacleSpec {
  enum class Kind { kPlane, kBox, kMesh };
  std::string name;
  Kind kind = Kind::kPlane;
  // Plane (in the obstacle frame): the solid side is behind `normal`.
  Eigen::Vector3d plane_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d plane_normal = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d box_size = Eigen::Vector3d::Ones();  // box centred at the obstacle origin
  std::string mesh_path;  // triangle surface (OBJ, ASCII or binary STL), outward normals
  double scale = 1.0;     // applied to the mesh file's coordinates
  std::vector<std::string> objects;  // objects it collides with; empty = all
  std::vector<ObstacleKeyframe> keyframes;  // empty = identity pose
};

struct CollisionSpec {
  std::vector<std::pair<std::string, std::string>> pairs;  // object pairs; empty: every pair
  double stiffness = 1.0e4;  // k (N/m) per contact
  double distance = 0.002;   // D (m), proximity threshold
  std::vector<ObstacleSpec> obstacles;
};

// Reads a triangle surface: OBJ (v / f lines, polygons fanned) or STL (ASCII or binary).
Status ReadTriangleSurface(const std::string& path, Vertices* vertices, Triangles* triangles);

// The pose of a keyframed obstacle at `frame`.
Eigen::Isometry3d ObstaclePose(const std::vector<ObstacleKeyframe>& keyframes, double frame);

// ---------------------------------------------------------------------------------------
// Detection over several objects (vertices in one global array) and obstacles.

struct Contact {
  int object_a = 0;      // object of the first triangle
  int object_b = 0;      // second object, or -1 - i for obstacle i
  std::array<int, 3> vertices_a = {{0, 0, 0}};  // global vertex indices
  std::array<int, 3> vertices_b = {{0, 0, 0}};  // unused for obstacles
  Eigen::Vector3d bary_a = Eigen::Vector3d(1, 0, 0), bary_b = Eigen::Vector3d(1, 0, 0);
  Eigen::Vector3d point_b = Eigen::Vector3d::Zero();  // obstacle point (scene frame)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();   // unit, from b towards a
  double gap = 0.0;                                    // signed n . (p_a - p_b) at detection
  bool obstacle() const { return object_b < 0; }
};

struct ContactStats {
  int contacts = 0;               // active contacts (delta > 0)
  int object_contacts = 0, obstacle_contacts = 0;
  double energy = 0.0;            // sum 1/2 k delta^2 (J)
  double max_penetration = 0.0;   // max delta (m), 0 without contact
};

class CollisionWorld {
 public:
  // Objects are surfaces in the global numbering of x; names match the spec's pairs (an
  // empty pair list with collision on means every pair). Obstacle meshes are read here.
  Status Init(const CollisionSpec& spec, const std::vector<std::string>& object_names,
              const std::vector<Triangles>& surfaces, const Vertices& x);
  // After a topology change of object i (fracture): new surface triangles, new tree.
  void Rebuild(int object, const Triangles& surface, const Vertices& x);
  // Poses the obstacles for a frame (fractional frames interpolate).
  void SetFrame(double frame);
  double frame() const { return frame_; }
  // Refits the trees to x and finds the contacts with gap < D + margin (margin >= 0 keeps
  // contacts that are about to become active). Cleared first. Coarse to fine: the roots'
  // boxes (broad phase), the two trees descended together to triangle pairs whose boxes
  // come within the limit, the exact triangle-triangle distance (pairs nearer than the limit
  // or cutting each other). Every vertex of a kept pair then gives one contact against the
  // other surface, at its closest point there (searched within the limit, or within its
  // triangle's size when the pair cuts, so that a vertex deeper than D is still pushed out);
  // its normal is that of the true closest point (the face normal inside a face, the
  // direction to an edge or corner) and inside / outside comes from the pseudo-normal. A
  // vertex of an obstacle mesh likewise gets one contact against the object's surface.
  // Planes are tested vertex by vertex without a tree.
  void Detect(const Vertices& x, double margin, std::vector<Contact>* contacts);

  // Penetration delta = D - n . (p_a - p_b) of a contact at x.
  double Penetration(const Contact& c, const Vertices& x) const;
  // Energy, active count and deepest penetration of `contacts` at x.
  ContactStats Evaluate(const std::vector<Contact>& contacts, const Vertices& x) const;

  bool enabled() const { return enabled_; }  // false when nothing can collide
  double stiffness() const { return spec_.stiffness; }
  double distance() const { return spec_.distance; }
  int num_trees_built() const { return trees_built_; }
  const AabbTree& tree(int object) const { return trees_.at(object); }
  // Obstacle i's triangles in the scene frame (empty for planes).
  const Vertices& obstacle_vertices(int i) const { return obstacles_.at(i).world; }
  const Triangles& obstacle_triangles(int i) const { return obstacles_.at(i).triangles; }

 private:
  struct Obstacle {
    ObstacleSpec spec;
    Vertices local, world;  // triangle surface (box, mesh), obstacle / scene frame
    Triangles triangles;
    Eigen::MatrixXd world_normals;  // #F by 3
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    std::vector<char> hits;  // per object: collides with it
    AabbTree tree;
  };
  void DetectPair(int a, int b, const Vertices& x, double limit, std::vector<Contact>* out) const;
  void DetectObstacle(int o, int i, const Vertices& x, double limit,
                      std::vector<Contact>* out) const;
  // A vertex's contact with a surface: its closest point there (triangle, barycentrics,
  // position), the normal from the surface towards the vertex's side and the signed gap.
  struct ClosestPointContact {
    int triangle = -1;
    Eigen::Vector3d bary = Eigen::Vector3d(1, 0, 0), point = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
    double gap = 0.0;
  };
  // For each (vertex of xv, search radius): the closest point on the surface (xs, tris,
  // tree) within the radius; kept when the signed gap is below `limit`.
  void VertexContacts(const Vertices& xv, const std::vector<std::pair<int, double>>& candidates,
                      const Vertices& xs, const Triangles& tris, const AabbTree& tree, double limit,
                      std::vector<std::pair<int, ClosestPointContact>>* out) const;
  // A surface triangle of `object` with global vertex v, and v's corner in it.
  bool Corner(int object, int v, std::array<int, 2>* corner) const;

  CollisionSpec spec_;
  bool enabled_ = false;
  std::vector<Triangles> surfaces_;
  std::vector<AabbTree> trees_;
  std::vector<char> needs_tree_;
  std::vector<std::vector<int>> surface_vertices_;        // per object, global
  std::vector<std::vector<std::array<int, 2>>> vertex_triangle_;  // per object: (tri, corner)
  std::vector<std::pair<int, int>> pairs_;                // object pairs to test
  std::vector<Obstacle> obstacles_;
  int trees_built_ = 0;
  double frame_ = 0.0;
};

// The penalty as an energy of the forward solve (ForwardProblem::potential). The solver calls
// Refresh at every Newton iteration; contacts are re-detected (with `margin`) only when a
// vertex has moved more than margin / 2 since the last detection or the obstacles were posed
// for another frame: the margin is a skin, so no pair left out can have come within D, and
// in between the normals and barycentrics stay fixed. E is then one piecewise quadratic
// (its Gauss-Newton Hessian k J^T J, J = dDelta/dx, is exact) and Newton converges on it;
// re-detecting at every iteration instead moves the closest points under the solver and
// stalls it at a force imbalance of 1e-2 N on the contact_pair sequence. (Insisting on a
// final detection at the solution does not settle either: contacts at the edge of the
// pressed face switch on and off from one detection to the next, so the solutions of the
// two ways differ by up to 0.27 mm there; this one is a converged minimum of one potential.)
class ContactPotential : public ForwardPotential {
 public:
  ContactPotential(CollisionWorld* world, double margin) : world_(world), margin_(margin) {}
  void Refresh(const Vertices& x) override;
  double Evaluate(const Vertices& x, Eigen::VectorXd* gradient) const override;
  void AddHessian(const Vertices& x, std::vector<Eigen::Triplet<double>>* triplets) const override;
  const std::vector<Contact>& contacts() const { return contacts_; }
  int detections() const { return detections_; }

 private:
  CollisionWorld* world_;
  double margin_;
  std::vector<Contact> contacts_;
  Vertices detected_at_;     // x at the last detection
  double detected_frame_ = 0.0;
  int detections_ = 0;
};

// Concatenates meshes into one (for a forward solve of several objects): mesh i's vertices
// start at (*offsets)[i] and its elements get region id i; masses are carried over.
TetMesh MergeMeshes(const std::vector<TetMesh>& meshes, std::vector<int>* offsets);

// Bundled contact sequences with ground truth: "contact_pair" (a soft block pressed and
// sheared onto another one, clamped at its base) and "tool_table" (a soft cantilever pushed
// onto a table by a rigid tool, an STL written beside the scene). Corotational FEM with the
// penalty on meshes twice as fine as the tracked ones, a virtual depth camera (the tool and
// the table occlude but return no points). Writes DIR/scene.yaml, DIR/clouds/frame_NNNN.pcd,
// DIR/ground_truth/frame_NNNN.csv (one row per tracked vertex of all objects in scene order)
// and DIR/README.md; deterministic.
// Also writes DIR/truth_contacts.csv: per frame, the ground-truth solve's Newton
// iterations, active contacts and deepest penetration.
std::vector<std::string> ContactScenarios();
Status GenerateContactSequence(const std::string& scenario, const std::string& dir,
                               void (*progress)(int done, int total) = nullptr);

}  // namespace femreg

#endif  // FEMREG_COLLISION_H_
