// Tests of femreg/meshing.h: TetGen's tetrahedralization of closed surfaces (targets,
// regions and cavities, merged vertices, real surfaces) and mesh files out.

#include "meshing_surfaces.h"

#include <tuple>

#include "femreg/geometry.h"

namespace femreg {
namespace {

using namespace meshing_testing;  // NOLINT: the shared surfaces and checks

// ---------------------------------------------------------------------------------------

TEST(MeshingOptionsTest, IsValidNamesTheField) {
  std::string error;
  EXPECT_TRUE(MeshingOptions().IsValid(&error)) << error;
  MeshingOptions o;
  o.edge_length = -1.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("edge_length"), std::string::npos) << error;
  o = MeshingOptions();
  o.radius_edge_ratio = 1.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("radius_edge_ratio"), std::string::npos) << error;
  o = MeshingOptions();
  o.max_volume = std::nan("");
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("max_volume"), std::string::npos) << error;
  o = MeshingOptions();
  o.min_dihedral_deg = 30.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("min_dihedral_deg"), std::string::npos) << error;
  o = MeshingOptions();
  o.wrap = -1.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("wrap"), std::string::npos) << error;
  o = MeshingOptions();
  o.wrap_offset = std::nan("");
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("wrap_offset"), std::string::npos) << error;
  o = MeshingOptions();
  o.max_tets = 0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("max_tets"), std::string::npos) << error;

  // Through TetrahedralizeSurface: the message names the source and the field.
  Surface cube = Cube();
  TetMesh mesh;
  o = MeshingOptions();
  o.edge_length = -1.0;
  const Status s = TetrahedralizeSurface(cube.V, cube.F, o, &mesh, nullptr, "cube.obj");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("cube.obj"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("edge_length"), std::string::npos) << s.message();
}

