// The hand_press generator (issue 38, femreg hand-press-data): its first frames are the same
// bytes on every run and agree with the bundled dataset, and its forces balance gravity.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/datasets.h"
#include "femreg_test_config.h"
#include "regenerate_compare.h"
#include "test_util.h"

namespace femreg {
namespace {

namespace fs = std::filesystem;
using testing_util::TempDir;

constexpr double kGravity = 9.81;
constexpr double kRadius = 0.05;  // m
const char kForcesHeader[] =
    "frame,force_x_N,force_y_N,force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm,table_force_N,"
    "hand_force_x_N,hand_force_y_N,hand_force_z_N,contact_force_x_N,contact_force_y_N,contact_force_z_N";

struct ForceRow {
  int frame = 0;
  Eigen::Vector3d force, torque, hand, contact;
  double table = 0.0;
};

// forces.csv: its header, then one row per frame.
std::vector<ForceRow> ReadForces(const std::string& path, std::string* header) {
  std::vector<ForceRow> rows;
  std::ifstream in(path);
  std::getline(in, *header);
  for (std::string line; std::getline(in, line);) {
    std::vector<double> v;
    std::stringstream ls(line);
    for (std::string cell; std::getline(ls, cell, ',');) v.push_back(std::atof(cell.c_str()));
    if (v.size() != 14) {
      ADD_FAILURE() << path << ": a row of " << v.size() << " cells: " << line;
      continue;
    }
    ForceRow r;
    r.frame = static_cast<int>(v[0]);
    r.force = Eigen::Vector3d(v[1], v[2], v[3]);
    r.torque = Eigen::Vector3d(v[4], v[5], v[6]);
    r.table = v[7];
    r.hand = Eigen::Vector3d(v[8], v[9], v[10]);
    r.contact = Eigen::Vector3d(v[11], v[12], v[13]);
    rows.push_back(r);
  }
  return rows;
}

// The external forces balance the weight, and their torque about the centre of mass (where
// gravity has none) vanishes: to a millionth of the weight (and of its moment over the
// radius), the bound the generator itself refuses a frame beyond. The resultant is the
// table's and the hand's.
void ExpectBalanced(const ForceRow& r, double weight) {
  SCOPED_TRACE("frame " + std::to_string(r.frame));
  EXPECT_LE((r.force - Eigen::Vector3d(0, 0, weight)).norm(), 1e-6 * weight);
  EXPECT_LE(r.torque.norm(), 1e-6 * weight * kRadius);
  // The table's normal force is the resultant's z less the hand's, to the rounding of the
  // file's 7 significant digits.
  EXPECT_NEAR(r.table, r.force.z() - r.hand.z(), 1e-5 * std::max(1.0, std::abs(r.table)));
  // The table's push (the obstacle's contact force) is the resultant less the hand's, its
  // normal part the table's normal force.
  EXPECT_LE((r.contact - (r.force - r.hand)).norm(), 1e-5 * std::max(1.0, r.force.norm()));
  EXPECT_NEAR(r.contact.z(), r.table, 1e-9 * std::max(1.0, std::abs(r.table)));
}

// The first three frames (the ball at rest under its weight, the hand coming down) twice:
// the same bytes both times (one thread, seeded noise), files like the bundled dataset's,
// and the weight balanced by the table alone.
TEST(HandPressData, FirstFramesAreDeterministicBalancedAndBundled) {
  constexpr int kFrames = 3;
  TempDir a("femreg_hand_press"), b("femreg_hand_press");
  HandPressReport report, again;
  Status status = GenerateHandPressSequence(a.path(), kFrames, &report);
  ASSERT_TRUE(status.ok()) << status.message();
  status = GenerateHandPressSequence(b.path(), kFrames, &again);
  ASSERT_TRUE(status.ok()) << status.message();
  int files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(a.path())) {
    if (!entry.is_regular_file()) continue;
    const fs::path rel = fs::relative(entry.path(), a.path());
    SCOPED_TRACE(rel.string());
    EXPECT_TRUE(regen::ReadBytes(entry.path().string()) ==
                regen::ReadBytes((fs::path(b.path()) / rel).string()))
        << "differs between two runs";
    ++files;
  }
  // clouds with and without the hand, ground truth, truth; scene, README.md, forces, log
  EXPECT_EQ(files, 4 * kFrames + 4);

