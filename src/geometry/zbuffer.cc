#include "geometry/zbuffer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "parallel/pool.h"
#include "parallel/threads.h"

namespace femreg {

bool PinholeCamera::Project(const Eigen::Vector3d& p, double* u, double* v, double* z) const {
  const Eigen::Vector3d q = rotation * (p - position);
  *z = q.z();
  if (q.z() <= near) return false;
  *u = fx * q.x() / q.z() + cx;
  *v = fy * q.y() / q.z() + cy;
  return true;
}

void ZBuffer::Reset(int w, int h) {
  width = w;
  height = h;
  const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  depth.assign(n, std::numeric_limits<double>::infinity());
  surface.assign(n, -1);
  triangle.assign(n, -1);
}

void Rasterize(const PinholeCamera& camera, const Vertices& positions, const Triangles& triangles,
               int surface_id, ZBuffer* zbuffer) {
  const int width = zbuffer->width, height = zbuffer->height;
  const int nv = static_cast<int>(positions.rows()), nf = static_cast<int>(triangles.rows());
  const int threads = ResolveThreadCount(0);
  // Each vertex projected once (a fine surface has about six triangles per vertex, each
  // smaller than a pixel).
  struct Projected {
    double u = 0.0, v = 0.0, z = 0.0;
    bool ok = false;
  };
  std::vector<Projected> projected(static_cast<size_t>(nv));
  ParallelFor(threads, nv, 8192, [&](int64_t i) {
    Projected& p = projected[static_cast<size_t>(i)];
    p.ok = camera.Project(positions.row(i), &p.u, &p.v, &p.z);
  });
  // The image in bands of rows, one per thread, each going through the triangles in order:
  // a pixel is written by one thread, and the nearest triangle (the first of equals) wins as
  // on one thread.
  const int bands = std::min(std::max(1, height), PhaseThreads(threads, nf, 8192));
  RunTasks(bands, bands, [&](int band) {
    const int row0 = static_cast<int>(static_cast<long long>(height) * band / bands);
    const int row1 = static_cast<int>(static_cast<long long>(height) * (band + 1) / bands) - 1;
    for (int f = 0; f < nf; ++f) {
      double u[3], v[3], z[3];
      bool ok = true;
      for (int k = 0; k < 3 && ok; ++k) {
        const Projected& p = projected[static_cast<size_t>(triangles(f, k))];
        ok = p.ok;
        u[k] = p.u;
        v[k] = p.v;
        z[k] = p.z;
      }
      if (!ok) continue;
      // Pixel centres at integer coordinates.
      const int v0 = std::max(row0, static_cast<int>(std::ceil(std::min({v[0], v[1], v[2]}))));
      const int v1 = std::min(row1, static_cast<int>(std::floor(std::max({v[0], v[1], v[2]}))));
      if (v0 > v1) continue;
      const int u0 = std::max(0, static_cast<int>(std::ceil(std::min({u[0], u[1], u[2]}))));
      const int u1 = std::min(width - 1, static_cast<int>(std::floor(std::max({u[0], u[1], u[2]}))));
      if (u0 > u1) continue;
      const double area = (u[1] - u[0]) * (v[2] - v[0]) - (u[2] - u[0]) * (v[1] - v[0]);
      if (std::abs(area) < 1e-12) continue;
      for (int py = v0; py <= v1; ++py) {
        for (int px = u0; px <= u1; ++px) {
          // Screen-space barycentrics.
          const double w0 = ((u[1] - px) * (v[2] - py) - (u[2] - px) * (v[1] - py)) / area;
          const double w1 = ((u[2] - px) * (v[0] - py) - (u[0] - px) * (v[2] - py)) / area;
          const double w2 = 1.0 - w0 - w1;
          if (w0 < 0 || w1 < 0 || w2 < 0) continue;
          // Perspective-correct depth: 1/z is linear in screen space.
          const double inv_z = w0 / z[0] + w1 / z[1] + w2 / z[2];
          const double depth = 1.0 / inv_z;
          const size_t idx = static_cast<size_t>(py) * width + px;
          if (depth < zbuffer->depth[idx]) {
            zbuffer->depth[idx] = depth;
            zbuffer->surface[idx] = surface_id;
            zbuffer->triangle[idx] = f;
          }
        }
      }
    }
  });
}

}  // namespace femreg
