// femreg/collision.h - contacts between objects and with rigid obstacles (docs/theory/contact.md):
// a broad and a coarse-to-fine narrow phase over the AABB hierarchies and exact closest
// points of femreg/geometry.h, for the pairs and obstacles of a CollisionSpec
// (femreg/collision_spec.h), and the penalty E = 1/2 k delta^2 (docs/theory/contact.md#response).
//
// Sign conventions. A contact ties a point p_a on a surface triangle of object a (a
// barycentric combination of its 3 vertices) to a point p_b on object b or on an obstacle.
// n is the unit contact normal, pointing from b towards a (the direction that separates
// them), held fixed between detections. The signed gap is g = n . (p_a - p_b): it equals the
// distance |p_a - p_b| while the surfaces have not crossed and is negative once they have
// (p_a inside b). D > 0 is the detection distance: contacts are found where g < D. The
// penetration is delta = -g, the same signed gap with the other sign; the penalty block of
// a contact is zero at a standoff s (E = 1/2 k max(0, s - g)^2, force k (s - g) n on p_a, away
// from b): registration puts s = lambda / k with the contact's augmented-Lagrangian
// multiplier lambda (0 for a new contact), the forward solve s = 0. "Deepest penetration"
// below is max(0, -g).
#ifndef FEMREG_COLLISION_H_
#define FEMREG_COLLISION_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "femreg/collision_spec.h"
#include "femreg/forward.h"
#include "femreg/geometry.h"
#include "femreg/mesh.h"
#include "femreg/status.h"

namespace femreg {

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
  // The vertex the contact is about (its multiplier's key with object_b): side a's global
  // vertex, or -1 - i for vertex i of an obstacle mesh pressing into a's triangle.
  int source = 0;
  bool obstacle() const { return object_b < 0; }
};

// Penetration and gap come from the same signed gaps g of the contacts detected within D.
struct ContactStats {
  int contacts = 0;               // touching contacts: g < tolerance (crossed or within it)
  int object_contacts = 0, obstacle_contacts = 0;
  double energy = 0.0;            // sum 1/2 k max(0, -g)^2 (J), the bare penalty's
  double max_penetration = 0.0;   // max(0, -min g) (m): how deep a vertex is in the other side
  double min_gap = 0.0;           // min g (m), < 0 once crossed; D when no contact is within D
};

class CollisionWorld {
 public:
  // Objects are surfaces in the global numbering of x; names match the spec's pairs (an
  // empty pair list with collision on means every pair). Obstacle meshes are read here (or
  // taken from ObstacleSpec::surface; one with no triangle or a bad index is an error).
  // obstacle_surfaces[i], where given with rows, is the surface object i meets the obstacles
  // with instead (an embedded surface, its vertices also in x); its contacts are object i's.
  Status Init(const CollisionSpec& spec, const std::vector<std::string>& object_names,
              const std::vector<Triangles>& surfaces, const Vertices& x,
              const std::vector<Triangles>& obstacle_surfaces = {});
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

  // Signed gap g = n . (p_a - p_b) of a contact at x (normal and closest points held).
  double Gap(const Contact& c, const Vertices& x) const;
  // Penetration -g of a contact at x (> 0 once the surfaces crossed).
  double Penetration(const Contact& c, const Vertices& x) const { return -Gap(c, x); }
  // Energy, active count and deepest penetration of `contacts` at x.
  ContactStats Evaluate(const std::vector<Contact>& contacts, const Vertices& x) const;

  bool enabled() const { return enabled_; }  // false when nothing can collide
  double stiffness() const { return spec_.stiffness; }
  double distance() const { return spec_.distance; }
  double tolerance() const { return spec_.tolerance; }
  bool augmented() const { return spec_.augmented; }
  // Coulomb friction (docs/theory/contact.md#friction): a contact's coefficient (its pair's,
  // its obstacle's, else collision.friction), whether any is > 0, and the slip eps (m).
  double Friction(const Contact& c) const;
  bool has_friction() const { return has_friction_; }
  double friction_slip() const { return spec_.friction_slip; }
  // How far obstacle i's material point now at p moved since the pose of `since_frame` (m).
  Eigen::Vector3d ObstacleMotion(int i, const Eigen::Vector3d& p, double since_frame) const;
  int num_obstacles() const { return static_cast<int>(obstacles_.size()); }
  const std::string& obstacle_name(int i) const { return obstacles_.at(i).spec.name; }
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
  // Per surface of the world (the objects', then their obstacle surfaces): its object.
  std::vector<int> owner_;
  std::vector<Obstacle> obstacles_;
  int trees_built_ = 0;
  double frame_ = 0.0;
  std::vector<std::pair<std::pair<int, int>, double>> pair_friction_;  // (a < b) -> mu
  bool has_friction_ = false;
};