TEST(MeshingTest, CubeFromObjIsFilledWithPositiveTetsOfTheTargetSize) {
  TempDir dir;
  const std::string path = dir.path() + "/cube.obj";
  WriteObj(path, Cube());
  Surface s;
  ASSERT_TRUE(ReadSurface(path, &s.V, &s.F).ok());
  ASSERT_EQ(s.F.rows(), 12);

  MeshingOptions options;
  options.edge_length = 0.1;
  TetMesh mesh;
  MeshingReport report;
  const Status status = TetrahedralizeSurface(s.V, s.F, options, &mesh, &report, path);
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectValidMesh(mesh);

  // The tets fill the cube exactly: TetGen splits the flat faces but moves no point off them.
  // Summing a few thousand tet volumes, each exact to ~1e-16 relative, leaves < 1e-12.
  EXPECT_NEAR(RestVolume(mesh), 1.0, 1e-12);
  EXPECT_NEAR(report.mesh_volume, 1.0, 1e-12);
  EXPECT_NEAR(report.surface_volume, 1.0, 1e-12);
  double area = 0.0;
  for (int f = 0; f < mesh.num_surface_triangles(); ++f) {
    const Eigen::Vector3d a = mesh.rest.row(mesh.surface(f, 0)),
                          b = mesh.rest.row(mesh.surface(f, 1)),
                          c = mesh.rest.row(mesh.surface(f, 2));
    area += 0.5 * (b - a).cross(c - a).norm();
    // Outward: the normal points away from the centre.
    EXPECT_GT((b - a).cross(c - a).dot((a + b + c) / 3.0 - Eigen::Vector3d(0.5, 0.5, 0.5)), 0.0);
  }
  EXPECT_NEAR(area, 6.0, 1e-12);
  for (int v : mesh.surface_vertices) {
    const Eigen::Vector3d p = mesh.rest.row(v);
    const double to_face = std::min(p.minCoeff(), 1.0 - p.maxCoeff());
    EXPECT_NEAR(to_face, 0.0, 1e-15);
  }

  // The size is honoured roughly: no tet is larger than the bound, so there are at least
  // volume / max_volume of them; Delaunay refinement makes tets below the bound, so allow up to 5
  // times as many (docs/notes/2026-11-28-figures-from-code-comments.md); TetGen is deterministic,
  // the margin
  // of 0.75 .. 1.1 L leaves room for another TetGen build, not for a wrong volume bound
  // (the regular tetrahedron's volume gives 0.82 L, half of it 0.65 L).
  const double max_volume = std::pow(0.1, 3) / (4.0 * std::sqrt(2.0));
  EXPECT_NEAR(report.max_volume, max_volume, 1e-15);
  EXPECT_GE(mesh.num_tets(), 1.0 / max_volume);
  EXPECT_LE(mesh.num_tets(), 5.0 / max_volume);
  const double mean_edge = MeanEdge(mesh);
  EXPECT_NEAR(report.mean_edge_length, mean_edge, 1e-12);
  EXPECT_GT(mean_edge, 0.75 * 0.1);
  EXPECT_LT(mean_edge, 1.1 * 0.1);
  // The quality bound: the radius-edge ratio <= 1.5 keeps the aspect ratio moderate; TetGen
  // does not bound dihedral angles this way (slivers), so only sanity bounds here.
  EXPECT_GT(report.quality.min_dihedral_deg, 0.0);
  EXPECT_LT(report.quality.max_dihedral_deg, 180.0);
  EXPECT_EQ(report.input_vertices, 8);
  EXPECT_EQ(report.input_triangles, 12);
  EXPECT_EQ(report.merged_vertices, 0);
  EXPECT_EQ(report.shells, 1);
  EXPECT_EQ(report.regions, 1);
  EXPECT_EQ(report.vertices, mesh.num_vertices());
  EXPECT_EQ(report.tets, mesh.num_tets());

  // The elements come along a curve through space, not in TetGen's order: consecutive ones are
  // neighbours (median centroid distance half an edge on a scan; TetGen's order gave 24 edges).
  std::vector<double> step;
  for (int t = 1; t < mesh.num_tets(); ++t) {
    Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) {
      a += 0.25 * mesh.rest.row(mesh.tets(t - 1, k)).transpose();
      b += 0.25 * mesh.rest.row(mesh.tets(t, k)).transpose();
    }
    step.push_back((b - a).norm());
  }
  std::nth_element(step.begin(), step.begin() + static_cast<std::ptrdiff_t>(step.size() / 2), step.end());
  EXPECT_LT(step[step.size() / 2], mean_edge);

  // A finer target makes more tets.
  options.edge_length = 0.05;
  TetMesh finer;
  ASSERT_TRUE(TetrahedralizeSurface(s.V, s.F, options, &finer, nullptr, path).ok());
  EXPECT_GT(finer.num_tets(), 4 * mesh.num_tets());  // 8 times in the bulk
}

