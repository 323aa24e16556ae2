// M = tr(A) I - sym(A) of a 3x3 A, written out: the polar rotation's Newton matrix (A = R^T F)
// and the corotational tangent's twist matrix (at the polar rotation, where A is symmetric).
#ifndef FEMREG_FEM_TWIST_MATRIX_H_
#define FEMREG_FEM_TWIST_MATRIX_H_

#include <Eigen/Core>

namespace femreg {

struct TwistMatrix {
  explicit TwistMatrix(const Eigen::Matrix3d& A) {
    const double trace = A.trace();
    m00 = trace - A(0, 0);
    m11 = trace - A(1, 1);
    m22 = trace - A(2, 2);
    m10 = -0.5 * (A(1, 0) + A(0, 1));
    m20 = -0.5 * (A(2, 0) + A(0, 2));
    m21 = -0.5 * (A(2, 1) + A(1, 2));
    c00 = m11 * m22 - m21 * m21;
    c11 = m00 * m22 - m20 * m20;
    c22 = m00 * m11 - m10 * m10;
    c10 = m21 * m20 - m10 * m22;
    c20 = m10 * m21 - m11 * m20;
    c21 = m10 * m20 - m00 * m21;
    det = m00 * c00 + m10 * c10 + m20 * c20;
  }
  // Well inside the positive definite cone: its pivots (the ratios of its leading principal
  // minors m00, c22, det) at least min_pivot. False on NaN.
  bool PivotsAtLeast(double min_pivot) const {
    return m00 >= min_pivot && c22 >= min_pivot * m00 && det >= min_pivot * c22;
  }
  // M's entries (m10 = M(1, 0), ...), its adjugate's (c00 = adj(M)(0, 0), ...), det M.
  double m00, m11, m22, m10, m20, m21;
  double c00, c11, c22, c10, c20, c21, det;
};

}  // namespace femreg

#endif  // FEMREG_FEM_TWIST_MATRIX_H_
