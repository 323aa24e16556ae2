#include "registration/prediction.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace femreg {

Eigen::Vector3d TurnVisibility(const Vertices& x, const Triangles& tris, const Eigen::Vector3d& c,
                               Eigen::Matrix3d* axes) {
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero(), N = Eigen::Matrix3d::Zero();
  for (int f = 0; f < tris.rows(); ++f) {
    const Eigen::Vector3d a = x.row(tris(f, 0)), b = x.row(tris(f, 1)), d = x.row(tris(f, 2));
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

// The predicted turn of object o's vertices [begin, end) that its surface does not show,
// taken out of *predicted: the least-squares rigid velocity (v, w) of the step d = x -
// x_before about the mass centre c; w's component along each hidden axis (in N's metric)
// is turned back about the predicted centre.
void TakeOutHiddenTurn(const TrackerState& state, int o, Vertices* predicted) {
  const ObjectState& object = state.objects[static_cast<size_t>(o)];
  const int begin = object.offset, n = object.mesh.num_vertices();
  double mass = 0.0;
  Eigen::Vector3d c = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
  for (int i = begin; i < begin + n; ++i) {
    const double m = state.mass(i);
    mass += m;
    c += m * state.x.row(i).transpose();
    v += m * (state.x.row(i) - state.x_before.row(i)).transpose();
  }
  if (!(mass > 0)) return;
  c /= mass;
  v /= mass;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  for (int i = begin; i < begin + n; ++i) {
    const double m = state.mass(i);
    const Eigen::Vector3d r = state.x.row(i).transpose() - c;
    const Eigen::Vector3d d = (state.x.row(i) - state.x_before.row(i)).transpose() - v;
    inertia += m * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
    moment += m * r.cross(d);
  }
  const Eigen::Vector3d w = inertia.ldlt().solve(moment);
  if (!w.allFinite() || w.isZero(0.0)) return;

  Eigen::Matrix3d axes;
  const Triangles tris = state.ObjectSurface(o);
  const Eigen::Vector3d visibility = TurnVisibility(state.x, tris, c, &axes);
  // w = sum_k a_k axes_k with a = axes^-1 w; the hidden part of each a_k is dropped.
  const Eigen::Vector3d a = axes.partialPivLu().solve(w);
  Eigen::Vector3d hidden = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    const double keep = std::min(1.0, visibility(k) / kVisibleTurn);
    hidden += (1.0 - keep) * a(k) * axes.col(k);
  }
  const double angle = hidden.norm();
  if (!(angle > 0) || !std::isfinite(angle)) return;
  const Eigen::Matrix3d undo = Eigen::AngleAxisd(-angle, hidden / angle).toRotationMatrix();
  const Eigen::Vector3d centre = c + v;  // where the prediction puts the mass centre
  for (int i = begin; i < begin + n; ++i) {
    const Eigen::Vector3d p = predicted->row(i).transpose() - centre;
    predicted->row(i) = (centre + undo * p).transpose();
  }
}

}  // namespace

Vertices PredictMotion(const TrackerState& state) {
  Vertices predicted = 2.0 * state.x - state.x_before;
  if (FractureLive(state)) return predicted;  // pieces turn as they part: their own pre-alignment
  for (size_t o = 0; o < state.objects.size(); ++o) {
    bool held = false;
    for (const auto& [name, anchor] : state.anchors) held = held || anchor.object == static_cast<int>(o);
    if (!held) TakeOutHiddenTurn(state, static_cast<int>(o), &predicted);
  }
  return predicted;
}

}  // namespace femreg