TEST(MeshingTest, SphereFromBinaryStlHasTheInscribedPolyhedronsVolume) {
  TempDir dir;
  const double r = 0.05;
  const Surface sphere = Icosphere(r, 3);  // 642 vertices, 1280 triangles
  const std::string path = dir.path() + "/sphere.stl";
  WriteBinaryStl(path, sphere);
  Surface s;
  ASSERT_TRUE(ReadSurface(path, &s.V, &s.F).ok());
  ASSERT_EQ(s.F.rows(), 1280);
  ASSERT_EQ(s.V.rows(), 642);  // the STL reader welds the 3840 corners by exact position

  TetMesh mesh;
  MeshingReport report;
  const Status status = TetrahedralizeSurface(s.V, s.F, MeshingOptions(), &mesh, &report, path);
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectValidMesh(mesh);
  // The tets fill the polyhedron the triangles bound, not the ball: compare with the
  // polyhedron's own volume (as read, in float precision) to summation rounding (1e-12
  // relative). Vertices on the sphere make an inscribed, convex polyhedron: it lies inside the
  // ball of radius r and contains the ball of radius d_min, the distance from the centre to
  // the nearest triangle plane; its volume is between theirs (0.9914 of the ball measured).
  const double polyhedron = EnclosedVolume(s);
  double d_min = r;
  for (int t = 0; t < s.F.rows(); ++t) {
    const Eigen::Vector3d a = s.V.row(s.F(t, 0)), b = s.V.row(s.F(t, 1)), c = s.V.row(s.F(t, 2));
    d_min = std::min(d_min, std::abs((b - a).cross(c - a).normalized().dot(a)));
  }
  EXPECT_NEAR(RestVolume(mesh), polyhedron, 1e-12 * polyhedron);
  EXPECT_LT(polyhedron, 4.0 / 3.0 * kPi * r * r * r);
  EXPECT_GT(polyhedron, 4.0 / 3.0 * kPi * d_min * d_min * d_min);
  EXPECT_GT(d_min, 0.98 * r);  // level 3: the triangles are small
  // The default target is the surface's mean edge length. The ball is only 13 of them
  // across, so the surface's triangles (whose edges TetGen keeps or splits, never joins) and
  // the refinement around them set the size as much as the volume bound does: the mean edge
  // comes out shorter than the target (0.85 L measured); only a loose check here.
  EXPECT_NEAR(report.edge_length, report.surface_mean_edge_length, 1e-15);
  EXPECT_GT(report.mean_edge_length, 0.6 * report.edge_length);
  EXPECT_LT(report.mean_edge_length, 1.1 * report.edge_length);
  // Every mesh vertex lies in the ball (TetGen adds points on the flat triangles and inside).
  for (int v = 0; v < mesh.num_vertices(); ++v) EXPECT_LE(mesh.rest.row(v).norm(), r * (1 + 1e-6));
}

TEST(MeshingTest, KeepSurfaceKeepsEveryInputTriangle) {
  const Surface sphere = Icosphere(1.0, 2);  // 320 triangles
  MeshingOptions options;
  options.keep_surface = true;
  options.edge_length = 0.2;
  TetMesh mesh;
  MeshingReport report;
  const Status status = TetrahedralizeSurface(sphere.V, sphere.F, options, &mesh, &report);
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectValidMesh(mesh);
  ASSERT_EQ(mesh.num_surface_triangles(), sphere.F.rows());
  // The same triangles, as sets of corner positions (TetGen copies the input points).
  auto key = [](const Vertices& V, int a, int b, int c) {
    std::vector<std::vector<double>> corners;
    for (int i : {a, b, c}) corners.push_back({V(i, 0), V(i, 1), V(i, 2)});
    std::sort(corners.begin(), corners.end());
    return corners;
  };
  std::set<std::vector<std::vector<double>>> input;
  for (int t = 0; t < sphere.F.rows(); ++t)
    input.insert(key(sphere.V, sphere.F(t, 0), sphere.F(t, 1), sphere.F(t, 2)));
  for (int t = 0; t < mesh.num_surface_triangles(); ++t) {
    EXPECT_TRUE(
        input.count(key(mesh.rest, mesh.surface(t, 0), mesh.surface(t, 1), mesh.surface(t, 2))))
        << "boundary triangle " << t << " is not an input triangle";
  }
  EXPECT_NE(report.tetgen_switches.find('Y'), std::string::npos);
  // Interior points were added for the size.
  EXPECT_GT(mesh.num_vertices(), sphere.V.rows());
}

