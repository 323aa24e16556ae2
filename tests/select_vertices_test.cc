// SelectVertices (femreg/scene.h): the box, plane, index and all selections of the scene's
// `select:` keys, and the errors that name where the selection was written.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "femreg/scene.h"
#include "test_util.h"

namespace femreg {
namespace {

using testing_util::Grid;

TEST(SelectVerticesTest, Box) {
  VertexSelection s;
  s.kind = VertexSelection::Kind::kBox;
  s.box_min = Eigen::Vector3d(0, 0, 0);
  s.box_max = Eigen::Vector3d(0, 2, 2);  // the face x = 0, boundaries included
  std::vector<int> v;
  ASSERT_TRUE(SelectVertices(s, Grid(), &v).ok());
  EXPECT_EQ(v, (std::vector<int>{0, 3, 6, 9, 12, 15, 18, 21, 24}));
  s.box_min = Eigen::Vector3d(0.5, 0.5, 0.5);
  s.box_max = Eigen::Vector3d(1.5, 1.5, 1.5);
  ASSERT_TRUE(SelectVertices(s, Grid(), &v).ok());
  EXPECT_EQ(v, (std::vector<int>{13}));
}

TEST(SelectVerticesTest, Plane) {
  VertexSelection s;
  s.kind = VertexSelection::Kind::kPlane;
  s.plane_point = Eigen::Vector3d(0, 0, 2);
  s.plane_normal = Eigen::Vector3d(0, 0, 3);  // not unit: normalized by SelectVertices
  std::vector<int> v;
  ASSERT_TRUE(SelectVertices(s, Grid(), &v).ok());
  EXPECT_EQ(v, (std::vector<int>{18, 19, 20, 21, 22, 23, 24, 25, 26}));
  s.plane_normal = Eigen::Vector3d(-1, 0, 0);
  s.plane_point = Eigen::Vector3d(0.5, 0, 0);
  ASSERT_TRUE(SelectVertices(s, Grid(), &v).ok());
  EXPECT_EQ(v.size(), 9u);
  for (int i : v) EXPECT_EQ(i % 3, 0);
}

TEST(SelectVerticesTest, IndicesAllAndErrors) {
  VertexSelection s;
  s.where = "beam.yaml:3 (loads[0].select)";
  std::vector<int> v;
  ASSERT_TRUE(SelectVertices(s, Grid(), &v).ok());  // kAll
  EXPECT_EQ(v.size(), 27u);
  s.kind = VertexSelection::Kind::kIndices;
  s.indices = {5, 1, 5};
  ASSERT_TRUE(SelectVertices(s, Grid(), &v).ok());
  EXPECT_EQ(v, (std::vector<int>{1, 5}));
  s.indices = {1, 27};
  Status status = SelectVertices(s, Grid(), &v);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("beam.yaml:3 (loads[0].select): vertex index 27 is out of range"),
            std::string::npos)
      << status.message();
  s.kind = VertexSelection::Kind::kBox;
  s.box_min = s.box_max = Eigen::Vector3d(9, 9, 9);
  status = SelectVertices(s, Grid(), &v);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("beam.yaml:3 (loads[0].select): the selection picks no vertex"),
            std::string::npos)
      << status.message();
}

}  // namespace
}  // namespace femreg
