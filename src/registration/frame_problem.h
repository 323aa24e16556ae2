// The energy a frame minimizes, built in one place from the tracker's state: the elastic
// blocks (once per topology), the temporal springs and anchors (once per frame), the data
// pairs and contacts (every outer iteration). Both back ends solve the result.
#ifndef FEMREG_REGISTRATION_FRAME_PROBLEM_H_
#define FEMREG_REGISTRATION_FRAME_PROBLEM_H_

#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include "energy/problem.h"
#include "femreg/collision.h"
#include "femreg/registration.h"
#include "registration/correspondences.h"
#include "registration/free_space.h"
#include "registration/embedded_surface.h"
#include "registration/tracker_state.h"

namespace femreg {

// Whether every element of the objects has a positive volume at x.
bool NoFlatElement(const TrackerState& state, const Vertices& x);

class FrameProblem {
 public:
  // The elastic blocks of every object (its model's rest data and rotations, read through
  // pointers, so refreshing the rotations needs no rebuild) and the coupling the fast back
  // end's pattern starts from. After the tracker is made and after a topology change.
  void BuildElastic(const TrackerState& state);
  // The elastic blocks' weight becomes scale x weights.elastic (the inversion barrier keeps
  // its own): the stiff start of a large motion (docs/theory/stopping.md#large-motions).
  void SetElasticScale(const TrackerState& state, double scale);
  // The temporal springs (w_t m_i towards state.frame_start) and the anchors at this frame's
  // targets: hard anchors move state->x onto their targets and hold them. Then the inversion
  // barrier, unless an element is flat or inverted at state->x (a user's state, or a run with
  // the barrier off before): that frame unfolds without it.
  void BuildFrameTerms(TrackerState* state);
  // The data blocks of this outer iteration's pairs with the data loss. Their weights: with
  // weights.data set (legacy), that per pair; else weights.data_per_area times the observed
  // area each pair stands for: a model->cloud pair its vertex's share of the rest surface
  // around it (times model_to_cloud_share), at most model_to_cloud_area_cap times the
  // cloud's area per point; a cloud->model pair the cloud's area per point (the median over
  // the touched triangles of rest area / pairs on it). Per pair, an object's model->cloud
  // pairs weigh less where they outnumber its cloud->model pairs (model_to_cloud_balance).
  // With a data surface (SetDataSurface), the pairs are on it: their areas are its, and
  // each becomes a block on the coarse vertices that carry its point (DataSurface::Map).
  void SetData(const std::vector<DataPair>& pairs, const RegistrationOptions& options);
  // Free space (registration/free_space.h, energy/free_space.h): for each free surface vertex
  // nearer to the sensor at state.x than the observed depth at its pixel minus
  // free_space.tolerance, unless its way out sideways is shorter (ObservedDepth::SidewaysExit),
  // a one-sided penalty of free_space.weight that pushes it back along its ray (held for the
  // solve) to that depth. In the data group: after SetData, every outer iteration. None when
  // free_space is off, nothing was observed (an empty `observed`) or no vertex is in front.
  void SetFreeSpace(const TrackerState& state, const ObservedDepth& observed);
  // The vertices of the last SetFreeSpace's blocks that are in front of their allowed depth at x.
  int FreeSpaceHeld(const Vertices& x) const;
  // The surface the pairs of SetData are found on (registration/embedded_surface.h); null:
  // the meshes' own. Kept by pointer; its rest areas are computed here.
  void SetDataSurface(const DataSurface* surface);
  // The external loads (gravity, nodal forces) of the objects that have them, about the
  // positions at the start of this outer iteration (energy/load.h). Every outer iteration.
  void SetLoads(const TrackerState& state);
  // The contact penalty of the detected contacts, zero at the gap lambda / k of each
  // contact's multiplier (none yet: k from the world, zero at contact). The contacts may be
  // detected on the collision positions (Tracker::Impl::CollisionPositions): a contact whose
  // side a lies past the meshes' vertices is on the data surface's (an embedded surface's)
  // vertices there, and acts on the 4 cage vertices that carry its point.
  void SetContacts(const std::vector<Contact>& contacts, const CollisionWorld& world,
                   const std::map<std::pair<int, int>, TrackerState::ContactMultiplier>& multipliers);
  // Coulomb friction of those contacts (docs/theory/contact.md#friction; frame_friction.cc): for
  // each with a coefficient > 0, a block on its slip since `reference` (the previous frame's
  // result) relative to the obstacle's motion since `reference_frame`, with the normal force
  // max(0, lambda - k g) of its penalty at the collision positions y held for the solve
  // (reference: the meshes' vertices). After SetContacts.
  void SetFriction(const std::vector<Contact>& contacts, const CollisionWorld& world,
                   const std::map<std::pair<int, int>, TrackerState::ContactMultiplier>& multipliers,
                   const Vertices& y, const Vertices& reference, double reference_frame);
  // The forces of the last SetContacts' and SetFriction's blocks at x, per object pair and
  // obstacle; empty after a topology change.
  std::vector<ContactForce> ContactForces(const Vertices& x) const;