TEST(MeshingTest, DisjointShellsAreRegionsAndNestedShellsCavities) {
  // Two disjoint cubes: two regions of volume 1 each.
  const Surface two = Join(Cube(), Cube(Eigen::Vector3d(2, 0, 0)));
  MeshingOptions options;
  options.edge_length = 0.25;
  TetMesh mesh;
  MeshingReport report;
  Status status = TetrahedralizeSurface(two.V, two.F, options, &mesh, &report);
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectValidMesh(mesh);
  EXPECT_EQ(report.shells, 2);
  EXPECT_EQ(report.cavities, 0);
  EXPECT_EQ(report.regions, 2);
  double volume[2] = {0, 0};
  for (int t = 0; t < mesh.num_tets(); ++t) {
    const Eigen::Vector3d c = (mesh.rest.row(mesh.tets(t, 0)) + mesh.rest.row(mesh.tets(t, 1)) +
                               mesh.rest.row(mesh.tets(t, 2)) + mesh.rest.row(mesh.tets(t, 3))) /
                              4.0;
    // Region 0 is the shell of the first triangle: the cube at the origin.
    EXPECT_EQ(mesh.region(t), c.x() < 1.5 ? 0 : 1);
    volume[mesh.region(t)] +=
        SignedTetVolume(mesh.rest.row(mesh.tets(t, 0)), mesh.rest.row(mesh.tets(t, 1)),
                        mesh.rest.row(mesh.tets(t, 2)), mesh.rest.row(mesh.tets(t, 3)));
  }
  EXPECT_NEAR(volume[0], 1.0, 1e-12);
  EXPECT_NEAR(volume[1], 1.0, 1e-12);
  options.region_per_shell = false;
  ASSERT_TRUE(TetrahedralizeSurface(two.V, two.F, options, &mesh, &report).ok());
  EXPECT_EQ(mesh.region.maxCoeff(), 0);

  // A cube of side 1 inside one of side 3: a hollow box of volume 26, the cavity unmeshed,
  // whichever way the inner shell faces.
  options.region_per_shell = true;
  for (bool flip : {true, false}) {
    const Surface hollow = Join(Cube(Eigen::Vector3d(-1, -1, -1), 3.0), Cube(), flip);
    status = TetrahedralizeSurface(hollow.V, hollow.F, options, &mesh, &report);
    ASSERT_TRUE(status.ok()) << status.message();
    ExpectValidMesh(mesh);
    EXPECT_EQ(report.shells, 2);
    EXPECT_EQ(report.cavities, 1);
    EXPECT_EQ(report.regions, 1);
    EXPECT_NEAR(RestVolume(mesh), 26.0, 1e-10);
    for (int t = 0; t < mesh.num_tets(); ++t) {
      const Eigen::Vector3d c = (mesh.rest.row(mesh.tets(t, 0)) + mesh.rest.row(mesh.tets(t, 1)) +
                                 mesh.rest.row(mesh.tets(t, 2)) + mesh.rest.row(mesh.tets(t, 3))) /
                                4.0;
      EXPECT_FALSE(c.minCoeff() > 0.0 && c.maxCoeff() < 1.0) << "tet " << t << " in the cavity";
    }
  }
}

TEST(MeshingTest, NearDuplicateVerticesAreMerged) {
  // Every triangle with its own corners, each a hair off (as a float export might leave them).
  const Surface cube = Cube();
  Surface soup;
  soup.V.resize(3 * cube.F.rows(), 3);
  soup.F.resize(cube.F.rows(), 3);
  for (int t = 0; t < cube.F.rows(); ++t) {
    for (int k = 0; k < 3; ++k) {
      soup.V.row(3 * t + k) = cube.V.row(cube.F(t, k)).array() + 1e-13 * ((t + k) % 3);
      soup.F(t, k) = 3 * t + k;
    }
  }
  TetMesh mesh;
  MeshingReport report;
  Status status = TetrahedralizeSurface(soup.V, soup.F, MeshingOptions(), &mesh, &report);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(report.merged_vertices, 36 - 8);
  EXPECT_EQ(report.surface_vertices, 8);
  EXPECT_NEAR(RestVolume(mesh), 1.0, 1e-9);  // the corners moved by <= 2e-13

  // With merging limited to exact copies the soup is open everywhere.
  MeshingOptions exact;
  exact.merge_distance = 0.0;
  status = TetrahedralizeSurface(soup.V, soup.F, exact, &mesh, &report, "soup.stl");
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("boundary edges"), std::string::npos) << status.message();

  // An unused vertex is dropped and counted.
  Surface extra = cube;
  extra.V.conservativeResize(9, 3);
  extra.V.row(8) << 5, 5, 5;
  ASSERT_TRUE(TetrahedralizeSurface(extra.V, extra.F, MeshingOptions(), &mesh, &report).ok());
  EXPECT_EQ(report.unused_vertices, 1);
  EXPECT_LE(mesh.rest.maxCoeff(), 1.0);
}

