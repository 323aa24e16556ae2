// femreg/tracker.h - the library entry point: build a Tracker from a scene, call Track once
// per point cloud, read the deformed vertices and the frame summary.
//
//   femreg::Scene scene;
//   femreg::Status s = femreg::LoadScene("scene.yaml", &scene);
//   std::unique_ptr<femreg::Tracker> tracker;
//   s = femreg::Tracker::Create(scene, &tracker);
//   for (each cloud) {
//     femreg::FrameSummary summary;
//     tracker->Track(cloud, &summary);
//     if (summary.IsSolutionUsable()) use(tracker->vertices(0));
//   }
#ifndef FEMREG_TRACKER_H_
#define FEMREG_TRACKER_H_

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "femreg/collision.h"
#include "femreg/collision_spec.h"
#include "femreg/fem.h"
#include "femreg/fracture.h"
#include "femreg/mesh.h"
#include "femreg/point_cloud.h"
#include "femreg/registration.h"
#include "femreg/status.h"

namespace femreg {

struct Scene;  // femreg/scene.h

class Tracker {
 public:
  // Loads every object's mesh, builds the rest data once, and checks the options; the
  // scene's labels, anchors, boundary clamps (hard anchors "boundary[i]", held at rest) and
  // effects (fracture, collision) are set up. Defined with the scene module (link
  // femreg::femreg; include femreg/scene.h to call it).
  static Status Create(const Scene& scene, std::unique_ptr<Tracker>* tracker);
  // The same with meshes built by the caller (positions in mesh.x are the initial shape):
  // materials[i] (one Material, or per region) belongs to meshes[i]; lumped masses come from
  // its densities unless mesh.mass is set.
  static Status Create(const std::vector<TetMesh>& meshes,
                       const std::vector<ObjectMaterial>& materials,
                       const RegistrationOptions& options, std::unique_ptr<Tracker>* tracker);
  ~Tracker();

  // Registers the meshes to one cloud (metres, scene frame). Never throws: bad input is
  // reported in the summary (termination kInvalidInput / kNoCorrespondences) and the shape
  // is then held by the temporal term. Returns an error Status only for misuse.
  Status Track(const PointCloud& cloud, FrameSummary* summary);

  int num_objects() const;
  const TetMesh& mesh(int object) const;          // rest data, topology and current x
  const Vertices& vertices(int object) const;     // #V by 3 current positions
  // Distance (m) from each vertex to its nearest cloud point in the last frame; NaN for
  // interior vertices and when there was no data.
  const Eigen::VectorXd& vertex_residuals(int object) const;
  // Whether each vertex had a data correspondence in the last frame (seen by the camera).
  const std::vector<char>& vertex_observed(int object) const;
  int frame() const;  // frames tracked so far
  // Puts object i's vertices at x (#V by 3, finite), e.g. a pose from a detector, and starts
  // afresh from there: the next frame predicts no velocity, catches up no held frame, searches
  // no pose after a lost one, starts no quiet pushing-only solve and carries no marks from the
  // last cloud; a frame lost later goes back to x.
  Status SetVertices(int object, const Vertices& x);

  // Anchors: vertex sets with a per-frame target. Hard anchors fix the vertices at the
  // targets; soft ones pull with `weight` (N/m per vertex; <= 0 uses weights.anchor).
  // Targets set once stay until changed.
  Status AddAnchor(const std::string& name, int object, const std::vector<int>& vertices,
                   bool hard, double weight = 0.0);
  Status SetAnchorTargets(const std::string& name, const Vertices& targets);
  // Moves the anchored set rigidly by translations[frame] from where it was when added
  // (frames past the end use the last entry), e.g. a gripper's path. SetAnchorTargets
  // clears it.
  Status SetAnchorTrajectory(const std::string& name,
                             const std::vector<Eigen::Vector3d>& translations);
  // The same with a rotation per frame too (axis * angle, rad, both lists as long): the set
  // is turned by rotations[frame] about `centre` (m, scene frame), then moved by
  // translations[frame], both from where it was when added.
  Status SetAnchorTrajectory(const std::string& name,
                             const std::vector<Eigen::Vector3d>& translations,
                             const std::vector<Eigen::Vector3d>& rotations,
                             const Eigen::Vector3d& centre);