  EXPECT_EQ(report.frames, kFrames);
  EXPECT_EQ(report.tracked_vertices, 1331);
  EXPECT_EQ(report.truth_vertices, 4913);
  // The inscribed polyhedron holds a little less than the ball's 80 x 4/3 pi r^3.
  const double ball = 80.0 * 4.0 / 3.0 * M_PI * std::pow(kRadius, 3);
  EXPECT_GT(report.mass_kg, 0.95 * ball);
  EXPECT_LE(report.mass_kg, ball);
  const double weight = report.mass_kg * kGravity;
  EXPECT_LE(report.max_force_imbalance_N, 1e-6 * weight);
  EXPECT_LE(report.max_torque_imbalance_Nm, 1e-6 * weight * kRadius);
  std::string header;
  const std::vector<ForceRow> rows = ReadForces(a.File("forces.csv"), &header);
  EXPECT_EQ(header, kForcesHeader);
  ASSERT_EQ(rows.size(), static_cast<size_t>(kFrames));
  for (const ForceRow& r : rows) {
    ExpectBalanced(r, weight);
    EXPECT_EQ(r.hand.norm(), 0.0);  // it has not come down yet
    EXPECT_NEAR(r.table, weight, 1e-6 * weight);
  }
  // The hand's points are in the clouds (the palm above the ball's top, 0.1 m).
  PointCloud cloud;
  ASSERT_TRUE(ReadPointCloud(a.File("clouds/frame_0000.pcd"), &cloud).ok());
  int above = 0;
  for (int i = 0; i < cloud.size(); ++i) above += cloud.points(i, 2) > 0.15 ? 1 : 0;
  EXPECT_GT(above, 100);
  // Without the hand: the same points less the hand's, each one of the cloud's.
  PointCloud only_ball;
  ASSERT_TRUE(ReadPointCloud(a.File("clouds_without_hand/frame_0000.pcd"), &only_ball).ok());
  EXPECT_EQ(only_ball.size() + above, cloud.size());
  int kept = 0;
  for (int i = 0, j = 0; i < cloud.size() && j < only_ball.size(); ++i) {
    if ((cloud.points.row(i) - only_ball.points.row(j)).norm() == 0.0) ++kept, ++j;
  }
  EXPECT_EQ(kept, only_ball.size());
  for (int j = 0; j < only_ball.size(); ++j) EXPECT_LE(only_ball.points(j, 2), 0.15);

  // Against the bundled dataset (tools/make_datasets.sh), within what may vary from one CPU
  // or BLAS build to another: the bounds tests/synth_test.cc argues for the synth datasets,
  // whose solves stop at looser tolerances than these (truth_solve.csv).
  const fs::path bundled = fs::path(FEMREG_DATASETS_DIR) / "hand_press";
  const double kMaxShift = 20e-6;  // m
  EXPECT_TRUE(regen::ReadBytes((bundled / "scene.yaml").string()) ==
              regen::ReadBytes(a.File("scene.yaml")))
      << "scene.yaml differs from the bundled one (regenerate with tools/make_datasets.sh "
         "hand_press)";
  for (int f = 0; f < kFrames; ++f) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04d", f);
    SCOPED_TRACE(name);
    const std::string n(name);
    const regen::Deviation truth = regen::CompareGroundTruth(
        (bundled / "ground_truth" / (n + ".csv")).string(), a.File("ground_truth/" + n + ".csv"));
    ASSERT_TRUE(truth.ok) << truth.Report();
    EXPECT_LE(truth.max, kMaxShift) << truth.Report();
    EXPECT_LE(truth.flips, 2) << truth.Report();
    const regen::Deviation surface = regen::CompareVtuSurfaces(
        (bundled / "truth" / (n + ".vtu")).string(), a.File("truth/" + n + ".vtu"));
    ASSERT_TRUE(surface.ok) << surface.Report();
    EXPECT_LE(surface.max, kMaxShift) << surface.Report();
    std::string why;
    EXPECT_TRUE(regen::CloudsAgree((bundled / "clouds" / (n + ".pcd")).string(),
                                   a.File("clouds/" + n + ".pcd"), &why))
        << why;
  }
  std::string bundled_header;
  const std::vector<ForceRow> bundled_rows =
      ReadForces((bundled / "forces.csv").string(), &bundled_header);
  ASSERT_GE(bundled_rows.size(), rows.size());
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_LE((bundled_rows[i].force - rows[i].force).norm(), 1e-6 * weight);
    EXPECT_LE((bundled_rows[i].hand - rows[i].hand).norm(), 1e-6 * weight);
    EXPECT_LE((bundled_rows[i].contact - rows[i].contact).norm(), 1e-6 * weight);
  }
}