TEST(MeshingTest, SelfIntersectionCheckAgreesWithTetGen) {
  // Spheres with a few vertices pushed at random, some far enough to fold the surface
  // through itself. Whatever the check refuses, TetGen (without the check) must fail on too,
  // and whatever it accepts TetGen must mesh: no false alarm, no miss, by TetGen's own
  // judgement (docs/notes/2026-11-28-figures-from-code-comments.md).
  std::mt19937 rng(7);
  std::normal_distribution<double> push(0.0, 0.5);
  int refused = 0, accepted = 0;
  for (int i = 0; i < 30; ++i) {
    Surface s = Icosphere(1.0, 2);
    std::uniform_int_distribution<int> pick(0, static_cast<int>(s.V.rows()) - 1);
    for (int k = 0; k <= i % 3; ++k)
      s.V.row(pick(rng)) += Eigen::RowVector3d(push(rng), push(rng), push(rng));
    MeshingOptions checked, unchecked;
    checked.edge_length = unchecked.edge_length = 0.5;
    checked.remesh = unchecked.remesh = false;  // TetGen judges the input itself
    unchecked.check_self_intersections = false;
    TetMesh mesh;
    const Status with_check = TetrahedralizeSurface(s.V, s.F, checked, &mesh, nullptr, "sphere");
    const Status tetgen_alone =
        TetrahedralizeSurface(s.V, s.F, unchecked, &mesh, nullptr, "sphere");
    EXPECT_EQ(with_check.ok(), tetgen_alone.ok())
        << "case " << i << ": with the check: " << with_check.message()
        << "\nTetGen alone: " << tetgen_alone.message();
    (with_check.ok() ? accepted : refused) += 1;
  }
  // Both kinds occurred, so the comparison meant something.
  EXPECT_GT(refused, 0);
  EXPECT_GT(accepted, 0);
}

// The vertices of `points` outside `mesh` (in no element, up to round-off). EmbedPoints
// without clamping looks among the nearest elements only; one it finds outside them all is
// tested against every element.
int Outside(const TetMesh& mesh, const Vertices& points) {
  const EmbeddedPoints e = EmbedPoints(mesh, points, /*clamp=*/false);
  int outside = 0;
  for (size_t i = 0; i < e.barycentric.size(); ++i) {
    if (e.barycentric[i].minCoeff() >= -1e-9) continue;
    const Eigen::Vector3d p = points.row(static_cast<Eigen::Index>(i)).transpose();
    bool inside = false;
    for (int t = 0; t < mesh.num_tets() && !inside; ++t) {
      Eigen::Matrix3d D;
      for (int k = 0; k < 3; ++k) D.col(k) = (mesh.rest.row(mesh.tets(t, k + 1)) - mesh.rest.row(mesh.tets(t, 0))).transpose();
      const Eigen::Vector3d l = D.inverse() * (p - mesh.rest.row(mesh.tets(t, 0)).transpose());
      inside = l.minCoeff() >= -1e-9 && l.sum() <= 1.0 + 1e-9;
    }
    outside += !inside;
  }
  return outside;
}

