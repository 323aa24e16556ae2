// femreg mesh --cage N: a coarse tetrahedral mesh of about N vertices around a fine surface.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "femreg/geometry.h"
#include "femreg/meshing.h"
#include "geometry/nearest.h"
#include "meshing/mesh_measures.h"
#include "meshing/wrap_surface.h"

namespace femreg {

namespace {

// Passes of meshing at most, and how close to the target vertex count a pass must come.
constexpr int kMaxPasses = 4;
constexpr double kCountTolerance = 0.15;
// Rounds of moving the boundary out, and the margin over the farthest outside vertex.
constexpr int kOffsetRounds = 4;
constexpr double kOffsetMargin = 1.2;

double SignedVolume(const TetMesh& m, int e, const Vertices& x) {
  const Eigen::Vector3d a = x.row(m.tets(e, 0));
  const Eigen::Vector3d b = x.row(m.tets(e, 1)), c = x.row(m.tets(e, 2)), d = x.row(m.tets(e, 3));
  return (b - a).cross(c - a).dot(d - a) / 6.0;
}

// The vertices of V outside the mesh at positions x (no element contains them), the farthest
// one's distance to its boundary, and per mesh vertex the largest distance of an outside vertex
// whose closest boundary triangle has it (how far that corner is to move out).
void Outside(const TetMesh& mesh, const Vertices& x, const Vertices& V, int* count, double* farthest,
             Eigen::VectorXd* push) {
  TetMesh at = mesh;
  at.rest = x;
  const EmbeddedPoints e = EmbedPoints(at, V, /*clamp=*/false);
  const SurfaceIndex boundary(x, mesh.surface);
  *count = 0;
  *farthest = 0.0;
  push->setZero(x.rows());
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    if (e.barycentric[static_cast<size_t>(i)].minCoeff() >= -1e-12) continue;
    ++*count;
    const SurfaceIndex::Hit hit = boundary.Closest(V.row(i).transpose());
    if (hit.triangle < 0) continue;
    const double d = std::sqrt(hit.squared_distance);
    *farthest = std::max(*farthest, d);
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.surface(hit.triangle, k);
      (*push)(v) = std::max((*push)(v), d);
    }
  }
}

}  // namespace

