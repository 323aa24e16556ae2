// Exact closest points: point-triangle (Voronoi regions, Ericson 2005 5.1.5), segment-segment
// (Ericson 5.1.9, parallel and degenerate segments) and triangle-triangle (edge-face
// intersection, else the best of 6 vertex-face and 9 edge-edge pairs).
#include <algorithm>
#include <cmath>
#include <limits>

#include "femreg/geometry.h"

namespace femreg {

Eigen::Vector3d TriangleClosestPoint(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                       const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                       Eigen::Vector3d* barycentric) {
  Eigen::Vector3d w;
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  auto done = [&](double u, double v, double t) {
    w = Eigen::Vector3d(u, v, t);
    if (barycentric) *barycentric = w;
    return Eigen::Vector3d(u * a + v * b + t * c);
  };
  if (d1 <= 0 && d2 <= 0) return done(1, 0, 0);
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return done(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0 && d1 - d3 > 0) {
    const double v = d1 / (d1 - d3);
    return done(1 - v, v, 0);
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return done(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0 && d2 - d6 > 0) {
    const double t = d2 / (d2 - d6);
    return done(1 - t, 0, t);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0 && (d4 - d3) + (d5 - d6) > 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return done(0, 1 - t, t);
  }
  const double sum = va + vb + vc;
  if (!(std::abs(sum) > 0)) {
    // Degenerate (collinear) triangle that fell through: best of its three edges.
    double best = std::numeric_limits<double>::infinity();
    Eigen::Vector3d best_w(1, 0, 0);
    const Eigen::Vector3d* v[3] = {&a, &b, &c};
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3;
      const Eigen::Vector3d e = *v[j] - *v[i];
      const double len2 = e.squaredNorm();
      const double s = len2 > 0 ? std::clamp((p - *v[i]).dot(e) / len2, 0.0, 1.0) : 0.0;
      const double d = (p - (*v[i] + s * e)).squaredNorm();
      if (d < best) {
        best = d;
        best_w.setZero();
        best_w[i] = 1 - s;
        best_w[j] = s;
      }
    }
    return done(best_w[0], best_w[1], best_w[2]);
  }
  const double denom = 1.0 / sum;
  const double v = vb * denom, t = vc * denom;
  return done(1 - v - t, v, t);
}

double ClosestSegmentSegment(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                             const Eigen::Vector3d& q0, const Eigen::Vector3d& q1, double* s_out,
                             double* t_out) {
  const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  const double tiny = 1e-30;
  double s = 0.0, t = 0.0;
  if (a <= tiny && e <= tiny) {
    s = t = 0.0;
  } else if (a <= tiny) {
    s = 0.0;
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= tiny) {
      t = 0.0;
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2);
      const double denom = a * e - b * b;  // >= 0; 0 when parallel
      // Parallel (relative to the lengths): any s works; take s = 0 and fix it up below.
      s = denom > 1e-14 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  if (s_out) *s_out = s;
  if (t_out) *t_out = t;
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

namespace {

// Where segment (p, q) crosses the face of triangle t (not in its plane), if it does.
bool SegmentThroughTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                            const Eigen::Vector3d* t, Eigen::Vector3d* hit) {
  const Eigen::Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]);
  const double nn = n.norm();
  if (!(nn > 0)) return false;
  const double dp = n.dot(p - t[0]) / nn, dq = n.dot(q - t[0]) / nn;
  if ((dp > 0 && dq > 0) || (dp < 0 && dq < 0) || dp == dq) return false;  // same side, or in plane
  const double s = dp / (dp - dq);
  const Eigen::Vector3d x = p + s * (q - p);
  // Inside test by the signs of the sub-triangle normals (edges included).
  const double scale = 1e-12 * nn;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d& a = t[i];
    const Eigen::Vector3d& b = t[(i + 1) % 3];
    if ((b - a).cross(x - a).dot(n) < -scale) return false;
  }
  *hit = x;
  return true;
}

}  // namespace

TrianglePairDistance TriangleTriangleDistance(const Eigen::Vector3d* t1, const Eigen::Vector3d* t2) {
  TrianglePairDistance r;
  // Intersection: an edge of one triangle through the other's face.
  for (int pass = 0; pass < 2; ++pass) {
    const Eigen::Vector3d* a = pass == 0 ? t1 : t2;
    const Eigen::Vector3d* b = pass == 0 ? t2 : t1;
    for (int i = 0; i < 3; ++i) {
      Eigen::Vector3d x;
      if (SegmentThroughTriangle(a[i], a[(i + 1) % 3], b, &x)) {
        r.intersecting = true;
        r.distance = 0.0;
        r.p = TriangleClosestPoint(x, t1[0], t1[1], t1[2], &r.bary_p);
        r.q = TriangleClosestPoint(x, t2[0], t2[1], t2[2], &r.bary_q);
        return r;
      }
    }
  }
  double best = std::numeric_limits<double>::infinity();
  // Vertex-face, both ways.
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d w;
    Eigen::Vector3d c = TriangleClosestPoint(t1[i], t2[0], t2[1], t2[2], &w);
    double d = (t1[i] - c).norm();
    if (d < best) {
      best = d;
      r.p = t1[i];
      r.bary_p = Eigen::Vector3d::Unit(i);
      r.q = c;
      r.bary_q = w;
    }
    c = TriangleClosestPoint(t2[i], t1[0], t1[1], t1[2], &w);
    d = (t2[i] - c).norm();
    if (d < best) {
      best = d;
      r.p = c;
      r.bary_p = w;
      r.q = t2[i];
      r.bary_q = Eigen::Vector3d::Unit(i);
    }
  }
  // Edge-edge.
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3;
      double s = 0, t = 0;
      const double d = ClosestSegmentSegment(t1[i], t1[i1], t2[j], t2[j1], &s, &t);
      if (d < best) {
        best = d;
        r.bary_p.setZero();
        r.bary_p[i] = 1 - s;
        r.bary_p[i1] = s;
        r.bary_q.setZero();
        r.bary_q[j] = 1 - t;
        r.bary_q[j1] = t;
        r.p = t1[i] + s * (t1[i1] - t1[i]);
        r.q = t2[j] + t * (t2[j1] - t2[j]);
      }
    }
  }
  r.distance = best;
  return r;
}

}  // namespace femreg