TEST(MeshingTest, RealSurfaces) {
  // Public surfaces beside the repository when present (not part of it): the Bunny is
  // clean; the dragon has duplicated triangles; the smoothed liver folds through itself in
  // 7 places (TetGen's -d finds the same 7 pairs).
  const std::string dir = FEMREG_SHARED_MESHES_DIR;
  if (!fs::exists(dir + "/Bunny.stl")) GTEST_SKIP() << dir << " does not exist";
  Surface s;
  ASSERT_TRUE(ReadSurface(dir + "/Bunny.stl", &s.V, &s.F).ok());
  MeshingOptions options;
  options.edge_length = 1.0;  // the Bunny is about 5 x 5 x 4 (units of the file)
  TetMesh mesh;
  MeshingReport report;
  Status status = TetrahedralizeSurface(s.V, s.F, options, &mesh, &report, "Bunny.stl");
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectValidMesh(mesh);
  // The mesh fills the remeshed surface exactly; remeshing at L = 1 cuts a few % off the ears.
  EXPECT_TRUE(report.remeshed);
  EXPECT_NEAR(report.mesh_volume, report.remeshed_volume, 1e-12 * report.surface_volume);
  EXPECT_NEAR(report.remeshed_volume, report.surface_volume, 0.05 * report.surface_volume);
  options.remesh = false;
  status = TetrahedralizeSurface(s.V, s.F, options, &mesh, &report, "Bunny.stl");
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_NEAR(report.mesh_volume, report.surface_volume, 1e-12 * report.surface_volume);
  options.remesh = true;

  ASSERT_TRUE(ReadSurface(dir + "/dragon.obj", &s.V, &s.F).ok());
  status = TetrahedralizeSurface(s.V, s.F, options, &mesh, &report, "dragon.obj");
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("non-manifold"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("coincide"), std::string::npos) << status.message();

  ASSERT_TRUE(ReadSurface(dir + "/liver-smooth.obj", &s.V, &s.F).ok());
  status = TetrahedralizeSurface(s.V, s.F, options, &mesh, &report, "liver-smooth.obj");
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("7 pairs of triangles that cross"), std::string::npos)
      << status.message();

  // Wrapped first, both are meshed: the liver (about 6 x 5 x 4) at alpha 0.2, the dragon
  // (about 23 x 16 x 10) at alpha 1. As it is, the wrap holds every vertex of the input;
  // remeshed to L, about the same volume.
  for (const auto& [name, alpha, length] :
       {std::tuple<const char*, double, double>{"liver-smooth.obj", 0.2, 0.3}, {"dragon.obj", 1.0, 0.6}}) {
    ASSERT_TRUE(ReadSurface(dir + "/" + name, &s.V, &s.F).ok());
    MeshingOptions wrap;
    wrap.wrap = alpha;
    wrap.keep_surface = true;  // the wrap as it is
    status = TetrahedralizeSurface(s.V, s.F, wrap, &mesh, &report, name);
    ASSERT_TRUE(status.ok()) << status.message();
    ExpectValidMesh(mesh);
    EXPECT_TRUE(report.wrapped);
    EXPECT_EQ(Outside(mesh, s.V), 0) << name;
    const double wrapped_volume = report.surface_volume;
    wrap.keep_surface = false;
    wrap.edge_length = length;
    status = TetrahedralizeSurface(s.V, s.F, wrap, &mesh, &report, name);
    ASSERT_TRUE(status.ok()) << status.message();
    ExpectValidMesh(mesh);
    EXPECT_NEAR(RestVolume(mesh), wrapped_volume, 0.03 * wrapped_volume) << name;
  }
}

