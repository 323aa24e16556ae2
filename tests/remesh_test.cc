// TetrahedralizeSurface with the surface remeshed to the edge length first (the default when
// an edge length is given): the mean edge follows L on surfaces finer and coarser than L,
// the tetrahedra have no sliver, a box keeps its edges and corners.

#include "meshing_surfaces.h"

namespace femreg {
namespace {

using namespace meshing_testing;  // NOLINT: the shared surfaces and checks

// A box [0, size.x] x [0, size.y] x [0, size.z] made of the unit cube's 12 triangles.
Surface Box(const Eigen::Vector3d& size) {
  Surface s = Cube();
  for (int v = 0; v < s.V.rows(); ++v) s.V.row(v) = s.V.row(v).cwiseProduct(size.transpose());
  return s;
}

// A sphere of radius 0.075 (a 15 cm object in metres) with edges of about 0.0031 (levels 4:
// 5,120 triangles, finer than every L below) or 0.05 (levels 0: the icosahedron, coarser).
Surface FineSphere() { return Icosphere(0.075, 4); }
Surface CoarseSphere() { return Icosphere(0.075, 0); }

MeshingReport MeshOrFail(const Surface& s, const MeshingOptions& options, TetMesh* mesh,
                         const std::string& source) {
  MeshingReport report;
  const Status status = TetrahedralizeSurface(s.V, s.F, options, mesh, &report, source);
  EXPECT_TRUE(status.ok()) << status.message();
  return report;
}

TEST(RemeshTest, MeanEdgeFollowsTheTargetOnFineAndCoarseSurfaces) {
  for (const bool fine : {true, false}) {
    const Surface s = fine ? FineSphere() : CoarseSphere();
    int previous_vertices = 0;
    for (const double length : {0.02, 0.012, 0.008}) {
      SCOPED_TRACE(std::string(fine ? "fine" : "coarse") + " sphere, L = " +
                   std::to_string(length));
      MeshingOptions options;
      options.edge_length = length;
      TetMesh mesh;
      const MeshingReport report = MeshOrFail(s, options, &mesh, "sphere");
      ASSERT_GT(mesh.num_tets(), 0);
      ExpectValidMesh(mesh);
      EXPECT_TRUE(report.remeshed);
      std::printf("%s sphere (%d triangles), L = %g: %d vertices, mean edge %.4g (%.3f L), "
                  "surface %.4g, dihedral %.1f .. %.1f deg, %.3f %% below 10\n",
                  fine ? "fine" : "coarse", report.input_triangles, length, report.vertices,
                  report.mean_edge_length, report.mean_edge_length / length,
                  report.remeshed_mean_edge_length, report.quality.min_dihedral_deg,
                  report.quality.max_dihedral_deg, 100.0 * report.small_dihedral_share);
      // The target: within about 15 % of L, on and inside the solid.
      EXPECT_NEAR(report.mean_edge_length, length, 0.15 * length);
      // The surface's edges within the remeshing's band, [4/5, 4/3] L: an edge in it is left
      // alone, so a coarse surface split in halves can land anywhere in it (1.23 L at 0.008).
      EXPECT_GT(report.remeshed_mean_edge_length, 0.8 * length);
      EXPECT_LT(report.remeshed_mean_edge_length, 4.0 / 3.0 * length);
      // No sliver: the remeshed surface's triangles are near equilateral, TetGen's quality
      // bound does the inside.
      EXPECT_GT(report.quality.min_dihedral_deg, 5.0);
      EXPECT_LT(report.quality.max_dihedral_deg, 172.0);
      EXPECT_LT(report.small_dihedral_share, 0.01);
      // The vertex count follows L (about (L0 / L)^3 in the bulk).
      EXPECT_GT(report.vertices, 2 * previous_vertices);
      previous_vertices = report.vertices;
      // The mesh fills the remeshed surface exactly; that one is within a few % of the input
      // (chords of a curved surface, on its own vertices for the coarse one).
      EXPECT_NEAR(report.mesh_volume, report.remeshed_volume, 1e-9 * report.remeshed_volume);
      EXPECT_NEAR(report.remeshed_volume, report.surface_volume, 0.05 * report.surface_volume);
      EXPECT_EQ(report.boundary_triangles, report.remeshed_triangles);
      EXPECT_EQ(report.tetgen_switches.back(), 'Y');  // TetGen kept the remeshed surface
    }
  }
}

TEST(RemeshTest, WithoutRemeshingAFineSurfaceStaysFine) {
  // The behaviour the remeshing replaces (and --no-remesh keeps): TetGen does not coarsen the
  // surface, so a surface finer than L makes edges well below L and the count hardly follows L.
  const Surface s = FineSphere();
  MeshingOptions options;
  options.remesh = false;
  options.edge_length = 0.02;
  TetMesh mesh;
  const MeshingReport coarse = MeshOrFail(s, options, &mesh, "sphere");
  options.edge_length = 0.012;
  const MeshingReport finer = MeshOrFail(s, options, &mesh, "sphere");
  EXPECT_FALSE(coarse.remeshed);
  EXPECT_LT(coarse.mean_edge_length, 0.5 * 0.02);
  EXPECT_LT(finer.vertices, 2 * coarse.vertices);
  EXPECT_NEAR(coarse.mesh_volume, coarse.surface_volume, 1e-9 * coarse.surface_volume);

  // No edge length (the surface's mean), or keep_surface: no remeshing either.
  MeshingOptions defaults;
  EXPECT_FALSE(MeshOrFail(CoarseSphere(), defaults, &mesh, "sphere").remeshed);
  MeshingOptions keep;
  keep.edge_length = 0.02;
  keep.keep_surface = true;
  const MeshingReport kept = MeshOrFail(s, keep, &mesh, "sphere");
  EXPECT_FALSE(kept.remeshed);
  EXPECT_EQ(kept.boundary_triangles, s.F.rows());
}

TEST(RemeshTest, BoxKeepsItsEdgesAndCorners) {
  const Eigen::Vector3d size(0.2, 0.1, 0.06);
  const Surface box = Box(size);
  MeshingOptions options;
  options.edge_length = 0.02;
  TetMesh mesh;
  const MeshingReport report = MeshOrFail(box, options, &mesh, "box");
  ExpectValidMesh(mesh);
  EXPECT_EQ(report.sharp_edges, 12);  // the faces' diagonals are flat
  EXPECT_EQ(report.corner_vertices, 8);
  EXPECT_NEAR(report.mean_edge_length, 0.02, 0.15 * 0.02);
  EXPECT_GT(report.quality.min_dihedral_deg, 5.0);
  // The box stays a box: the volume to rounding, every surface vertex on a face, every corner
  // a vertex of the mesh.
  EXPECT_NEAR(report.mesh_volume, size.prod(), 1e-9 * size.prod());
  for (int v : mesh.surface_vertices) {
    const Eigen::Vector3d p = mesh.rest.row(v);
    const double to_face = std::min(p.minCoeff(), (size - p).minCoeff());
    EXPECT_NEAR(to_face, 0.0, 1e-12) << "vertex " << v << " at " << p.transpose();
  }
  for (int c = 0; c < box.V.rows(); ++c) {
    double nearest = 1e300;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      nearest = std::min(nearest, (mesh.rest.row(v) - box.V.row(c)).norm());
    }
    EXPECT_LT(nearest, 1e-12) << "corner " << c;
  }

