// The library's writers of a registration run's files (femreg/results.h): a stats.csv row has
// a cell per header column, StatsFile appends rows after the header, and summary.json records
// the run and its inputs.
#include "femreg/results.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "femreg/scene.h"
#include "femreg/tracker.h"
#include "test_util.h"

namespace femreg {
namespace {

// The cells of a stats.csv line: commas outside the quoted message.
int Cells(const std::string& line) {
  int cells = 1;
  bool quoted = false;
  for (char c : line) {
    if (c == '"') quoted = !quoted;
    if (c == ',' && !quoted) ++cells;
  }
  return cells;
}

FrameRecord Record() {
  FrameRecord row;
  row.file = "clouds/frame_0003.pcd";
  row.summary.message = "a \"quoted\", message";
  row.have_errors = true;
  row.errors.all.mean = 0.002;
  row.pieces = 2;
  row.piece_errors.resize(2);
  row.piece_errors[0].count = 4;
  row.piece_errors[0].mean = 0.001;
  row.piece_seen = row.piece_hidden = row.piece_errors;
  row.break_frame = 3;
  return row;
}

TEST(Results, AStatsRowHasACellPerHeaderColumn) {
  const std::string header = kStatsHeader;
  ASSERT_EQ(header.back(), '\n');
  const std::string row = StatsRow(3, Record());
  ASSERT_EQ(row.back(), '\n');
  EXPECT_EQ(Cells(row), Cells(header));
  EXPECT_EQ(Cells(StatsRow(0, FrameRecord())), Cells(header));
  // The file's name without its folder; the message quoted, its own quotes made single.
  EXPECT_EQ(row.rfind("3,frame_0003.pcd,", 0), 0u) << row;
  EXPECT_NE(row.find(",\"a 'quoted', message\"\n"), std::string::npos) << row;
  // Per piece, ';' between pieces, an empty entry for a piece without vertices.
  EXPECT_NE(row.find(",2,1.0000;,1.0000;,1.0000;,3,"), std::string::npos) << row;
}

TEST(Results, StatsFileAppendsRowsAfterTheHeader) {
  testing_util::TempDir dir("femreg_results");
  StatsFile stats;
  ASSERT_TRUE(stats.Open(dir.File("stats.csv")).ok());
  const std::string first = StatsRow(0, Record()), second = StatsRow(1, FrameRecord());
  ASSERT_TRUE(stats.Append(first).ok());
  // Flushed with every row: the file holds what was appended while it is open.
  EXPECT_EQ(testing_util::Slurp(dir.File("stats.csv")), std::string(kStatsHeader) + first);
  ASSERT_TRUE(stats.Append(second).ok());
  EXPECT_EQ(testing_util::Slurp(dir.File("stats.csv")), std::string(kStatsHeader) + first + second);
  StatsFile nowhere;
  EXPECT_FALSE(nowhere.Open(dir.File("no/such/folder/stats.csv")).ok());
}

TEST(Results, SummaryJsonRecordsTheRunAndItsInputs) {
  Scene scene;
  ASSERT_TRUE(ParseScene("objects: [{name: block, generate: {shape: box, size: [0.04, 0.04, 0.02], "
                         "cells: [4, 4, 2]}}]\n",
                         "block.yaml", "", &scene)
                  .ok());
  std::unique_ptr<Tracker> tracker;
  ASSERT_TRUE(Tracker::Create(scene, &tracker).ok());
  PointCloud cloud;
  const TetMesh& mesh = tracker->mesh(0);
  cloud.points.resize(static_cast<int>(mesh.surface_vertices.size()), 3);
  for (size_t i = 0; i < mesh.surface_vertices.size(); ++i) {
    cloud.points.row(static_cast<int>(i)) = mesh.rest.row(mesh.surface_vertices[i]);
  }
  std::vector<FrameRecord> rows(1);
  rows[0].file = "frame_0000.pcd";
  ASSERT_TRUE(tracker->Track(cloud, &rows[0].summary).ok());
  const RunTotals totals = ComputeRunTotals(rows);
  EXPECT_EQ(totals.frames, 1);
  EXPECT_EQ(totals.usable, rows[0].summary.IsSolutionUsable() ? 1 : 0);
  EXPECT_FALSE(totals.have_errors);

  RunInputs run;
  run.scene = "block.yaml";
  run.frames_source = "clouds";
  run.frame_files = {"clouds/frame_0000.pcd", "clouds/frame_0001.pcd"};
  run.overrides = {"registration.weights.elastic=2"};
  run.interrupted = true;
  run.interrupted_by = "SIGTERM";
  run.max_frames = 5;
  const std::string json = SummaryJson(run, scene, *tracker, rows);
  for (const char* key : {"\"femreg_version\"", "\"scene\": \"block.yaml\"", "\"frames_source\": \"clouds\"",
                          "\"frames_total\": 2", "\"frames_done\": 1", "\"interrupted\": true",
                          "\"interrupted_by\": \"SIGTERM\"", "\"name\": \"block\"", "\"max_frames\": 5",
                          "\"registration.weights.elastic=2\"", "\"frame_files\"", "\"tum_list\": null"}) {
    EXPECT_NE(json.find(key), std::string::npos) << key << "\n" << json;
  }
  // Not interrupted: no interrupted_by; no ground truth: no vertex errors.
  run.interrupted = false;
  const std::string whole = SummaryJson(run, scene, *tracker, rows);
  EXPECT_EQ(whole.find("\"interrupted_by\""), std::string::npos);
  EXPECT_EQ(whole.find("\"vertex_error_mm\""), std::string::npos);
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// The summary.json SummaryJson writes for a scene (YAML) with no frames, at `path`.
::testing::AssertionResult WriteSummaryOf(const std::string& yaml, const std::string& path) {
  Scene scene;
  const Status parsed = ParseScene(yaml, "summary.yaml", "", &scene);
  if (!parsed.ok()) return ::testing::AssertionFailure() << parsed.message();
  std::unique_ptr<Tracker> tracker;
  const Status created = Tracker::Create(scene, &tracker);
  if (!created.ok()) return ::testing::AssertionFailure() << created.message();
  WriteText(path, SummaryJson(RunInputs(), scene, *tracker, {}));
  return ::testing::AssertionSuccess();
}

// femreg eval takes the scene order of a run's objects from its summary.json: the names as
// SummaryJson writes them, and errors that name the file.
TEST(Results, ReadSummaryObjectNamesReadsWhatSummaryJsonWrites) {
  const testing_util::TempDir dir("femreg_results");
  const std::string path = dir.path() + "/summary.json";
  ASSERT_TRUE(WriteSummaryOf("objects:\n"
                             "  - {name: top, generate: {shape: box, size: [0.04, 0.04, 0.02], cells: [2, 2, 1]}}\n"
                             "  - {name: base, generate: {shape: box, size: [0.04, 0.04, 0.02], cells: [2, 2, 1]},"
                             " pose: {translation: [0, 0, -0.05]}}\n",
                             path));
  std::vector<std::string> names;
  ASSERT_TRUE(ReadSummaryObjectNames(path, &names).ok());
  EXPECT_EQ(names, (std::vector<std::string>{"top", "base"}));

  const std::string missing = dir.path() + "/none.json";
  Status status = ReadSummaryObjectNames(missing, &names);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message().rfind(missing + ": cannot open", 0), 0u) << status.message();
  WriteText(path, "{\"objects\": [{\"name\": \"top\"}");
  status = ReadSummaryObjectNames(path, &names);
  EXPECT_EQ(status.message(), path + ": not JSON (not a summary.json written by femreg register)");
  WriteText(path, "[{\"name\": \"top\"}]");
  status = ReadSummaryObjectNames(path, &names);
  EXPECT_EQ(status.message(), path + ": JSON, but not an object (not a summary.json written by femreg register)");
  WriteText(path, "{\"frames_done\": 3}");
  status = ReadSummaryObjectNames(path, &names);
  EXPECT_EQ(status.message(), path + ": no \"objects\" list (not a summary.json written by femreg register)");
  WriteText(path, "{\"objects\": [{\"name\": \"top\"}, {\"vertices\": 8}]}");
  status = ReadSummaryObjectNames(path, &names);
  EXPECT_EQ(status.message(), path + ": objects[1] has no \"name\"");
  EXPECT_TRUE(names.empty());
}

// femreg eval says when a run's force columns are not an estimate: summary.json's
// forces.estimate, as SummaryJson writes it; -1 when a summary does not say.
TEST(Results, ReadSummaryForcesEstimatedReadsWhatSummaryJsonWrites) {
  for (const bool estimate : {false, true}) {
    const testing_util::TempDir dir("femreg_results");
    const std::string path = dir.path() + "/summary.json";
    ASSERT_TRUE(WriteSummaryOf("objects:\n"
                               "  - {name: top, generate: {shape: box, size: [0.04, 0.04, 0.02], cells: [2, 2, 1]}}\n"
                               "registration: {forces: {estimate: " + std::string(estimate ? "true" : "false") + "}}\n",
                               path));
    int estimated = -2;
    ASSERT_TRUE(ReadSummaryForcesEstimated(path, &estimated).ok());
    EXPECT_EQ(estimated, estimate ? 1 : 0);
    WriteText(path, "{\"objects\": []}");
    ASSERT_TRUE(ReadSummaryForcesEstimated(path, &estimated).ok());
    EXPECT_EQ(estimated, -1);
    WriteText(path, "{\"forces\": ");
    const Status status = ReadSummaryForcesEstimated(path, &estimated);
    EXPECT_EQ(status.message(), path + ": not JSON (not a summary.json written by femreg register)");
  }
}

}  // namespace
}  // namespace femreg
