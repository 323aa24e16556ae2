// Flying pixels: a depth camera's pixels on a depth edge that mix the near and the far
// surface and land between them (docs/guide/depth-images.md#flying-pixels).
#ifndef FEMREG_REGISTRATION_FLYING_PIXELS_H_
#define FEMREG_REGISTRATION_FLYING_PIXELS_H_

#include "femreg/registration.h"

namespace femreg {

// Removes the points of a depth image of `camera` that no surface around them supports:
// a point is projected to its pixel, and kept if two of the points in its 8 neighbouring
// samples (pixels, or every k-th pixel when the image was sampled so, k <= 4 found from the
// cloud) that lie within tolerance * k * z / fx (that many sample footprints) of its depth z are
// off one line through it (a surface, not the one-pixel curtain of mixed pixels along an
// edge), if fewer than two neighbouring pixels hold a point (nothing to judge by), or if it
// is not between surfaces (no neighbour both nearer and one farther by more than that).
// Returns how many were removed; -1 when the cloud is not one depth image of this camera
// (more than a tenth of its points outside the image, behind the camera or sharing a
// pixel), and then it is left as it is.
int RemoveFlyingPixels(const CameraOptions& camera, double tolerance, PointCloud* cloud);

}  // namespace femreg

#endif  // FEMREG_REGISTRATION_FLYING_PIXELS_H_
