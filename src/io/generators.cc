// Structured tetrahedral meshes: a box, and a cylinder and a ball mapped from box grids.
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <functional>

#include "femreg/io.h"

namespace femreg {
namespace {

// The Kuhn (Freudenthal) split of the unit cube into 6 tetrahedra around the diagonal from
// corner 0 to corner 7; a corner's bits are its x (1), y (2) and z (4) offsets.
constexpr int kKuhnTets[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7},
                                 {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};

// A grid of nx * ny * nz cells whose point (i, j, k) is at `point(i, j, k)`, each cell split
// by Kuhn. With `mirror`, cells below the middle of an axis are reflected along that axis,
// so that every cell's diagonal points away from the grid's centre (which keeps the cells
// at the corners of a grid mapped onto a round shape well shaped). Reflecting per axis
// index keeps neighbouring cells conforming: a face's diagonal depends only on the two
// axes in its plane, which both cells share.
TetMesh GridMesh(int nx, int ny, int nz, const std::function<Eigen::Vector3d(int, int, int)>& point,
                 bool mirror) {
  auto id = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  TetMesh mesh;
  mesh.rest.resize((nx + 1) * (ny + 1) * (nz + 1), 3);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) mesh.rest.row(id(i, j, k)) = point(i, j, k).transpose();
  mesh.tets.resize(6 * nx * ny * nz, 4);
  int t = 0;
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        int flip = 0;
        if (mirror) {
          if (2 * i + 1 < nx) flip |= 1;
          if (2 * j + 1 < ny) flip |= 2;
          if (2 * k + 1 < nz) flip |= 4;
        }
        for (const auto& tet : kKuhnTets) {
          for (int c = 0; c < 4; ++c) {
            const int corner = tet[c] ^ flip;
            mesh.tets(t, c) = id(i + (corner & 1), j + ((corner >> 1) & 1), k + ((corner >> 2) & 1));
          }
          ++t;
        }
      }
    }
  }
  mesh.region = Eigen::VectorXi::Zero(mesh.num_tets());
  const Status status = FinalizeMesh(&mesh, "generated mesh");
  assert(status.ok());
  (void)status;
  return mesh;
}

// Maps the cube [-1, 1]^d (d = 2 or 3 leading coordinates of p) onto the unit ball: the
// square shell at max-norm m goes to the sphere of radius m, blended with the identity
// towards the centre. Monotone along rays, so the map is one-to-one.
Eigen::Vector3d CubeToBall(Eigen::Vector3d p, int d) {
  double m = 0.0, norm2 = 0.0;
  for (int a = 0; a < d; ++a) {
    m = std::max(m, std::abs(p(a)));
    norm2 += p(a) * p(a);
  }
  if (norm2 == 0.0) return p;
  const double scale = (1.0 - m) + m * m / std::sqrt(norm2);
  for (int a = 0; a < d; ++a) p(a) *= scale;
  return p;
}

}  // namespace

TetMesh MakeBox(const Eigen::Vector3d& size, int nx, int ny, int nz, const Eigen::Vector3d& origin) {
  nx = std::max(nx, 1);
  ny = std::max(ny, 1);
  nz = std::max(nz, 1);
  return GridMesh(
      nx, ny, nz,
      [&](int i, int j, int k) {
        return Eigen::Vector3d(origin.x() + size.x() * i / nx, origin.y() + size.y() * j / ny,
                               origin.z() + size.z() * k / nz);
      },
      /*mirror=*/false);
}

TetMesh MakeCylinder(double radius, double length, int n_radial, int n_axial) {
  const int n = 2 * std::max(n_radial, 1);
  n_axial = std::max(n_axial, 1);
  return GridMesh(
      n, n, n_axial,
      [&](int i, int j, int k) {
        const Eigen::Vector3d p(2.0 * i / n - 1.0, 2.0 * j / n - 1.0, 0.0);
        const Eigen::Vector3d q = CubeToBall(p, 2);
        return Eigen::Vector3d(radius * q.x(), radius * q.y(), length * k / n_axial);
      },
      /*mirror=*/true);
}

TetMesh MakeSphere(double radius, int n) {
  const int cells = 2 * std::max(n, 1);
  return GridMesh(
      cells, cells, cells,
      [&](int i, int j, int k) {
        const Eigen::Vector3d p(2.0 * i / cells - 1.0, 2.0 * j / cells - 1.0,
                                2.0 * k / cells - 1.0);
        return Eigen::Vector3d(radius * CubeToBall(p, 3));
      },
      /*mirror=*/true);
}

}  // namespace femreg