// A variant (another noise draw, the camera at the side, a scene that gets the stiffness
// wrong): the scene and README say so, the camera and the noise differ from the bundled
// frame's, the ball's weight is balanced as before; options out of range are refused.
TEST(HandPressData, VariantsSayWhatTheyVaryAndRefuseNonsense) {
  TempDir a("femreg_hand_press_variant");
  HandPressOptions options;
  options.seed = 3;
  options.camera_azimuth_deg = 90.0;
  options.scene_youngs_modulus = 12345.678;  // more digits than a stream's default six
  HandPressReport report;
  const Status status = GenerateHandPressSequence(a.path(), 1, &report, nullptr, options);
  ASSERT_TRUE(status.ok()) << status.message();
  const std::string scene = regen::ReadBytes(a.File("scene.yaml"));
  EXPECT_NE(scene.find("position: [0.39, 0, 0.44]"), std::string::npos) << scene;
  // Every digit, so that the printed options make the same variant again.
  EXPECT_NE(scene.find("youngs_modulus: 12345.678,"), std::string::npos) << scene;
  EXPECT_NE(scene.find("hand-press-data --scene-youngs-modulus 12345.678 --camera-azimuth 90 --seed 3"),
            std::string::npos)
      << scene;
  EXPECT_NE(regen::ReadBytes(a.File("README.md")).find("**A variant**"), std::string::npos);
  const double weight = report.mass_kg * kGravity;
  EXPECT_LE(report.max_force_imbalance_N, 1e-6 * weight);
  // Seen from +x, the ball's points lie on that side of its centre.
  PointCloud cloud, bundled;
  ASSERT_TRUE(ReadPointCloud(a.File("clouds_without_hand/frame_0000.pcd"), &cloud).ok());
  ASSERT_TRUE(ReadPointCloud(std::string(FEMREG_DATASETS_DIR) +
                                 "/hand_press/clouds_without_hand/frame_0000.pcd",
                             &bundled).ok());
  ASSERT_GT(cloud.size(), 500);
  EXPECT_GT(cloud.points.col(0).mean(), 0.02);
  EXPECT_LT(std::abs(bundled.points.col(0).mean()), 0.005);  // the bundled camera: in front

  // Another noise draw alone: the same ground truth, other clouds.
  TempDir b("femreg_hand_press_seed");
  HandPressOptions seeded;
  seeded.seed = 3;
  ASSERT_TRUE(GenerateHandPressSequence(b.path(), 1, nullptr, nullptr, seeded).ok());
  const std::string bundled_dir = std::string(FEMREG_DATASETS_DIR) + "/hand_press/";
  const regen::Deviation truth = regen::CompareGroundTruth(bundled_dir + "ground_truth/frame_0000.csv",
                                                           b.File("ground_truth/frame_0000.csv"));
  ASSERT_TRUE(truth.ok) << truth.Report();
  EXPECT_LE(truth.max, 20e-6) << truth.Report();
  EXPECT_FALSE(regen::ReadBytes(bundled_dir + "clouds/frame_0000.pcd") == regen::ReadBytes(b.File("clouds/frame_0000.pcd")));

  HandPressOptions bad;
  bad.press_scale = 2.0;
  EXPECT_FALSE(GenerateHandPressSequence(a.path(), 1, nullptr, nullptr, bad).ok());
  bad = HandPressOptions();
  bad.youngs_modulus = -1.0;
  const Status refused = GenerateHandPressSequence(a.path(), 1, nullptr, nullptr, bad);
  EXPECT_FALSE(refused.ok());
  EXPECT_NE(refused.message().find("Young's modulus"), std::string::npos) << refused.message();
}

