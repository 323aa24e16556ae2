// The surface checks before TetGen runs: open, self-intersecting, non-manifold and
// inconsistently oriented surfaces refused, naming what is wrong.

#include "meshing_surfaces.h"

namespace femreg {
namespace {

using namespace meshing_testing;  // NOLINT: the shared surfaces and checks

TEST(MeshingTest, OpenSurfaceIsRefusedWithItsBoundaryEdges) {
  Surface open = Cube();
  open.F.conservativeResize(11, 3);  // one triangle of the top missing: 3 boundary edges
  const std::string message = Refusal(open);
  EXPECT_NE(message.find("3 boundary edges: the surface is open"), std::string::npos) << message;
  // The example edge is given by its corners' positions.
  EXPECT_NE(message.find("the edge ("), std::string::npos) << message;
}

TEST(MeshingTest, SelfIntersectingSurfaceIsRefusedNamingTriangles) {
  // Two cubes overlapping by half: their faces cross.
  const Surface overlapping = Join(Cube(), Cube(Eigen::Vector3d(0.5, 0.5, 0.5)));
  std::string message = Refusal(overlapping);
  EXPECT_NE(message.find("self-intersections"), std::string::npos) << message;
  EXPECT_NE(message.find("cross"), std::string::npos) << message;
  EXPECT_NE(message.find("triangles "), std::string::npos) << message;

  // The top corner (1,1,1) pulled down through the bottom face: its triangles cross the
  // bottom's (topologically still a closed, consistently oriented surface).
  Surface folded = Cube();
  folded.V.row(7) << 0.5, 0.5, -1.0;
  message = Refusal(folded);
  EXPECT_NE(message.find("self-intersections"), std::string::npos) << message;

  // Two cubes touching along a face (not sharing vertices): they touch, which TetGen cannot
  // mesh as two solids.
  const Surface touching = Join(Cube(), Cube(Eigen::Vector3d(1, 0.25, 0.25), 0.5));
  message = Refusal(touching);
  EXPECT_NE(message.find("touch"), std::string::npos) << message;

  // With the check off, TetGen itself stops on the crossing.
  MeshingOptions unchecked;
  unchecked.check_self_intersections = false;
  message = Refusal(overlapping, unchecked);
  EXPECT_NE(message.find("TetGen"), std::string::npos) << message;
}

TEST(MeshingTest, NonManifoldAndInconsistentSurfacesAreRefused) {
  // Two cubes sharing an edge: after merging, that edge is in 4 triangles.
  std::string message = Refusal(Join(Cube(), Cube(Eigen::Vector3d(1, 1, 0))));
  EXPECT_NE(message.find("edges shared by more than two triangles (non-manifold)"),
            std::string::npos)
      << message;
  // Two cubes sharing a corner: one vertex, two fans.
  message = Refusal(Join(Cube(), Cube(Eigen::Vector3d(1, 1, 1))));
  EXPECT_NE(message.find("1 vertices where separate sheets"), std::string::npos) << message;
  // One triangle flipped: its three edges run the same way as their neighbours'.
  Surface flipped = Cube();
  flipped.F.row(3) = Eigen::RowVector3i(Cube().F(3, 0), Cube().F(3, 2), Cube().F(3, 1));
  message = Refusal(flipped);
  EXPECT_NE(message.find("3 edges whose two triangles are oriented inconsistently"),
            std::string::npos)
      << message;
  // A zero-area triangle (a corner repeated).
  Surface sliver = Cube();
  sliver.F.conservativeResize(13, 3);
  sliver.F.row(12) << 0, 1, 1;
  message = Refusal(sliver);
  EXPECT_NE(message.find("1 zero-area triangles"), std::string::npos) << message;
  // A closed sheet with no volume: a triangle and its reverse. The self-intersection check
  // calls them coincident; without it, the volume check refuses them.
  Surface pillow;
  pillow.V = Cube().V.topRows(3);
  pillow.F.resize(2, 3);
  pillow.F << 0, 1, 2, 0, 2, 1;
  message = Refusal(pillow);
  EXPECT_NE(message.find("coincide"), std::string::npos) << message;
  MeshingOptions unchecked;
  unchecked.check_self_intersections = false;
  message = Refusal(pillow, unchecked);
  EXPECT_NE(message.find("encloses no volume"), std::string::npos) << message;
  // Out-of-range indices and non-finite coordinates.
  Surface bad = Cube();
  bad.F(5, 1) = 8;
  message = Refusal(bad);
  EXPECT_NE(message.find("triangle 5 refers to vertex 8"), std::string::npos) << message;
  bad = Cube();
  bad.V(2, 1) = std::nan("");
  message = Refusal(bad);
  EXPECT_NE(message.find("vertex 2 is not finite"), std::string::npos) << message;
}

}  // namespace
}  // namespace femreg
