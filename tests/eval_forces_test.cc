// femreg eval's forces from a result whose frames differ in mode (forces.when_occluded): which
// frames estimated the forces, read from stats.csv's forces_estimated.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "femreg/ground_truth.h"
#include "test_util.h"

namespace femreg {
namespace {

constexpr char kColumns[] = "frame,force_x_N,force_y_N,force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm";

TEST(EvalForces, StatsSayWhichFramesEstimatedTheForces) {
  testing_util::TempDir dir("femreg_eval_forces_test");
  std::vector<ForceFrame> back;
  bool has_columns = false;
  ASSERT_TRUE(ReadForces(dir.Write("forces.csv", std::string(kColumns) + "\n0,1,2,3,4,5,6\n"), &back, &has_columns).ok());
  ASSERT_EQ(back.size(), 1u);
  EXPECT_EQ(back[0].estimated, -1);  // no forces_estimated column: not said
  ASSERT_TRUE(ReadForces(dir.Write("mixed.csv", std::string(kColumns) +
                                                     ",forces_estimated\n0,1,2,3,4,5,6,0\n1,1,2,3,4,5,6,1\n"),
                         &back, &has_columns)
                  .ok());
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].estimated, 0);
  EXPECT_EQ(back[1].estimated, 1);
  const Status flag =
      ReadForces(dir.Write("flag.csv", std::string(kColumns) + ",forces_estimated\n0,1,2,3,4,5,6,yes\n"), &back,
                 &has_columns);
  EXPECT_FALSE(flag.ok());
  EXPECT_NE(flag.message().find("flag.csv:2: forces_estimated must be 0 or 1"), std::string::npos) << flag.message();
}

}  // namespace
}  // namespace femreg
