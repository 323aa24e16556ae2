// femreg eval: VTU geometry in file order, surface distances, and the command on results
// equal to the ground truth and offset from it.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
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

// forces.csv round trip; the same columns found by name among stats.csv's others, past a
// quoted message with commas; a frame without an estimate left out; no columns, no error.
TEST(EvalTest, ForcesCsvAndStatsColumns) {
  TempDir dir;
  std::vector<ForceFrame> frames(2);
  frames[0].frame = 0;
  frames[0].force = Eigen::Vector3d(0.125, -1e-17, -2.5);
  frames[0].torque = Eigen::Vector3d(1e-3, 0.0, -4.5e-4);
  frames[1].frame = 1;
  frames[1].force = Eigen::Vector3d(-0.5, 0.25, -3.0);
  const std::string path = dir.path() + "/forces.csv";
  ASSERT_TRUE(WriteForces(path, frames).ok());
  const std::string text = testing_util::Slurp(path);
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "frame,force_x_N,force_y_N,force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm");
  EXPECT_EQ(text.find("-0.000000000"), std::string::npos) << text;  // round-off written as 0
  std::vector<ForceFrame> back;
  bool has_columns = false;
  ASSERT_TRUE(ReadForces(path, &back, &has_columns).ok());
  EXPECT_TRUE(has_columns);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[1].frame, 1);
  EXPECT_LT((back[0].force - frames[0].force).norm(), 1e-9);
  EXPECT_LT((back[0].torque - frames[0].torque).norm(), 1e-9);
  EXPECT_LT((back[1].force - frames[1].force).norm(), 1e-9);

  const std::string stats = dir.Write(
      "stats.csv",
      "frame,file,termination,torque_x_Nm,force_x_N,force_y_N,force_z_N,torque_y_Nm,torque_z_Nm,"
      "message\n"
      "0,frame_0000.pcd,CONVERGED,0.5,1,2,3,0.25,-1e-2,\"converged, 3 outer iterations\"\n"
      "1,frame_0001.pcd,FAILED,,,,,,,\"no points, \"\"kept\"\"\"\r\n"
      "2,frame_0002.pcd,CONVERGED,0,+4,5,6,0,0,\"\"\n");
  ASSERT_TRUE(ReadForces(stats, &back, &has_columns).ok());
  EXPECT_TRUE(has_columns);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].frame, 0);
  EXPECT_EQ(back[0].force, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(back[0].torque, Eigen::Vector3d(0.5, 0.25, -1e-2));
  EXPECT_EQ(back[1].frame, 2);
  EXPECT_EQ(back[1].force, Eigen::Vector3d(4, 5, 6));
  ASSERT_TRUE(
      ReadForces(dir.Write("old.csv", "frame,file,message\n0,a.pcd,\"ok\"\n"), &back, &has_columns)
          .ok());
  EXPECT_FALSE(has_columns);
  EXPECT_TRUE(back.empty());

  const Status bad = ReadForces(
      dir.Write("bad.csv",
                "frame,force_x_N,force_y_N,force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm\n"
                "0,1,2,3,4,5,6\n1,1,x,3,4,5,6\n"),
      &back, &has_columns);
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("bad.csv:3: force_y_N is not a number ('x')"), std::string::npos)
      << bad.message();
  const Status short_row = ReadForces(
      dir.Write("short.csv",
                "frame,force_x_N,force_y_N,force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm\n0,1,2\n"),
      &back, &has_columns);
  EXPECT_FALSE(short_row.ok());
  EXPECT_NE(short_row.message().find("short.csv:2:"), std::string::npos) << short_row.message();
  EXPECT_FALSE(ReadForces(dir.path() + "/missing.csv", &back, &has_columns).ok());
}

