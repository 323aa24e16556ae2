// Sensors and scenes shared by the synth tests.
#ifndef FEMREG_TESTS_SYNTH_SAMPLES_H_
#define FEMREG_TESTS_SYNTH_SAMPLES_H_

#include <Eigen/Core>
#include <string>

#include "femreg/synth.h"

namespace femreg {
namespace testing_util {

// A camera at the origin looking along +z (image y down = world -y up), with the default noise.
inline DepthSensorOptions AxisSensor() {
  DepthSensorOptions s;
  s.camera.enabled = true;
  s.camera.position = Eigen::Vector3d::Zero();
  s.camera.target = Eigen::Vector3d::UnitZ();
  s.camera.up = -Eigen::Vector3d::UnitY();
  s.camera.width = 120;
  s.camera.height = 90;
  s.camera.fx = s.camera.fy = 100.0;
  s.camera.cx = 59.5;
  s.camera.cy = 44.5;
  return s;
}

// A synth scene: a 4 x 4 x 2 cm block clamped at its bottom, a camera above and in front,
// the lines `synth` of its synth: section (indented by two spaces), a 2 x 2 cm tool pressing
// its top from frame 0 to `press` (a keyframe), and `after` (top-level lines) at the end.
inline std::string BlockPressSynthScene(const std::string& synth,
                                        const std::string& press = "{frame: 1, translation: [0, 0, -0.014]}",
                                        const std::string& after = "") {
  return "objects:\n"
         "  - name: block\n"
         "    generate: {shape: box, size: [0.04, 0.04, 0.02], cells: [4, 4, 2]}\n"
         "    material: {youngs_modulus: 1e4, poisson_ratio: 0.3}\n"
         "boundary:\n"
         "  - {select: {box: {min: [-1, -1, -1], max: [1, 1, 0.0001]}}, clamp: true}\n"
         "registration:\n"
         "  camera: {position: [0.02, -0.1, 0.1], target: [0.02, 0.02, 0], up: [0, 0, 1],\n"
         "           fx: 60, fy: 60, cx: 39.5, cy: 29.5, width: 80, height: 60}\n"
         "synth:\n" +
         synth +
         "  bodies:\n"
         "    - {name: tool, box: {min: [0.01, 0.01, 0.03], max: [0.03, 0.03, 0.05]}, press: true,\n"
         "       keyframes: [{frame: 0}, " +
         press + "]}\n" + after;
}

// A synth scene: one clamped bar, a camera in front and above, and `synth` (the lines of its
// synth: section, indented by two spaces).
inline std::string BarSynthScene(const std::string& synth) {
  return "objects:\n"
         "  - name: bar\n"
         "    generate: {shape: box, size: [0.1, 0.02, 0.02], cells: [5, 1, 1]}\n"
         "    material: {youngs_modulus: 1e5, poisson_ratio: 0.3}\n"
         "boundary:\n"
         "  - {select: {box: {min: [-1, -1, -1], max: [0.0001, 1, 1]}}, clamp: true}\n"
         "registration:\n"
         "  camera: {position: [0.05, -0.2, 0.1], target: [0.05, 0, 0], up: [0, 0, 1],\n"
         "           fx: 60, fy: 60, cx: 39.5, cy: 29.5, width: 80, height: 60}\n"
         "synth:\n" +
         synth;
}

}  // namespace testing_util
}  // namespace femreg

#endif  // FEMREG_TESTS_SYNTH_SAMPLES_H_
