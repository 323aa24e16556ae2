// The mass-spring regularizer's stiffness (registration/frame_problem.cc).
#include <gtest/gtest.h>
#include <cmath>
#include "femreg/fem.h"
#include "femreg/io.h"
#include "femreg/registration.h"
#include "registration/frame_problem.h"
#include "registration/tracker_state.h"

namespace femreg {
namespace {

// The elastic energy of one box mesh of `material` under `regularizer`, uniformly dilated by
// 1 + strain about the origin, as the frame's problem evaluates it.
double DilatedElasticEnergy(Regularizer regularizer, const Material& material, double strain) {
  TrackerState state;
  state.options.regularizer = regularizer;
  state.options.weights.barrier = 0.0;  // the elastic group's energy is the springs' alone
  state.objects.resize(1);
  ObjectState& o = state.objects[0];
  o.mesh = MakeBox(Eigen::Vector3d(0.1, 0.06, 0.04), 4, 3, 2);
  o.material = ObjectMaterial(material);
  o.model.Build(o.mesh, ElasticModelType::kCorotational, o.material);
  state.RebuildGlobalArrays();
  FrameProblem problem;
  problem.BuildElastic(state);
  return problem.problem().Evaluate((1.0 + strain) * o.mesh.rest).elastic;
}

// A uniform dilation stretches every edge by the same strain, so the springs' energy is
// exact there: with k = E sum V_e / L^2 (Van Gelder's stiffness) it is 3 E V strain^2, what
// the element of Poisson's ratio 1/4 stores, the one ratio a network of springs on the
// edges can have. A sixth of the volumes, as before, made the network six times softer.
TEST(MassSpring, AUniformDilationCostsWhatItCostsAnElementOfPoissonsRatioAQuarter) {
  Material material;
  material.youngs_modulus = 3.0e4;
  material.poisson_ratio = 0.25;
  const double strain = 1e-3;
  const double springs = DilatedElasticEnergy(Regularizer::kMassSpring, material, strain);
  const double elements = DilatedElasticEnergy(Regularizer::kCorotational, material, strain);
  const double volume = 0.1 * 0.06 * 0.04;
  EXPECT_NEAR(springs, 3.0 * material.youngs_modulus * volume * strain * strain, 1e-9 * springs);
  EXPECT_NEAR(springs, elements, 1e-6 * elements);
}

}  // namespace
}  // namespace femreg
