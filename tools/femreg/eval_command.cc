// femreg eval: a `femreg register` result against a `femreg synth` ground truth.
//
// Per frame: the vertex error (mean, RMS, 95th percentile, max; mm) for the vertices the
// camera saw in that frame and for the hidden ones, and the distance between the tracked
// surface and the ground truth mesh's surface (symmetric mean and Hausdorff, sampled at the
// vertices and triangle centroids of both). A CSV and a printed table, with a totals row.
// When the dataset has forces.csv and the result's stats.csv the force columns, also the
// error of the estimated resultant external force and of its torque, with their medians
// (eval_forces.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <memory>
#include <regex>
#include <sstream>

#include "cli_util.h"
#include "commands.h"
#include "eval_forces.h"
#include "femreg/eval.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/results.h"

namespace fs = std::filesystem;

namespace femreg {
namespace cli {
namespace {

struct EvalRow {
  std::string label;
  bool have_mesh = true;  // false: the vertex truth was another mesh's (an embedded surface's run)
  ErrorStats seen, hidden, all;
  bool have_surface = false;
  SurfaceDistance surface;
  bool have_embedded = false;  // the embedded surfaces' vertices against ground_truth/surface
  ErrorStats embedded_all, embedded_seen;
};

// The points of an embedded surface's frame as `femreg register` writes it (WriteTrianglesVtp:
// PolyData, raw appended data with UInt64 headers, Float64 points); other VTPs are refused.
Status ReadRegisterSurfaceVtp(const std::string& path, Vertices* points) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto fail = [&](const std::string& why) {
    return Status::Error(path + ": " + why + " (not an embedded surface written by femreg register)");
  };
  const auto attribute = [&](size_t from, const std::string& name, std::string* value) {
    const size_t at = text.find(name + "=\"", from);
    if (at == std::string::npos) return false;
    const size_t begin = at + name.size() + 2, end = text.find('"', begin);
    if (end == std::string::npos) return false;
    *value = text.substr(begin, end - begin);
    return true;
  };
  std::string value;
  if (text.find("<VTKFile type=\"PolyData\"") == std::string::npos) return fail("no PolyData");
  if (!attribute(0, "header_type", &value) || value != "UInt64") return fail("its header_type is not UInt64");
  if (!attribute(0, "NumberOfPoints", &value)) return fail("no NumberOfPoints");
  long long n = -1;
  try {
    n = std::stoll(value);
  } catch (...) {
  }
  if (n < 0 || n > (1LL << 31)) return fail("NumberOfPoints \"" + value + "\"");
  const size_t tag = text.find("Name=\"Points\"");
  const size_t tag_start = tag == std::string::npos ? tag : text.rfind("<DataArray", tag);
  if (tag_start == std::string::npos) return fail("no Points array");
  if (!attribute(tag_start, "type", &value) || value != "Float64") return fail("its points are not Float64");
  if (!attribute(tag_start, "offset", &value)) return fail("its points are not appended");
  const long long offset = std::stoll(value);
  const size_t appended = text.find("<AppendedData encoding=\"raw\">");
  const size_t mark = appended == std::string::npos ? appended : text.find('_', appended);
  if (mark == std::string::npos) return fail("no raw appended data");
  const size_t begin = mark + 1 + static_cast<size_t>(offset);
  const size_t bytes = static_cast<size_t>(n) * 3 * sizeof(double);
  if (offset < 0 || begin + sizeof(uint64_t) + bytes > text.size()) return fail("its points run past the end");
  uint64_t count = 0;
  std::memcpy(&count, text.data() + begin, sizeof(count));
  if (count != bytes) return fail("its points' block has " + std::to_string(count) + " bytes, not " + std::to_string(bytes));
  points->resize(n, 3);
  std::vector<double> xyz(static_cast<size_t>(3 * n));
  std::memcpy(xyz.data(), text.data() + begin + sizeof(uint64_t), bytes);
  for (long long i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) (*points)(i, k) = xyz[static_cast<size_t>(3 * i + k)];
  }
  return Status::Ok();
}

// Object names of a register result, in scene order (from summary.json when present).
Status ResultObjects(const std::string& result, const std::vector<std::string>& files,
                     std::vector<std::string>* names,
                     std::map<std::string, std::vector<std::string>>* frames) {
  const std::regex frame_name(R"((.+)_(\d+)\.vtu)");
  for (const std::string& file : files) {
    std::smatch m;
    const std::string base = fs::path(file).filename().string();
    if (!std::regex_match(base, m, frame_name)) continue;
    (*frames)[m[1].str()].push_back(file);
  }
  if (frames->empty()) return Status::Error(result + "/frames: no <object>_NNNN.vtu files");
  const std::string summary = (fs::path(result) / "summary.json").string();
  std::error_code ec;
  if (fs::exists(summary, ec)) {
    // The scene order of the objects; a summary that cannot be read leaves the files' order.
    std::vector<std::string> listed;
    const Status read = ReadSummaryObjectNames(summary, &listed);
    if (!read.ok()) {
      std::cerr << "femreg eval: warning: " << read.message() << "; the objects in the frame files' order\n";
    }
    for (const std::string& name : listed) {
      if (frames->count(name) && std::find(names->begin(), names->end(), name) == names->end()) {
        names->push_back(name);
      }
    }
  }
  for (const auto& kv : *frames) {
    if (std::find(names->begin(), names->end(), kv.first) == names->end()) names->push_back(kv.first);
  }
  return Status::Ok();
}

std::string StatsCells(const ErrorStats& s) {
  char buf[160];
  std::snprintf(buf, sizeof(buf), "%d,%.4f,%.4f,%.4f,%.4f", s.count, s.mean * 1e3, s.rms * 1e3,
                s.p95 * 1e3, s.max * 1e3);
  return buf;
}

int RunEval(const std::string& result, const std::string& dataset, std::string csv) {
  auto fail = [](const std::string& message) {
    std::cerr << "femreg eval: " << message << "\n";
    return 1;
  };
  // The dataset's folder; its ground_truth/ folder itself (what `register --ground-truth`
  // takes) stands for it.
  std::string truth_dir = dataset;
  fs::path given = fs::path(dataset).lexically_normal();
  if (!given.has_filename()) given = given.parent_path();  // a trailing slash
  if (!fs::is_directory(given / "ground_truth") && given.filename() == "ground_truth") {
    truth_dir = given.parent_path().empty() ? std::string(".") : given.parent_path().string();
  }
  std::vector<std::string> result_files, truth_csvs, truth_vtus;
  Status status = ListFiles((fs::path(result) / "frames").string(), {".vtu"}, &result_files);
  if (!status.ok()) return fail(status.message() + " (RESULT must be a `femreg register` output folder)");
  status = ListFiles((fs::path(truth_dir) / "ground_truth").string(), {".csv"}, &truth_csvs);
  if (!status.ok()) return fail(status.message() + " (DATASET must be a dataset or `femreg synth` output folder with ground_truth/)");
  // Fracture sequences keep the events and per-piece positions beside the frames.
  truth_csvs.erase(std::remove_if(truth_csvs.begin(), truth_csvs.end(),
                                  [](const std::string& f) {
                                    const std::string n = fs::path(f).filename().string();
                                    return n == "events.csv" ||
                                           (n.size() > 11 && n.compare(n.size() - 11, 11, "_pieces.csv") == 0);
                                  }),
                   truth_csvs.end());
  const bool have_truth_surface = fs::is_directory(fs::path(truth_dir) / "truth");
  if (have_truth_surface) {
    status = ListFiles((fs::path(truth_dir) / "truth").string(), {".vtu"}, &truth_vtus);
    if (!status.ok()) return fail(status.message());
  }
  std::vector<std::string> objects;
  std::map<std::string, std::vector<std::string>> frames;
  status = ResultObjects(result, result_files, &objects, &frames);
  if (!status.ok()) return fail(status.message());
  size_t num_frames = frames[objects[0]].size();
  for (const std::string& o : objects) num_frames = std::min(num_frames, frames[o].size());
  // Embedded surfaces (frames/<object>_surface_NNNN.vtp), in the objects' order, and their
  // truth (ground_truth/surface/, a row per vertex of every embedded surface in scene order).
  std::vector<std::string> surface_files;
  ListFiles((fs::path(result) / "frames").string(), {".vtp"}, &surface_files);  // none: no surfaces
  std::map<std::string, std::vector<std::string>> surface_frames;
  const std::regex surface_name(R"((.+)_surface_(\d+)\.vtp)");
  for (const std::string& file : surface_files) {
    std::smatch m;
    const std::string base = fs::path(file).filename().string();
    if (std::regex_match(base, m, surface_name) && frames.count(m[1].str())) surface_frames[m[1].str()].push_back(file);
  }
  std::vector<std::string> surface_objects;
  for (const std::string& o : objects) {
    if (surface_frames.count(o)) surface_objects.push_back(o);
  }
  const fs::path surface_truth_dir = fs::path(truth_dir) / "ground_truth" / "surface";
  const bool have_embedded = !surface_objects.empty() && fs::is_directory(surface_truth_dir);
  std::vector<double> pooled_embedded, pooled_embedded_seen;
  if (truth_csvs.size() < num_frames) {
    return fail(truth_dir + "/ground_truth has " + std::to_string(truth_csvs.size()) +
                " frames for " + std::to_string(num_frames) + " result frames");
  }
  if (have_truth_surface && truth_vtus.size() < num_frames) {
    return fail(truth_dir + "/truth has " + std::to_string(truth_vtus.size()) + " frames for " +
                std::to_string(num_frames) + " result frames");
  }

  std::vector<EvalRow> rows;
  std::vector<double> pooled_seen, pooled_hidden, pooled_all;
  double surface_sum = 0.0, hausdorff = 0.0;
  size_t surface_count = 0;
  // Fracture results (an original_vertex field): vertices are matched through their
  // original vertex, piece by piece, as `femreg register --ground-truth` does.
  std::vector<FractureFrame> fracture;
  std::vector<int> initial_vertices(objects.size(), -1);  // per object: rows in the truth
  int added_before = 0;  // vertices the splits had added up to the previous frame
  for (size_t f = 0; f < num_frames; ++f) {
    Vertices positions(0, 3);
    Vertices surface_points(0, 3);
    Triangles surface(0, 3);
    std::vector<VtuGeometry> geometries;
    for (const std::string& o : objects) {
      geometries.emplace_back();
      VtuGeometry& g = geometries.back();
      status = ReadVtuGeometry(frames[o][f], &g);
      if (!status.ok()) return fail(status.message());
      const Eigen::Index offset = positions.rows();
      positions.conservativeResize(offset + g.points.rows(), 3);
      positions.bottomRows(g.points.rows()) = g.points;
      const Eigen::Index tri_offset = surface.rows();
      surface.conservativeResize(tri_offset + g.surface.rows(), 3);
      surface.bottomRows(g.surface.rows()) = g.surface.array() + static_cast<int>(offset);
    }
    GroundTruthFrame truth;
    status = ReadGroundTruthFrame(truth_csvs[f], &truth);
    if (!status.ok()) return fail(status.message());
    if (!geometries.empty() && !geometries[0].original.empty()) {
      // Each object against its rows of the truth, piece by piece; `truth` then becomes the
      // truth each tracked vertex was compared with.
      std::vector<PieceTruthRow> piece_truth;
      const fs::path side = fs::path(truth_csvs[f]).parent_path() /
                            (fs::path(truth_csvs[f]).stem().string() + "_pieces.csv");
      if (fs::exists(side)) {
        status = ReadPieceTruth(side.string(), &piece_truth);
        if (!status.ok()) return fail(status.message());
      }
      FractureFrame frame;
      std::vector<TetMesh> meshes(geometries.size());
      std::vector<TrackedObject> tracked(geometries.size());
      for (size_t i = 0; i < geometries.size(); ++i) {
        const VtuGeometry& g = geometries[i];
        if (g.original.size() != static_cast<size_t>(g.points.rows())) {
          return fail(frames[objects[i]][f] + ": no original_vertex field, unlike " + frames[objects[0]][f]);
        }
        if (initial_vertices[i] < 0) {
          initial_vertices[i] = *std::max_element(g.original.begin(), g.original.end()) + 1;
        }
        frame.splits += static_cast<int>(g.points.rows()) - initial_vertices[i];  // net new vertices
        // The rest positions place a split vertex on a piece its truth does not reach
        // (ComputePieceErrors).
        meshes[i].rest = g.rest.rows() == g.points.rows() ? g.rest : g.points;
        meshes[i].x = g.points;
        meshes[i].tets = g.tets;
        tracked[i] = {&meshes[i], &g.points, &g.original, initial_vertices[i]};
      }
      PieceErrors pe;
      status = ComputePieceErrors(tracked, truth, piece_truth, &pe);
      if (!status.ok()) return fail(truth_csvs[f] + ": " + status.message());
      frame.pieces = static_cast<int>(pe.pieces.size());
      frame.piece_errors = pe.pieces;
      // Splits this frame: the growth of the vertex count since the last frame.
      const int added = frame.splits;
      frame.splits = std::max(0, added - added_before);
      added_before = std::max(added_before, added);
      fracture.push_back(frame);
      truth = std::move(pe.matched);  // the truth each tracked vertex was compared with
    }
    EvalRow row;
    row.label = std::to_string(f);
    const fs::path surface_truth_path = surface_truth_dir / fs::path(truth_csvs[f]).filename();
    if (have_embedded && fs::exists(surface_truth_path)) {
      Vertices embedded(0, 3);
      for (const std::string& o : surface_objects) {
        if (surface_frames[o].size() <= f) return fail(result + "/frames: no frame " + std::to_string(f) + " of " + o + "'s surface");
        Vertices v;
        status = ReadRegisterSurfaceVtp(surface_frames[o][f], &v);
        if (!status.ok()) return fail(status.message());
        embedded.conservativeResize(embedded.rows() + v.rows(), 3);
        embedded.bottomRows(v.rows()) = v;
      }
      GroundTruthFrame surface_truth;
      status = ReadGroundTruthFrame(surface_truth_path.string(), &surface_truth);
      if (!status.ok()) return fail(status.message());
      if (surface_truth.positions.rows() != embedded.rows()) {
        return fail(surface_truth_path.string() + ": " + std::to_string(surface_truth.positions.rows()) +
                    " rows, the embedded surfaces " + std::to_string(embedded.rows()) + " vertices");
      }
      std::vector<double> all, seen;
      for (Eigen::Index i = 0; i < embedded.rows(); ++i) {
        const double e = (embedded.row(i) - surface_truth.positions.row(i)).norm();
        all.push_back(e);
        if (surface_truth.visible[static_cast<size_t>(i)]) seen.push_back(e);
      }
      pooled_embedded.insert(pooled_embedded.end(), all.begin(), all.end());
      pooled_embedded_seen.insert(pooled_embedded_seen.end(), seen.begin(), seen.end());
      row.embedded_all = ComputeErrorStats(all);
      row.embedded_seen = ComputeErrorStats(seen);
      row.have_embedded = true;
    }
    if (truth.positions.rows() != positions.rows()) {
      // With the embedded surfaces compared, the vertex truth may be another mesh's (the
      // sequence's ground truth mesh), as `femreg register --ground-truth` takes it.
      if (!row.have_embedded) {
        return fail(truth_csvs[f] + ": " + std::to_string(truth.positions.rows()) + " vertices, the result " +
                    std::to_string(positions.rows()) + " (" + frames[objects[0]][f] + ")");
      }
      row.have_mesh = false;
      rows.push_back(row);
      continue;
    }
    std::vector<double> seen, hidden, all;
    for (Eigen::Index i = 0; i < positions.rows(); ++i) {
      const double e = (positions.row(i) - truth.positions.row(i)).norm();
      all.push_back(e);
      (truth.visible[static_cast<size_t>(i)] ? seen : hidden).push_back(e);
    }
    pooled_seen.insert(pooled_seen.end(), seen.begin(), seen.end());
    pooled_hidden.insert(pooled_hidden.end(), hidden.begin(), hidden.end());
    pooled_all.insert(pooled_all.end(), all.begin(), all.end());
    row.seen = ComputeErrorStats(seen);
    row.hidden = ComputeErrorStats(hidden);
    row.all = ComputeErrorStats(all);
    if (have_truth_surface) {
      VtuGeometry t;
      status = ReadVtuGeometry(truth_vtus[f], &t);
      if (!status.ok()) return fail(status.message());
      row.surface = ComputeSurfaceDistance(positions, surface, t.points, t.surface);
      row.have_surface = true;
      surface_sum += row.surface.mean;
      ++surface_count;
      hausdorff = std::max(hausdorff, row.surface.hausdorff);
    }
    rows.push_back(row);
  }
  EvalRow total;
  total.label = "total";
  total.seen = ComputeErrorStats(pooled_seen);
  total.hidden = ComputeErrorStats(pooled_hidden);
  total.all = ComputeErrorStats(pooled_all);
  total.have_surface = surface_count > 0;
  total.surface.mean = surface_count ? surface_sum / static_cast<double>(surface_count) : 0.0;
  total.surface.hausdorff = hausdorff;
  total.have_mesh = !pooled_all.empty();
  total.have_embedded = !pooled_embedded.empty();
  total.embedded_all = ComputeErrorStats(pooled_embedded);
  total.embedded_seen = ComputeErrorStats(pooled_embedded_seen);
  bool any_embedded = false;
  for (const EvalRow& r : rows) any_embedded = any_embedded || r.have_embedded;

  // The estimated external force (stats.csv) against the true one (forces.csv), when both
  // are there.
  ForceReport forces;
  status = CompareForceFiles(result, truth_dir, num_frames, &forces);
  if (!status.ok()) return fail(status.message());

  std::ostringstream out;
  out << "frame,seen_count,seen_mean_mm,seen_rms_mm,seen_p95_mm,seen_max_mm,hidden_count,"
         "hidden_mean_mm,hidden_rms_mm,hidden_p95_mm,hidden_max_mm,all_count,all_mean_mm,"
         "all_rms_mm,all_p95_mm,all_max_mm,surface_mean_mm,surface_hausdorff_mm";
  if (any_embedded) out << ",err_surface_mean_mm,err_surface_p95_mm,err_surface_max_mm,err_surface_seen_mean_mm";
  if (forces.compared) out << ",force_true_N,force_error_N,force_error_pct,torque_error_Nm";
  if (forces.contact) out << ",contact_force_error_N";
  out << "\n";
  std::vector<const EvalRow*> all_rows;
  for (const EvalRow& r : rows) all_rows.push_back(&r);
  all_rows.push_back(&total);
  for (size_t i = 0; i < all_rows.size(); ++i) {
    const EvalRow* r = all_rows[i];
    out << r->label << ",";
    if (r->have_mesh) {
      out << StatsCells(r->seen) << "," << StatsCells(r->hidden) << "," << StatsCells(r->all) << ",";
    } else {
      out << std::string(15, ',');
    }
    if (r->have_surface) {
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%.4f,%.4f", r->surface.mean * 1e3, r->surface.hausdorff * 1e3);
      out << buf;
    } else {
      out << ",";
    }
    if (any_embedded) {
      char buf[128] = ",,,,";
      if (r->have_embedded) {
        std::snprintf(buf, sizeof(buf), ",%.4f,%.4f,%.4f,%.4f", r->embedded_all.mean * 1e3, r->embedded_all.p95 * 1e3,
                      r->embedded_all.max * 1e3, r->embedded_seen.mean * 1e3);
      }
      out << buf;
    }
    if (forces.compared) {
      out << "," << (r == &total ? forces.MedianCells() : forces.Cells(static_cast<int>(i)));
    }
    out << "\n";
  }
  if (csv.empty()) csv = (fs::path(result) / "eval.csv").string();
  status = WriteFileAtomically(csv, out.str());
  if (!status.ok()) return fail(status.message());

  std::printf("femreg eval: %zu frames of %s against %s (errors in mm)\n", num_frames,
              result.c_str(), truth_dir.c_str());
  std::printf("%6s | %5s %7s %7s %7s %7s | %5s %7s %7s %7s %7s | %7s %7s\n", "frame", "seen",
              "mean", "rms", "p95", "max", "hidden", "mean", "rms", "p95", "max", "surf", "hausd");
  for (const EvalRow* r : all_rows) {
    if (r == &total) std::printf("%s\n", std::string(100, '-').c_str());
    if (!r->have_mesh) {
      std::printf("%6s | %s\n", r->label.c_str(), "the vertex truth is another mesh's: see the embedded surfaces");
      continue;
    }
    std::printf("%6s | %5d %7.2f %7.2f %7.2f %7.2f | %5d %7.2f %7.2f %7.2f %7.2f | ", r->label.c_str(),
                r->seen.count, r->seen.mean * 1e3, r->seen.rms * 1e3, r->seen.p95 * 1e3,
                r->seen.max * 1e3, r->hidden.count, r->hidden.mean * 1e3, r->hidden.rms * 1e3,
                r->hidden.p95 * 1e3, r->hidden.max * 1e3);
    if (r->have_surface) {
      std::printf("%7.2f %7.2f\n", r->surface.mean * 1e3, r->surface.hausdorff * 1e3);
    } else {
      std::printf("%7s %7s\n", "-", "-");
    }
  }
  if (any_embedded) {
    std::printf("Embedded surfaces (%s) against %s, per vertex (mm):\n", result.c_str(), surface_truth_dir.string().c_str());
    std::printf("%6s | %8s %7s %7s %7s\n", "frame", "vertices", "mean", "p95", "max");
    for (const EvalRow* r : all_rows) {
      if (!r->have_embedded) continue;
      std::printf("%6s | %8d %7.3f %7.3f %7.3f   seen %7.3f\n", r->label.c_str(), r->embedded_all.count,
                  r->embedded_all.mean * 1e3, r->embedded_all.p95 * 1e3, r->embedded_all.max * 1e3,
                  r->embedded_seen.mean * 1e3);
    }
  }
  if (!fracture.empty()) PrintFractureReport(fracture, (fs::path(truth_dir) / "ground_truth").string(), true);
  std::printf("Totals pool every vertex of every frame; surf is the mean over frames of the "
              "symmetric mean surface distance, hausd the largest Hausdorff distance.\n");
  if (forces.compared) forces.Print();
  if (!forces.note.empty()) std::printf("%s\n", forces.note.c_str());
  std::printf("CSV: %s\n", csv.c_str());
  return 0;
}

}  // namespace

