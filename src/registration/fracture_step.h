// Fracture between outer iterations (docs/theory/fracture.md; femreg/fracture.h): detection on
// every object, node splits, and the tracker's state carried to the new topology.
#ifndef FEMREG_REGISTRATION_FRACTURE_STEP_H_
#define FEMREG_REGISTRATION_FRACTURE_STEP_H_

#include <vector>

#include "femreg/registration.h"
#include "geometry/nearest.h"
#include "registration/tracker_state.h"

namespace femreg {

// Detection and splits after outer iteration k's solve (state->fracture must be set). On a
// topology change every global array of the state (x, the previous frames, masses, anchors,
// the collision world's surfaces) is carried to the new vertices and, per new global
// vertex, its old global index is returned; empty when nothing split. Splits are added to
// summary->fractures, the time to summary->time.fracture.
std::vector<int> FractureStep(int k, const PointIndex& cloud_index, TrackerState* state,
                              FrameSummary* summary);

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_FRACTURE_STEP_H_
