// Every input in fuzz/regressions/TARGET/ (inputs that once crashed, hung or aborted a
// reader: found by the fuzzers of tools/fuzz.sh or reported in issue 13) runs through the
// same code as its fuzz target (fuzz/fuzz_inputs.h), here in the normal build without
// libFuzzer. Each must come back as a Status: an error naming the file with a short message,
// or a mesh or cloud that passes the target's consistency checks (a broken check aborts).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "femreg_test_config.h"
#include "fuzz/fuzz_inputs.h"

namespace femreg {
namespace {

namespace fs = std::filesystem;

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

Status RunTarget(const std::string& target, const std::string& bytes) {
  return fuzz::RunInput(target, reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
}

class FuzzRegressions : public ::testing::Test {
 protected:
  static void TearDownTestSuite() { fuzz::RemoveScratchDir(); }
};

TEST_F(FuzzRegressions, EveryStoredInputIsReadOrRefusedWithAMessage) {
  const fs::path root = fs::path(FEMREG_SOURCE_DIR) / "fuzz" / "regressions";
  int inputs = 0;
  for (const std::string& target : fuzz::TargetNames()) {
    const fs::path dir = root / target;
    if (!fs::is_directory(dir)) continue;
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(dir)) {
      if (entry.is_regular_file()) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& file : files) {
      SCOPED_TRACE(target + "/" + file.filename().string());
      const Status status = RunTarget(target, ReadBytes(file));  // aborts on a broken promise
      if (!status.ok()) {
        EXPECT_LT(status.message().size(), fuzz::kMaxMessage);
      }
      ++inputs;
    }
  }
  EXPECT_GE(inputs, 20) << "fuzz/regressions/ lost its inputs";
}

// The inputs of issue 13 are refused, each with the line or offset of its bad count.
TEST_F(FuzzRegressions, Issue13InputsAreRefusedAtTheirBadCount) {
  const fs::path root = fs::path(FEMREG_SOURCE_DIR) / "fuzz" / "regressions";
  struct Case {
    const char* target;
    const char* file;
    const char* expected;  // in the message
  };
  const Case cases[] = {
      {"pcd", "issue13_fields_label_ascii.pcd", ":4: SIZE has 3 entries, FIELDS (line 3) has 4"},
      {"pcd", "issue13_fields_label_binary.pcd", ":4: SIZE has 3 entries"},
      {"pcd", "issue13_fields_label_compressed.pcd", ":4: SIZE has 3 entries"},
      {"pcd", "issue13_no_fields_line.pcd", ":10: no FIELDS line before DATA"},
      {"vtk_legacy", "issue13_points_4e9_ascii.vtk", ":5: POINTS: 4000000000 tuples of 3 values cannot fit in the 13 bytes left"},
      {"vtk_legacy", "issue13_points_negative_binary.vtk", ":5: POINTS: negative size"},
      {"gmsh", "issue13_node_block_2p62.msh", ":6: the number of nodes in the block is 4611686018427387904"},
      {"vtu", "issue13_components_negative.vtu", "byte 189: DataArray NumberOfComponents='-4' is out of range (1 to 1024)"},
      {"vtu", "issue13_components_4294967299.vtu", "NumberOfComponents='4294967299' is out of range"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const Status status = RunTarget(c.target, ReadBytes(root / c.target / c.file));
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find(c.expected), std::string::npos) << status.message();
  }
}

// A 4 MB token is quoted by its first 80 characters and its length, in every text reader.
TEST_F(FuzzRegressions, AHugeBadTokenIsNotEchoedWhole) {
  const std::string token(4 << 20, 'q');
  const std::pair<const char*, std::string> inputs[] = {
      {"xyz", "0 0 0\n" + token + " 1 2\n"},
      {"gmsh", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n" + token + "\n"},
      {"medit", "MeshVersionFormatted 2\nDimension 3\n" + token + " 3\n"},
      {"vtk_legacy", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 float\n" + token},
      {"pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n0 0 " + token + "\n"},
      {"ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 " + token + "\n"},
      {"tetgen", "1 3 0 0\n1 0 0 " + token + "\n"},
  };
  for (const auto& [target, text] : inputs) {
    SCOPED_TRACE(target);
    const Status status = RunTarget(target, text);
    ASSERT_FALSE(status.ok());
    EXPECT_LT(status.message().size(), 400u) << status.message().substr(0, 400);
    EXPECT_NE(status.message().find("(4194304 bytes)"), std::string::npos) << status.message().substr(0, 400);
  }
}

}  // namespace
}  // namespace femreg