Status MakeCage(const Vertices& V, const Triangles& F, int target_vertices, const MeshingOptions& options,
                TetMesh* mesh, CageReport* report_out, const std::string& source) {
  CageReport local;
  CageReport& report = report_out != nullptr ? *report_out : local;
  report = CageReport();
  if (target_vertices < 8) return Status::Error(source + ": a cage needs a target of at least 8 vertices");
  // A broken surface is wrapped once, here, and each pass meshes the wrap; the cage is still
  // moved out until the input's own vertices are inside.
  MeshingOptions base = options;
  Vertices wrapped_vertices;
  Triangles wrapped_triangles;
  MeshingReport wrap;  // its wrap fields
  wrap.input_vertices = static_cast<int>(V.rows());
  wrap.input_triangles = static_cast<int>(F.rows());
  // The report is of the input, wrapped, whether the passes succeed or not.
  auto input_and_wrap = [&]() {
    report.meshing.input_vertices = wrap.input_vertices;
    report.meshing.input_triangles = wrap.input_triangles;
    internal::CopyWrapReport(wrap, &report.meshing);
  };
  if (options.wrap > 0.0) {
    const Status status =
        internal::WrapForMeshing(V, F, options, source, &wrapped_vertices, &wrapped_triangles, &wrap);
    input_and_wrap();
    if (!status.ok()) return status;
    base.wrap = 0.0;
  }
  const bool hint = options.wrap == 0.0;  // a wrap's refusal does not suggest wrapping it
  // The passes' messages name the wrap's triangles, not the input's.
  const std::string mesh_source = hint ? source : source + " wrapped at alpha " + internal::Fmt(options.wrap);
  const Vertices& surface_vertices = options.wrap > 0.0 ? wrapped_vertices : V;
  const Triangles& surface_triangles = options.wrap > 0.0 ? wrapped_triangles : F;
  // The first pass' edge length from the solid's volume: a mesh of well-shaped elements of
  // edge L has about 1.5 Vol / L^3 interior vertices, and a coarse one as many again on its
  // surface.
  MeshingOptions pass = base;
  pass.remesh = true;
  pass.keep_surface = false;
  pass.edge_length = 0.0;
  {
    MeshingReport probe;
    MeshingOptions check = base;
    // A tiny edge length against a bound of one element stops it after the checks, with
    // the volume measured.
    check.max_tets = 1;
    check.edge_length =
        1e-6 * ((surface_vertices.colwise().maxCoeff() - surface_vertices.colwise().minCoeff()).norm() + 1e-300);
    TetMesh unused;
    internal::Tetrahedralize(surface_vertices, surface_triangles, check, &unused, &probe, mesh_source, hint);
    if (!(probe.surface_volume > 0.0)) {
      // The checks failed: run them again for their message.
      MeshingOptions plain = base;
      plain.remesh = false;
      const Status status =
          internal::Tetrahedralize(surface_vertices, surface_triangles, plain, &unused, &probe, mesh_source, hint);
      report.meshing = probe;
      input_and_wrap();
      return status.ok() ? Status::Error(source + ": the surface encloses no volume") : status;
    }
    pass.edge_length = std::cbrt(3.0 * probe.surface_volume / target_vertices);
  }
  for (int p = 0; p < kMaxPasses; ++p) {
    report.passes = p + 1;
    report.edge_length = pass.edge_length;
    const Status status =
        internal::Tetrahedralize(surface_vertices, surface_triangles, pass, mesh, &report.meshing, mesh_source, hint);
    input_and_wrap();
    if (!status.ok()) {
      // The cage's edge length is its own choice: what the user can change is the detail.
      if (!report.meshing.remeshed && report.meshing.surface_vertices > 0 && report.meshing.edge_length > 0) {
        const std::string length = internal::Fmt(pass.edge_length);
        return Status::Error(status.message() + "\n  for a cage of edge length " + length +
                             ", parts thinner than that fold when remeshed: --wrap ALPHA with ALPHA near " +
                             length + " smooths them first");
      }
      return status;
    }
    const double ratio = static_cast<double>(report.meshing.vertices) / target_vertices;
    if (std::abs(ratio - 1.0) <= kCountTolerance) break;
    // The count goes with L^-3 inside and L^-2 on the surface: a coarse cage is in between.
    pass.edge_length *= std::pow(ratio, 0.4);
  }

  // Out along the boundary's vertex normals until the input is inside.
  Vertices x = mesh->rest;
  Eigen::VectorXd push;
  Outside(*mesh, x, V, &report.outside_before, &report.outside_max_before, &push);
  report.outside_vertices = report.outside_before;
  report.outside_max = report.outside_max_before;
  Eigen::MatrixXd normals = Eigen::MatrixXd::Zero(x.rows(), 3);
  double volume = 0.0;
  for (int f = 0; f < mesh->num_surface_triangles(); ++f) {
    const Eigen::Vector3d a = x.row(mesh->surface(f, 0)), b = x.row(mesh->surface(f, 1)), c = x.row(mesh->surface(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);
    volume += a.dot(n) / 6.0;
    for (int k = 0; k < 3; ++k) normals.row(mesh->surface(f, k)) += n.transpose();
  }
  const double outward = volume >= 0.0 ? 1.0 : -1.0;  // the surface's orientation
  for (Eigen::Index v = 0; v < normals.rows(); ++v) {
    const double n = normals.row(v).norm();
    if (n > 0) normals.row(v) *= outward / n;
  }
  // Each corner moves by as much as the scan sticks out over its triangles (a local move:
  // a uniform one to cover an ear's tip would fatten the whole body).
  for (int round = 0; round < kOffsetRounds && report.outside_vertices > 0; ++round) {
    double scale = kOffsetMargin;
    bool moved = false;
    for (int halving = 0; halving < 4 && !moved; ++halving, scale *= 0.5) {
      const Vertices trial = x + (scale * push).asDiagonal() * normals;
      bool valid = true;
      for (int e = 0; e < mesh->num_tets() && valid; ++e) valid = SignedVolume(*mesh, e, trial) > 0.0;
      if (!valid) continue;
      x = trial;
      report.offset = std::max(report.offset, (x - mesh->rest).rowwise().norm().maxCoeff());
      moved = true;
    }
    if (!moved) break;
    Outside(*mesh, x, V, &report.outside_vertices, &report.outside_max, &push);
  }
  mesh->rest = x;
  mesh->x = x;
  return FinalizeMesh(mesh, source);
}

}  // namespace femreg
