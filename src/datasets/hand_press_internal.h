// What the hand_press generator's files share (hand_press.cc: the simulation and the
// frames; hand_press_files.cc: the ball's material, the camera, the tracking scene and the
// README).
#ifndef FEMREG_DATASETS_HAND_PRESS_INTERNAL_H_
#define FEMREG_DATASETS_HAND_PRESS_INTERNAL_H_

#include <string>

#include "femreg/datasets.h"
#include "femreg/fem.h"
#include "femreg/mesh.h"
#include "femreg/registration.h"

namespace femreg {
namespace hand_press_internal {

constexpr double kRadius = 0.05;  // m; the ball rests on the table z = 0, centre at z = kRadius
constexpr int kTrackedCells = 5;  // MakeSphere: (2n + 1)^3 vertices (1331)
constexpr int kTruthCells = 8;    // the ground truth's mesh (4913 vertices)
constexpr int kFrames = 30;
constexpr double kGravity = 9.81;  // m/s^2, along -z
// A vertex closer than this to the far side of a surface has crossed it (m).
constexpr double kCrossing = 1e-6;
// A held vertex whose reaction pulls on its surface by more than this is let go (N): well
// below a vertex's share of the weight (the weight over the ground truth's vertices).
constexpr double kPull = 1e-7;
constexpr int kMaxRounds = 40;      // active-set rounds per substep
constexpr double kMaxStep = 0.002;  // m: the hand's largest motion in one substep

Material Foam(const HandPressOptions& options);
CameraOptions Camera(const HandPressOptions& options);
// The generator's options that differ from the bundled sequence's, as hand-press-data's
// arguments (" --seed 2 ..."; empty for the bundled sequence).
std::string VariantArguments(const HandPressOptions& options);
// `format` (printf, one double) applied to a.
std::string Format(const char* format, double a);
// The tracking scene, as a new user writes it from datasets/README.md: the ball, its
// material, the camera, the table and gravity; nothing about the hand.
std::string TrackingScene(const HandPressOptions& options);

std::string Readme(const HandPressReport& r, const TetMesh& fine, const HandPressOptions& options);

}  // namespace hand_press_internal
}  // namespace femreg

#endif  // FEMREG_DATASETS_HAND_PRESS_INTERNAL_H_
