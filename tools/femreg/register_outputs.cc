// femreg register's output files (register_outputs.h).
#include "register_outputs.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.h"
#include "commands.h"
#include "provenance.h"
#include "femreg/collision.h"
#include "femreg/eval.h"
#include "femreg/ground_truth.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"
#include "femreg/version.h"
#include "mesh_warnings.h"

namespace fs = std::filesystem;

namespace femreg {
namespace cli {
namespace register_outputs {

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

extern const char kStatsHeader[];
const char kStatsHeader[] =
    "frame,file,termination,outer_iterations,inner_iterations,cloud_points,nonfinite_dropped,"
    "points_used,model_to_cloud,cloud_to_model,rejected,rms_residual_mm,e_data,e_elastic,"
    "e_temporal,e_anchor,e_total,t_preprocess_ms,t_prealign_ms,t_rotations_ms,"
    "t_correspondences_ms,t_build_ms,t_solve_ms,t_total_ms,err_mean_mm,err_rms_mm,"
    "err_p95_mm,err_max_mm,err_seen_mean_mm,err_seen_max_mm,err_hidden_mean_mm,"
    "err_hidden_max_mm,fractures,pieces,err_piece_mean_mm,err_piece_seen_mm,err_piece_hidden_mm,"
    "break_frame,e_collision,contacts,"
    "object_contacts,obstacle_contacts,max_penetration_mm,min_gap_mm,t_collision_ms,stopped_by,"
    "factorizations,linear_solves,pcg_iterations,t_assembly_ms,t_factorization_ms,"
    "t_linear_solve_ms,t_evaluation_ms,t_fracture_ms,e_load,e_equilibrium,force_x_N,force_y_N,"
    "force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm,occluded_points,implausible_points,contact_force_x_N,"
    "contact_force_y_N,contact_force_z_N,friction_force_x_N,friction_force_y_N,friction_force_z_N,"
    "confidence,confidence_fit,confidence_coverage,confidence_residual_mm,strain_p95,lost,free_space_vertices,"
    "err_surface_mean_mm,err_surface_p95_mm,err_surface_max_mm,err_surface_seen_mean_mm,message\n";

std::string StatsRow(size_t i, const FrameRow& row) {
  std::ostringstream os;
  char buf[1024];
  const FrameSummary& s = row.summary;
  std::snprintf(buf, sizeof(buf),
                "%zu,%s,%s,%d,%d,%d,%d,%d,%d,%d,%d,%.4f,%.6g,%.6g,%.6g,%.6g,%.6g,%.3f,%.3f,%.3f,"
                "%.3f,%.3f,%.3f,%.3f",
                i, fs::path(row.file).filename().string().c_str(), ToString(s.termination),
                s.outer_iterations, s.inner_iterations, s.cloud_points, s.nonfinite_dropped,
                s.points_used, s.model_to_cloud, s.cloud_to_model, s.rejected,
                s.rms_residual * 1e3, s.final.data, s.final.elastic, s.final.temporal,
                s.final.anchor, s.final.total(), s.time.preprocess * 1e3, s.time.prealign * 1e3,
                s.time.rotations * 1e3, s.time.correspondences * 1e3, s.time.build * 1e3,
                s.time.solve * 1e3, s.time.total * 1e3);
  os << buf;
  if (row.have_errors) {
    const VertexErrors& e = row.errors;
    std::snprintf(buf, sizeof(buf), ",%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f", e.all.mean * 1e3,
                  e.all.rms * 1e3, e.all.p95 * 1e3, e.all.max * 1e3, e.seen.mean * 1e3,
                  e.seen.max * 1e3, e.hidden.mean * 1e3, e.hidden.max * 1e3);
    os << buf;
  } else {
    os << ",,,,,,,,";
  }
  os << "," << s.fractures.size() << "," << row.pieces << ",";
  // Per piece, ';' between pieces; a piece with no seen (hidden) vertex has an empty entry.
  auto per_piece = [&](const std::vector<ErrorStats>& stats) {
    for (size_t p = 0; p < stats.size(); ++p) {
      if (p) os << ";";
      if (stats[p].count == 0) continue;
      std::snprintf(buf, sizeof(buf), "%.4f", stats[p].mean * 1e3);
      os << buf;
    }
  };
  per_piece(row.piece_errors);
  os << ",";
  per_piece(row.piece_seen);
  os << ",";
  per_piece(row.piece_hidden);
  os << "," << row.break_frame;
  std::snprintf(buf, sizeof(buf), ",%.6g,%d,%d,%d,%.4f,%.4f,%.3f", s.final.collision, s.contacts,
                s.object_contacts, s.obstacle_contacts, s.max_penetration * 1e3, s.min_gap * 1e3,
                s.time.collision * 1e3);
  os << buf;
  std::snprintf(buf, sizeof(buf), ",%s,%d,%d,%d,%.3f,%.3f,%.3f,%.3f,%.3f", s.stopped_by.c_str(),
                s.factorizations, s.linear_solves, s.pcg_iterations, s.time.assembly * 1e3,
                s.time.factorization * 1e3, s.time.linear_solve * 1e3, s.time.evaluation * 1e3,
                s.time.fracture * 1e3);
  os << buf;
  std::snprintf(buf, sizeof(buf), ",%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g", s.final.load,
                s.final.equilibrium, s.force.x(), s.force.y(), s.force.z(), s.torque.x(), s.torque.y(),
                s.torque.z());
  os << buf << "," << s.occluded_points << "," << s.implausible_points;
  // The obstacles' force on the objects, and its friction part (pairs' forces cancel).
  Eigen::Vector3d obstacle = Eigen::Vector3d::Zero(), friction = Eigen::Vector3d::Zero();
  for (const ContactForce& f : s.contact_forces) {
    if (!f.obstacle()) continue;
    obstacle += f.force;
    friction += f.friction;
  }
  std::snprintf(buf, sizeof(buf), ",%.6g,%.6g,%.6g,%.6g,%.6g,%.6g", obstacle.x(), obstacle.y(),
                obstacle.z(), friction.x(), friction.y(), friction.z());
  os << buf;
  const FrameConfidence& c = s.confidence;
  std::snprintf(buf, sizeof(buf), ",%.4f,%.4f,%.4f,%.4f,%.4g,%d", c.confidence, c.fit, c.coverage,
                c.residual * 1e3, c.strain, s.lost ? 1 : 0);
  os << buf << "," << s.free_space_vertices;
  if (row.have_surface_errors) {  // the embedded surfaces' vertices against their ground truth
    const VertexErrors& e = row.surface_errors;
    std::snprintf(buf, sizeof(buf), ",%.4f,%.4f,%.4f,%.4f", e.all.mean * 1e3, e.all.p95 * 1e3, e.all.max * 1e3,
                  e.seen.mean * 1e3);
    os << buf;
  } else {
    os << ",,,,";
  }
  std::string msg = row.read_error.empty() ? s.message : row.read_error;
  std::replace(msg.begin(), msg.end(), '"', '\'');
  os << ",\"" << msg << "\"\n";
  return os.str();
}

Totals ComputeTotals(const std::vector<FrameRow>& rows) {
  Totals t;
  t.frames = static_cast<int>(rows.size());
  std::vector<double> ms;
  double sum_all = 0, sum_seen = 0, sum_hidden = 0;
  int n_err = 0, n_seen = 0, n_hidden = 0;
  for (const FrameRow& r : rows) {
    if (r.summary.IsSolutionUsable()) ++t.usable;
    ms.push_back(r.summary.time.total * 1e3);
    if (r.have_errors) {
      t.have_errors = true;
      sum_all += r.errors.all.mean * r.errors.all.count;
      n_err += r.errors.all.count;
      t.err_max = std::max(t.err_max, r.errors.all.max);
      sum_seen += r.errors.seen.mean * r.errors.seen.count;
      n_seen += r.errors.seen.count;
      t.seen_max = std::max(t.seen_max, r.errors.seen.max);
      sum_hidden += r.errors.hidden.mean * r.errors.hidden.count;
      n_hidden += r.errors.hidden.count;
      t.hidden_max = std::max(t.hidden_max, r.errors.hidden.max);
    }
  }
  t.median_ms = Median(ms);
  double total_ms = 0;
  for (double m : ms) total_ms += m;
  t.mean_ms = ms.empty() ? 0 : total_ms / ms.size();
  t.fps = total_ms > 0 ? 1e3 * ms.size() / total_ms : 0;
  t.err_mean = n_err ? sum_all / n_err : 0;
  t.seen_mean = n_seen ? sum_seen / n_seen : 0;
  t.hidden_mean = n_hidden ? sum_hidden / n_hidden : 0;
  return t;
}

// Per frame, the contact forces per object pair and obstacle (N): on `object` by `by`.
nlohmann::ordered_json ContactForcesJson(const Scene& scene, const Tracker& tracker,
                                         const std::vector<FrameRow>& rows) {
  using json = nlohmann::ordered_json;
  auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  auto object_name = [&](int i) {
    return i >= 0 && i < static_cast<int>(scene.objects.size()) ? scene.objects[i].name : std::to_string(i);
  };
  const CollisionWorld* world = tracker.collision();
  json frames = json::array();
  for (const FrameRow& r : rows) {
    json list = json::array();
    for (const ContactForce& f : r.summary.contact_forces) {
      const int o = -1 - f.other;
      const std::string by = !f.obstacle() ? object_name(f.other)
                             : world != nullptr && o < world->num_obstacles() ? world->obstacle_name(o)
                                                                              : "obstacle " + std::to_string(o);
      list.push_back({{"object", object_name(f.object)},
                      {"by", by},
                      {"obstacle", f.obstacle()},
                      {"contacts", f.contacts},
                      {"force_N", {number(f.force.x()), number(f.force.y()), number(f.force.z())}},
                      {"friction_N", {number(f.friction.x()), number(f.friction.y()), number(f.friction.z())}}});
    }
    frames.push_back(list);
  }
  return frames;
}

std::string SummaryJson(const RegisterArgs& args, const Scene& scene, const Tracker& tracker,
                        const std::vector<FrameRow>& rows, const std::vector<std::string>& files,
                        const std::vector<std::string>& truth_files, bool interrupted) {
  using json = nlohmann::ordered_json;
  auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  const Totals t = ComputeTotals(rows);
  int unreadable = 0;
  double voxel = 0.0, coverage = 1.0;
  std::string visibility = "none";
  for (const FrameRow& r : rows) {
    if (!r.read_error.empty()) {
      ++unreadable;
      continue;
    }
    voxel = std::max(voxel, r.summary.voxel_size);
    if (r.summary.outer_iterations > 0) {
      coverage = std::min(coverage, r.summary.coverage);
      visibility = r.summary.visibility;
    }
  }
  const RegistrationOptions& o = tracker.options();
  json j;
  j["femreg_version"] = Version();
  j["scene"] = args.scene;
  j["frames_source"] = args.frames;
  j["frames_total"] = files.size();
  j["frames_done"] = t.frames;
  j["interrupted"] = interrupted;
  if (interrupted) j["interrupted_by"] = InterruptName();
  j["frames_usable"] = t.usable;
  j["frames_unreadable"] = unreadable;
  // How the clouds were used: the automatic subsampling's voxel (0: none), how visibility
  // was decided (the last solved frame) and the smallest coverage of the surface.
  j["clouds"] = {{"auto_voxel_m", number(voxel)},
                 {"visibility", visibility},
                 {"reciprocity", number(o.data.reciprocity)},
                 {"min_coverage", number(coverage)}};
  j["regularizer"] = ToString(o.regularizer);
  j["backend"] = ToString(o.solver.backend);
  // What solved the frames (a contact scene runs on Ceres whatever the option says).
  json used = json::array();
  for (const FrameRow& r : rows) {
    const std::string b = ToString(r.summary.backend);
    if (std::find(used.begin(), used.end(), b) == used.end()) used.push_back(b);
  }
  j["backends_used"] = used;
  json objects = json::array();
  Scene chosen = scene;  // the element and nu the tracker used (Tracker::Create)
  ChooseRegistrationElements(&chosen);
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const TetMesh& m = tracker.mesh(static_cast<int>(i));
    objects.push_back({{"name", scene.objects[i].name},
                       {"vertices", m.num_vertices()},
                       {"tetrahedra", m.num_tets()},
                       {"youngs_modulus", number(scene.objects[i].material.youngs_modulus)},
                       {"poisson_ratio", number(scene.objects[i].material.poisson_ratio)},
                       {"element", ToString(chosen.objects[i].material_model)},
                       {"elastic_poisson_ratio", number(chosen.objects[i].material.poisson_ratio)}});
  }
  j["objects"] = objects;
  j["solver"] = {{"backend", ToString(o.solver.backend)},
                 {"max_outer_iterations", o.solver.max_outer_iterations},
                 {"max_inner_iterations", o.solver.max_inner_iterations},
                 {"linear_solver", ToString(o.solver.linear_solver)},
                 {"trust_region", ToString(o.solver.trust_region)},
                 {"preconditioner", ToString(o.solver.preconditioner)},
                 {"threads", o.solver.num_threads}};
  // How the first frame was posed (registration.initial_pose; FrameSummary::initial_pose).
  if (!rows.empty()) {
    const FrameSummary& first = rows.front().summary;
    j["initial_pose"] = {{"option", ToString(o.initial_pose)},
                         {"chosen", first.initial_pose.empty() ? "given" : first.initial_pose},
                         {"ambiguous", first.pose_ambiguous},
                         {"first_frame_ms", number(first.time.total * 1e3)}};
  }
  if (!tracker.original_vertices(0).empty()) {
    // Fracture: the pieces at the end, the frame the body first came apart in (null: never),
    // the node splits, and after the break the mean error per piece over the frames.
    int splits = 0, break_frame = -1, pieces = 1;
    std::vector<double> sum, sum_seen, sum_hidden;
    std::vector<int> n, n_seen, n_hidden;
    for (const FrameRow& r : rows) {
      splits += static_cast<int>(r.summary.fractures.size());
      pieces = r.pieces;
      if (break_frame < 0) break_frame = r.break_frame;
      if (r.break_frame < 0) continue;
      auto add = [](const std::vector<ErrorStats>& stats, std::vector<double>* s, std::vector<int>* c) {
        if (s->size() < stats.size()) {
          s->resize(stats.size(), 0.0);
          c->resize(stats.size(), 0);
        }
        for (size_t p = 0; p < stats.size(); ++p) {
          (*s)[p] += stats[p].mean * stats[p].count;
          (*c)[p] += stats[p].count;
        }
      };
      add(r.piece_errors, &sum, &n);
      add(r.piece_seen, &sum_seen, &n_seen);
      add(r.piece_hidden, &sum_hidden, &n_hidden);
    }
    auto means = [&](const std::vector<double>& s, const std::vector<int>& c) {
      json list = json::array();
      for (size_t p = 0; p < s.size(); ++p) list.push_back(c[p] > 0 ? number(1e3 * s[p] / c[p]) : json(nullptr));
      return list;
    };
    j["fracture"] = {{"pieces", pieces},
                     {"break_frame", break_frame >= 0 ? json(break_frame) : json(nullptr)},
                     {"splits", splits},
                     // Pieces in ConnectedPieces order (by their lowest vertex).
                     {"piece_error_after_break_mm",
                      {{"mean", means(sum, n)}, {"seen", means(sum_seen, n_seen)}, {"hidden", means(sum_hidden, n_hidden)}}}};
  }
  j["ms_per_frame_median"] = number(t.median_ms);
  j["ms_per_frame_mean"] = number(t.mean_ms);
  j["frames_per_second"] = number(t.fps);
  if (t.have_errors) {
    j["vertex_error_mm"] = {{"mean", number(t.err_mean * 1e3)},
                            {"max", number(t.err_max * 1e3)},
                            {"seen_mean", number(t.seen_mean * 1e3)},
                            {"seen_max", number(t.seen_max * 1e3)},
                            {"hidden_mean", number(t.hidden_mean * 1e3)},
                            {"hidden_max", number(t.hidden_max * 1e3)}};
  }
  {
    // The external forces' resultant per frame (N): what the run estimated (or, without
    // registration.forces.estimate, the data term's pull).
    json forces = json::array();
    for (const FrameRow& r : rows) {
      const FrameSummary& s = r.summary;
      forces.push_back({{"force_N", {number(s.force.x()), number(s.force.y()), number(s.force.z())}},
                        {"torque_Nm", {number(s.torque.x()), number(s.torque.y()), number(s.torque.z())}}});
    }
    j["forces"] = {{"estimated", o.forces.estimate}, {"per_frame", forces}};
  }
  {
    // How far each frame can be trusted, and the frames where the object was lost.
    json confidence = json::array(), lost = json::array();
    for (size_t i = 0; i < rows.size(); ++i) {
      confidence.push_back(number(rows[i].summary.confidence.confidence));
      if (rows[i].summary.lost) lost.push_back(i);
    }
    j["tracking"] = {{"confidence_per_frame", confidence}, {"lost_frames", lost}};
  }
  {
    // Surface vertices held back by free space per frame (registration.free_space).
    json held = json::array();
    for (const FrameRow& r : rows) held.push_back(r.summary.free_space_vertices);
    j["free_space"] = {{"enabled", o.free_space.enabled},
                       {"tolerance_m", number(o.free_space.tolerance)},
                       {"weight_N_per_m", number(o.free_space.weight)},
                       {"vertices_per_frame", held}};
  }
  double deepest = 0.0;
  int contacts = 0;
  json gaps = json::array(), penetrations = json::array();
  for (const FrameRow& r : rows) {
    deepest = std::max(deepest, r.summary.max_penetration);
    contacts = std::max(contacts, r.summary.contacts);
    gaps.push_back(number(r.summary.min_gap * 1e3));
    penetrations.push_back(number(r.summary.max_penetration * 1e3));
  }
  if (contacts > 0 || deepest > 0) {
    // Per frame from the same signed gaps: penetration_mm = max(0, -min_gap_mm).
    j["contacts"] = {{"max_per_frame", contacts},
                     {"max_penetration_mm", number(deepest * 1e3)},
                     {"min_gap_mm", gaps},
                     {"penetration_mm", penetrations},
                     {"collision", tracker.collision() != nullptr},
                     {"forces_per_frame", ContactForcesJson(scene, tracker, rows)}};
  }
  json flags = {{"no_collision", args.no_collision}, {"max_frames", args.max_frames},
                {"threads", args.threads}, {"depth_scale", args.depth_scale},
                {"mask_dir", args.mask_dir.empty() ? json(nullptr) : json(args.mask_dir)},
                {"intrinsics", args.intrinsics.empty() ? json(nullptr) : json(args.intrinsics)}};
  j["command_line"] = flags;
  j["provenance"] = ProvenanceJson(scene, o, args.sets, files, truth_files);
  std::error_code ec;
  const fs::path tum_list = args.tum_list.empty() ? fs::path() : fs::absolute(args.tum_list, ec).lexically_normal();
  j["provenance"]["tum_list"] = args.tum_list.empty() ? json(nullptr) : json(ec ? args.tum_list : tum_list.string());
  // A file name or description that is not UTF-8 must not end the run: replace its bytes.
  return j.dump(2, ' ', false, json::error_handler_t::replace) + "\n";
}

}  // namespace register_outputs
}  // namespace cli
}  // namespace femreg
