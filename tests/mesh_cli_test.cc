// The femreg mesh command: refuses to overwrite, reports errors.

#include "meshing_surfaces.h"

namespace femreg {
namespace {

using namespace meshing_testing;  // NOLINT: the shared surfaces and checks


#ifdef FEMREG_CLI_PATH
// Runs the command line; returns its exit code and what it printed.
int RunCli(const std::string& args, std::string* out, std::string* err) {
  TempDir dir("femreg_meshing_cli");
  const std::string o = dir.path() + "/stdout", e = dir.path() + "/stderr";
  const int rc =
      std::system((std::string(FEMREG_CLI_PATH) + " " + args + " > " + o + " 2> " + e).c_str());
  if (out != nullptr) *out = ReadAll(o);
  if (err != nullptr) *err = ReadAll(e);
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST(MeshCliTest, MeshesRefusesToOverwriteAndReportsErrors) {
  TempDir dir;
  const std::string cube = dir.path() + "/cube.obj";
  WriteObj(cube, Cube());
  const std::string out_path = dir.path() + "/cube.msh";
  std::string out, err;
  ASSERT_EQ(RunCli("mesh " + cube + " --out " + out_path + " --edge-length 0.25", &out, &err), 0)
      << err;
  EXPECT_NE(out.find("8 vertices, 12 triangles"), std::string::npos) << out;
  EXPECT_NE(out.find("tetrahedra"), std::string::npos) << out;
  EXPECT_NE(out.find("dihedral angles"), std::string::npos) << out;
  TetMesh mesh;
  ASSERT_TRUE(ReadTetMesh(out_path, &mesh).ok());
  EXPECT_NEAR(RestVolume(mesh), 1.0, 1e-12);

  // A second run refuses to overwrite, and the file stays as it was.
  const std::string before = ReadAll(out_path);
  EXPECT_EQ(RunCli("mesh " + cube + " --out " + out_path + " --edge-length 0.5", &out, &err), 1);
  EXPECT_NE(err.find("exists; pass --force"), std::string::npos) << err;
  EXPECT_EQ(ReadAll(out_path), before);
  // --force overwrites (a coarser mesh now).
  EXPECT_EQ(
      RunCli("mesh " + cube + " --out " + out_path + " --edge-length 0.5 --force", &out, &err), 0)
      << err;
  TetMesh coarser;
  ASSERT_TRUE(ReadTetMesh(out_path, &coarser).ok());
  EXPECT_LT(coarser.num_tets(), mesh.num_tets());

  // --json: one object with the counts; --scale multiplies the coordinates.
  const std::string json_path = dir.path() + "/cube.vtu";
  ASSERT_EQ(RunCli("mesh " + cube + " --out " + json_path + " --scale 0.001 --json", &out, &err), 0)
      << err;
  EXPECT_EQ(out.rfind("{", 0), 0u) << out;
  EXPECT_NE(out.find("\"ok\": true"), std::string::npos) << out;
  EXPECT_NE(out.find("\"tetrahedra\": "), std::string::npos) << out;
  ASSERT_TRUE(ReadTetMesh(json_path, &mesh).ok());
  EXPECT_NEAR(RestVolume(mesh), 1e-9, 1e-21);

  // An open surface: exit 1, the reason on stderr, nothing written.
  Surface open = Cube();
  open.F.conservativeResize(11, 3);
  const std::string open_path = dir.path() + "/open.obj";
  WriteObj(open_path, open);
  const std::string not_written = dir.path() + "/open.vtk";
  EXPECT_EQ(RunCli("mesh " + open_path + " --out " + not_written, &out, &err), 1);
  EXPECT_NE(err.find(open_path), std::string::npos) << err;
  EXPECT_NE(err.find("boundary edges"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(not_written));
  EXPECT_EQ(RunCli("mesh " + open_path + " --out " + not_written + " --json", &out, &err), 1);
  EXPECT_NE(out.find("\"ok\": false"), std::string::npos) << out;

  // An unknown output format is refused before any work; bad option values by CLI11.
  EXPECT_EQ(RunCli("mesh " + cube + " --out " + dir.path() + "/cube.stl", &out, &err), 1);
  EXPECT_NE(err.find("unknown mesh format"), std::string::npos) << err;
  EXPECT_NE(RunCli("mesh " + cube + " --out " + dir.path() + "/x.vtu --quality 0.5", &out, &err),
            0);
  EXPECT_NE(RunCli("mesh " + cube + " --out " + dir.path() + "/x.vtu --edge-length -1", &out, &err),
            0);
  EXPECT_FALSE(fs::exists(dir.path() + "/x.vtu"));
  // --help explains the options and their units.
  ASSERT_EQ(RunCli("mesh --help", &out, &err), 0);
  for (const char* option : {"--edge-length", "--quality", "--max-volume", "--scale", "--force",
                             "--json", "--keep-surface", "millimetres"}) {
    EXPECT_NE(out.find(option), std::string::npos) << option;
  }
}

// --edge-length remeshes the surface first and says so; --no-remesh gives TetGen the input.
TEST(MeshCliTest, EdgeLengthRemeshesUnlessTold) {
  TempDir dir;
  const std::string sphere = dir.path() + "/sphere.obj";
  WriteObj(sphere, Icosphere(0.075, 4));  // edges of about 3 mm
  const std::string out_path = dir.path() + "/sphere.vtu";
  std::string out, err;
  ASSERT_EQ(RunCli("mesh " + sphere + " --out " + out_path + " --edge-length 0.015", &out, &err), 0)
      << err;
  EXPECT_NE(out.find("remeshed:"), std::string::npos) << out;
  EXPECT_NE(out.find("remeshed surface kept"), std::string::npos) << out;
  EXPECT_NE(out.find("% of the tetrahedra below 10 deg"), std::string::npos) << out;
  TetMesh remeshed;
  ASSERT_TRUE(ReadTetMesh(out_path, &remeshed).ok());
  ASSERT_EQ(RunCli("mesh " + sphere + " --out " + out_path + " --edge-length 0.015 --force " +
                       "--no-remesh --json",
                   &out, &err),
            0)
      << err;
  EXPECT_NE(out.find("\"remeshed\": null"), std::string::npos) << out;
  EXPECT_NE(out.find("\"remesh\": false"), std::string::npos) << out;
  TetMesh as_is;
  ASSERT_TRUE(ReadTetMesh(out_path, &as_is).ok());
  EXPECT_GT(as_is.num_vertices(), 3 * remeshed.num_vertices());  // the 3 mm surface stays
  EXPECT_NE(RunCli("mesh " + sphere + " --out " + out_path + " --force --feature-angle 0", &out,
                   &err),
            0);
  ASSERT_EQ(RunCli("mesh --help", &out, &err), 0);
  for (const char* option : {"--no-remesh", "--feature-angle", "--remesh-iterations"}) {
    EXPECT_NE(out.find(option), std::string::npos) << option;
  }
}
// --cage N: about N vertices, every surface vertex inside, said in the report (text and JSON);
// refused with --edge-length.
TEST(MeshCliTest, MakesACageAroundTheSurface) {
  TempDir dir;
  const std::string sphere = dir.path() + "/sphere.obj";
  WriteObj(sphere, Icosphere(0.05, 4));
  const std::string out_path = dir.path() + "/cage.vtu";
  std::string out, err;
  ASSERT_EQ(RunCli("mesh " + sphere + " --out " + out_path + " --cage 120", &out, &err), 0) << err;
  EXPECT_NE(out.find("cage:"), std::string::npos) << out;
  EXPECT_NE(out.find(", 0 still are"), std::string::npos) << out;
  TetMesh cage;
  ASSERT_TRUE(ReadTetMesh(out_path, &cage).ok());
  EXPECT_NEAR(cage.num_vertices(), 120, 0.3 * 120);
  ASSERT_EQ(RunCli("mesh " + sphere + " --out " + out_path + " --cage 120 --force --json", &out, &err), 0) << err;
  EXPECT_NE(out.find("\"cage\": {\"target_vertices\": 120"), std::string::npos) << out;
  EXPECT_NE(out.find("\"outside\": 0,"), std::string::npos) << out;
  EXPECT_EQ(RunCli("mesh " + sphere + " --out " + out_path + " --cage 120 --edge-length 0.01 --force", &out, &err), 1);
  EXPECT_NE(err.find("--cage chooses the edge length"), std::string::npos) << err;
}

// Two cubes that cross each other: refused with the way round it, meshed with --wrap, the
// wrap in the text and JSON reports.
TEST(MeshCliTest, WrapsASurfaceTheChecksRefuse) {
  TempDir dir;
  const std::string crossing = dir.path() + "/crossing.obj";
  WriteObj(crossing, Join(Cube(), Cube(Eigen::Vector3d(0.5, 0.25, 0.25))));
  const std::string out_path = dir.path() + "/wrapped.vtu";
  std::string out, err;
  EXPECT_EQ(RunCli("mesh " + crossing + " --out " + out_path, &out, &err), 1);
  EXPECT_NE(err.find("cross"), std::string::npos) << err;
  EXPECT_NE(err.find("--wrap ALPHA"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out_path));
  ASSERT_EQ(RunCli("mesh " + crossing + " --out " + out_path + " --wrap 0.1 --edge-length 0.2", &out, &err), 0)
      << err;
  EXPECT_NE(out.find("wrapped:   alpha 0.1, offset 0.003333"), std::string::npos) << out;
  TetMesh mesh;
  ASSERT_TRUE(ReadTetMesh(out_path, &mesh).ok());
  EXPECT_NEAR(RestVolume(mesh), 1.71875, 0.06 * 1.71875);  // the union's volume
  ASSERT_EQ(RunCli("mesh " + crossing + " --out " + out_path + " --wrap 0.1 --wrap-offset 0.01 --force --json",
                   &out, &err),
            0)
      << err;
  EXPECT_NE(out.find("\"wrapped\": {\"alpha\": 0.1, \"offset\": 0.01,"), std::string::npos) << out;
  EXPECT_EQ(RunCli("mesh " + crossing + " --out " + out_path + " --wrap -1 --force", &out, &err), 2);
}

#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