// Errors per frame matched by number, the relative error undefined for a true force of 0,
// and the medians over the frames.
TEST(EvalTest, ForceErrorsAndTheirMedians) {
  auto frame = [](int f, const Eigen::Vector3d& force, const Eigen::Vector3d& torque) {
    ForceFrame r;
    r.frame = f;
    r.force = force;
    r.torque = torque;
    return r;
  };
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  const std::vector<ForceFrame> truth = {frame(0, {0, 0, -1}, zero), frame(1, {0, 0, -2}, zero),
                                         frame(2, {0, 0, -4}, zero), frame(3, zero, zero),
                                         frame(4, {1, 0, 0}, zero)};
  const std::vector<ForceFrame> estimated = {
      frame(3, {0, 0.05, 0}, zero), frame(0, {0, 0, -1.1}, zero),
      frame(1, {0, 0.1, -2}, {0.01, 0, 0}), frame(2, {0, 0, -3.2}, zero),
      frame(7, {1, 1, 1}, zero)};
  const std::vector<ForceError> errors = CompareForces(estimated, truth);
  ASSERT_EQ(errors.size(), 4u);  // frame 4 has no estimate, frame 7 no truth
  for (int f = 0; f < 4; ++f) EXPECT_EQ(errors[f].frame, f);
  EXPECT_NEAR(errors[0].error, 0.1, 1e-12);
  EXPECT_NEAR(errors[0].relative, 0.1, 1e-12);
  EXPECT_NEAR(errors[1].relative, 0.05, 1e-12);
  EXPECT_NEAR(errors[1].torque_error, 0.01, 1e-12);
  EXPECT_NEAR(errors[2].true_force, 4.0, 1e-12);
  EXPECT_NEAR(errors[2].relative, 0.2, 1e-12);
  EXPECT_NEAR(errors[3].error, 0.05, 1e-12);
  EXPECT_TRUE(std::isnan(errors[3].relative));
  const ForceErrorMedians m = MedianForceErrors(errors);
  EXPECT_NEAR(m.relative, 0.1, 1e-12);  // of 0.1, 0.05, 0.2
  EXPECT_NEAR(m.error, 0.1, 1e-12);     // of 0.1, 0.1, 0.8, 0.05
  EXPECT_NEAR(m.torque_error, 0.0, 1e-12);
  EXPECT_TRUE(std::isnan(MedianForceErrors({}).relative));
  // Neither side has the obstacles' push: no contact error.
  EXPECT_TRUE(std::isnan(errors[0].contact_error));
  EXPECT_TRUE(std::isnan(m.contact_error));
}