  // Equilibrium registration (registration.forces, energy/equilibrium.h): where forces may
  // act, their penalties, the surface's normals and the turns the step does not make
  // (solver.hold_hidden_turns; `data`, may be null, as for HoldHiddenTurns) at state.x. Every
  // outer iteration, after SetLoads and SetContacts; off (no equilibrium) unless `on`.
  // `pushing_only`: the frame's forces push only (forces.pushing_only, or a frame that
  // forces.when_occluded switched), their penalty left out while `smooth_start`.
  void SetEquilibrium(const TrackerState& state, bool on, DataSurface* data = nullptr, bool pushing_only = false,
                      bool smooth_start = false);
  // Puts back an equilibrium the problem had (problem().shared_equilibrium()), or another.
  void SetEquilibrium(std::shared_ptr<const energy::Equilibrium> equilibrium) {
    problem_.SetEquilibrium(std::move(equilibrium));
  }
  // The external forces on the vertices at state.x (N, #V by 3): what the elastic forces,
  // gravity and the loads leave unbalanced, the contacts' forces and the estimated ones
  // (without forces.estimate: the data term's pull). Zero at clamps and anchors (their
  // reactions are not reported).
  Vertices ExternalForces(const TrackerState& state) const;

  const energy::Problem& problem() const { return problem_; }

 private:
  // The nodal-volume energy of the objects whose neo-Hookean element has it (material.volume:
  // nodal), times the elastic weight; none if no object has.
  void BuildNodalVolume(const TrackerState& state, double weight);
  void BuildAreas(const TrackerState& state);
  energy::Problem problem_;
  // The inversion barrier's set (null: off) and its blocks on every element.
  energy::TermSet<energy::InversionBarrier>* barrier_ = nullptr;
  std::vector<energy::InversionBarrier> barrier_blocks_;
  // Rest areas (m^2), from BuildElastic: per global vertex, a third of the surface
  // triangles around it; per surface triangle, keyed by its sorted vertices.
  std::vector<double> vertex_area_;
  std::unordered_map<uint64_t, double> triangle_area_;
  std::vector<int> vertex_object_;  // per global vertex, its object (weights.model_to_cloud_balance)
  // The data surface (null: none) and its rest areas, as above in its numbering.
  const DataSurface* data_surface_ = nullptr;
  std::vector<double> surface_vertex_area_;
  std::unordered_map<uint64_t, double> surface_triangle_area_;
  int num_objects_ = 0;
  std::vector<energy::FreeSpacePenalty> free_space_;  // the last SetFreeSpace's blocks
  // For ContactForces: the contacts of the collision set, each penalty's (standoff, k), the
  // friction blocks and their contacts.
  std::vector<Contact> force_contacts_;
  std::vector<std::pair<double, double>> force_penalty_;
  // A contact's side a on the data surface as cage vertices: n 0 for a point of a mesh's own
  // surface (the contact's vertices are the meshes'), else the 4 that carry it.
  DataSurface::Stencil ContactStencil(const Contact& c) const;
  std::vector<energy::Friction<3>> force_friction_obstacle_;
  std::vector<energy::Friction<4>> force_friction_embedded_;
  std::vector<int> force_friction_embedded_contact_;
  std::vector<energy::Friction<6>> force_friction_pair_;
  std::vector<int> force_friction_obstacle_contact_, force_friction_pair_contact_;
  double friction_slip_ = 1.0;
};

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_FRAME_PROBLEM_H_
