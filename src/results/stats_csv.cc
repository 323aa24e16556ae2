// stats.csv: its header, a frame's row, the appending file, and the run's totals; see
// femreg/results.h.
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "femreg/results.h"

namespace fs = std::filesystem;

namespace femreg {

namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

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
    "force_z_N,torque_x_Nm,torque_y_Nm,torque_z_Nm,force_weight,misfit_ratio,forces_estimated,quiet_start,occluded_points,implausible_points,contact_force_x_N,"
    "contact_force_y_N,contact_force_z_N,friction_force_x_N,friction_force_y_N,friction_force_z_N,"
    "confidence,confidence_fit,confidence_coverage,confidence_residual_mm,strain_p95,confidence_volume_change,lost,free_space_vertices,flying_pixels,depth_offset_mm,"
    "err_surface_mean_mm,err_surface_p95_mm,err_surface_max_mm,err_surface_seen_mean_mm,t_outputs_ms,message\n";

std::string StatsRow(size_t i, const FrameRecord& row) {
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
  os << buf;
  std::snprintf(buf, sizeof(buf), ",%.6g,%.4f", s.force_weight, s.misfit_ratio);
  os << buf << "," << (s.forces_estimated ? 1 : 0) << "," << (s.quiet_start ? 1 : 0) << "," << s.occluded_points
     << "," << s.implausible_points;
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
  std::snprintf(buf, sizeof(buf), ",%.4f,%.4f,%.4f,%.4f,%.4g,%.4g,%d", c.confidence, c.fit, c.coverage,
                c.residual * 1e3, c.strain, c.volume_change, s.lost ? 1 : 0);
  os << buf << "," << s.free_space_vertices << "," << s.flying_pixels;
  std::snprintf(buf, sizeof(buf), ",%.4f", s.depth_offset * 1e3);
  os << buf;
  if (row.have_surface_errors) {  // the embedded surfaces' vertices against their ground truth
    const VertexErrors& e = row.surface_errors;
    std::snprintf(buf, sizeof(buf), ",%.4f,%.4f,%.4f,%.4f", e.all.mean * 1e3, e.all.p95 * 1e3, e.all.max * 1e3,
                  e.seen.mean * 1e3);
    os << buf;
  } else {
    os << ",,,,";
  }
  std::snprintf(buf, sizeof(buf), ",%.3f", s.time.outputs * 1e3);
  os << buf;
  std::string msg = row.read_error.empty() ? s.message : row.read_error;
  std::replace(msg.begin(), msg.end(), '"', '\'');
  os << ",\"" << msg << "\"\n";
  return os.str();
}

RunTotals ComputeRunTotals(const std::vector<FrameRecord>& rows) {
  RunTotals t;
  t.frames = static_cast<int>(rows.size());
  std::vector<double> ms;
  double sum_all = 0, sum_seen = 0, sum_hidden = 0;
  int n_err = 0, n_seen = 0, n_hidden = 0;
  for (const FrameRecord& r : rows) {
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

Status StatsFile::Open(const std::string& path) {
  path_ = path;
  file_.reset(std::fopen(path.c_str(), "wb"));
  if (!file_) return Status::Error(path + ": cannot create file: " + std::strerror(errno));
  return Append(kStatsHeader);
}

Status StatsFile::Append(const std::string& text) {
  if (std::fwrite(text.data(), 1, text.size(), file_.get()) != text.size() || std::fflush(file_.get()) != 0) {
    return Status::Error(path_ + ": write failed: " + std::strerror(errno));
  }
  return Status::Ok();
}

}  // namespace femreg