// The obstacles' push (contact_force_*_N) where both files have it: read when the three cells
// hold numbers, compared frame by frame, its median over the frames that have it.
TEST(EvalTest, ObstaclePushWhereBothFilesHaveIt) {
  TempDir dir;
  const std::string header =
      "frame,force_x_N,force_y_N,force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm,contact_force_x_N,"
      "contact_force_y_N,contact_force_z_N\n";
  bool has_columns = false;
  auto read = [&](const std::string& name, const std::string& rows) {
    std::vector<ForceFrame> frames;
    EXPECT_TRUE(ReadForces(dir.Write(name, header + rows), &frames, &has_columns).ok()) << name;
    return frames;
  };
  const std::vector<ForceFrame> truth =
      read("truth.csv", "0,0,0,1,0,0,0,0,0,1\n1,0,0,1,0,0,0,0,0,3\n2,0,0,1,0,0,0,0,0,2\n");
  ASSERT_EQ(truth.size(), 3u);
  EXPECT_TRUE(truth[1].has_contact);
  EXPECT_EQ(truth[1].contact, Eigen::Vector3d(0, 0, 3));
  // Frame 1's push is left empty (as a row without the estimate's force cells would be).
  const std::vector<ForceFrame> estimated =
      read("stats.csv", "0,0,0,1,0,0,0,0,0,0.75\n1,0,0,1,0,0,0,,,\n2,0,0,1,0,0,0,0.5,0,2\n");
  ASSERT_EQ(estimated.size(), 3u);
  EXPECT_FALSE(estimated[1].has_contact);
  const std::vector<ForceError> errors = CompareForces(estimated, truth);
  ASSERT_EQ(errors.size(), 3u);
  EXPECT_NEAR(errors[0].contact_error, 0.25, 1e-12);
  EXPECT_TRUE(std::isnan(errors[1].contact_error));
  EXPECT_NEAR(errors[2].contact_error, 0.5, 1e-12);
  EXPECT_NEAR(errors[2].true_contact, 2.0, 1e-12);
  const ForceErrorMedians m = MedianForceErrors(errors);
  EXPECT_NEAR(m.contact_error, 0.375, 1e-12);  // of 0.25 and 0.5
  EXPECT_NEAR(m.true_contact, 1.5, 1e-12);     // of 1 and 2
  std::vector<ForceFrame> back;
  const Status bad = ReadForces(dir.Write("bad.csv", header + "0,0,0,1,0,0,0,0,0,one\n"), &back, &has_columns);
  EXPECT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("bad.csv:2: contact_force_z_N is not a number ('one')"), std::string::npos)
      << bad.message();
  // Two of the three cells: a typo, not a frame without the push.
  const Status part = ReadForces(dir.Write("part.csv", header + "0,0,0,1,0,0,0,0,,1\n"), &back, &has_columns);
  EXPECT_FALSE(part.ok());
  EXPECT_NE(part.message().find("part.csv:2: contact_force_y_N is empty"), std::string::npos) << part.message();
  // Two of the three columns.
  const Status columns = ReadForces(
      dir.Write("columns.csv", "frame,force_x_N,force_y_N,force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm,"
                               "contact_force_x_N,contact_force_z_N\n0,0,0,1,0,0,0,0,1\n"),
      &back, &has_columns);
  EXPECT_FALSE(columns.ok());
  EXPECT_NE(columns.message().find("columns.csv: the header has contact force columns but not contact_force_y_N"),
            std::string::npos)
      << columns.message();
}

