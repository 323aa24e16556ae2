#include "registration/force_weight.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace femreg {

bool AdaptForceWeight(double misfit_ratio, TrackerState* state,
                      const std::function<bool(double lower_scale)>& lower_pays) {
  if (!(misfit_ratio > 0.0) || !std::isfinite(misfit_ratio)) return false;
  std::vector<double>& ratios = state->misfit_ratios;
  ratios.push_back(misfit_ratio);
  if (static_cast<int>(ratios.size()) > kMisfitFrames) ratios.erase(ratios.begin());
  if (static_cast<int>(ratios.size()) < kMisfitFrames) return false;
  std::vector<double> sorted = ratios;
  std::nth_element(sorted.begin(), sorted.begin() + kMisfitFrames / 2, sorted.end());
  const double median = sorted[kMisfitFrames / 2];
  const double bound = state->options.forces.misfit_ratio;
  double& scale = state->force_weight_scale;
  const double before = scale;
  if (median > bound) {
    const double lower = std::max(kMinForceWeightScale, scale / kForceWeightStep);
    if (lower < scale && lower_pays && !lower_pays(lower)) {
      ratios.clear();  // not the penalty's misfit: three more frames before the next try
      return false;
    }
    scale = lower;
  } else if (median < 1.0 + kMisfitRaiseShare * (bound - 1.0)) {
    scale = std::min(1.0, scale * kForceWeightStep);
  }
  if (scale == before) return false;
  ratios.clear();  // measured at the old weight
  return true;
}

}  // namespace femreg
