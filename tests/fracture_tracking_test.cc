// Fracture in tracking: the bundled break, cut and tear sequences tracked with `femreg
// register`'s matching of pieces, and fracture off.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "femreg/eval.h"
#include "femreg/fracture.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"
#include "femreg_test_config.h"

namespace femreg {
namespace {

// Tracks a bundled fracture sequence with `femreg register`'s matching of pieces.
struct SequenceResult {
  int first_split = -1, first_break = -1, truth_split = -1, truth_break = -1;
  int final_pieces = 0;
  std::vector<double> piece_mean;  // mean over the frames after the tracker's break (m)
  bool finite = true, usable = true;
  std::unique_ptr<Tracker> tracker;
};

SequenceResult TrackSequence(const std::string& name, int frames = -1,
                             SolverBackend backend = SolverBackend::kCeres, bool pushing_only = false) {
  namespace fs = std::filesystem;
  SequenceResult r;
  const fs::path dir = fs::path(FEMREG_DATASETS_DIR) / name;
  Scene scene;
  Status status = LoadScene((dir / "scene.yaml").string(), &scene);
  EXPECT_TRUE(status.ok()) << status.message();
  scene.registration.solver.backend = backend;
  if (pushing_only) {
    scene.registration.forces.estimate = true;
    scene.registration.forces.pushing_only = true;
  }
  status = Tracker::Create(scene, &r.tracker);
  EXPECT_TRUE(status.ok()) << status.message();
  if (!status.ok()) return r;
  std::vector<double> sum;
  std::vector<int> count;
  const int n = frames > 0 ? frames : 24;
  for (int f = 0; f < n; ++f) {
    char file[64];
    std::snprintf(file, sizeof(file), "frame_%04d", f);
    PointCloud cloud;
    EXPECT_TRUE(ReadPointCloud((dir / "clouds" / (std::string(file) + ".pcd")).string(), &cloud).ok());
    FrameSummary summary;
    EXPECT_TRUE(r.tracker->Track(cloud, &summary).ok());
    r.usable = r.usable && summary.IsSolutionUsable();
    r.finite = r.finite && r.tracker->vertices(0).allFinite();
    if (r.first_split < 0 && !summary.fractures.empty()) r.first_split = f;
    const TetMesh& mesh = r.tracker->mesh(0);
    EXPECT_TRUE(CheckMesh(mesh).ok()) << name << " frame " << f << ": " << CheckMesh(mesh).ToString();
    std::vector<int> piece;
    r.final_pieces = ConnectedPieces(mesh, &piece);
    if (r.first_break < 0 && r.final_pieces >= 2) r.first_break = f;
    GroundTruthFrame truth;
    EXPECT_TRUE(ReadGroundTruthFrame((dir / "ground_truth" / (std::string(file) + ".csv")).string(), &truth).ok());
    std::vector<PieceTruthRow> sides;
    const fs::path side = dir / "ground_truth" / (std::string(file) + "_pieces.csv");
    if (fs::exists(side)) {
      EXPECT_TRUE(ReadPieceTruth(side.string(), &sides).ok());
    }
    const PieceErrors pe = ComputePieceErrors(mesh, r.tracker->vertices(0),
                                              r.tracker->original_vertices(0), truth, sides);
    if (r.first_break >= 0) {
      for (size_t p = 0; p < pe.pieces.size(); ++p) {
        if (sum.size() <= p) {
          sum.resize(p + 1, 0.0);
          count.resize(p + 1, 0);
        }
        sum[p] += pe.pieces[p].mean;
        ++count[p];
      }
    }
  }
  for (size_t p = 0; p < sum.size(); ++p) r.piece_mean.push_back(sum[p] / count[p]);
  std::ifstream events(dir / "ground_truth" / "events.csv");
  std::string line;
  std::getline(events, line);
  while (std::getline(events, line)) {
    int frame = 0, node = 0, pieces = 0;
    double nx, ny, nz, measure;
    if (std::sscanf(line.c_str(), "%d,%d,%lf,%lf,%lf,%lf,%d", &frame, &node, &nx, &ny, &nz, &measure, &pieces) != 7) continue;
    if (r.truth_split < 0) r.truth_split = frame;
    if (r.truth_break < 0 && pieces >= 2) r.truth_break = frame;
  }
  // A cut (no splits in the ground truth): the first frame with a pieces file.
  for (int f = 0; r.truth_break < 0 && f < n; ++f) {
    char file[64];
    std::snprintf(file, sizeof(file), "frame_%04d_pieces.csv", f);
    if (fs::exists(dir / "ground_truth" / file)) r.truth_break = f;
  }
  return r;
}

// The beam breaks once, in the ground truth's frame; both pieces are tracked; the free
// piece (no anchor) stays well posed.
TEST(FractureTracking, BeamBreakSequence) {
  SequenceResult r = TrackSequence("beam_break");
  EXPECT_TRUE(r.finite);
  EXPECT_TRUE(r.usable);
  EXPECT_GE(r.truth_break, 0);
  EXPECT_LE(std::abs(r.first_split - r.truth_split), 1);
  EXPECT_EQ(r.first_break, r.truth_break);
  EXPECT_EQ(r.final_pieces, 2);
  ASSERT_GE(r.piece_mean.size(), 2u);
  // The camera's visibility test on: with the crack's surface paired with no data, the free
  // piece (seen on its side and top only) no longer slides along its axis, and, kept in its
  // shape when the beam parts (relax_pieces puts only held pieces back at rest), it does not
  // start off along it. Stated bounds (mean over a piece's vertices and the frames after the
  // break): the clamped piece within 0.5 mm, the free one within the 1.0 mm (measured
  // values: docs/notes/2026-11-29-fracture-cost.md).
  EXPECT_TRUE(r.tracker->options().data.visibility);
  EXPECT_LT(r.piece_mean[0], 0.0005);
  EXPECT_LT(r.piece_mean[1], 0.0010);
  for (size_t p = 0; p < r.piece_mean.size(); ++p) {
    std::printf("beam_break piece %zu: mean error %.2f mm\n", p, 1e3 * r.piece_mean[p]);
  }
  std::printf("beam_break: split at %d (truth %d), pieces from %d (truth %d)\n", r.first_split,
              r.truth_split, r.first_break, r.truth_break);

  // A frame that sees only the clamped piece: the free piece has no data and no anchor,
  // and the temporal term holds it (no singular solve, no drift).
  const TetMesh& mesh = r.tracker->mesh(0);
  std::vector<int> piece;
  ASSERT_GE(ConnectedPieces(mesh, &piece), 2);
  PointCloud cloud;
  ASSERT_TRUE(ReadPointCloud(std::string(FEMREG_DATASETS_DIR) + "/beam_break/clouds/frame_0023.pcd", &cloud).ok());
  std::vector<int> keep;
  for (int i = 0; i < cloud.size(); ++i) if (cloud.points(i, 0) < 0.1) keep.push_back(i);
  PointCloud seen;
  seen.points.resize(static_cast<int>(keep.size()), 3);
  for (size_t i = 0; i < keep.size(); ++i) seen.points.row(static_cast<int>(i)) = cloud.points.row(keep[i]);
  // (No further splits in this frame, so that vertices compare one to one.)
  ASSERT_TRUE(r.tracker->EnableFracture({FractureOptions()}).ok());
  const Vertices before = r.tracker->vertices(0);
  FrameSummary summary;
  ASSERT_TRUE(r.tracker->Track(seen, &summary).ok());
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.message;
  const Vertices& after = r.tracker->vertices(0);
  ASSERT_TRUE(after.allFinite());
  ASSERT_EQ(after.rows(), before.rows());
  double free_motion = 0.0;
  const int free_piece = piece[mesh.num_vertices() - 1] == piece[0] ? 1 : piece[mesh.num_vertices() - 1];
  for (int v = 0; v < after.rows(); ++v) {
    if (piece[v] == free_piece) free_motion = std::max(free_motion, (after.row(v) - before.row(v)).norm());
  }
  // Held where it was, up to the constant-velocity prediction of one frame.
  EXPECT_LT(free_motion, 0.05);
}

// The beam bent, then cut (datasets/beam_cut, a slab of the ground truth's elements removed
// at frame 7, 70-75 mm from the clamp, where the tracked mesh has no face): with cut_through
// the crack opened by the criterion goes through the section in that frame, so the beam is in
// two pieces from the true frame on and stays in two; each piece is tracked within 1 mm on
// average after the break. The cut runs along the face loop
// nearest the crack, so a piece lacks or carries up to a cell of material at its crack end;
// with the data there pulling it, the free piece slid along its axis (measured values:
// docs/notes/2026-11-29-fracture-pieces.md).
TEST(FractureTracking, BeamCutComesApartInTheTrueFrame) {
  Scene scene;
  ASSERT_TRUE(LoadScene(std::string(FEMREG_DATASETS_DIR) + "/beam_cut/scene.yaml", &scene).ok());
  EXPECT_TRUE(scene.effects.fracture_options.cut_through);
  SequenceResult r = TrackSequence("beam_cut", 12);
  EXPECT_TRUE(r.finite);
  EXPECT_TRUE(r.usable);
  EXPECT_EQ(r.truth_break, 7);
  EXPECT_EQ(r.first_break, r.truth_break);
  EXPECT_EQ(r.final_pieces, 2);
  ASSERT_EQ(r.piece_mean.size(), 2u);
  EXPECT_LT(r.piece_mean[0], 0.001);
  EXPECT_LT(r.piece_mean[1], 0.001);
  for (size_t p = 0; p < r.piece_mean.size(); ++p) {
    std::printf("beam_cut piece %zu: mean error %.2f mm\n", p, 1e3 * r.piece_mean[p]);
  }
  // Without the cut the crack stalls: the beam is not in two pieces in the true frame.
  scene.effects.fracture_options.cut_through = false;
  std::unique_ptr<Tracker> tracker;
  ASSERT_TRUE(Tracker::Create(scene, &tracker).ok());
  std::vector<int> piece;
  for (int f = 0; f <= 7; ++f) {
    char file[96];
    std::snprintf(file, sizeof(file), "%s/beam_cut/clouds/frame_%04d.pcd", FEMREG_DATASETS_DIR, f);
    PointCloud cloud;
    ASSERT_TRUE(ReadPointCloud(file, &cloud).ok());
    FrameSummary summary;
    ASSERT_TRUE(tracker->Track(cloud, &summary).ok());
  }
  EXPECT_EQ(ConnectedPieces(tracker->mesh(0), &piece), 1);
}

// Estimating the forces, pushing only (no friction bound), on the fast back end. From the warm
// start's shape (a classic fit, held by pulls that the pushing-only penalty prices at its
// balance weight) the solves crept to the outer-iteration cap and beam_cut's pieces drifted
// 8-14 mm; each frame now starts from the equilibrium without that penalty, and so does the
// outer iteration after a split (without, beam_break's pieces flew apart in the break's frame)
// (docs/notes/2026-12-05-pushing-only-smooth-start.md).
class PushingOnlySequence : public testing::TestWithParam<std::pair<const char*, int>> {};

TEST_P(PushingOnlySequence, EachPieceIsTrackedWithinAMillimetreAndAHalf) {
  const auto [name, frames] = GetParam();
  SequenceResult r = TrackSequence(name, frames, SolverBackend::kFast, /*pushing_only=*/true);
  EXPECT_TRUE(r.finite);
  EXPECT_TRUE(r.usable);
  EXPECT_EQ(r.final_pieces, 2);
  ASSERT_EQ(r.piece_mean.size(), 2u);
  for (size_t p = 0; p < r.piece_mean.size(); ++p) {
    std::printf("%s, pushing only: piece %zu mean error %.2f mm\n", name, p, 1e3 * r.piece_mean[p]);
    EXPECT_LT(r.piece_mean[p], 0.0015) << name << " piece " << p;
  }
}

INSTANTIATE_TEST_SUITE_P(FractureTracking, PushingOnlySequence,
                         testing::Values(std::make_pair("beam_cut", 12), std::make_pair("beam_break", 24)));

// The same cut with its ground truth from CalculiX (datasets/beam_cut_calculix, made by
// tools/make_calculix_cut.sh): two pieces from the true frame, each within the 1 mm on
// average over the frames after the break.
TEST(FractureTracking, BeamCutFromCalculixComesApartInTheTrueFrame) {
  SequenceResult r = TrackSequence("beam_cut_calculix", 12);
  EXPECT_TRUE(r.finite);
  EXPECT_TRUE(r.usable);
  EXPECT_EQ(r.truth_break, 7);
  EXPECT_EQ(r.first_break, r.truth_break);
  EXPECT_EQ(r.final_pieces, 2);
  ASSERT_EQ(r.piece_mean.size(), 2u);
  for (size_t p = 0; p < r.piece_mean.size(); ++p) {
    EXPECT_LT(r.piece_mean[p], 0.001) << "piece " << p;
    std::printf("beam_cut_calculix piece %zu: mean error %.2f mm\n", p, 1e3 * r.piece_mean[p]);
  }
}

// The slab tears into two pieces, as the ground truth does. Pulled evenly, the tracked
// slab's measure is nearly uniform, so the scene allows one crack (max_cracks: 1) placed
// where the camera sees the slab open (data_gap: true); the crack front through the slab's
// thickness splits together. On both back ends (their rounding differs, and a crack that
// grows only by luck would show it). Stated bounds: the first split within 2 frames of the
// ground truth's, two pieces within 1 frame of it and to the end, each piece within 1.5 mm
// on average over the frames after the tracker's break (measured values, with the crack's
// surface paired with no data: docs/notes/2026-11-29-fracture-pieces.md).
class SlabTearSequence : public ::testing::TestWithParam<SolverBackend> {};

TEST_P(SlabTearSequence, TearsIntoTheTwoPiecesOfTheGroundTruth) {
  Scene scene;
  ASSERT_TRUE(LoadScene(std::string(FEMREG_DATASETS_DIR) + "/slab_tear/scene.yaml", &scene).ok());
  EXPECT_EQ(scene.effects.fracture_options.max_cracks, 1);
  EXPECT_TRUE(scene.effects.fracture_options.data_gap);
  SequenceResult r = TrackSequence("slab_tear", -1, GetParam());
  EXPECT_TRUE(r.finite);
  EXPECT_TRUE(r.usable);
  ASSERT_GE(r.truth_split, 0);
  ASSERT_GE(r.truth_break, 0);
  EXPECT_LE(std::abs(r.first_split - r.truth_split), 2);
  ASSERT_GE(r.first_break, 0);
  EXPECT_LE(std::abs(r.first_break - r.truth_break), 1);
  EXPECT_EQ(r.final_pieces, 2);
  ASSERT_EQ(r.piece_mean.size(), 2u);
  for (size_t p = 0; p < r.piece_mean.size(); ++p) {
    EXPECT_LT(r.piece_mean[p], 0.0015) << "piece " << p;
    std::printf("slab_tear (%s) piece %zu: mean error %.2f mm\n", ToString(GetParam()), p,
                1e3 * r.piece_mean[p]);
  }
  std::printf("slab_tear (%s): split at %d (truth %d), pieces from %d (truth %d)\n",
              ToString(GetParam()), r.first_split, r.truth_split, r.first_break, r.truth_break);
}

INSTANTIATE_TEST_SUITE_P(FractureTracking, SlabTearSequence,
                         ::testing::Values(SolverBackend::kCeres, SolverBackend::kFast),
                         [](const ::testing::TestParamInfo<SolverBackend>& info) {
                           return std::string(ToString(info.param));
                         });

// Before the break, fracture on tracks as fracture off (what it turns off stays on until the
// measure nears the toughness, and the detection changes nothing it does not act on), and its
// measure is an output all the same.
TEST(FractureTracking, BeforeTheBreakOnTracksAsOff) {
  Scene scene;
  ASSERT_TRUE(LoadScene(std::string(FEMREG_DATASETS_DIR) + "/beam_break/scene.yaml", &scene).ok());
  std::unique_ptr<Tracker> on, off;
  ASSERT_TRUE(Tracker::Create(scene, &on).ok());
  scene.effects.fracture = false;
  ASSERT_TRUE(Tracker::Create(scene, &off).ok());
  for (int f = 0; f < 6; ++f) {
    char file[96];
    std::snprintf(file, sizeof(file), "%s/beam_break/clouds/frame_%04d.pcd", FEMREG_DATASETS_DIR, f);
    PointCloud cloud;
    ASSERT_TRUE(ReadPointCloud(file, &cloud).ok());
    FrameSummary a, b;
    ASSERT_TRUE(on->Track(cloud, &a).ok());
    ASSERT_TRUE(off->Track(cloud, &b).ok());
    EXPECT_TRUE(a.fractures.empty());
    EXPECT_GT(a.time.fracture, 0.0);
    ASSERT_EQ(on->vertices(0).rows(), off->vertices(0).rows());
    EXPECT_LT((on->vertices(0) - off->vertices(0)).rowwise().norm().maxCoeff(), 1e-6) << "frame " << f;
    // The measure over the whole mesh, not only where it nears the toughness.
    const Eigen::VectorXd& measure = on->fracture_measure(0);
    ASSERT_EQ(measure.size(), on->mesh(0).num_vertices());
    if (f > 0) {
      EXPECT_GT(measure.maxCoeff(), 0.0) << "frame " << f;
      // Below the 0.3 of beam_break's 6 kPa toughness at which fracture has its say.
      EXPECT_LT(measure.maxCoeff(), 0.3 * 6000.0) << "frame " << f;
      EXPECT_GT((measure.array() > 0.0).count(), measure.size() / 2) << "frame " << f;
    }
  }
}

// Fracture off: nothing is computed or exposed.
TEST(FractureTracking, OffComputesNothing) {
  Scene scene;
  ASSERT_TRUE(LoadScene(std::string(FEMREG_DATASETS_DIR) + "/beam_break/scene.yaml", &scene).ok());
  scene.effects.fracture = false;
  std::unique_ptr<Tracker> tracker;
  ASSERT_TRUE(Tracker::Create(scene, &tracker).ok());
  PointCloud cloud;
  ASSERT_TRUE(ReadPointCloud(std::string(FEMREG_DATASETS_DIR) + "/beam_break/clouds/frame_0014.pcd", &cloud).ok());
  FrameSummary summary;
  ASSERT_TRUE(tracker->Track(cloud, &summary).ok());
  EXPECT_TRUE(summary.fractures.empty());
  EXPECT_EQ(summary.time.fracture, 0.0);
  EXPECT_EQ(tracker->fracture_measure(0).size(), 0);
  EXPECT_TRUE(tracker->original_vertices(0).empty());
}

}  // namespace
}  // namespace femreg