// A tracked beam split on its own nodes a cell before the ground truth's crack: the copies
// of the split vertices on the free piece have a truth row only on the clamped piece. They
// are compared with the free piece's motion carried to them (here a rigid motion, so a
// tracked result equal to the truth has no error), not with the clamped piece's position;
// and a tracked beam still whole keeps each vertex's own row.
TEST(EvalTest, PieceErrorsCarryTheMatchedPiecesMotionToASplitVertexItDoesNotReach) {
  TetMesh whole = MakeBox(Eigen::Vector3d(0.2, 0.03, 0.03), 12, 2, 2);
  const double cell = 0.2 / 12, tracked_cut = 4 * cell, truth_cut = 5 * cell;
  // The tracked split at x = 4 cells: the elements beyond it take copies of its 9 vertices.
  TetMesh mesh = whole;
  std::vector<int> original(static_cast<size_t>(whole.num_vertices()));
  for (int v = 0; v < whole.num_vertices(); ++v) original[static_cast<size_t>(v)] = v;
  std::vector<int> copy_of(static_cast<size_t>(whole.num_vertices()), -1);
  std::vector<Eigen::RowVector3d> added;
  for (int e = 0; e < mesh.num_tets(); ++e) {
    double cx = 0.0;
    for (int k = 0; k < 4; ++k) cx += 0.25 * whole.rest(whole.tets(e, k), 0);
    if (cx < tracked_cut) continue;
    for (int k = 0; k < 4; ++k) {
      const int v = whole.tets(e, k);
      if (std::abs(whole.rest(v, 0) - tracked_cut) > 1e-9) continue;
      if (copy_of[static_cast<size_t>(v)] < 0) {
        copy_of[static_cast<size_t>(v)] = whole.num_vertices() + static_cast<int>(added.size());
        added.push_back(whole.rest.row(v));
        original.push_back(v);
      }
      mesh.tets(e, k) = copy_of[static_cast<size_t>(v)];
    }
  }
  ASSERT_EQ(added.size(), 9u);
  mesh.rest.conservativeResize(whole.num_vertices() + 9, 3);
  for (size_t i = 0; i < added.size(); ++i) mesh.rest.row(whole.num_vertices() + static_cast<int>(i)) = added[i];
  mesh.x = mesh.rest;
  BuildTopology(&mesh);
  std::vector<int> piece;
  ASSERT_EQ(ConnectedPieces(mesh, &piece), 2);

  // The truth: the clamped piece (x <= 5 cells) at rest, the free one (x >= 5 cells) turned
  // and carried away; side rows for every vertex on each piece its material reaches.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d t(0.03, 0.01, -0.02);
  auto moved = [&](const Eigen::Vector3d& X) { return Eigen::Vector3d(R * X + t); };
  GroundTruthFrame truth;
  truth.positions = whole.rest;
  truth.visible.assign(static_cast<size_t>(whole.num_vertices()), 1);
  std::vector<PieceTruthRow> rows;
  for (int v = 0; v < whole.num_vertices(); ++v) {
    const Eigen::Vector3d X = whole.rest.row(v);
    if (X.x() <= truth_cut + 1e-9) rows.push_back({v, 0, X});
    if (X.x() >= truth_cut - 1e-9) rows.push_back({v, 1, moved(X)});
    if (X.x() > truth_cut + 1e-9) truth.positions.row(v) = moved(X).transpose();
  }
  // The tracked result is the truth: each piece where its material is.
  const int free_piece = piece[mesh.num_vertices() - 1];
  Vertices positions = mesh.rest;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (piece[static_cast<size_t>(v)] == free_piece) positions.row(v) = moved(mesh.rest.row(v)).transpose();
  }
  PieceErrors pe = ComputePieceErrors(mesh, positions, original, truth, rows);
  ASSERT_EQ(pe.pieces.size(), 2u);
  EXPECT_NEAR(pe.pieces[0].max, 0.0, 1e-9);
  EXPECT_NEAR(pe.pieces[1].max, 0.0, 1e-9);
  // A copy is compared with where the free piece's motion puts it; its only row (the clamped
  // piece's, at rest) is more than 1 cm from there.
  for (int c = whole.num_vertices(); c < mesh.num_vertices(); ++c) {
    const Eigen::Vector3d X = mesh.rest.row(c);
    EXPECT_NEAR((Eigen::Vector3d(pe.matched.positions.row(c)) - moved(X)).norm(), 0.0, 1e-9);
    EXPECT_GT((moved(X) - X).norm(), 0.01);
  }

  // The whole tracked beam beside the broken truth: a vertex keeps the truth of the piece it
  // is on (its only row), whatever piece the whole beam is matched to.
  Vertices whole_positions = truth.positions;
  std::vector<int> identity(static_cast<size_t>(whole.num_vertices()));
  for (int v = 0; v < whole.num_vertices(); ++v) identity[static_cast<size_t>(v)] = v;
  pe = ComputePieceErrors(whole, whole_positions, identity, truth, rows);
  ASSERT_EQ(pe.pieces.size(), 1u);
  int far_off = 0;
  for (int v = 0; v < whole.num_vertices(); ++v) {
    if ((pe.matched.positions.row(v) - truth.positions.row(v)).norm() > 1e-12) ++far_off;
  }
  // Only the vertices of the truth's crack (rows on both pieces) take the matched piece's.
  EXPECT_LE(far_off, 9);
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
  // A summary.json eval cannot read (the objects' order comes from it): a warning that names
  // the file, and the frame files' order.
  const std::string summary = dir.path() + "/same/result/summary.json";
  std::ofstream(summary) << "{\"objects\": [";
  const testing_util::CliRun run = testing_util::Femreg("eval " + dir.path() + "/same/result " + dir.path() +
                                                        "/same/truth --csv " + csv);
  EXPECT_EQ(run.code, 0) << run.out;
  EXPECT_NE(run.out.find("femreg eval: warning: " + summary + ": not JSON"), std::string::npos) << run.out;
  EXPECT_EQ(Totals(csv).size(), 17u);

  WriteCase(dir.path() + "/offset", Eigen::Vector3d(0.0, 0.0, 0.004));
  csv = dir.path() + "/offset.csv";
  ASSERT_EQ(std::system((cli + " eval " + dir.path() + "/offset/result " + dir.path() +
                         "/offset/truth --csv " + csv + " > /dev/null").c_str()),
            0);
  t = Totals(csv);
  ASSERT_EQ(t.size(), 17u);
  for (int i : {1, 2, 3, 4, 6, 7, 8, 9}) EXPECT_NEAR(t[i], 4.0, 1e-4) << "column " << i;  // mm
  EXPECT_NEAR(t[16], 4.0, 1e-3);  // Hausdorff: the z faces are 4 mm apart
  // The dataset's ground_truth/ folder (what register --ground-truth takes) stands for it.
  const std::string inner_csv = dir.path() + "/offset_inner.csv";
  ASSERT_EQ(std::system((cli + " eval " + dir.path() + "/offset/result " + dir.path() +
                         "/offset/truth/ground_truth --csv " + inner_csv + " > /dev/null").c_str()),
            0);
  const std::vector<double> inner = Totals(inner_csv);
  ASSERT_EQ(inner.size(), t.size());
  for (size_t i = 0; i < t.size(); ++i) EXPECT_NEAR(inner[i], t[i], 1e-9) << "column " << i;
  // ... written with a trailing slash too.
  ASSERT_EQ(std::system((cli + " eval " + dir.path() + "/offset/result " + dir.path() +
                         "/offset/truth/ground_truth/ --csv " + inner_csv + " > /dev/null").c_str()),
            0);

  // A ground truth folder with too few frames fails with a message.
  fs::remove(dir.path() + "/offset/truth/ground_truth/frame_0000.csv");
  EXPECT_NE(std::system((cli + " eval " + dir.path() + "/offset/result " + dir.path() +
                         "/offset/truth > /dev/null 2>&1").c_str()),
            0);
}

