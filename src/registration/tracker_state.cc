#include "registration/tracker_state.h"

#include <algorithm>
#include <cstddef>
#include <limits>

#include "parallel/pool.h"
#include "parallel/threads.h"

namespace femreg {

std::vector<std::pair<int, double>> RegionDensities(const ObjectMaterial& material) {
  std::vector<std::pair<int, double>> densities;
  for (const auto& r : material.regions) densities.emplace_back(r.first, r.second.density);
  return densities;
}

void TrackerState::RebuildGlobalArrays() {
  num_vertices = 0;
  int num_triangles = 0;
  for (ObjectState& o : objects) {
    o.offset = num_vertices;
    num_vertices += o.mesh.num_vertices();
    num_triangles += o.mesh.num_surface_triangles();
  }
  mass.resize(num_vertices);
  vertex_object.resize(num_vertices);
  residuals.resize(objects.size());
  observed.resize(objects.size());
  external_forces.resize(objects.size());
  surface.resize(num_triangles, 3);
  surface_vertices.clear();
  int row = 0;
  for (size_t i = 0; i < objects.size(); ++i) {
    const ObjectState& o = objects[i];
    const int nv = o.mesh.num_vertices();
    mass.segment(o.offset, nv) = o.mesh.mass;
    for (int v = 0; v < nv; ++v) vertex_object[o.offset + v] = static_cast<int>(i);
    residuals[i] = Eigen::VectorXd::Constant(nv, std::numeric_limits<double>::quiet_NaN());
    observed[i].assign(nv, 0);
    external_forces[i] = Vertices::Zero(nv, 3);
    surface.middleRows(row, o.mesh.num_surface_triangles()) = o.mesh.surface.array() + o.offset;
    row += o.mesh.num_surface_triangles();
    for (int v : o.mesh.surface_vertices) surface_vertices.push_back(v + o.offset);
  }
  double length = 0.0;
  int edges = 0;
  for (const ObjectState& o : objects) {
    for (int f = 0; f < o.mesh.num_surface_triangles(); ++f) {
      for (int k = 0; k < 3; ++k) {
        length += (o.mesh.rest.row(o.mesh.surface(f, k)) - o.mesh.rest.row(o.mesh.surface(f, (k + 1) % 3))).norm();
        ++edges;
      }
    }
  }
  mean_edge_length = edges > 0 ? length / edges : 0.0;
}

Eigen::MatrixXd TrackerState::VertexNormals() const {
  // The face normals and the normalization in parallel; the sums per vertex in face order on
  // one thread, so that the result is the same on any thread count.
  const int nf = static_cast<int>(surface.rows());
  const int threads = ResolveThreadCount(0);
  Eigen::MatrixXd face(nf, 3);
  ParallelFor(threads, nf, 4096, [&](int64_t f) {
    const Eigen::Vector3d a = x.row(surface(f, 0)), b = x.row(surface(f, 1)), c = x.row(surface(f, 2));
    face.row(f) = (b - a).cross(c - a).transpose();  // area weighted
  });
  Eigen::MatrixXd n = Eigen::MatrixXd::Zero(num_vertices, 3);
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) n.row(surface(f, k)) += face.row(f);
  }
  ParallelFor(threads, num_vertices, 4096, [&](int64_t v) {
    const double len = n.row(v).norm();
    if (len > 0) n.row(v) /= len;
  });
  return n;
}

double BulkMove(const TrackerState& state, const Eigen::VectorXd& moves, const std::vector<char>& fixed) {
  double bulk = 0.0;
  std::vector<double> free;
  for (const ObjectState& o : state.objects) {
    free.clear();
    for (int v = 0; v < o.mesh.num_vertices(); ++v) {
      const int g = v + o.offset;
      const bool held = static_cast<size_t>(g) < fixed.size() && fixed[static_cast<size_t>(g)];
      if (g < moves.size() && !held) free.push_back(moves(g));
    }
    if (free.empty()) continue;
    const size_t at = (99 * free.size() + 99) / 100 - 1;  // the ceil(0.99 n)-th smallest
    std::nth_element(free.begin(), free.begin() + static_cast<std::ptrdiff_t>(at), free.end());
    bulk = std::max(bulk, free[at]);
  }
  return bulk;
}

double StiffRestartVolume(const RegistrationOptions& options, bool estimating_forces) {
  const double v = options.solver.stiff_restart_volume;
  if (v >= 0) return v;
  return estimating_forces ? 0.1 : 0.0;
}

double CrushedVolumeRatio(const TrackerState& state, const Vertices& from, const Vertices& to) {
  double smallest = 1.0;
  std::vector<double> ratio;  // per tet (1: not measured); their minimum, in any order
  for (const ObjectState& o : state.objects) {
    ratio.assign(static_cast<size_t>(o.mesh.num_tets()), 1.0);
    ParallelFor(state.options.solver.num_threads, o.mesh.num_tets(), 4096, [&](int64_t t) {
      auto volume = [&](const Vertices& x, int offset) {
        auto at = [&](int k) { return Eigen::Vector3d(x.row(offset + o.mesh.tets(t, k))); };
        return SignedTetVolume(at(0), at(1), at(2), at(3));
      };
      const double before = volume(from, o.offset), rest = volume(o.mesh.rest, 0);
      if (!(before > 0) || !(rest > 0)) return;
      const double now = volume(to, o.offset);
      ratio[static_cast<size_t>(t)] = std::max(now / before, now / rest);
    });
    for (double r : ratio) smallest = std::min(smallest, r);
  }
  return smallest;
}

Triangles TrackerState::ObjectSurface(int i) const {
  const ObjectState& o = objects[i];
  return o.mesh.surface.array() + o.offset;
}

}  // namespace femreg
