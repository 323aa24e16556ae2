// femreg eval: VTU geometry in file order, surface distances, and the command on results
// equal to the ground truth and offset from it.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "femreg/eval.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg_test_config.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace femreg {
namespace {

class TempDir : public testing_util::TempDir {
 public:
  TempDir() : testing_util::TempDir("femreg_eval_test") {}
};

TEST(EvalTest, VtuGeometryKeepsTheFileOrder) {
  TempDir dir;
  TetMesh mesh = MakeBox(Eigen::Vector3d(0.1, 0.05, 0.05), 3, 2, 2);
  Vertices moved = mesh.rest;
  moved.col(2) += 0.3 * moved.col(0).cwiseProduct(moved.col(0));  // bent
  const std::string path = dir.path() + "/m.vtu";
  ASSERT_TRUE(WriteVtu(path, mesh, moved).ok());
  VtuGeometry g;
  ASSERT_TRUE(ReadVtuGeometry(path, &g).ok());
  ASSERT_EQ(g.points.rows(), mesh.num_vertices());
  EXPECT_EQ((g.points - moved).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(g.tets, mesh.tets);
  EXPECT_EQ(g.surface.rows(), mesh.num_surface_triangles());
  EXPECT_FALSE(ReadVtuGeometry(dir.path() + "/missing.vtu", &g).ok());
}

TEST(EvalTest, SurfaceDistanceOfAShiftedBox) {
  TetMesh coarse = MakeBox(Eigen::Vector3d(0.1, 0.05, 0.05), 4, 2, 2);
  TetMesh fine = MakeBox(Eigen::Vector3d(0.1, 0.05, 0.05), 8, 4, 4);
  // The same box meshed differently: zero distance.
  SurfaceDistance d = ComputeSurfaceDistance(coarse.rest, coarse.surface, fine.rest, fine.surface);
  EXPECT_LT(d.hausdorff, 1e-12);
  EXPECT_GT(d.samples_a, 0);
  // Shifted along x by 3 mm: the x faces are 3 mm apart, the others slide.
  Vertices shifted = coarse.rest;
  shifted.col(0).array() += 0.003;
  d = ComputeSurfaceDistance(shifted, coarse.surface, fine.rest, fine.surface);
  EXPECT_NEAR(d.hausdorff, 0.003, 1e-12);
  EXPECT_GT(d.mean, 0.0);
  EXPECT_LT(d.mean, 0.003);
}

// Ground truth CSVs: what WriteGroundTruthFrame writes reads back; blanks, '+', CRLF and
// comment lines are accepted; a malformed row is refused with its line and field.
TEST(EvalTest, GroundTruthCsvRoundTripAndErrors) {
  TempDir dir;
  GroundTruthFrame frame;
  frame.positions.resize(3, 3);
  frame.positions << 0.1, -0.25, 3e-5, 1.5, 0.0, -2.0, -1e-10, 0.5, 0.125;
  frame.visible = {1, 0, 1};
  const std::string path = dir.path() + "/truth.csv";
  ASSERT_TRUE(WriteGroundTruthFrame(path, frame).ok());
  GroundTruthFrame back;
  ASSERT_TRUE(ReadGroundTruthFrame(path, &back).ok());
  ASSERT_EQ(back.positions.rows(), 3);
  EXPECT_LT((back.positions - frame.positions).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_EQ(back.visible, frame.visible);

  auto read = [&](const std::string& text, GroundTruthFrame* out) {
    std::ofstream(path, std::ios::binary) << text;
    return ReadGroundTruthFrame(path, out);
  };
  ASSERT_TRUE(read("x,y,z,visible\r\n# a comment\r\n 1.5 , +2,-3e-3,1\r\n\r\n4,5,6,0", &back).ok());
  ASSERT_EQ(back.positions.rows(), 2);
  EXPECT_DOUBLE_EQ(back.positions(0, 0), 1.5);
  EXPECT_DOUBLE_EQ(back.positions(0, 1), 2.0);
  EXPECT_DOUBLE_EQ(back.positions(0, 2), -3e-3);
  EXPECT_DOUBLE_EQ(back.positions(1, 2), 6.0);
  EXPECT_EQ(back.visible, (std::vector<char>{1, 0}));

  const struct {
    const char* text;
    const char* message;
  } bad[] = {
      {"x,y,z,visible\n1,2,3,1\n1,2,3\n", "truth.csv:3: expected 'x,y,z,visible', the row ends after z"},
      {"1,2,3,\n", "truth.csv:1: expected 'x,y,z,visible', visible is not a number"},
      {"1,abc,3,1\n", "truth.csv:1: expected 'x,y,z,visible', y is not a number"},
      {"1,2 3,3,1\n", "truth.csv:1: expected 'x,y,z,visible', y is not a number"},
      {"1,2,3,1,5\n", "truth.csv:1: expected 'x,y,z,visible', the row has more fields"},
      {"1,2,3,1,\n", "truth.csv:1: expected 'x,y,z,visible', the row has more fields"},
      {"1,nan,3,1\n", "truth.csv:1: non-finite coordinate"},
      {"x,y,z,visible\n", "truth.csv: no vertex rows"},
  };
  for (const auto& b : bad) {
    const Status s = read(b.text, &back);
    EXPECT_FALSE(s.ok()) << b.text;
    EXPECT_NE(s.message().find(b.message), std::string::npos) << s.message();
  }
  EXPECT_FALSE(ReadGroundTruthFrame(dir.path() + "/missing.csv", &back).ok());
}

#ifdef FEMREG_CLI_PATH
// A fake `femreg register` result and `femreg synth` ground truth for one frame.
void WriteCase(const std::string& root, const Eigen::Vector3d& offset) {
  fs::create_directories(root + "/result/frames");
  fs::create_directories(root + "/truth/ground_truth");
  fs::create_directories(root + "/truth/truth");
  TetMesh mesh = MakeBox(Eigen::Vector3d(0.1, 0.04, 0.04), 5, 2, 2);
  TetMesh fine = MakeBox(Eigen::Vector3d(0.1, 0.04, 0.04), 10, 4, 4);
  GroundTruthFrame truth;
  truth.positions = mesh.rest;
  truth.visible.assign(static_cast<size_t>(mesh.num_vertices()), 0);
  for (int v = 0; v < mesh.num_vertices(); v += 2) truth.visible[static_cast<size_t>(v)] = 1;
  Vertices result = mesh.rest;
  result.rowwise() += offset.transpose();
  ASSERT_TRUE(WriteVtu(root + "/result/frames/box_0000.vtu", mesh, result).ok());
  ASSERT_TRUE(WriteGroundTruthFrame(root + "/truth/ground_truth/frame_0000.csv", truth).ok());
  ASSERT_TRUE(WriteVtuSurface(root + "/truth/truth/frame_0000.vtu", fine.rest, fine.surface).ok());
}

// The totals row of the CSV as numbers (after the label).
std::vector<double> Totals(const std::string& csv) {
  std::ifstream in(csv);
  std::string line, last;
  while (std::getline(in, line)) {
    if (!line.empty()) last = line;
  }
  EXPECT_EQ(last.rfind("total,", 0), 0u) << last;
  std::vector<double> values;
  std::stringstream ss(last.substr(6));
  std::string cell;
  while (std::getline(ss, cell, ',')) values.push_back(std::atof(cell.c_str()));
  return values;
}

TEST(EvalCliTest, ZeroErrorOnTheGroundTruthAndExactlyAnOffset) {
  TempDir dir;
  WriteCase(dir.path() + "/same", Eigen::Vector3d::Zero());
  const std::string cli = FEMREG_CLI_PATH;
  std::string csv = dir.path() + "/same.csv";
  ASSERT_EQ(std::system((cli + " eval " + dir.path() + "/same/result " + dir.path() +
                         "/same/truth --csv " + csv + " > /dev/null").c_str()),
            0);
  // seen: count, mean, rms, p95, max; hidden: the same; all: the same; surface mean, Hausdorff
  std::vector<double> t = Totals(csv);
  ASSERT_EQ(t.size(), 17u);
  EXPECT_EQ(t[0], 27);   // 54 vertices, every other one seen
  EXPECT_EQ(t[5], 27);
  for (int i : {1, 2, 3, 4, 6, 7, 8, 9, 15, 16}) EXPECT_NEAR(t[i], 0.0, 1e-4) << "column " << i;

  WriteCase(dir.path() + "/offset", Eigen::Vector3d(0.0, 0.0, 0.004));
  csv = dir.path() + "/offset.csv";
  ASSERT_EQ(std::system((cli + " eval " + dir.path() + "/offset/result " + dir.path() +
                         "/offset/truth --csv " + csv + " > /dev/null").c_str()),
            0);
  t = Totals(csv);
  ASSERT_EQ(t.size(), 17u);
  for (int i : {1, 2, 3, 4, 6, 7, 8, 9}) EXPECT_NEAR(t[i], 4.0, 1e-4) << "column " << i;  // mm
  EXPECT_NEAR(t[16], 4.0, 1e-3);  // Hausdorff: the z faces are 4 mm apart

  // A ground truth folder with too few frames fails with a message.
  fs::remove(dir.path() + "/offset/truth/ground_truth/frame_0000.csv");
  EXPECT_NE(std::system((cli + " eval " + dir.path() + "/offset/result " + dir.path() +
                         "/offset/truth > /dev/null 2>&1").c_str()),
            0);
}
#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
