// Collision: the bundled contact sequences registered end to end with collision on and off,
// touching without crossing, their regeneration, and the CLI's penetration report
// (collision_test.cc has the contact terms and the forward solve).
#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/collision.h"
#include "femreg/datasets.h"
#include "femreg/forward.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"
#include "femreg_test_config.h"
#include "regenerate_compare.h"
#include "test_util.h"

namespace femreg {
namespace {

using V3 = Eigen::Vector3d;

// These small problems run faster on one thread (testing_util::UseOneOpenMpThread).
const bool kOneThread = testing_util::UseOneOpenMpThread();

// The bundled contact sequences registered end to end, with collision on and off: per frame
// the deepest penetration (measured with the scene's collision section also when the tracker
// has collision off) and the mean vertex error against the ground truth, seen and hidden.
struct SequenceRun {
  std::vector<double> penetration, seen, hidden;  // per frame (m)
  double D = 0.0;
  double Mean(const std::vector<double>& v) const {
    double sum = 0.0;
    for (double e : v) sum += e;
    return v.empty() ? 0.0 : sum / v.size();
  }
  double Max(const std::vector<double>& v) const {
    return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
  }
};

// The bundled sequence's clouds in frame order: dir/clouds/frame_0000.pcd on, up to the first
// missing number.
std::vector<std::string> CloudFiles(const std::string& dir) {
  std::vector<std::string> files;
  for (int f = 0;; ++f) {
    char file[64];
    std::snprintf(file, sizeof(file), "frame_%04d", f);
    const std::string cloud_path = dir + "/clouds/" + file + ".pcd";
    if (!std::filesystem::exists(cloud_path)) break;
    files.push_back(cloud_path);
  }
  return files;
}

SequenceRun RegisterSequence(const std::string& name, bool collision) {
  SequenceRun run;
  const std::string dir = std::string(FEMREG_DATASETS_DIR) + "/" + name;
  Scene scene;
  EXPECT_TRUE(LoadScene(dir + "/scene.yaml", &scene).ok());
  EXPECT_TRUE(scene.effects.collision);
  scene.effects.collision = collision;
  run.D = scene.collision.distance;
  std::unique_ptr<Tracker> tracker;
  EXPECT_TRUE(Tracker::Create(scene, &tracker).ok());
  if (!tracker) return run;
  EXPECT_EQ(tracker->collision() != nullptr, collision);
  // The meter: the same spec, outside the tracker.
  std::vector<std::string> names;
  std::vector<Triangles> surfaces;
  int total = 0;
  for (int i = 0; i < tracker->num_objects(); ++i) {
    names.push_back(scene.objects[i].name);
    surfaces.push_back(tracker->mesh(i).surface.array() + total);
    total += tracker->mesh(i).num_vertices();
  }
  CollisionWorld meter;
  Vertices x(total, 3);
  const std::vector<std::string> clouds = CloudFiles(dir);
  for (int f = 0; f < static_cast<int>(clouds.size()); ++f) {
    PointCloud cloud;
    EXPECT_TRUE(ReadPointCloud(clouds[static_cast<size_t>(f)], &cloud).ok());
    FrameSummary summary;
    EXPECT_TRUE(tracker->Track(cloud, &summary).ok());
    EXPECT_TRUE(summary.IsSolutionUsable()) << name << " frame " << f << ": " << summary.message;
    int row = 0;
    for (int i = 0; i < tracker->num_objects(); ++i) {
      x.middleRows(row, tracker->vertices(i).rows()) = tracker->vertices(i);
      row += static_cast<int>(tracker->vertices(i).rows());
    }
    if (f == 0) {
      EXPECT_TRUE(meter.Init(scene.collision, names, surfaces, x).ok());
    }
    meter.SetFrame(f);
    std::vector<Contact> contacts;
    meter.Detect(x, 0.0, &contacts);
    run.penetration.push_back(meter.Evaluate(contacts, x).max_penetration);
    if (collision) {
      EXPECT_NEAR(summary.max_penetration, run.penetration.back(), 1e-12);
    }
    GroundTruthFrame truth;
    const std::string file = std::filesystem::path(clouds[static_cast<size_t>(f)]).stem().string();
    EXPECT_TRUE(ReadGroundTruthFrame(dir + "/ground_truth/" + file + ".csv", &truth).ok());
    const VertexErrors e = ComputeVertexErrors(x, truth);
    run.seen.push_back(e.seen.mean);
    run.hidden.push_back(e.hidden.mean);
  }
  EXPECT_EQ(run.penetration.size(), 12u) << name;
  return run;
}

// contact_pair: a block pressed 7 mm onto another, then sheared. With collision on the
// surfaces never cross and the hidden vertices (the contact faces) are tracked to a fraction
// of a millimetre; off, the top block sinks into the base by several millimetres.
// (The figures when the bounds were set: docs/notes/2026-11-28-figures-from-code-comments.md.)
TEST(CollisionSequences, ContactPairStaysApartAndTracksTheHiddenContactFaces) {
  const SequenceRun on = RegisterSequence("contact_pair", true);
  const SequenceRun off = RegisterSequence("contact_pair", false);
  EXPECT_LT(on.Max(on.penetration), 0.5e-3);
  EXPECT_GT(off.Max(off.penetration), 2e-3);
  EXPECT_LT(on.Mean(on.seen), 0.3e-3);
  EXPECT_LT(on.Mean(on.hidden), 0.3e-3);
  EXPECT_LT(2 * on.Mean(on.hidden), off.Mean(off.hidden));
}

// tool_table: a slab pushed onto a table by a tool. On, nothing crosses the tool or the
// table; off, the slab passes into the tool it cannot see under (the figures when the bounds
// were set: docs/notes/2026-11-28-figures-from-code-comments.md).
TEST(CollisionSequences, ToolTableStaysOutOfTheToolAndTheTable) {
  const SequenceRun on = RegisterSequence("tool_table", true);
  const SequenceRun off = RegisterSequence("tool_table", false);
  EXPECT_LT(on.Max(on.penetration), 0.5e-3);
  EXPECT_GT(off.Max(off.penetration), 2 * on.Max(on.penetration));
  EXPECT_LT(on.Mean(on.seen), 0.5e-3);
  EXPECT_LT(on.Mean(on.hidden), 0.5e-3);
  EXPECT_LT(on.Mean(on.hidden), off.Mean(off.hidden));
}

// truth_contacts.csv rows: frame,newton_iterations,termination,final_residual_N,contacts,
// max_penetration_mm.
void CompareTruthContacts(const std::string& bundled, const std::string& regenerated, double max_shift) {
  auto rows = [](const std::string& path) {
    std::vector<std::vector<std::string>> out;
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
      std::vector<std::string> cells;
      std::stringstream ls(line);
      for (std::string c; std::getline(ls, c, ',');) cells.push_back(c);
      out.push_back(cells);
    }
    return out;
  };
  const auto a = rows(bundled), b = rows(regenerated);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a[0], b[0]);  // header
  for (size_t r = 1; r < a.size(); ++r) {
    SCOPED_TRACE("row " + std::to_string(r));
    ASSERT_EQ(a[r].size(), 6u);
    ASSERT_EQ(b[r].size(), 6u);
    EXPECT_EQ(a[r][0], b[r][0]);  // frame
    EXPECT_EQ(a[r][2], b[r][2]);  // termination
    const double ca = std::atof(a[r][4].c_str()), cb = std::atof(b[r][4].c_str());
    EXPECT_LE(std::abs(ca - cb), 0.1 * std::max(ca, cb)) << "contacts";
    EXPECT_LE(std::abs(std::atof(a[r][5].c_str()) - std::atof(b[r][5].c_str())), max_shift * 1e3)
        << "max_penetration_mm";
  }
}

