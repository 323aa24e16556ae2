// The element simulate and calibrate use by default for a nearly incompressible object
// (ChooseForwardElements, femreg/scene.h): a gel cantilever at nu 0.49 sagging under its own
// weight on a coarse mesh (16 x 3 x 3 cells) against the sag of a fine one (64 x 12 x 12,
// nodal volume; docs/notes/2026-11-29-nearly-incompressible.md), where the linear element
// on the coarse mesh locks.
#include <gtest/gtest.h>

#include <string>

#include "femreg/calibration.h"
#include "femreg/scene.h"

namespace femreg {
namespace {

const char kBeam[] =
    "objects:\n"
    "  - name: gel\n"
    "    generate: {shape: box, size: [0.2, 0.04, 0.04], cells: [16, 3, 3]}\n"
    "    material: {youngs_modulus: 3e5, poisson_ratio: 0.49, density: 1000MODEL}\n"
    "gravity: [0, 0, -9.81]\n"
    "boundary:\n"
    "  - {select: {box: {min: [-1, -1, -1], max: [0.0001, 1, 1]}}, clamp: true}\n"
    "forward: {max_iterations: 60, load_steps: 2}\n";

// The fine mesh's mean vertical displacement of the free end face (m).
constexpr double kFineSag = -45.8e-3;

// The same mean on the coarse mesh, with `model` appended to the material.
double CoarseSag(const std::string& model) {
  std::string text = kBeam;
  text.replace(text.find("MODEL"), 5, model);
  Scene scene;
  Status status = ParseScene(text, "beam.yaml", ".", &scene);
  EXPECT_TRUE(status.ok()) << status.message();
  TetMesh mesh;
  status = SolveSceneObject(scene, 0, &mesh);
  EXPECT_TRUE(status.ok()) << status.message();
  double sum = 0.0;
  int n = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.rest(v, 0) > 0.2 - 1e-9) {
      sum += mesh.x(v, 2) - mesh.rest(v, 2);
      ++n;
    }
  }
  EXPECT_EQ(n, 16);
  return n ? sum / n : 0.0;
}

TEST(NearlyIncompressible, DefaultElementSagsLikeTheFineMesh) {
  const double sag = CoarseSag("");
  const double locked = CoarseSag(", model: hooke");
  std::printf("coarse sag at nu 0.49: default %.2f mm, hooke %.2f mm, fine mesh %.2f mm\n",
              sag * 1e3, locked * 1e3, kFineSag * 1e3);
  // The default reaches three quarters of the fine sag (the rest is the coarse mesh's
  // bending stiffness); the linear element locks at a quarter of it.
  EXPECT_GT(sag / kFineSag, 0.7);
  EXPECT_LT(sag / kFineSag, 1.05);
  EXPECT_LT(locked / kFineSag, 0.4);
}

// A stiff one (E 10 MPa, nu 0.45, 1.2 mm of sag) in two load steps: near each step's
// solution the neo-Hookean energy's round-off exceeds a Newton step's decrease, and the line
// search must not refuse the step for it (without: 58 iterations, 55 of them failing).
TEST(NearlyIncompressible, StiffSagConvergesInFewNewtonIterations) {
  std::string text = kBeam;
  text.replace(text.find("MODEL"), 5, "");
  const std::string soft = "youngs_modulus: 3e5, poisson_ratio: 0.49";
  text.replace(text.find(soft), soft.size(), "youngs_modulus: 1e7, poisson_ratio: 0.45");
  Scene scene;
  Status status = ParseScene(text, "beam.yaml", ".", &scene);
  ASSERT_TRUE(status.ok()) << status.message();
  TetMesh mesh;
  ForwardSummary summary;
  status = SolveSceneObject(scene, 0, &mesh, &summary);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_LE(summary.NumNewtonIterations(), 10) << summary.BriefReport();
  for (const ForwardLoadStep& step : summary.load_steps) {
    EXPECT_EQ(step.termination, ForwardTermination::kConverged) << summary.BriefReport();
  }
}

}  // namespace
}  // namespace femreg