// A CSV file's cells, row by row (no quoting), a trailing empty cell kept.
std::vector<std::vector<std::string>> CsvCells(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    rows.emplace_back();
    std::stringstream ls(line);
    for (std::string cell; std::getline(ls, cell, ',');) rows.back().push_back(cell);
    if (!line.empty() && line.back() == ',') rows.back().push_back("");
  }
  return rows;
}

// A register result of four frames with force estimates in stats.csv, against a dataset
// with forces.csv: eval adds the force columns to eval.csv (medians in the totals row) and
// prints the median relative error. Without the columns in stats.csv, or without
// forces.csv, its CSV is what it was before.
TEST(EvalCliTest, ForceErrorsWhenTheDatasetHasForcesAndTheResultEstimates) {
  TempDir dir;
  const std::string root = dir.path() + "/forces";
  WriteCase(root, Eigen::Vector3d(0.0, 0.0, 0.001));
  for (int f = 1; f < 4; ++f) {
    const std::string n = std::to_string(f);
    fs::copy_file(root + "/result/frames/box_0000.vtu",
                  root + "/result/frames/box_000" + n + ".vtu");
    fs::copy_file(root + "/truth/ground_truth/frame_0000.csv",
                  root + "/truth/ground_truth/frame_000" + n + ".csv");
    fs::copy_file(root + "/truth/truth/frame_0000.vtu",
                  root + "/truth/truth/frame_000" + n + ".vtu");
  }
  const std::string result = root + "/result", truth = root + "/truth";
  const std::string plain_csv = dir.path() + "/plain.csv";
  testing_util::CliRun run =
      testing_util::Femreg("eval " + result + " " + truth + " --csv " + plain_csv);
  ASSERT_EQ(run.code, 0) << run.out;
  const std::string plain = testing_util::Slurp(plain_csv);

  // True forces: 1, 2 and 4 N down, then none; the estimates are 10 %, 5 % and 20 % off,
  // and 0.05 N where there is no force.
  std::vector<ForceFrame> forces(4);
  const double down[4] = {-1, -2, -4, 0};
  for (int f = 0; f < 4; ++f) {
    forces[f].frame = f;
    forces[f].force = Eigen::Vector3d(0, 0, down[f]);
  }
  ASSERT_TRUE(WriteForces(truth + "/forces.csv", forces).ok());
  std::ofstream(result + "/stats.csv")
      << "frame,file,termination,force_x_N,force_y_N,force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm,"
         "message\n"
         "0,frame_0000.pcd,CONVERGED,0,0,-1.1,0,0,0,\"converged, 3 outer iterations\"\n"
         "1,frame_0001.pcd,CONVERGED,0,0.1,-2,0.01,0,0,\"converged\"\n"
         "2,frame_0002.pcd,CONVERGED,0,0,-3.2,0,0,0,\"converged\"\n"
         "3,frame_0003.pcd,CONVERGED,0.05,0,0,0,0,0,\"converged\"\n";
  const std::string csv = dir.path() + "/forces.csv";
  run = testing_util::Femreg("eval " + result + " " + truth + " --csv " + csv);
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_NE(run.out.find("Median resultant-force error: 10.00% of the true force over 3 frames (1 "
                         "more with a true force of 0"),
            std::string::npos)
      << run.out;
  const std::vector<std::vector<std::string>> rows = CsvCells(csv),
                                              plain_rows = CsvCells(plain_csv);
  ASSERT_EQ(rows.size(), 6u);  // header, 4 frames, totals
  ASSERT_EQ(plain_rows.size(), rows.size());
  const std::vector<std::string> tail(rows[0].end() - 4, rows[0].end());
  EXPECT_EQ(tail, (std::vector<std::string>{"force_true_N", "force_error_N", "force_error_pct",
                                            "torque_error_Nm"}));
  const size_t at = rows[0].size() - 4;
  auto cell = [&](size_t row, size_t k) { return std::atof(rows[row][at + k].c_str()); };
  for (size_t r = 0; r < rows.size(); ++r) {  // the columns of the plain run, then the forces'
    ASSERT_EQ(rows[r].size(), rows[0].size()) << "row " << r;
    EXPECT_EQ(std::vector<std::string>(rows[r].begin(), rows[r].begin() + at), plain_rows[r])
        << "row " << r;
  }
  EXPECT_NEAR(cell(1, 0), 1.0, 1e-6);
  EXPECT_NEAR(cell(1, 1), 0.1, 1e-6);
  EXPECT_NEAR(cell(1, 2), 10.0, 1e-3);
  EXPECT_NEAR(cell(2, 2), 5.0, 1e-3);
  EXPECT_NEAR(cell(2, 3), 0.01, 1e-6);
  EXPECT_NEAR(cell(3, 2), 20.0, 1e-3);
  EXPECT_NEAR(cell(4, 1), 0.05, 1e-6);
  EXPECT_EQ(rows[4][at + 2], "");  // no relative error of a force of 0
  EXPECT_EQ(rows[5][0], "total");
  EXPECT_EQ(rows[5][at], "");
  EXPECT_NEAR(cell(5, 1), 0.1, 1e-6);   // median of 0.1, 0.1, 0.8, 0.05
  EXPECT_NEAR(cell(5, 2), 10.0, 1e-3);  // median of 10, 5, 20
  EXPECT_EQ(run.out.find("did not estimate"), std::string::npos) << run.out;  // no summary.json
  // A run that did not estimate them says what its columns hold.
  std::ofstream(result + "/summary.json") << "{\"forces\": {\"estimate\": false}, \"objects\": []}";
  run = testing_util::Femreg("eval " + result + " " + truth + " --csv " + csv);
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_NE(run.out.find("The run did not estimate the forces: these are its data term's pull"),
            std::string::npos)
      << run.out;
  std::ofstream(result + "/summary.json") << "{\"forces\": {\"estimate\": true}, \"objects\": []}";
  run = testing_util::Femreg("eval " + result + " " + truth + " --csv " + csv);
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_EQ(run.out.find("did not estimate"), std::string::npos) << run.out;
  fs::remove(result + "/summary.json");
  EXPECT_EQ(run.out.find("obstacles' push"), std::string::npos) << run.out;  // not in the files

  // With the obstacles' push in both files: its error per frame and its median.
  {
    std::ofstream(truth + "/forces.csv")
        << "frame,force_x_N,force_y_N,force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm,contact_force_x_N,"
           "contact_force_y_N,contact_force_z_N\n0,0,0,-1,0,0,0,0,0,2\n1,0,0,-2,0,0,0,0,0,3\n";
    std::ofstream(result + "/stats.csv")
        << "frame,file,termination,force_x_N,force_y_N,force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm,"
           "contact_force_x_N,contact_force_y_N,contact_force_z_N,message\n"
           "0,frame_0000.pcd,CONVERGED,0,0,-1,0,0,0,0,0,1.5,\"converged\"\n"
           "1,frame_0001.pcd,CONVERGED,0,0,-2,0,0,0,0,0,3.5,\"converged\"\n";
    run = testing_util::Femreg("eval " + result + " " + truth + " --csv " + csv);
    ASSERT_EQ(run.code, 0) << run.out;
    EXPECT_NE(run.out.find("Median error of the obstacles' push (contact_force_*_N): 0.5000 N over 2 frames, the "
                           "true push's median 2.5000 N"),
              std::string::npos)
        << run.out;
    const std::vector<std::vector<std::string>> with = CsvCells(csv);
    ASSERT_EQ(with.size(), 6u);
    EXPECT_EQ(with[0].back(), "contact_force_error_N");
    for (size_t r = 0; r < with.size(); ++r) ASSERT_EQ(with[r].size(), with[0].size()) << "row " << r;
    EXPECT_NEAR(std::atof(with[1].back().c_str()), 0.5, 1e-6);
    EXPECT_EQ(with[3].back(), "");  // frame 2: no truth
    EXPECT_NEAR(std::atof(with[5].back().c_str()), 0.5, 1e-6);
    // A result written before stats.csv had the push: said, not compared.
    std::ofstream(result + "/stats.csv")
        << "frame,file,termination,force_x_N,force_y_N,force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm,message\n"
           "0,frame_0000.pcd,CONVERGED,0,0,-1,0,0,0,\"converged\"\n";
    run = testing_util::Femreg("eval " + result + " " + truth + " --csv " + csv);
    ASSERT_EQ(run.code, 0) << run.out;
    EXPECT_NE(run.out.find("has it in no frame it has the truth of"), std::string::npos) << run.out;
    EXPECT_EQ(CsvCells(csv)[0].back(), "torque_error_Nm");
  }

  // A result without force columns, or a dataset without forces.csv: as before.
  std::ofstream(result + "/stats.csv")
      << "frame,file,termination,message\n0,frame_0000.pcd,CONVERGED,\"ok\"\n";
  run = testing_util::Femreg("eval " + result + " " + truth + " --csv " + csv);
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_EQ(testing_util::Slurp(csv), plain);
  EXPECT_EQ(run.out.find("resultant"), std::string::npos) << run.out;
  fs::remove(truth + "/forces.csv");
  fs::remove(result + "/stats.csv");
  run = testing_util::Femreg("eval " + result + " " + truth + " --csv " + csv);
  ASSERT_EQ(run.code, 0) << run.out;
  EXPECT_EQ(testing_util::Slurp(csv), plain);

  // A forces.csv that cannot be read is an error that names it.
  std::ofstream(truth + "/forces.csv") << "frame,force\n0,1\n";
  run = testing_util::Femreg("eval " + result + " " + truth + " --csv " + csv);
  EXPECT_NE(run.code, 0);
  EXPECT_NE(run.out.find("forces.csv: expected the header frame,force_x_N"), std::string::npos)
      << run.out;
}
#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