// The penalty as an energy of the forward solve (ForwardProblem::potential): each contact
// becomes the energy layer's ContactPenalty block (the same one registration's frame problem
// minimizes), zero at contact (1/2 k max(0, -g)^2: no multipliers, the forward solve has no
// outer iterations), whose value, gradient and k J^T J are evaluated here. The solver calls
// Refresh at every Newton iteration; contacts are re-detected (with `margin`) only when a
// vertex has moved more than margin / 2 since the last detection or the obstacles were posed
// for another frame: the margin is a skin, so no pair left out can have come within D, and
// in between the normals and barycentrics stay fixed. E is then one piecewise quadratic
// (its Gauss-Newton Hessian k J^T J, J = dDelta/dx, is exact) and Newton converges on it;
// re-detecting at every iteration instead moves the closest points under the solver and
// stalls it at a force imbalance of 1e-2 N on the contact_pair sequence. (Insisting on a
// final detection at the solution does not settle either: contacts at the edge of the pressed face
// switch on and off from one detection to the next, so the solutions of the two ways differ there
// (docs/notes/2026-11-28-figures-from-code-comments.md); this one is a converged minimum of one
// potential.)
class ContactPotential : public ForwardPotential {
 public:
  ContactPotential(CollisionWorld* world, double margin) : world_(world), margin_(margin) {}
  void Refresh(const Vertices& x) override;
  double Evaluate(const Vertices& x, Eigen::VectorXd* gradient) const override;
  void AddHessian(const Vertices& x, std::vector<Eigen::Triplet<double>>* triplets) const override;
  const std::vector<Contact>& contacts() const { return contacts_; }
  int detections() const { return detections_; }
  // Friction (the world's coefficients): each contact's slip is measured from the positions
  // of the first call (Refresh, or AddHessian for the solver's move of prescribed vertices)
  // after the obstacles were posed for another frame (or after ResetFriction), relative to the
  // obstacles' motion since the frame before; its normal force is the penalty's at the last
  // Refresh, held within a Newton iteration.
  void ResetFriction() { reference_.resize(0, 3); }
  // The contact forces at x per object pair and obstacle (N), normal and friction parts.
  std::vector<ContactForce> Forces(const Vertices& x) const;

 private:
  // Calls f(block, contact, friction) for each contact's penalty and friction blocks.
  template <class F>
  void ForEachBlock(F&& f) const;
  CollisionWorld* world_;
  double margin_;
  std::vector<Contact> contacts_;
  Vertices detected_at_;     // x at the last detection
  double detected_frame_ = 0.0;
  int detections_ = 0;
  // Friction: the positions the slip is measured from, the frame they were solved for and the
  // obstacles' frame the slip is relative to. Mutable: AddHessian may be asked first in a frame
  // (the predictor of moved prescribed vertices) and starts the frame's slip itself.
  mutable Vertices reference_;
  mutable double reference_frame_ = 0.0;
  mutable double motion_from_ = 0.0;
  std::vector<double> friction_weight_;           // per contact: mu lambda / eps (0: none)
  std::vector<Eigen::Vector3d> friction_motion_;  // per contact: the obstacle's motion
};

// Concatenates meshes into one (for a forward solve of several objects): mesh i's vertices
// start at (*offsets)[i] and its elements get region id i; masses are carried over.
TetMesh MergeMeshes(const std::vector<TetMesh>& meshes, std::vector<int>* offsets);

}  // namespace femreg

#endif  // FEMREG_COLLISION_H_
