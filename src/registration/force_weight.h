// forces.adaptive_weight: the penalty on the estimated forces, adapted from frame to frame to
// the misfit they leave (docs/guide/forces.md#choosing-the-weight). No single forces.weight
// suits every scene: a deep push on a small patch or a fast bend needs far smaller a
// penalty than a traction spread over the body. The discrepancy principle chooses it from
// the data: the forces should leave about the misfit the sensor and the mesh leave anyway,
// which the classic fit that starts every frame (its warm start) measures.
#ifndef FEMREG_REGISTRATION_FORCE_WEIGHT_H_
#define FEMREG_REGISTRATION_FORCE_WEIGHT_H_

#include <functional>

#include "registration/tracker_state.h"

namespace femreg {

// The lowest factor on forces.weight, and the factor of one move (half a decade).
constexpr double kMinForceWeightScale = 0.01;
constexpr double kForceWeightStep = 3.1622776601683795;
// The frames a decision looks at: the median of their ratios, all solved at the current
// weight (a single frame's ratio scatters by a tenth and more).
constexpr int kMisfitFrames = 3;
// The weight rises back once the median ratio is within this share of misfit_ratio's excess
// over 1 (below it, hysteresis: the ratio at the lower weight is lower).
constexpr double kMisfitRaiseShare = 0.25;

// A lower weight is taken only where it explains the misfit: the frame's last solve again at
// it, from the frame's result and with its pairs, must leave at most this share of the data
// energy's excess over the classic fit's (the warm start's shape, the same pairs). An
// occluder's points in the cloud leave misfit that no allowed force explains; a lower weight
// would only let the forces pull the body towards them.
constexpr double kLowerWeightKeeps = 0.8;

// After a frame solved with the forces estimated and its misfit ratio (FrameSummary::
// misfit_ratio, > 0) measured: records the ratio and moves state->force_weight_scale one step
// down where the median of the last kMisfitFrames ratios at the current weight exceeds
// options.forces.misfit_ratio, one step up (never above 1) where it is within
// kMisfitRaiseShare of its excess. `lower_pays` (may be null) is asked before a step down,
// with the lower scale; false keeps the weight and starts the count again. Returns whether
// the weight moved.
bool AdaptForceWeight(double misfit_ratio, TrackerState* state,
                      const std::function<bool(double lower_scale)>& lower_pays = nullptr);

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_FORCE_WEIGHT_H_
