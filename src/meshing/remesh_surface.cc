// RemeshSurface (remesh_surface.h) with CGAL's Polygon_mesh_processing: detect_sharp_edges
// marks the feature lines, isotropic_remeshing does the rest. CGAL needs -frounding-math for
// its filtered predicates: CMakeLists.txt gives it to this file alone.
#include "meshing/remesh_surface.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/detect_features.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <set>
#include <vector>

#include "mesh/disjoint_sets.h"
#include "meshing/mesh_measures.h"
#include "parallel/stopwatch.h"

namespace femreg {
namespace internal {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using VertexIndex = Mesh::Vertex_index;
using EdgeIndex = Mesh::Edge_index;
namespace pmp = CGAL::Polygon_mesh_processing;

using internal::Fmt;

}  // namespace

Status RemeshSurface(const Vertices& V, const Triangles& F, const RemeshSettings& settings,
                     const std::string& source, RemeshResult* out) {
  *out = RemeshResult();
  if (!(settings.edge_length > 0.0)) {
    return Status::Error(source + ": remeshing needs an edge length > 0, got " +
                         Fmt(settings.edge_length));
  }
  Mesh mesh;
  std::vector<VertexIndex> vertex(static_cast<size_t>(V.rows()));
  for (int v = 0; v < V.rows(); ++v) {
    vertex[static_cast<size_t>(v)] = mesh.add_vertex(Point(V(v, 0), V(v, 1), V(v, 2)));
  }
  for (int t = 0; t < F.rows(); ++t) {
    const auto face = mesh.add_face(vertex[static_cast<size_t>(F(t, 0))],
                                    vertex[static_cast<size_t>(F(t, 1))],
                                    vertex[static_cast<size_t>(F(t, 2))]);
    // The checks before guarantee a closed, oriented 2-manifold; this is a second opinion.
    if (face == Mesh::null_face()) {
      return Status::Error(source + ": triangle " + std::to_string(t) +
                           " cannot join the surface for remeshing (not a consistently "
                           "oriented 2-manifold there)");
    }
  }

  auto is_feature = mesh.add_property_map<EdgeIndex, bool>("e:femreg_feature", false).first;
  auto feature_degree = mesh.add_property_map<VertexIndex, int>("v:femreg_degree", 0).first;
  auto is_corner = mesh.add_property_map<VertexIndex, bool>("v:femreg_corner", false).first;
  try {
    if (settings.feature_angle_deg < 180.0) {
      pmp::detect_sharp_edges(mesh, settings.feature_angle_deg, is_feature,
                              CGAL::parameters::vertex_feature_degree_map(feature_degree));
    }
    // A connected set of sharp edges shorter than 2 L in all is a scan's noise or a detail
    // below the target size, not a feature: kept, its vertices could not be collapsed, and
    // edges of almost no length would make flat tetrahedra.
    DisjointSets lines(static_cast<int>(mesh.number_of_vertices()));
    for (EdgeIndex e : mesh.edges()) {
      if (is_feature[e]) {
        lines.Unite(static_cast<int>(static_cast<size_t>(mesh.vertex(e, 0))),
                    static_cast<int>(static_cast<size_t>(mesh.vertex(e, 1))));
      }
    }
    std::vector<double> line_length(mesh.number_of_vertices(), 0.0);
    auto line_of = [&](EdgeIndex e) {
      return static_cast<size_t>(lines.Find(static_cast<int>(static_cast<size_t>(mesh.vertex(e, 0)))));
    };
    for (EdgeIndex e : mesh.edges()) {
      if (is_feature[e]) {
        line_length[line_of(e)] += std::sqrt(CGAL::to_double(
            CGAL::squared_distance(mesh.point(mesh.vertex(e, 0)), mesh.point(mesh.vertex(e, 1)))));
      }
    }
    for (VertexIndex v : mesh.vertices()) feature_degree[v] = 0;
    for (EdgeIndex e : mesh.edges()) {
      if (is_feature[e] && line_length[line_of(e)] < 2.0 * settings.edge_length) {
        is_feature[e] = false;
        ++out->dropped_sharp_edges;
      }
      if (is_feature[e]) {
        ++out->sharp_edges;
        ++feature_degree[mesh.vertex(e, 0)];
        ++feature_degree[mesh.vertex(e, 1)];
      }
    }
    // Where three or more feature lines meet (a box's corner), the vertex stays: moving it
    // along one line would cut the others.
    for (VertexIndex v : mesh.vertices()) {
      is_corner[v] = feature_degree[v] >= 3;
      out->corner_vertices += is_corner[v] ? 1 : 0;
    }
    pmp::isotropic_remeshing(faces(mesh), settings.edge_length, mesh,
                             CGAL::parameters::number_of_iterations(
                                 static_cast<unsigned int>(settings.iterations))
                                 .edge_is_constrained_map(is_feature)
                                 .vertex_is_constrained_map(is_corner)
                                 .protect_constraints(false)
                                 .relax_constraints(true));
    // Where two feature lines come close (a crease's sides), their vertices can end up a
    // hair apart with the edge between them not collapsible (it joins two lines): remesh the
    // two rings of faces around such edges once more without feature lines; the faces
    // around that patch keep its border.
    std::set<Mesh::Face_index> patch;
    for (EdgeIndex e : mesh.edges()) {
      const double length = std::sqrt(CGAL::to_double(
          CGAL::squared_distance(mesh.point(mesh.vertex(e, 0)), mesh.point(mesh.vertex(e, 1)))));
      if (length >= 0.1 * settings.edge_length) continue;
      ++out->short_edges;
      for (int k = 0; k < 2; ++k) {
        for (auto f : faces_around_target(mesh.halfedge(mesh.vertex(e, k)), mesh)) {
          if (f != Mesh::null_face()) patch.insert(f);
        }
      }
    }
    if (!patch.empty()) {
      std::set<Mesh::Face_index> ring = patch;
      for (auto f : ring) {
        for (VertexIndex v : vertices_around_face(mesh.halfedge(f), mesh)) {
          for (auto g : faces_around_target(mesh.halfedge(v), mesh)) {
            if (g != Mesh::null_face()) patch.insert(g);
          }
        }
      }
      const std::vector<Mesh::Face_index> range(patch.begin(), patch.end());
      pmp::isotropic_remeshing(range, settings.edge_length, mesh,
                               CGAL::parameters::number_of_iterations(
                                   static_cast<unsigned int>(settings.iterations)));
    }
  } catch (const std::exception& e) {
    return Status::Error(source + ": remeshing to edge length " + Fmt(settings.edge_length) +
                         " failed (CGAL: " + e.what() + ")");
  }
  mesh.collect_garbage();

  out->vertices.resize(static_cast<Eigen::Index>(mesh.number_of_vertices()), 3);
  for (VertexIndex v : mesh.vertices()) {
    const Point& p = mesh.point(v);
    const auto row = static_cast<Eigen::Index>(static_cast<size_t>(v));
    out->vertices.row(row) << p.x(), p.y(), p.z();
  }
  out->triangles.resize(static_cast<Eigen::Index>(mesh.number_of_faces()), 3);
  Eigen::Index row = 0;
  for (auto f : mesh.faces()) {
    int k = 0;
    for (VertexIndex v : vertices_around_face(mesh.halfedge(f), mesh)) {
      if (k < 3) out->triangles(row, k) = static_cast<int>(static_cast<size_t>(v));
      ++k;
    }
    if (k != 3) {
      return Status::Error(source + ": remeshing left a face with " + std::to_string(k) +
                           " corners");
    }
    ++row;
  }
  return Status::Ok();
}

Status RemeshCheckedSurface(const CheckedSurface& surface, const MeshingOptions& options,
                            const std::string& source, CheckedSurface* out,
                            MeshingReport* report) {
  const auto start = std::chrono::steady_clock::now();
  RemeshSettings settings;
  settings.edge_length = options.edge_length;
  settings.feature_angle_deg = options.feature_angle_deg;
  settings.iterations = options.remesh_iterations;
  // Shell by shell, in the input's order: the remeshed shells come out in the same order, so
  // that region ids (by shell) mean the same pieces with and without remeshing.
  RemeshResult remeshed;
  Status status = Status::Ok();
  report->sharp_edges = report->dropped_sharp_edges = report->corner_vertices = 0;
  report->short_edges = 0;
  for (const SurfaceShell& shell : surface.shells) {
    std::vector<int> index(static_cast<size_t>(surface.vertices.rows()), -1);
    Vertices V(0, 3);
    Triangles F(static_cast<Eigen::Index>(shell.triangles.size()), 3);
    int count = 0;
    for (size_t t = 0; t < shell.triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) {
        int& i = index[static_cast<size_t>(surface.triangles(shell.triangles[t], k))];
        if (i < 0) i = count++;
        F(static_cast<Eigen::Index>(t), k) = i;
      }
    }
    V.resize(count, 3);
    for (size_t v = 0; v < index.size(); ++v) {
      if (index[v] >= 0) V.row(index[v]) = surface.vertices.row(static_cast<Eigen::Index>(v));
    }
    RemeshResult piece;
    status = RemeshSurface(V, F, settings, source, &piece);
    if (!status.ok()) break;
    report->sharp_edges += piece.sharp_edges;
    report->dropped_sharp_edges += piece.dropped_sharp_edges;
    report->short_edges += piece.short_edges;
    report->corner_vertices += piece.corner_vertices;
    const Eigen::Index v0 = remeshed.vertices.rows(), f0 = remeshed.triangles.rows();
    remeshed.vertices.conservativeResize(v0 + piece.vertices.rows(), 3);
    remeshed.vertices.bottomRows(piece.vertices.rows()) = piece.vertices;
    remeshed.triangles.conservativeResize(f0 + piece.triangles.rows(), 3);
    remeshed.triangles.bottomRows(piece.triangles.rows()) =
        piece.triangles.array() + static_cast<int>(v0);
  }
  if (status.ok()) {
    // Merge nothing (0: exact copies only): the remeshed vertices are distinct by construction.
    status = CheckSurface(remeshed.vertices, remeshed.triangles, 0.0,
                          options.check_self_intersections,
                          source + " remeshed to edge length " + Fmt(options.edge_length), out);
    if (!status.ok()) {
      status = Status::Error(status.message() +
                             " (a smaller edge length, more remesh iterations, or no remeshing "
                             "may help)");
    }
  }
  if (status.ok() && out->shells.size() != surface.shells.size()) {
    status = Status::Error(source + ": the surface remeshed to edge length " +
                           Fmt(options.edge_length) + " has " +
                           std::to_string(out->shells.size()) + " closed shells, the input " +
                           std::to_string(surface.shells.size()) +
                           " (a smaller edge length keeps small shells)");
  }
  if (status.ok()) {
    report->remeshed = true;
    report->remeshed_vertices = static_cast<int>(out->vertices.rows());
    report->remeshed_triangles = static_cast<int>(out->triangles.rows());
    report->remeshed_mean_edge_length = out->mean_edge_length;
    report->remeshed_volume = 0.0;
    for (const SurfaceShell& shell : out->shells) {
      const double volume = std::abs(shell.signed_volume);
      report->remeshed_volume += shell.depth % 2 == 0 ? volume : -volume;
    }
  }
  report->remesh_seconds = Seconds(start);
  return status;
}

}  // namespace internal
}  // namespace femreg
