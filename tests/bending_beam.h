// What tracker_test.cc and embedded_surface_test.cc share: a beam clamped at x = 0 whose free
// end is bent down and twisted, simulated on a mesh twice as fine as the tracked one and seen
// by the virtual depth camera; its camera and its foam.
#ifndef FEMREG_TESTS_BENDING_BEAM_H_
#define FEMREG_TESTS_BENDING_BEAM_H_

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <vector>

#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/io.h"
#include "femreg/synth.h"

namespace femreg {
namespace bending_beam {

constexpr double kLength = 0.2, kWidth = 0.04;

inline DepthSensorOptions Sensor() {
  DepthSensorOptions s;
  s.camera.enabled = true;
  s.camera.position = Eigen::Vector3d(0.1, -0.25, 0.2);
  s.camera.target = Eigen::Vector3d(0.1, 0.02, 0.0);
  s.camera.up = Eigen::Vector3d::UnitZ();
  s.camera.width = 160;
  s.camera.height = 120;
  s.camera.fx = s.camera.fy = 140.0;
  s.camera.cx = 79.5;
  s.camera.cy = 59.5;
  return s;
}

inline Material Foam() {
  Material m;
  m.youngs_modulus = 5e4;
  m.poisson_ratio = 0.35;
  m.density = 200;
  return m;
}

// The simulated beam's mesh at rest: 20 by 4 by 4 cells (a tracked mesh of 10 by 2 by 2 has
// half its resolution).
inline TetMesh FineBeam() {
  TetMesh fine = MakeBox(Eigen::Vector3d(kLength, kWidth, kWidth), 20, 4, 4);
  ComputeLumpedMasses(&fine, 200);
  return fine;
}

// One frame of the bent beam: the fine mesh at the frame's positions (fine.x), the camera's
// depth image of it, the cloud sampled from that image and the forward solve's summary.
struct BeamFrame {
  const TetMesh& fine;
  const DepthSensor& sensor;
  const DepthImage& image;
  const PointCloud& cloud;
  const ForwardSummary& summary;
};

// `frames` frames of the fine beam: frame f (s = f / (frames - 1), 0 for one frame) has its
// end dropped by drop * s and turned by 0.3 s rad about the beam's axis, and its cloud sampled
// with the seed seed + f. on_frame sees every frame in order.
inline void BendFineBeam(int frames, double drop, uint64_t seed,
                         const std::function<void(const BeamFrame&)>& on_frame) {
  TetMesh fine = FineBeam();
  ElasticModel model;
  model.Build(fine, ElasticModelType::kCorotational, Foam());
  DepthSensor sensor(Sensor());
  ForwardProblem problem;
  for (int v = 0; v < fine.num_vertices(); ++v) {
    if (fine.rest(v, 0) < 1e-9) problem.clamped.push_back(v);
  }
  for (int f = 0; f < frames; ++f) {
    const double s = frames > 1 ? double(f) / (frames - 1) : 0.0;
    const Eigen::Vector3d centre(kLength, kWidth / 2, kWidth / 2);
    const Eigen::Matrix3d twist = Eigen::AngleAxisd(0.3 * s, Eigen::Vector3d::UnitX()).toRotationMatrix();
    problem.prescribed.clear();
    for (int v = 0; v < fine.num_vertices(); ++v) {
      if (fine.rest(v, 0) > kLength - 1e-9) {
        const Eigen::Vector3d X = fine.rest.row(v);
        const Eigen::Vector3d moved = centre + twist * (X - centre) + Eigen::Vector3d(0, 0, -drop * s);
        problem.prescribed.emplace_back(v, moved - X);
      }
    }
    ForwardSummary summary;
    EXPECT_TRUE(SolveQuasiStatic(problem, ForwardOptions(), &model, &fine, &summary).ok());
    const std::vector<RenderSurface> surfaces = {{&fine.x, &fine.surface}};
    const DepthImage image = sensor.Render(surfaces);
    const PointCloud cloud = sensor.Sample(image, surfaces, seed + f);
    on_frame({fine, sensor, image, cloud, summary});
  }
}

}  // namespace bending_beam
}  // namespace femreg

#endif  // FEMREG_TESTS_BENDING_BEAM_H_
