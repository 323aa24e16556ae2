// femreg register's output files (register_outputs.h); stats.csv and summary.json are the
// library's (femreg/results.h).
#include "register_outputs.h"

#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "cli_util.h"
#include "femreg/io.h"
#include "femreg/point_cloud.h"

namespace fs = std::filesystem;

namespace femreg {
namespace cli {
namespace register_outputs {

RunInputs MakeRunInputs(const RegisterArgs& args, const std::vector<std::string>& files,
                        const std::vector<std::string>& truth_files, bool interrupted) {
  RunInputs run;
  run.scene = args.scene;
  run.frames_source = args.frames;
  run.frame_files = files;
  run.truth_files = truth_files;
  run.overrides = args.sets;
  run.tum_list = args.tum_list;
  run.interrupted = interrupted;
  if (interrupted) run.interrupted_by = InterruptName();
  run.no_collision = args.no_collision;
  run.max_frames = args.max_frames;
  run.threads = args.threads;
  run.depth_scale = args.depth_scale;
  run.mask_dir = args.mask_dir;
  run.intrinsics = args.intrinsics;
  return run;
}

Status WriteFrameFiles(const RegisterArgs& args, size_t f, const Scene& scene, const Tracker& tracker,
                       const PointCloud& used, const Vertices& vertex_error, const Vertices& surface_error,
                       std::vector<PvdEntry>* cloud_pvd, std::vector<std::vector<PvdEntry>>* pvd,
                       std::vector<std::vector<PvdEntry>>* surface_pvd) {
  Status status;
  char name[64];
  // The cloud the frame was fitted to (`used`, above), beside the meshes: ParaView shows it
  // over them.
  {
    std::snprintf(name, sizeof(name), "cloud_%04zu.vtp", f);
    const std::string rel = std::string("frames/") + name;
    status = WriteCloudVtp((fs::path(args.out) / rel).string(), used.points,
                           used.has_normals() ? &used.normals : nullptr);
    if (status.ok()) cloud_pvd->push_back({static_cast<double>(f), rel});
    if (!status.ok()) return status;
  }
  int vertex_offset = 0;
  for (int i = 0; i < tracker.num_objects(); ++i) {
    const TetMesh& m = tracker.mesh(i);
    std::snprintf(name, sizeof(name), "%s_%04zu.vtu", scene.objects[static_cast<size_t>(i)].name.c_str(), f);
    std::vector<MeshField> fields(3);
    if (tracker.fracture_measure(i).size() == m.num_vertices()) {
      fields.emplace_back();
      fields.back().name = "fracture_measure";  // largest eigenvalue of zeta / area (Pa)
      fields.back().values = tracker.fracture_measure(i);
    }
    const std::vector<int>& original = tracker.original_vertices(i);
    if (static_cast<int>(original.size()) == m.num_vertices()) {
      fields.emplace_back();  // the vertex of the first mesh each vertex comes from
      fields.back().name = "original_vertex";
      fields.back().values.resize(m.num_vertices(), 1);
      for (int v = 0; v < m.num_vertices(); ++v) fields.back().values(v, 0) = original[v];
    }
    fields[0].name = "displacement";
    fields[0].values = m.x - m.rest;
    fields[1].name = "residual";
    fields[1].values = tracker.vertex_residuals(i);
    fields[2].name = "observed";
    fields[2].values.resize(m.num_vertices(), 1);
    for (int v = 0; v < m.num_vertices(); ++v) fields[2].values(v, 0) = tracker.vertex_observed(i)[v];
    if (vertex_error.rows() >= vertex_offset + m.num_vertices()) {
      const Vertices e = vertex_error.middleRows(vertex_offset, m.num_vertices());
      fields.emplace_back();
      fields.back().name = "error";  // m, |x - x_true| against the ground truth
      fields.back().values = e.rowwise().norm();
      fields.emplace_back();
      fields.back().name = "error_vector";  // m, x - x_true
      fields.back().values = e;
    }
    if (tracker.external_forces(i).rows() == m.num_vertices()) {
      fields.emplace_back();
      fields.back().name = "force";  // N, the external force on each vertex (FrameSummary::force)
      fields.back().values = tracker.external_forces(i);
    }
    vertex_offset += m.num_vertices();
    const std::string rel = std::string("frames/") + name;
    status = WriteVtu((fs::path(args.out) / rel).string(), m, m.x, fields);
    if (!status.ok()) return status;
    (*pvd)[static_cast<size_t>(i)].push_back({static_cast<double>(f), rel});
  }
  // Each embedded surface beside its mesh: NAME_surface_NNNN.vtp (and .ply on request).
  int surface_offset = 0;
  for (int i = 0; i < tracker.num_objects(); ++i) {
    if (!tracker.has_embedded_surface(i)) continue;
    const Vertices v = tracker.surface_vertices(i);
    std::vector<std::pair<std::string, Eigen::VectorXd>> fields;
    if (surface_error.rows() >= surface_offset + v.rows()) {
      fields.emplace_back("error", surface_error.middleRows(surface_offset, v.rows()).rowwise().norm());
    }
    surface_offset += static_cast<int>(v.rows());
    const std::string object_name = scene.objects[static_cast<size_t>(i)].name;
    std::snprintf(name, sizeof(name), "_surface_%04zu", f);
    const std::string rel = "frames/" + object_name + name + ".vtp";
    status = WriteTrianglesVtp((fs::path(args.out) / rel).string(), v, tracker.surface_triangles(i), fields);
    if (status.ok() && args.surface_ply) {
      status = WriteTrianglesPly((fs::path(args.out) / ("frames/" + object_name + name + ".ply")).string(), v,
                                 tracker.surface_triangles(i));
    }
    if (!status.ok()) return status;
    (*surface_pvd)[static_cast<size_t>(i)].push_back({static_cast<double>(f), rel});
  }
  return Status::Ok();
}

}  // namespace register_outputs
}  // namespace cli
}  // namespace femreg