// The bundled sequence's forces: every frame balances gravity, the table only pushes, the
// palm pushes down while it presses, the table carries nothing while the ball is lifted
// (the grasp holds the weight) and nothing touches the ball once the hand has left.
TEST(HandPressData, BundledForcesBalanceGravity) {
  const fs::path bundled = fs::path(FEMREG_DATASETS_DIR) / "hand_press";
  std::string header;
  const std::vector<ForceRow> rows = ReadForces((bundled / "forces.csv").string(), &header);
  EXPECT_EQ(header, kForcesHeader);
  ASSERT_EQ(rows.size(), 30u);
  // The weight is the resultant at rest (frame 0: the table alone).
  const double weight = rows[0].table;
  const double ball = 80.0 * 4.0 / 3.0 * M_PI * std::pow(kRadius, 3) * kGravity;
  EXPECT_GT(weight, 0.95 * ball);
  EXPECT_LE(weight, ball);
  for (const ForceRow& r : rows) {
    ExpectBalanced(r, weight);
    EXPECT_GE(r.table, 0.0) << "frame " << r.frame << ": the table pulls";
  }
  EXPECT_LT(rows[7].hand.z(), -5 * weight);  // the press (frames 3-8)
  for (int f : {16, 17, 18, 19, 20}) {       // lifted
    EXPECT_EQ(rows[static_cast<size_t>(f)].table, 0.0) << "frame " << f;
    EXPECT_NEAR(rows[static_cast<size_t>(f)].hand.z(), weight, 1e-6 * weight) << "frame " << f;
  }
  EXPECT_EQ(rows[29].hand.norm(), 0.0);  // let go
}

#ifdef FEMREG_CLI_PATH
// Seen from the side the ball is carried to, the hand coming down is two thirds of the first
// cloud. The given pose (the ball on the table, right) fits the cloud badly by the trimmed
// distance, and a pose that puts the ball in the hand fits it better. It must not replace the
// given one: the cloud covers what the camera should see of the ball far better at the given
// pose. Until it was checked, the ball started up in the hand
// (docs/notes/2026-12-08-hand-press-varied.md).
// The first `frames` frames of hand_press seen from +x (--camera-azimuth 90), made in `dir` and
// registered at the defaults on one thread into dir/out.
void RegisterSideView(const std::string& dir, int frames) {
  HandPressOptions options;
  options.camera_azimuth_deg = 90.0;
  const std::string data = dir + "/data";
  const Status made = GenerateHandPressSequence(data, frames, nullptr, nullptr, options);
  ASSERT_TRUE(made.ok()) << made.message();
  const testing_util::CliRun r = testing_util::Femreg(
      "register --scene " + data + "/scene.yaml --frames " + data + "/clouds --ground-truth " + data +
      "/ground_truth --out " + dir + "/out --threads 1 --no-progress --report none");
  ASSERT_EQ(r.code, 0) << r.out;
}

TEST(HandPressRegistration, AHandThatIsMostOfTheFirstCloudLeavesTheBallWhereItIs) {
  TempDir tmp;
  ASSERT_NO_FATAL_FAILURE(RegisterSideView(tmp.path(), 1));
  const std::string summary = regen::ReadBytes(tmp.path() + "/out/summary.json");
  // Searched (the hand makes the given pose's fit bad), and kept.
  EXPECT_NE(summary.find("\"chosen\": \"given, searched\""), std::string::npos) << summary.substr(0, 2000);
  const std::vector<std::string> errors = testing_util::StatsColumn(tmp.path() + "/out", "err_mean_mm");
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_LT(std::stod(errors[0]), 1.0);
}