// forces.csv rows: frame and the contact forces' resultant and torque. The resultant balances
// the clamp's reaction, which follows the slab's deformation as a whole, not which pairs at
// the pressed face's edge are active: `max_force` bounds it by the slab's axial stiffness
// times the mean shift allowed, `max_torque` by that force times the slab's length.
void CompareBundledForces(const std::string& bundled, const std::string& regenerated,
                          double max_force, double max_torque) {
  std::vector<ForceFrame> a, b;
  bool columns_a = false, columns_b = false;
  ASSERT_TRUE(ReadForces(bundled, &a, &columns_a).ok());
  ASSERT_TRUE(ReadForces(regenerated, &b, &columns_b).ok());
  ASSERT_TRUE(columns_a && columns_b);
  ASSERT_EQ(a.size(), b.size());
  for (size_t r = 0; r < a.size(); ++r) {
    SCOPED_TRACE("frame " + std::to_string(a[r].frame));
    EXPECT_EQ(a[r].frame, b[r].frame);
    EXPECT_LE((a[r].force - b[r].force).norm(), max_force);
    EXPECT_LE((a[r].torque - b[r].torque).norm(), max_torque);
  }
}

// tool_table with the forces estimated, pushing only and frictionless (as it was made): every
// frame stops on a tolerance. Where the cone's pieces model a step badly (its line search cut to
// a sliver), the majorized step goes on; without it one frame stalled.
TEST(CollisionSequences, ToolTablePushingOnlyConvergesEveryFrame) {
  const std::string dir = std::string(FEMREG_DATASETS_DIR) + "/tool_table";
  Scene scene;
  ASSERT_TRUE(LoadScene(dir + "/scene.yaml", &scene).ok());
  scene.registration.forces.estimate = true;
  scene.registration.forces.pushing_only = true;
  scene.registration.forces.friction = 0.0;
  scene.registration.solver.num_threads = 1;
  std::unique_ptr<Tracker> tracker;
  ASSERT_TRUE(Tracker::Create(scene, &tracker).ok());
  const std::vector<std::string> clouds = CloudFiles(dir);
  ASSERT_EQ(clouds.size(), 12u);
  for (size_t f = 0; f < clouds.size(); ++f) {
    PointCloud cloud;
    ASSERT_TRUE(ReadPointCloud(clouds[f], &cloud).ok());
    FrameSummary summary;
    ASSERT_TRUE(tracker->Track(cloud, &summary).ok());
    EXPECT_EQ(summary.termination, TerminationType::kConverged) << "frame " << f << ": " << summary.message;
  }
}

