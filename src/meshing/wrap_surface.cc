// WrapSurface (wrap_surface.h) with CGAL's alpha_wrap_3 on the triangle soup. CGAL needs
// -frounding-math for its filtered predicates: CMakeLists.txt gives it to this file.
#include "meshing/wrap_surface.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>

#include <array>
#include <chrono>
#include <cmath>
#include <exception>
#include <vector>

#include "meshing/mesh_measures.h"

namespace femreg {
namespace internal {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;

}  // namespace

Status WrapSurface(const Vertices& V, const Triangles& F, double alpha, double offset,
                   const std::string& source, Vertices* wrapped_vertices, Triangles* wrapped_triangles) {
  if (!(alpha > 0.0 && std::isfinite(alpha)) || !(offset > 0.0 && std::isfinite(offset))) {
    return Status::Error(source + ": the wrap needs alpha and offset > 0, got " + Fmt(alpha) + " and " +
                         Fmt(offset));
  }
  if (!V.allFinite()) return Status::Error(source + ": a vertex is not finite: nothing can be wrapped");
  std::vector<Point> points;
  points.reserve(static_cast<size_t>(V.rows()));
  for (Eigen::Index v = 0; v < V.rows(); ++v) points.emplace_back(V(v, 0), V(v, 1), V(v, 2));
  std::vector<std::array<size_t, 3>> faces;
  faces.reserve(static_cast<size_t>(F.rows()));
  for (Eigen::Index t = 0; t < F.rows(); ++t) {
    const std::array<size_t, 3> f = {static_cast<size_t>(F(t, 0)), static_cast<size_t>(F(t, 1)),
                                     static_cast<size_t>(F(t, 2))};
    if (f[0] >= points.size() || f[1] >= points.size() || f[2] >= points.size()) {
      return Status::Error(source + ": triangle " + std::to_string(t) + " refers to a vertex that does not exist");
    }
    // A flat triangle (corners repeated or on a line) wraps as nothing: CGAL skips it, and
    // one with nothing else to wrap would fail.
    if (CGAL::collinear(points[f[0]], points[f[1]], points[f[2]])) continue;
    faces.push_back(f);
  }
  if (faces.empty()) {
    return Status::Error(source + ": nothing to wrap: every triangle is flat (its corners on a line or repeated)");
  }
  Mesh wrap;
  try {
    CGAL::alpha_wrap_3(points, faces, alpha, offset, wrap);
  } catch (const std::exception& e) {
    return Status::Error(source + ": the alpha wrap (alpha " + Fmt(alpha) + ", offset " + Fmt(offset) +
                         ") failed (CGAL: " + e.what() + ")");
  }
  if (wrap.number_of_faces() == 0) {
    return Status::Error(source + ": the alpha wrap (alpha " + Fmt(alpha) + ", offset " + Fmt(offset) +
                         ") is empty");
  }
  // The wrap's vertices in their order, numbered without the gaps a Surface_mesh may keep.
  std::vector<int> index(wrap.num_vertices(), -1);
  wrapped_vertices->resize(static_cast<Eigen::Index>(wrap.number_of_vertices()), 3);
  int n = 0;
  for (const Mesh::Vertex_index v : wrap.vertices()) {
    const Point& p = wrap.point(v);
    wrapped_vertices->row(n) << CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z());
    index[static_cast<size_t>(v)] = n++;
  }
  wrapped_triangles->resize(static_cast<Eigen::Index>(wrap.number_of_faces()), 3);
  int t = 0;
  for (const Mesh::Face_index f : wrap.faces()) {
    int k = 0;
    for (const Mesh::Vertex_index v : wrap.vertices_around_face(wrap.halfedge(f))) {
      if (k < 3) (*wrapped_triangles)(t, k) = index[static_cast<size_t>(v)];
      ++k;
    }
    if (k != 3) return Status::Error(source + ": the alpha wrap has a face of " + std::to_string(k) + " corners");
    ++t;
  }
  return Status::Ok();
}

Status WithWrapHint(const Status& refusal) {
  if (refusal.ok() || refusal.message().find("does not bound a volume") == std::string::npos) return refusal;
  return Status::Error(refusal.message() +
                       "\n  a scan's or an export's surface can be wrapped first into a closed one around it: "
                       "femreg mesh --wrap ALPHA (MeshingOptions::wrap), ALPHA about the narrowest gap or "
                       "detail to keep (docs/guide/meshing.md#broken-surfaces)");
}

Status WrapForMeshing(const Vertices& V, const Triangles& F, const MeshingOptions& options,
                      const std::string& source, Vertices* wrapped_vertices, Triangles* wrapped_triangles,
                      MeshingReport* report) {
  const auto start = std::chrono::steady_clock::now();
  report->wrap_alpha = options.wrap;
  report->wrap_offset = options.wrap_offset > 0.0 ? options.wrap_offset : options.wrap / 30.0;
  const Status status =
      WrapSurface(V, F, report->wrap_alpha, report->wrap_offset, source, wrapped_vertices, wrapped_triangles);
  report->wrap_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!status.ok()) return status;
  report->wrapped = true;
  report->wrapped_vertices = static_cast<int>(wrapped_vertices->rows());
  report->wrapped_triangles = static_cast<int>(wrapped_triangles->rows());
  return Status::Ok();
}

void CopyWrapReport(const MeshingReport& from, MeshingReport* to) {
  to->wrapped = from.wrapped;
  to->wrap_alpha = from.wrap_alpha;
  to->wrap_offset = from.wrap_offset;
  to->wrapped_vertices = from.wrapped_vertices;
  to->wrapped_triangles = from.wrapped_triangles;
  to->wrap_seconds = from.wrap_seconds;
}

}  // namespace internal
}  // namespace femreg
