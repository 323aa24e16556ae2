// The contacts an equilibrium step closes (solvers/fast/closing_contacts.h): found exactly from
// the linear penetration, and added round by round as the re-solved steps close more.
#include <gtest/gtest.h>

#include <Eigen/Core>

#include "energy/contact.h"
#include "energy/problem.h"
#include "solvers/fast/closing_contacts.h"

namespace femreg {
namespace fast_backend {
namespace {

// Four vertices above a table at z = 0, 1, 2, 3 and 4 mm above it (a point contact each:
// delta = -z).
struct Table {
  energy::Problem problem;
  Vertices x = Vertices::Zero(4, 3);
  Table() {
    problem.Reset(4);
    auto& contacts = problem.AddSet<energy::ContactPenalty<3>>(energy::TermGroup::kCollision);
    for (int v = 0; v < 4; ++v) {
      x(v, 2) = 0.001 * (v + 1);
      energy::ContactPenalty<3> b;
      b.vertices = {{v, (v + 1) % 4, (v + 2) % 4}};
      b.coefficients = {{1.0, 0.0, 0.0}};
      b.normal = Eigen::Vector3d::UnitZ();
      b.weight = 1e4;
      contacts.Add(b);
    }
  }
  // A step that lowers every vertex by `depth`.
  static Eigen::VectorXd Down(double depth) {
    Eigen::VectorXd dx = Eigen::VectorXd::Zero(12);
    for (int v = 0; v < 4; ++v) dx(3 * v + 2) = -depth;
    return dx;
  }
};

TEST(ClosingContacts, FindsTheContactsAStepClosesAndAddsTheNextStepsOnes) {
  Table t;
  ClosingContacts closing;
  EXPECT_EQ(closing.Find(t.problem, t.x, Table::Down(0.0005)), 0);
  EXPECT_TRUE(closing.empty());
  EXPECT_EQ(closing.Find(t.problem, t.x, Table::Down(0.0015)), 1);  // the 1 mm one
  // A deeper step closes the 2 and 3 mm ones too: added, the first kept and not counted again.
  EXPECT_EQ(closing.Find(t.problem, t.x, Table::Down(0.0035), /*add=*/true), 2);
  EXPECT_EQ(closing.Find(t.problem, t.x, Table::Down(0.0035), /*add=*/true), 0);
  // Their stiffness in K's product: k on each closed vertex's z, none on the open one's.
  Eigen::VectorXd y = Eigen::VectorXd::Zero(12);
  closing.AddProduct(Table::Down(-1.0), &y);  // p = +1 on every z
  for (int v = 0; v < 3; ++v) EXPECT_DOUBLE_EQ(y(3 * v + 2), 1e4);
  EXPECT_EQ(y(11), 0.0);
  // Without `add`, a search starts again.
  EXPECT_EQ(closing.Find(t.problem, t.x, Table::Down(0.0015)), 1);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(12);
  closing.AddForce(&f);  // k delta(x) d(delta)/dx on the closed branch: delta = -1 mm
  EXPECT_NEAR(f(2), 1e4 * 0.001, 1e-12);
  EXPECT_EQ(f.tail<9>().norm(), 0.0);
  closing.Clear();
  EXPECT_TRUE(closing.empty());
}

}  // namespace
}  // namespace fast_backend
}  // namespace femreg
