// The forward contact solve against CalculiX without running it: the press cases of
// tools/press_case.h (a soft block pressed onto a clamped soft block or a rigid plane,
// frictionless and with friction, pressed and slid) solved by femreg and compared with ccx's
// results stored in tests/fixtures/calculix_contact (remade by
// `tools/compare_calculix.sh build --only contact --fixture tests/fixtures/calculix_contact`):
// the total contact force within 3 %, the pressed block's free surface within 5 %; and the
// contact force balances the load the pressed face takes.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "femreg_test_config.h"
#include "tools/press_case.h"

namespace femreg {
namespace {

struct Reference {
  std::string name, args;
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // ccx: the support's force on the pressed block
  std::map<int, Eigen::Vector3d> u;                 // ccx: node -> displacement
};

std::vector<Reference> ReadReferences() {
  const std::string dir = std::string(FEMREG_FIXTURES_DIR) + "/calculix_contact/";
  std::vector<Reference> references;
  std::ifstream cases(dir + "cases.csv");
  std::string line;
  std::getline(cases, line);  // header
  while (std::getline(cases, line)) {
    std::vector<std::string> fields;
    std::stringstream ss(line);
    for (std::string f; std::getline(ss, f, ',');) fields.push_back(f);
    if (fields.size() != 5) continue;
    Reference r;
    r.name = fields[0];
    r.args = fields[1];
    r.force = Eigen::Vector3d(std::stod(fields[2]), std::stod(fields[3]), std::stod(fields[4]));
    std::ifstream u(dir + r.name + "_u.csv");
    std::getline(u, line);
    int id;
    char comma;
    Eigen::Vector3d d;
    while (u >> id >> comma >> d(0) >> comma >> d(1) >> comma >> d(2)) r.u[id] = d;
    references.push_back(r);
  }
  return references;
}

PressOptions Options(const std::string& args) {
  std::map<std::string, std::string> keys;
  std::stringstream ss(args);
  for (std::string kv; ss >> kv;) keys[kv.substr(0, kv.find('='))] = kv.substr(kv.find('=') + 1);
  PressOptions options;
  EXPECT_TRUE(ParsePressOptions(keys, &options).ok()) << args;
  return options;
}

class ContactPress : public ::testing::TestWithParam<int> {};

TEST_P(ContactPress, MatchesCalculixAndBalancesTheLoad) {
  const std::vector<Reference> references = ReadReferences();
  ASSERT_EQ(references.size(), 5u) << "tests/fixtures/calculix_contact/cases.csv";
  const Reference& ref = references[GetParam()];
  SCOPED_TRACE(ref.name + ": " + ref.args);
  const PressOptions options = Options(ref.args);
  PressResult result;
  const Status status = SolvePressCase(options, &result);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_TRUE(result.converged);

  // The support's push on the pressed block is what its pressed face takes, and, sliding,
  // friction is at most mu times the normal force.
  const Eigen::Vector3d& f = result.contact_force;
  EXPECT_LT((f + result.top_reaction).norm(), 1e-3 * f.norm());
  EXPECT_GT(f.z(), 0.0);
  const Eigen::Vector3d normal = f - result.friction_force;
  EXPECT_LE(result.friction_force.norm(), options.friction * normal.norm() * 1.01 + 1e-12);
  if (options.friction == 0.0) {
    EXPECT_EQ(result.friction_force.norm(), 0.0);
  }
  EXPECT_LT(result.max_penetration, 0.01 * options.press);

  // Against CalculiX: the total contact force within 3 %, the free surface within 5 % (rms).
  const double force_error = (f - ref.force).norm() / ref.force.norm();
  double diff = 0.0, size = 0.0;
  int compared = 0;
  for (int v = 0; v < result.top_rest.rows(); ++v) {
    if (!result.free_surface[v]) continue;
    const auto it = ref.u.find(result.top_offset + v + 1);
    ASSERT_NE(it, ref.u.end()) << "node " << result.top_offset + v + 1;
    const Eigen::Vector3d u = (result.top_x.row(v) - result.top_rest.row(v)).transpose();
    diff += (u - it->second).squaredNorm();
    size += it->second.squaredNorm();
    ++compared;
  }
  ASSERT_GT(compared, 50);
  const double displacement_error = std::sqrt(diff / size);
  RecordProperty("force_error", std::to_string(force_error));
  RecordProperty("displacement_error", std::to_string(displacement_error));
  EXPECT_LT(force_error, 0.03) << "femreg " << f.transpose() << ", ccx " << ref.force.transpose();
  EXPECT_LT(displacement_error, 0.05);
}

INSTANTIATE_TEST_SUITE_P(Cases, ContactPress, ::testing::Range(0, 5));

}  // namespace
}  // namespace femreg