  // External loads on object i, constant over frames, in the registration energy as in a
  // forward solve: gravity (m/s^2) on its lumped masses and nodal forces (vertex, N). The
  // data hold the object where it is seen; the loads shape what is not (a sag under the
  // object's own weight). Create(scene) sets the scene's gravity and loads unless
  // registration.loads is false. Replaces what was set before.
  Status SetExternalLoads(int object, const Eigen::Vector3d& gravity,
                          const std::vector<std::pair<int, Eigen::Vector3d>>& nodal_loads);

  // Equilibrium registration (RegistrationOptions::forces): estimated external forces act only
  // on these vertices of object i's free surface (indices into its mesh as created); by
  // default on all of it. Replaces what was set before; an empty list restores the default.
  Status SetForceRegion(int object, const std::vector<int>& vertices);
  // #V by 3: the external forces on object i's vertices in the last frame (N; see
  // FrameSummary::force), zero at clamps and anchors.
  const Vertices& external_forces(int object) const;

  // An embedded surface (docs/theory/embedded-surfaces.md): a fine triangle surface, its
  // vertices (#S by 3) in object i's rest frame, carried by the object's tetrahedra (each
  // vertex a fixed combination of the four vertices of the element it lies in, or of the
  // nearest element for one a little outside). The data terms, the visibility and the
  // occluders then act on it; the elastic energy and the contacts stay on the mesh. Not with
  // labels or fracture. Replaces what was set before.
  Status SetEmbeddedSurface(int object, const Vertices& rest, const Triangles& triangles);
  bool has_embedded_surface(int object) const;
  // Object i's embedded surface at the current positions (#S by 3; no rows without one) and
  // its triangles.
  Vertices surface_vertices(int object) const;
  const Triangles& surface_triangles(int object) const;
  // The largest distance (m) at rest from a vertex of object i's embedded surface outside the
  // mesh to its element (0 when all are inside).
  double surface_outside(int object) const;

  // Cloud points with this label (PointCloud::labels) belong to the object; -1: none.
  Status SetObjectLabel(int object, int label);

  // Contacts (docs/theory/contact.md; femreg/collision.h): the penalty between the spec's object
  // pairs (named by `names`, one per object; no pairs: every pair) and with its obstacles, which
  // an object with an embedded surface meets with that surface (before or after this call).
  // Nothing is built when nothing can collide.
  Status EnableCollision(const CollisionSpec& spec, const std::vector<std::string>& names);

  // Fracture (docs/theory/fracture.md; femreg/fracture.h): detection between outer iterations and
  // node splits, one FractureOptions per object. Off unless enabled (Create(scene) enables
  // it for effects.fracture); when off nothing is computed. After a split the meshes,
  // vertices() and the per-vertex outputs have the new vertex count.
  Status EnableFracture(const std::vector<FractureOptions>& options);
  // #V: the largest eigenvalue of the separation tensor over the node area (Pa) at the
  // last detection; empty when fracture is off.
  const Eigen::VectorXd& fracture_measure(int object) const;
  // #V: the vertex of the initial mesh each vertex comes from (replicas map to their
  // source); empty when fracture is off (then the identity).
  const std::vector<int>& original_vertices(int object) const;

  const RegistrationOptions& options() const;
  // The last frame's cloud as the registration used it: after the scene's transform, the
  // flying-pixel filter and the preprocessing (PrepareCloudForTracking), before the
  // automatic voxel thinning, in the scene's frame. Empty before the first frame.
  const PointCloud& prepared_cloud() const;
  // The contact detector, or null when collision is off or nothing can collide (then no
  // hierarchy is built and no contact residual is added). With an embedded surface it detects
  // on the meshes' vertices followed by the embedded surfaces' (the obstacles meet those), the
  // latter in the tracker's own order, not surface_vertices()'s: for its own use.
  const CollisionWorld* collision() const;

 private:
  Tracker();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace femreg

#endif  // FEMREG_TRACKER_H_
