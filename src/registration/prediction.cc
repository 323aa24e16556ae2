#include "registration/prediction.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "geometry/nearest.h"
#include "parallel/pool.h"
#include "parallel/threads.h"

namespace femreg {

Eigen::Vector3d TurnVisibility(const Vertices& x, const Eigen::Ref<const Triangles>& tris, const Eigen::Vector3d& c,
                               Eigen::Matrix3d* axes, int offset) {
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero(), N = Eigen::Matrix3d::Zero();
  for (int f = 0; f < tris.rows(); ++f) {
    const Eigen::Vector3d a = x.row(offset + tris(f, 0)), b = x.row(offset + tris(f, 1)),
                          d = x.row(offset + tris(f, 2));
    const Eigen::Vector3d an = (b - a).cross(d - a);  // twice the area times the normal
    const double area2 = an.norm();
    if (!(area2 > 0)) continue;
    const Eigen::Vector3d r = (a + b + d) / 3.0 - c;
    const Eigen::Vector3d g = r.cross(an / area2);
    M += area2 * g * g.transpose();
    N += area2 * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
  }
  // N is positive definite for any surface not on one line through c.
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix3d> eig(M, N);
  if (eig.info() != Eigen::Success) {
    if (axes) *axes = Eigen::Matrix3d::Identity();
    return Eigen::Vector3d::Ones();
  }
  if (axes) *axes = eig.eigenvectors();
  return eig.eigenvalues().cwiseMax(0.0).cwiseMin(1.0);
}

namespace {

bool Held(const TrackerState& state, int o) {
  for (const auto& [name, anchor] : state.anchors) {
    if (anchor.object == o) return true;
  }
  return false;
}

// Object o's vertices of *x turned by -turn (a rotation vector) about centre; false when the
// turn is zero.
bool TurnBack(const TrackerState& state, int o, const Eigen::Vector3d& turn, const Eigen::Vector3d& centre,
              Vertices* x) {
  const double angle = turn.norm();
  if (!(angle > 0) || !std::isfinite(angle)) return false;
  const Eigen::Matrix3d undo = Eigen::AngleAxisd(-angle, turn / angle).toRotationMatrix();
  const ObjectState& object = state.objects[static_cast<size_t>(o)];
  for (int i = object.offset; i < object.offset + object.mesh.num_vertices(); ++i) {
    const Eigen::Vector3d p = x->row(i).transpose() - centre;
    x->row(i) = (centre + undo * p).transpose();
  }
  return true;
}

// TurnVisibility of object o at x about c, on the surface the data see: its embedded
// surface's where it has one (`data` may be null), else its mesh's.
Eigen::Vector3d ObjectTurnVisibility(const TrackerState& state, int o, const Vertices& x, const Eigen::Vector3d& c,
                                     DataSurface* data, Eigen::Matrix3d* axes) {
  if (data != nullptr && data->embedded(o)) return TurnVisibility(data->Update(x).x, data->ObjectTriangles(o), c, axes);
  const ObjectState& object = state.objects[static_cast<size_t>(o)];
  return TurnVisibility(x, object.mesh.surface, c, axes, object.offset);
}

}  // namespace

HiddenTurn FindHiddenTurn(const TrackerState& state, int o, const Vertices& from, const Vertices& to,
                          DataSurface* data) {
  HiddenTurn out;
  const ObjectState& object = state.objects[static_cast<size_t>(o)];
  const int begin = object.offset, n = object.mesh.num_vertices();
  double mass = 0.0;
  Eigen::Vector3d c = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
  for (int i = begin; i < begin + n; ++i) {
    const double m = state.mass(i);
    mass += m;
    c += m * to.row(i).transpose();
    v += m * (to.row(i) - from.row(i)).transpose();
  }
  if (!(mass > 0)) return out;
  c /= mass;
  v /= mass;
  out.centre = c;
  out.velocity = v;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  for (int i = begin; i < begin + n; ++i) {
    const double m = state.mass(i);
    const Eigen::Vector3d r = to.row(i).transpose() - c;
    const Eigen::Vector3d d = (to.row(i) - from.row(i)).transpose() - v;
    inertia += m * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
    moment += m * r.cross(d);
  }
  const Eigen::Vector3d w = inertia.ldlt().solve(moment);
  if (!w.allFinite() || w.isZero(0.0)) return out;

  Eigen::Matrix3d axes;
  const Eigen::Vector3d visibility = ObjectTurnVisibility(state, o, to, c, data, &axes);
  // w = sum_k a_k axes_k with a = axes^-1 w; the hidden part of each a_k is kept.
  const Eigen::Vector3d a = axes.partialPivLu().solve(w);
  for (int k = 0; k < 3; ++k) {
    const double keep = std::min(1.0, visibility(k) / kVisibleTurn);
    out.turn += (1.0 - keep) * a(k) * axes.col(k);
  }
  if (!out.turn.allFinite()) out.turn.setZero();
  return out;
}

bool HoldHiddenTurns(const TrackerState& state, const Vertices& from, Vertices* x, DataSurface* data) {
  if (FractureLive(state)) return false;
  bool turned = false;
  for (size_t o = 0; o < state.objects.size(); ++o) {
    if (Held(state, static_cast<int>(o))) continue;
    const HiddenTurn h = FindHiddenTurn(state, static_cast<int>(o), from, *x, data);
    turned = TurnBack(state, static_cast<int>(o), h.turn, h.centre, x) || turned;
  }
  return turned;
}

std::vector<Eigen::Vector3d> HiddenTurnAxes(const TrackerState& state, int o, const Vertices& x, DataSurface* data) {
  std::vector<Eigen::Vector3d> hidden;
  if (FractureLive(state) || Held(state, o)) return hidden;
  const ObjectState& object = state.objects[static_cast<size_t>(o)];
  const int begin = object.offset, n = object.mesh.num_vertices();
  double mass = 0.0;
  Eigen::Vector3d c = Eigen::Vector3d::Zero(), centroid = Eigen::Vector3d::Zero();
  for (int i = begin; i < begin + n; ++i) {
    mass += state.mass(i);
    c += state.mass(i) * x.row(i).transpose();
    centroid += x.row(i).transpose();
  }
  if (!(mass > 0) || n < 2) return hidden;
  c /= mass;
  centroid /= static_cast<double>(n);
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (int i = begin; i < begin + n; ++i) {
    const Eigen::Vector3d r = x.row(i).transpose() - centroid;
    inertia += r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose();
  }
  Eigen::Matrix3d axes;
  const Eigen::Vector3d visibility = ObjectTurnVisibility(state, o, x, c, data, &axes);
  // A rigid move with turn w has sum_v r_v x d_v = I w, and FindHiddenTurn's component k of w
  // is e_k^T axes^-1 w = c_k^T I w with c_k = I^-1 axes^-T e_k.
  const Eigen::Matrix3d dual = inertia.ldlt().solve(axes.transpose().partialPivLu().solve(Eigen::Matrix3d::Identity()));
  for (int k = 0; k < 3; ++k) {
    if (visibility(k) < 0.5 * kVisibleTurn && dual.col(k).allFinite()) hidden.push_back(dual.col(k));
  }
  return hidden;
}

Vertices PredictMotion(const TrackerState& state, DataSurface* data) {
  Vertices predicted = 2.0 * state.x - state.x_before;
  if (FractureLive(state)) return predicted;  // pieces turn as they part: their own pre-alignment
  for (size_t o = 0; o < state.objects.size(); ++o) {
    if (Held(state, static_cast<int>(o))) continue;
    const HiddenTurn h = FindHiddenTurn(state, static_cast<int>(o), state.x_before, state.x, data);
    TurnBack(state, static_cast<int>(o), h.turn, h.centre + h.velocity, &predicted);  // the predicted centre
  }
  return predicted;
}

double StartMisfit(const TrackerState& state, const Vertices& x, const Vertices& points, double gate,
                   DataSurface* data) {
  const int nv = static_cast<int>(data != nullptr ? data->view().surface_vertices.size() : state.surface_vertices.size());
  const int np = static_cast<int>(points.rows());
  if (nv == 0 || np == 0) return 0.0;
  Vertices surface;
  if (data != nullptr) {
    surface = data->PairVerticesAt(x);  // the subsample only: not the whole scan
  } else {
    surface.resize(nv, 3);
    for (int i = 0; i < nv; ++i) surface.row(i) = x.row(state.surface_vertices[static_cast<size_t>(i)]);
  }
  const PointIndex index(surface);
  const double cap2 = gate > 0 ? gate * gate : std::numeric_limits<double>::infinity();
  std::vector<double> d2(static_cast<size_t>(np), 0.0);
  ParallelFor(0, np, 256, [&](int64_t i) { index.Nearest(points.row(i), &d2[static_cast<size_t>(i)]); });
  double sum = 0.0;  // in the points' order: the same on any thread count
  for (int i = 0; i < np; ++i) sum += std::min(d2[static_cast<size_t>(i)], cap2);
  return sum / static_cast<double>(np);
}

}  // namespace femreg