// A broken surface is refused with the way round it, and --wrap meshes a closed surface
// around it: two cubes that cross each other (their union's volume is 1.71875), and a box
// with a face missing (closed over, the opening being narrower than alpha). Meshed as it is
// (keep_surface), the wrap holds every input vertex; remeshed, its chords may cut a vertex
// off by up to about L^2 / (8 R).
TEST(MeshingTest, WrapMeshesAClosedSurfaceAroundABrokenOne) {
  const Surface crossing = Join(Cube(), Cube(Eigen::Vector3d(0.5, 0.25, 0.25)));
  Surface open = Cube();
  open.F.conservativeResize(open.F.rows() - 2, 3);  // one face of two triangles less
  for (const Surface* broken : std::vector<const Surface*>{&crossing, &open}) {
    const bool is_open = broken == &open;
    MeshingOptions options;
    TetMesh mesh;
    MeshingReport report;
    Status status = TetrahedralizeSurface(broken->V, broken->F, options, &mesh, &report, "broken.obj");
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("--wrap"), std::string::npos) << status.message();
    EXPECT_FALSE(report.wrapped);

    options.wrap = is_open ? 1.5 : 0.1;  // the open face is 1 across: a wider alpha closes it
    options.keep_surface = true;          // the wrap as it is
    status = TetrahedralizeSurface(broken->V, broken->F, options, &mesh, &report, "broken.obj");
    ASSERT_TRUE(status.ok()) << status.message();
    ExpectValidMesh(mesh);
    EXPECT_TRUE(report.wrapped);
    EXPECT_NEAR(report.wrap_offset, options.wrap / 30.0, 1e-15);
    EXPECT_GT(report.wrapped_triangles, 0);
    EXPECT_EQ(report.shells, 1);
    // The wrap lies outside the input: every input vertex is in the mesh, which holds the
    // solid and little more (the offset, and corners rounded at alpha).
    EXPECT_EQ(Outside(mesh, broken->V), 0);
    const double solid = is_open ? 1.0 : 1.71875;
    EXPECT_GT(RestVolume(mesh), solid);
    EXPECT_LT(RestVolume(mesh), (is_open ? 1.3 : 1.06) * solid);
    options.keep_surface = false;
    options.edge_length = 0.2;  // remeshed: about the same solid
    status = TetrahedralizeSurface(broken->V, broken->F, options, &mesh, &report, "broken.obj");
    ASSERT_TRUE(status.ok()) << status.message();
    ExpectValidMesh(mesh);
    EXPECT_NEAR(RestVolume(mesh), report.surface_volume, 0.05 * report.surface_volume);
  }

  // Without an edge length the wrap is meshed at its own detail: L = alpha.
  {
    MeshingOptions options;
    options.wrap = 0.25;
    TetMesh mesh;
    MeshingReport report;
    ASSERT_TRUE(TetrahedralizeSurface(crossing.V, crossing.F, options, &mesh, &report, "crossing.obj").ok());
    EXPECT_EQ(report.edge_length, 0.25);
    EXPECT_TRUE(report.remeshed);
    EXPECT_NEAR(report.mean_edge_length, 0.25, 0.1);
  }

  // Nothing to wrap: flat triangles only, refused (CGAL skips them, and would fail on none);
  // input that is not a surface at all is refused without the hint.
  {
    Vertices flat(4, 3);
    flat << 0, 0, 0, 1, 0, 0, 2, 0, 0, 1, 1e-30, 0;
    Triangles tri(2, 3);
    tri << 0, 1, 2, 0, 0, 3;
    MeshingOptions options;
    options.wrap = 0.1;
    TetMesh mesh;
    Status status = TetrahedralizeSurface(flat, tri, options, &mesh, nullptr, "flat.obj");
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("flat"), std::string::npos) << status.message();
    tri << 0, 1, 2, 0, 1, 7;
    status = TetrahedralizeSurface(flat, tri, options, &mesh, nullptr, "flat.obj");
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("does not exist"), std::string::npos) << status.message();
    options.wrap = 0.0;
    status = TetrahedralizeSurface(Vertices::Zero(3, 3), Triangles(Eigen::RowVector3i(0, 1, 2)), options, &mesh,
                                   nullptr, "point.obj");
    ASSERT_FALSE(status.ok());
    EXPECT_EQ(status.message().find("--wrap"), std::string::npos) << status.message();
  }

  // A cage of the crossing cubes: the wrap made once, every input vertex inside.
  MeshingOptions options;
  options.wrap = 0.2;
  TetMesh cage;
  CageReport report;
  Status status = MakeCage(crossing.V, crossing.F, 60, options, &cage, &report, "crossing.obj");
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectValidMesh(cage);
  EXPECT_TRUE(report.meshing.wrapped);
  EXPECT_EQ(report.meshing.input_triangles, crossing.F.rows());
  EXPECT_EQ(report.outside_vertices, 0);
  EXPECT_EQ(Outside(cage, crossing.V), 0);
  options.wrap = 0.0;
  status = MakeCage(crossing.V, crossing.F, 60, options, &cage, &report, "crossing.obj");
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("--wrap"), std::string::npos) << status.message();
  EXPECT_FALSE(report.meshing.wrapped);
  // A wrap the cage refuses (merged into nothing by a huge merge distance): the report keeps
  // the wrap, and the message does not suggest wrapping it again.
  options.wrap = 0.2;
  options.merge_distance = 10.0;
  status = MakeCage(crossing.V, crossing.F, 60, options, &cage, &report, "crossing.obj");
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message().find("--wrap ALPHA (MeshingOptions::wrap)"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("wrapped at alpha 0.2"), std::string::npos) << status.message();
  EXPECT_TRUE(report.meshing.wrapped);
  EXPECT_EQ(report.meshing.input_triangles, crossing.F.rows());
}

