// The separation case of the CalculiX comparison (tools/cut_case.h): femreg's forward solve of a
// beam bent, then cut by removing a slab of its elements, against ccx's *MODEL CHANGE, TYPE=
// ELEMENT, REMOVE (tests/fixtures/calculix_cut, written by tools/compare_calculix.py).
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>

#include "femreg_test_config.h"
#include "tools/cut_case.h"

namespace femreg {
namespace {

// The cut parts the beam in two: the clamped piece springs back to rest, the free one follows
// the gripper rigidly (nothing else holds it), and before the cut the bent beam agrees with
// ccx's NLGEOM solve within 0.5 % of the largest displacement (0.13 % when written), after it
// within 0.1 %.
TEST(CutCase, SeparatesIntoARestingAndARigidPieceAsCalculixDoes) {
  CutOptions options;
  options.bend = 0.4;
  CutResult r;
  ASSERT_TRUE(SolveCutCase(options, &r).ok());
  EXPECT_TRUE(r.converged) << r.report;
  EXPECT_EQ(r.slab.size(), 216u);  // one cell of the 6 x 6 section, 6 tetrahedra each
  int free_count = 0;
  double clamped_max = 0.0;
  for (int v = 0; v < r.mesh.num_vertices(); ++v) {
    if (r.piece[static_cast<size_t>(v)] == 1) {
      ++free_count;
    } else {
      clamped_max = std::max(clamped_max, r.u_cut.row(v).norm());
    }
  }
  EXPECT_EQ(free_count, 26 * 49);  // the vertices from x = 75 mm on
  EXPECT_LT(clamped_max, 1e-9);
  // The free piece: a rigid motion of its rest shape.
  Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
  for (int v = 0; v < r.mesh.num_vertices(); ++v) {
    if (r.piece[static_cast<size_t>(v)] != 1) continue;
    ca += r.mesh.rest.row(v).transpose() / free_count;
    cb += (r.mesh.rest.row(v) + r.u_cut.row(v)).transpose() / free_count;
  }
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (int v = 0; v < r.mesh.num_vertices(); ++v) {
    if (r.piece[static_cast<size_t>(v)] != 1) continue;
    H += (r.mesh.rest.row(v).transpose() - ca) * (r.mesh.rest.row(v) + r.u_cut.row(v) - cb.transpose());
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d R = svd.matrixV() * svd.matrixU().transpose();
  double rigid = 0.0;
  for (int v = 0; v < r.mesh.num_vertices(); ++v) {
    if (r.piece[static_cast<size_t>(v)] != 1) continue;
    const Eigen::Vector3d X = r.mesh.rest.row(v);
    rigid = std::max(rigid, (R * (X - ca) + cb - X - r.u_cut.row(v).transpose()).norm());
  }
  EXPECT_LT(rigid, 1e-8);

  std::ifstream in(std::string(FEMREG_SOURCE_DIR) + "/tests/fixtures/calculix_cut/bend0.4_u.csv");
  ASSERT_TRUE(in.good());
  std::string line;
  std::getline(in, line);
  double max_bent = 0.0, max_cut = 0.0, diff_bent = 0.0, diff_cut = 0.0;
  int rows = 0;
  while (std::getline(in, line)) {
    int id;
    Eigen::Vector3d a, b;
    ASSERT_EQ(std::sscanf(line.c_str(), "%d,%lf,%lf,%lf,%lf,%lf,%lf", &id, &a.x(), &a.y(), &a.z(), &b.x(),
                          &b.y(), &b.z()),
              7)
        << line;
    ASSERT_GE(id, 1);
    ASSERT_LE(id, r.mesh.num_vertices());
    max_bent = std::max(max_bent, a.norm());
    max_cut = std::max(max_cut, b.norm());
    diff_bent = std::max(diff_bent, (r.u_bent.row(id - 1).transpose() - a).norm());
    diff_cut = std::max(diff_cut, (r.u_cut.row(id - 1).transpose() - b).norm());
    ++rows;
  }
  EXPECT_GT(rows, 500);
  EXPECT_GT(max_bent, 0.04);
  EXPECT_LT(diff_bent / max_bent, 0.005);
  EXPECT_LT(diff_cut / max_cut, 0.001);
  std::printf("cut case against ccx: bent %.3f %%, cut %.4f %% of the largest displacement\n",
              100 * diff_bent / max_bent, 100 * diff_cut / max_cut);
}

}  // namespace
}  // namespace femreg
