// Flying pixels: a depth camera's pixels on a depth edge that mix the near and the far
// surface and land between them (docs/guide/depth-images.md#flying-pixels).
#ifndef FEMREG_REGISTRATION_FLYING_PIXELS_H_
#define FEMREG_REGISTRATION_FLYING_PIXELS_H_

#include "femreg/registration.h"

namespace femreg {

// Removes the points of a depth image of `camera` that no surface around them supports. Each
// point is projected to its pixel; the image may keep every k-th pixel (k <= 4, found from the
// cloud). The depth's noise sigma (taken as c z^2) is estimated from the image: the spread of
// its second differences of depth along rows and columns, which on a plane is sqrt(6) times
// the depth's noise. The tolerance at depth z is tolerance * sigma(z), never below one sample
// footprint (k z / fx). A point is judged only if it lies between
// surfaces: one of its 8 neighbouring samples nearer and another farther than the tolerance, or,
// beside a sample missing inside the image (a masked tool or hand), one farther.
// It is kept if a surface around it predicts its depth within the tolerance: in two directions
// off one line, the neighbour's depth or the plane through the neighbour and the next sample
// continued to it (or the parabola through three in a row); or a plane fitted to one half or one corner quadrant of its 5 x 5
// neighbourhood, which fits its own samples within the tolerance (RMS). The one-pixel curtain
// of mixed pixels along an edge supports itself only along the edge, and goes. Support comes
// only from points that stay: the points around those removed are judged again without them,
// until none goes (mixed pixels two samples deep hold each other up until one of them goes).
// Returns how many were removed; -1 when the cloud is not one depth image of this camera
// (more than a tenth of its points outside the image, behind the camera or sharing a
// pixel), and then it is left as it is.
int RemoveFlyingPixels(const CameraOptions& camera, double tolerance, PointCloud* cloud);

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_FLYING_PIXELS_H_