// The bundled contact sequences are what `femreg contact-data` writes today (one thread, as
// tools/make_datasets.sh runs it), within tolerances that say what can vary from one CPU or
// BLAS build to another:
//
// - What is integer by construction is compared exactly: the files and their rows, the
//   vertex counts, and scene.yaml, README.md and tool.stl (written from constants).
// - Ground-truth positions: the solve converges to a force imbalance below 1e-8 N (see
//   truth_contacts.csv); with a stiffness of order E h = 3e4 Pa x 7.5 mm = 225 N/m for the
//   softest block that alone is 1e-8 / 225 = 4e-11 m. What varies far more is which contact
//   pairs are active: ContactPotential re-detects them when a vertex has moved more than half
//   the margin, a floating-point comparison, and its header measures that two detection
//   histories differ by up to 0.27 mm at the edge of the pressed face. Roundoff (OpenBLAS
//   picks its kernels by CPU; CHOLMOD factorizes through it) can change that history, so a
//   vertex may move by up to kMaxShift = 0.3 mm; only the vertices near that edge do, so the
//   mean over all vertices stays below a tenth of it (the figures measured against the
//   bundled files: docs/notes/2026-11-28-figures-from-code-comments.md).
// - Visibility: a vertex is seen when it lies within 2 mm of the depth image; one within
//   0.3 mm of that threshold may flip: at most 2 per frame.
// - Clouds: as regen::CloudsAgree says (the camera sees the moved surface; a pixel that
//   flips shifts the noise draws of the pixels after it).
// - truth_contacts.csv: the same frames, terminations and (within 10%) contact counts; the
//   deepest penetration within kMaxShift; the Newton iteration counts may differ.
// - forces.csv (tool_table): as CompareBundledForces says, with the slab's E A / L and a tenth of
//   kMaxShift, the bound on the mean shift.
TEST(CollisionSequences, BundledSequencesRegenerateWithinTolerance) {
  namespace fs = std::filesystem;
  const double kMaxShift = 3e-4;  // m
  for (const std::string name : {"tool_table", "contact_pair"}) {
    SCOPED_TRACE(name);
    testing_util::TempDir dir("femreg_contact_regen");
    ASSERT_TRUE(GenerateContactSequence(name, dir.path()).ok());
    const fs::path bundled = fs::path(FEMREG_DATASETS_DIR) / name;
    int files = 0;
    for (const auto& entry : fs::recursive_directory_iterator(dir.path())) {
      if (!entry.is_regular_file()) continue;
      const fs::path rel = fs::relative(entry.path(), dir.path());
      const std::string mine = entry.path().string(), theirs = (bundled / rel).string();
      SCOPED_TRACE(rel.string() + " (regenerate with tools/make_datasets.sh)");
      ASSERT_TRUE(fs::is_regular_file(theirs)) << "not bundled";
      ++files;
      const std::string ext = rel.extension().string();
      if (rel.parent_path() == "ground_truth") {
        const regen::Deviation d = regen::CompareGroundTruth(theirs, mine);
        ASSERT_TRUE(d.ok) << d.Report();
        EXPECT_LE(d.max, kMaxShift) << d.Report();
        EXPECT_LE(d.mean, 0.1 * kMaxShift) << d.Report();
        EXPECT_LE(d.flips, 2) << d.Report();
      } else if (ext == ".pcd") {
        std::string why;
        EXPECT_TRUE(regen::CloudsAgree(theirs, mine, &why)) << why;
      } else if (rel == "truth_contacts.csv") {
        CompareTruthContacts(theirs, mine, kMaxShift);
      } else if (rel == "forces.csv") {
        const double length = 0.12, axial = 5e4 * 0.04 * 0.01 / length;  // tool_table's slab, N/m
        CompareBundledForces(theirs, mine, axial * 0.1 * kMaxShift,
                             axial * 0.1 * kMaxShift * length);
      } else {
        EXPECT_TRUE(regen::ReadBytes(theirs) == regen::ReadBytes(mine)) << "differs";
      }
    }
    EXPECT_GT(files, 24);
  }
}