TEST(MeshingTest, TooFineATargetIsRefusedBeforeTetGenRuns) {
  const Surface cube = Cube();
  MeshingOptions options;
  options.edge_length = 1e-4;  // at least 7e12 tets
  const std::string message = Refusal(cube, options);
  EXPECT_NE(message.find("max_tets"), std::string::npos) << message;
}

TEST(MeshingTest, WrittenMeshesReadBackInEveryFormat) {
  TempDir dir;
  const Surface two = Join(Cube(), Cube(Eigen::Vector3d(2, 0, 0)));
  MeshingOptions options;
  options.edge_length = 0.3;
  TetMesh mesh;
  ASSERT_TRUE(TetrahedralizeSurface(two.V, two.F, options, &mesh, nullptr).ok());
  for (const char* ext : {".vtu", ".msh", ".mesh", ".vtk"}) {
    const std::string path = dir.path() + "/out" + ext;
    Status s = WriteTetMesh(path, mesh);
    ASSERT_TRUE(s.ok()) << s.message();
    TetMesh back;
    s = ReadTetMesh(path, &back);
    ASSERT_TRUE(s.ok()) << ext << ": " << s.message();
    EXPECT_EQ(back.num_vertices(), mesh.num_vertices()) << ext;
    EXPECT_EQ(back.num_tets(), mesh.num_tets()) << ext;
    EXPECT_EQ(back.tets, mesh.tets) << ext;
    EXPECT_EQ(back.region, mesh.region) << ext;
    // Text formats print 17 significant digits and VTU stores doubles: positions come back
    // to the last bit or so; 1e-14 leaves room for a reader's decimal conversion.
    EXPECT_LT((back.rest - mesh.rest).cwiseAbs().maxCoeff(), 1e-14) << ext;
  }
  // Unknown extensions and folders that do not exist are refused, and nothing is left.
  EXPECT_FALSE(WriteTetMesh(dir.path() + "/out.stl", mesh).ok());
  const Status s = WriteTetMesh(dir.path() + "/no/such/folder/out.vtk", mesh);
  EXPECT_FALSE(s.ok());
  EXPECT_FALSE(fs::exists(dir.path() + "/out.stl"));
}

}  // namespace
}  // namespace femreg