// From the same side, through the set-down: with the forces estimated where the hand holds
// the ball, a classic warm start's data springs pressed it into the table, and the contacts'
// multipliers took that in as forces of the physical balance: frame 24 ended deep in the table,
// its forces and balance off by orders of magnitude (docs/notes/2026-12-08-hand-press-varied.md).
// The bounds are far above what the frames reach now and far below what they reached then.
// Where the lift stops (frame 19), the prediction carried it on, and the ball's own points,
// inside the body at that start, were taken for the hand's: over a thousand a frame were
// marked implausible in frames 19-21, and the ball ended off its points until frame 24
// (docs/notes/2026-12-08-marks-from-the-side.md). The bounds lie between then and now.
TEST(HandPressRegistration, SeenFromTheSideTheTablePushesWhatTheBallWeighs) {
  TempDir tmp;
  ASSERT_NO_FATAL_FAILURE(RegisterSideView(tmp.path(), 25));
  const std::string out = tmp.path() + "/out";
  const std::vector<std::string> balance = testing_util::StatsColumn(out, "e_equilibrium");
  const std::vector<std::string> push = testing_util::StatsColumn(out, "contact_force_z_N");
  const std::vector<std::string> depth = testing_util::StatsColumn(out, "max_penetration_mm");
  ASSERT_EQ(balance.size(), 25u);
  ASSERT_EQ(push.size(), 25u);
  ASSERT_EQ(depth.size(), 25u);
  for (size_t f = 0; f < balance.size(); ++f) {
    SCOPED_TRACE("frame " + std::to_string(f));
    EXPECT_LT(std::stod(balance[f]), 100.0);
    EXPECT_LT(std::abs(std::stod(push[f])), 50.0);
    EXPECT_LT(std::stod(depth[f]), 1.0);
  }
  const std::vector<std::string> implausible = testing_util::StatsColumn(out, "implausible_points");
  const std::vector<std::string> errors = testing_util::StatsColumn(out, "err_mean_mm");
  ASSERT_EQ(implausible.size(), 25u);
  ASSERT_EQ(errors.size(), 25u);
  for (size_t f : {19, 20, 21}) EXPECT_LT(std::stoi(implausible[f]), 600) << "frame " << f;
  EXPECT_LT(std::stod(errors[23]), 4.0);
}

// Pushing only (the hand and the table push; the grasp's friction unbounded), on the fast back
// end: the steps that close contacts with the table are solved again until they close no new
// one. With a single re-solve the line searches cut the steps to nothing while the ball was
// set down, and the mean error was 2.87 mm (Ceres: 2.5). The bound on the PCG iterations over
// the sequence (a count, not a time) lies between what the solves take since a solve whose
// re-solves across the penalty's kinks do not settle drops them for its later steps (about
// 3,100) and what they took before (about 4,600; docs/notes/2026-12-07-what-the-pushing-hand-costs.md).
// Every frame ends balanced: a hidden-turn hold that its contacts see is undone (frames 7-9 ended
// with an equilibrium energy of 2.7-38 when it was not; since, 0.08-0.4 over nudged settings).
TEST(HandPressRegistration, PushingOnlyOnTheFastBackEndSetsTheBallDown) {
  const std::string data = std::string(FEMREG_DATASETS_DIR) + "/hand_press";
  TempDir tmp;
  const testing_util::CliRun r = testing_util::Femreg(
      "register --scene " + data + "/scene.yaml --frames " + data + "/clouds --ground-truth " + data +
      "/ground_truth --out " + tmp.path() + "/out --threads 1 --no-progress --report none" +
      " --set registration.forces.estimate=true --set registration.forces.pushing_only=true");
  ASSERT_EQ(r.code, 0) << r.out;
  const std::vector<std::string> errors = testing_util::StatsColumn(tmp.path() + "/out", "err_mean_mm");
  ASSERT_EQ(errors.size(), 30u);
  double sum = 0.0;
  for (const std::string& e : errors) sum += std::stod(e);
  std::printf("hand_press, pushing only: mean vertex error %.3f mm\n", sum / 30.0);
  EXPECT_LT(sum / 30.0, 2.42);
  int pcg = 0;
  for (const std::string& c : testing_util::StatsColumn(tmp.path() + "/out", "pcg_iterations")) pcg += std::stoi(c);
  std::printf("hand_press, pushing only: %d PCG iterations\n", pcg);
  EXPECT_LT(pcg, 4000);
  const std::vector<std::string> balance = testing_util::StatsColumn(tmp.path() + "/out", "e_equilibrium");
  ASSERT_EQ(balance.size(), 30u);
  for (size_t f = 0; f < balance.size(); ++f) EXPECT_LT(std::stod(balance[f]), 1.0) << "frame " << f;
}
#endif

}  // namespace
}  // namespace femreg