  // Without feature lines the remeshing cuts the edges and corners off: the volume shrinks.
  options.feature_angle_deg = 180.0;
  const MeshingReport rounded = MeshOrFail(box, options, &mesh, "box");
  EXPECT_EQ(rounded.sharp_edges, 0);
  std::printf("box %g x %g x %g, L = 0.02: volume %.6g with feature lines, %.6g without\n",
              size.x(), size.y(), size.z(), report.mesh_volume, rounded.mesh_volume);
  EXPECT_LT(rounded.mesh_volume, (1.0 - 1e-3) * size.prod());
}

TEST(RemeshTest, ShellsKeepTheirRegionsAndCavities) {
  // Two boxes side by side and a box with a cavity: regions numbered by the input's shells.
  const Surface two =
      Join(Box(Eigen::Vector3d(0.1, 0.1, 0.1)), Cube(Eigen::Vector3d(0.2, 0, 0), 0.1));
  MeshingOptions options;
  options.edge_length = 0.025;
  TetMesh mesh;
  const MeshingReport report = MeshOrFail(two, options, &mesh, "two boxes");
  EXPECT_EQ(report.regions, 2);
  for (int t = 0; t < mesh.num_tets(); ++t) {
    const double x = (mesh.rest(mesh.tets(t, 0), 0) + mesh.rest(mesh.tets(t, 1), 0) +
                      mesh.rest(mesh.tets(t, 2), 0) + mesh.rest(mesh.tets(t, 3), 0)) / 4.0;
    EXPECT_EQ(mesh.region(t), x < 0.15 ? 0 : 1);
  }
  const Surface hollow =
      Join(Cube(Eigen::Vector3d(-0.1, -0.1, -0.1), 0.3), Cube(Eigen::Vector3d::Zero(), 0.1));
  const MeshingReport r = MeshOrFail(hollow, options, &mesh, "hollow box");
  EXPECT_EQ(r.cavities, 1);
  EXPECT_NEAR(r.mesh_volume, 0.027 - 0.001, 1e-9);
}

TEST(RemeshTest, OptionsAreChecked) {
  MeshingOptions o;
  std::string error;
  o.feature_angle_deg = 0.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("feature_angle_deg"), std::string::npos) << error;
  o = MeshingOptions();
  o.remesh_iterations = 0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("remesh_iterations"), std::string::npos) << error;
}

}  // namespace
}  // namespace femreg