#ifdef FEMREG_CLI_PATH
// The last value of a stats.csv column.
double LastColumn(const std::string& csv, const std::string& column) {
  std::ifstream in(csv);
  std::string header, line, last;
  std::getline(in, header);
  while (std::getline(in, line)) last = line;
  std::vector<std::string> names, cells;
  std::stringstream hs(header), ls(last);
  for (std::string c; std::getline(hs, c, ',');) names.push_back(c);
  for (std::string c; std::getline(ls, c, ',');) cells.push_back(c);
  for (size_t i = 0; i < names.size() && i < cells.size(); ++i)
    if (names[i] == column) return std::atof(cells[i].c_str());
  ADD_FAILURE() << column << " not in " << csv;
  return 0.0;
}

// `femreg register --no-collision` registers without the contact term but still measures the
// penetration with the scene's collision section, so on and off compare in stats.csv.
TEST(CollisionCli, RegisterWithAndWithoutCollisionReportsThePenetration) {
  testing_util::TempDir dir("femreg_collision_test");
  const std::string data = std::string(FEMREG_DATASETS_DIR) + "/contact_pair";
  const std::string base = std::string(FEMREG_CLI_PATH) + " register --scene " + data +
                           "/scene.yaml --frames " + data + "/clouds --ground-truth " + data +
                           "/ground_truth --no-progress --report none --out " + dir.path();
  ASSERT_EQ(std::system((base + "/on > " + dir.path() + "/on.txt").c_str()), 0);
  ASSERT_EQ(std::system((base + "/off --no-collision > " + dir.path() + "/off.txt").c_str()), 0);
  const double D_mm = 1.5;
  EXPECT_LT(LastColumn(dir.path() + "/on/stats.csv", "max_penetration_mm"), 0.5);
  EXPECT_LT(LastColumn(dir.path() + "/on/stats.csv", "min_gap_mm"), D_mm);  // detected
  EXPECT_GT(LastColumn(dir.path() + "/off/stats.csv", "max_penetration_mm"), 2.0);
  // Both from the same signed gap: the penetration is the negative smallest gap.
  EXPECT_NEAR(LastColumn(dir.path() + "/off/stats.csv", "max_penetration_mm"),
              -LastColumn(dir.path() + "/off/stats.csv", "min_gap_mm"), 1e-4);
  EXPECT_EQ(LastColumn(dir.path() + "/off/stats.csv", "t_collision_ms"), 0.0);  // not in the tracker
  std::ifstream off(dir.path() + "/off.txt");
  const std::string text((std::istreambuf_iterator<char>(off)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("collision off, measured only"), std::string::npos) << text;
  EXPECT_NE(text.find("deeper than collision.tolerance"), std::string::npos) << text;
}
#endif  // FEMREG_CLI_PATH

}  // namespace
}  // namespace femreg