void AddEvalCommand(CLI::App* app) {
  auto result = std::make_shared<std::string>();
  auto truth = std::make_shared<std::string>();
  auto csv = std::make_shared<std::string>();
  CLI::App* cmd = app->add_subcommand(
      "eval",
      "Evaluate a `femreg register` result against a `femreg synth` ground truth: per frame the "
      "vertex error of seen and hidden vertices (mean, RMS, p95, max; mm) and the tracked-to-true "
      "surface distance (symmetric mean, Hausdorff). With the dataset's forces.csv and force "
      "columns in the result's stats.csv (force_x_N, ..., torque_z_Nm), also the error of the "
      "estimated resultant external force per frame (N, and % of the true force) and of its "
      "torque (N m), and their medians over the frames; where both files also have the obstacles' "
      "push (contact_force_x_N, ...: a table's, a tool's given as an obstacle), its error too. "
      "With embedded surfaces "
      "(frames/<object>_surface_NNNN.vtp) and the dataset's ground_truth/surface/, also their "
      "vertices' errors (err_surface_mean_mm, _p95_mm, _max_mm, _seen_mean_mm, as femreg register's "
      "stats.csv); the vertex truth may then be another mesh's. Prints a table and writes a CSV.");
  cmd->add_option("result", *result, "A `femreg register` output folder (frames/<object>_NNNN.vtu)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("dataset", *truth,
                  "A dataset or `femreg synth` output folder (ground_truth/*.csv, truth/*.vtu; forces.csv), "
                  "e.g. datasets/demo; its ground_truth/ folder is taken for it too")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--csv", *csv,
                  "CSV file to write (default RESULT/eval.csv); with forces, the columns "
                  "force_true_N, force_error_N, force_error_pct and torque_error_Nm (and "
                  "contact_force_error_N where forces.csv has the obstacles' push, "
                  "contact_force_*_N), medians in the totals row");
  cmd->callback([=] { SetExitCode(RunEval(*result, *truth, *csv)); });
}

}  // namespace cli
}  // namespace femreg
