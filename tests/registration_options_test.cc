// RegistrationOptions: the option names round trip through ToString / FromString, and
// IsValid names the first bad field.
#include <gtest/gtest.h>

#include <string>

#include "femreg/registration.h"

namespace femreg {
namespace {

TEST(RegistrationOptionsTest, NamesRoundTripAndValidation) {
  for (RobustLoss v : {RobustLoss::kNone, RobustLoss::kHuber, RobustLoss::kCauchy,
                       RobustLoss::kTukey}) {
    RobustLoss parsed = RobustLoss::kNone;
    ASSERT_TRUE(FromString(ToString(v), &parsed));
    EXPECT_EQ(parsed, v);
  }
  LinearSolver solver;
  EXPECT_FALSE(FromString("cholesky", &solver));
  EXPECT_STREQ(ToString(TrustRegion::kLevenbergMarquardt), "levenberg_marquardt");

  RegistrationOptions options;
  std::string error;
  EXPECT_TRUE(options.IsValid(&error)) << error;
  options.data.loss_scale = -1;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error, "data.loss_scale must be > 0 (got -1)");
  options = RegistrationOptions();
  options.solver.max_outer_iterations = 0;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("solver.max_outer_iterations", 0), 0u) << error;
  options = RegistrationOptions();
  options.data.model_to_cloud = options.data.cloud_to_model = false;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_EQ(error.rfind("data.model_to_cloud", 0), 0u) << error;
}

}  // namespace
}  // namespace femreg
