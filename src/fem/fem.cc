#include "femreg/fem.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <sstream>

#include "fem/twist_matrix.h"
#include "parallel/pool.h"

namespace femreg {

bool Material::IsValid(std::string* error) const {
  // "poisson_ratio must be in (-1, 0.5) (got 0.5)", the field's name first: the scene parser
  // puts the message at that key's line (scene/parse_objects.cc).
  return CheckFieldRanges(*this, error);
}

const Material& ObjectMaterial::ForRegion(int region) const {
  for (const auto& r : regions) {
    if (r.first == region) return r.second;
  }
  return material;
}

bool ObjectMaterial::IsValid(std::string* error) const {
  std::string e;
  if (!material.IsValid(&e)) {
    if (error) *error = e;
    return false;
  }
  for (size_t i = 0; i < regions.size(); ++i) {
    if (!regions[i].second.IsValid(&e)) {
      if (error) {
        *error = "regions[" + std::to_string(i) + "] (region " + std::to_string(regions[i].first) +
                 "): " + e;
      }
      return false;
    }
  }
  return true;
}

const char* ToString(ElasticModelType type) {
  switch (type) {
    case ElasticModelType::kCorotational:
      return "corotational";
    case ElasticModelType::kLinear:
      return "linear";
    case ElasticModelType::kNeoHookean:
      return "neo_hookean";
  }
  return "unknown";
}

bool FromString(const std::string& name, ElasticModelType* type) {
  if (name == "corotational") {
    *type = ElasticModelType::kCorotational;
  } else if (name == "linear") {
    *type = ElasticModelType::kLinear;
  } else if (name == "neo_hookean") {
    *type = ElasticModelType::kNeoHookean;
  } else {
    return false;
  }
  return true;
}

const char* ToString(MaterialModel model) {
  switch (model) {
    case MaterialModel::kHooke:
      return "hooke";
    case MaterialModel::kNeoHookean:
      return "neo_hookean";
  }
  return "unknown";
}

bool FromString(const std::string& name, MaterialModel* model) {
  if (name == "hooke") {
    *model = MaterialModel::kHooke;
  } else if (name == "neo_hookean") {
    *model = MaterialModel::kNeoHookean;
  } else {
    return false;
  }
  return true;
}

const char* ToString(MaterialVolume volume) {
  return volume == MaterialVolume::kNodal ? "nodal" : "element";
}

bool FromString(const std::string& name, MaterialVolume* volume) {
  if (name != "element" && name != "nodal") return false;
  *volume = name == "nodal" ? MaterialVolume::kNodal : MaterialVolume::kElement;
  return true;
}

Matrix6 IsotropicElasticity(double E, double nu) {
  const double lambda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  const double mu = E / (2.0 * (1.0 + nu));
  Matrix6 C = Matrix6::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) C(i, j) = lambda;
    C(i, i) = lambda + 2.0 * mu;
    C(i + 3, i + 3) = mu;
  }
  return C;
}

ElementRest BuildElementRest(const Eigen::Matrix<double, 3, 4>& X, const Material& material) {
  ElementRest r;
  Eigen::Matrix3d Dm;
  Dm << X.col(1) - X.col(0), X.col(2) - X.col(0), X.col(3) - X.col(0);
  r.volume = std::abs(Dm.determinant()) / 6.0;
  r.dm_inv = Dm.inverse();
  const Matrix6 C = IsotropicElasticity(material.youngs_modulus, material.poisson_ratio);
  r.lambda = C(0, 1);
  r.mu = C(3, 3);
  for (int i = 0; i < 4; ++i) r.X.segment<3>(3 * i) = X.col(i);
  return r;
}

Matrix6x12 StrainDisplacement(const ElementRest& rest) {
  const Eigen::Matrix<double, 3, 4> grad = ShapeGradients(rest);
  Matrix6x12 L = Matrix6x12::Zero();
  for (int i = 0; i < 4; ++i) {
    const double gx = grad(0, i), gy = grad(1, i), gz = grad(2, i);
    const int c = 3 * i;
    L(0, c + 0) = gx;
    L(1, c + 1) = gy;
    L(2, c + 2) = gz;
    L(3, c + 1) = gz;
    L(3, c + 2) = gy;
    L(4, c + 0) = gz;
    L(4, c + 2) = gx;
    L(5, c + 0) = gy;
    L(5, c + 1) = gx;
  }
  return L;
}

Matrix6 HookeMatrix(const ElementRest& rest) {
  Matrix6 C = Matrix6::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) C(i, j) = rest.lambda;
    C(i, i) = rest.lambda + 2.0 * rest.mu;
    C(i + 3, i + 3) = rest.mu;
  }
  return C;
}

Matrix12 ElementStiffness(const ElementRest& rest) {
  const Matrix6x12 L = StrainDisplacement(rest);
  return rest.volume * L.transpose() * HookeMatrix(rest) * L;
}

Matrix6x12 ElementResidualMatrix(const ElementRest& rest) {
  // C's symmetric square root in closed form: on the normal strains C = lambda 1 1^T + 2 mu I
  // (eigenvalues 3 lambda + 2 mu along 1 and 2 mu across it), on the shears mu I.
  const double across = std::sqrt(std::max(0.0, 2.0 * rest.mu));
  const double along = std::sqrt(std::max(0.0, 3.0 * rest.lambda + 2.0 * rest.mu));
  Matrix6 C_half = Matrix6::Zero();
  C_half.topLeftCorner<3, 3>().setConstant((along - across) / 3.0);
  C_half.topLeftCorner<3, 3>().diagonal().array() += across;
  C_half.bottomRightCorner<3, 3>().diagonal().setConstant(std::sqrt(std::max(0.0, rest.mu)));
  return std::sqrt(rest.volume) * C_half * StrainDisplacement(rest);
}

Eigen::Matrix3d PolarRotation(const Eigen::Matrix3d& F) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU();
  Eigen::Matrix3d V = svd.matrixV();
  // Irving et al. 2004: make U and V proper rotations; the sign goes to the smallest
  // singular value, so an inverted element keeps the rotation nearest to F.
  if (U.determinant() < 0) U.col(2) *= -1.0;
  if (V.determinant() < 0) V.col(2) *= -1.0;
  Eigen::Matrix3d R = U * V.transpose();
  if (!R.allFinite()) R.setIdentity();
  return R;
}

// The warm-started polar rotation's Newton steps stop once the angle left is surely below this
// (rad): far below what moves a force or an energy.
constexpr double kPolarTolerance = 1e-10;

Eigen::Matrix3d PolarRotation(const Eigen::Matrix3d& F, const Eigen::Matrix3d& start) {
  // Newton's method on SO(3) for the R that maximizes f(R) = tr(R^T F), R <- R exp([w]):
  // with A = R^T F, f(R exp([w])) = f(R) + g.w - 1/2 w^T M w + O(|w|^3), where
  // g = 2 axial(skew(A)) and M = tr(A) I - sym(A), so w = M^-1 g. At the maximum A = R^T F
  // is symmetric (the stretch S) and M's eigenvalues are the sums of pairs of its
  // eigenvalues, s1 + s2, s1 + s3, s2 + s3 with s3 < 0 for an inverted F: M is positive
  // definite, and the maximum unique, unless an inverted F has s2 = |s3| (then the SVD's
  // choice is as good as any other, and is taken).
  if (!F.allFinite()) return PolarRotation(F);
  const double scale = F.cwiseAbs().maxCoeff();
  if (scale == 0.0) return PolarRotation(F);
  // The 3x3 algebra below is written out (M's leading minors, its adjugate, the quaternion
  // rotation): this runs for every element in every outer iteration. No square root and two
  // divisions per step (docs/notes/2026-11-28-figures-from-code-comments.md).
  const double min_pivot = 1e-4 * scale;  // M's pivots >= this (Cholesky diagonal >= 1e-2 sqrt(scale))
  Eigen::Matrix3d R = start;
  for (int iteration = 0; iteration < 12; ++iteration) {
    const Eigen::Matrix3d A = R.transpose() * F;
    const double g0 = A(2, 1) - A(1, 2), g1 = A(0, 2) - A(2, 0), g2 = A(1, 0) - A(0, 1);
    // M = tr(A) I - sym(A) must be well inside the positive definite cone: its pivots (the
    // ratios of its leading principal minors), relative to F's size, say how far (an
    // inverted element near the tie, or a start past a saddle).
    const TwistMatrix m(A);
    if (!m.PivotsAtLeast(min_pivot)) return PolarRotation(F);
    const double c00 = m.c00, c11 = m.c11, c22 = m.c22, c10 = m.c10, c20 = m.c20, c21 = m.c21;
    const double det = m.det;
    // w = M^-1 g = adj(M) g / det(M).
    const double inv_det = 1.0 / det;
    const double w0 = (c00 * g0 + c10 * g1 + c20 * g2) * inv_det;
    const double w1 = (c10 * g0 + c11 * g1 + c21 * g2) * inv_det;
    const double w2 = (c20 * g0 + c21 * g1 + c22 * g2) * inv_det;
    const double angle2 = w0 * w0 + w1 * w1 + w2 * w2;
    if (!(angle2 < 1.0)) return PolarRotation(F);  // far from the start: Newton's basin unclear
    if (angle2 > 0.0) {
      // R <- R Q(w), Q the rotation of the unit quaternion (1, w/2)/|(1, w/2)|: Q = I + a W +
      // b W^2 with W^2 = w w^T - |w|^2 I, a = 1/n^2, b = 1/(2 n^2), n^2 = 1 + |w|^2/4. It agrees
      // with exp([w]) (a = sin t/t, b = (1 - cos t)/t^2) to second order, so the steps still
      // converge quadratically, is orthogonal for any w, and needs no sine or cosine.
      const double a = 1.0 / (1.0 + 0.25 * angle2), b = 0.5 * a;
      Eigen::Matrix3d E;
      E << 1.0 + b * (w0 * w0 - angle2), b * w0 * w1 - a * w2, b * w0 * w2 + a * w1,
          b * w1 * w0 + a * w2, 1.0 + b * (w1 * w1 - angle2), b * w1 * w2 - a * w0,
          b * w2 * w0 - a * w1, b * w2 * w1 + a * w0, 1.0 + b * (w2 * w2 - angle2);
      R = (R * E).eval();
    }
    // The steps converge cubically: the angle left after a step w is a fraction of
    // |A| / lambda_min(M) |w|^3, so with |A| <= 3 max|F_ij| and lambda_min(M) >=
    // det M / tr(adj M) it is below max|F_ij| tr(adj M) / det M |w|^3. Stop once that is below
    // kPolarTolerance, not once the step itself is: that takes one or two more steps
    // (docs/notes/2026-12-06-polar-rotation-stop.md).
    const double ratio = scale * (c00 + c11 + c22) * inv_det;
    if (angle2 * angle2 * angle2 * ratio * ratio <= kPolarTolerance * kPolarTolerance) {
      // One Newton-Schulz step restores orthonormality to round-off (the products above
      // drift by an ulp each, and warm starts chain them frame after frame).
      return R * (1.5 * Eigen::Matrix3d::Identity() - 0.5 * R.transpose() * R);
    }
  }
  return PolarRotation(F);
}

Eigen::Matrix3d DeformationGradient(const Eigen::Matrix<double, 3, 4>& x,
                                    const Eigen::Matrix3d& dm_inv) {
  Eigen::Matrix3d Ds;
  Ds << x.col(1) - x.col(0), x.col(2) - x.col(0), x.col(3) - x.col(0);
  return Ds * dm_inv;
}

namespace {
Vector12 RotatedDisplacement(const ElementRest& rest, const Eigen::Matrix3d& R,
                             const Vector12& x) {
  Vector12 u;
  for (int i = 0; i < 4; ++i) {
    u.segment<3>(3 * i) = R.transpose() * x.segment<3>(3 * i) - rest.X.segment<3>(3 * i);
  }
  return u;
}
}  // namespace

Vector6 ElementResidual(const ElementRest& rest, const Eigen::Matrix3d& R, const Vector12& x) {
  return ElementResidualMatrix(rest) * RotatedDisplacement(rest, R, x);
}

double ElementEnergy(const ElementRest& rest, const Eigen::Matrix3d& R, const Vector12& x) {
  return 0.5 * ElementResidual(rest, R, x).squaredNorm();
}

Vector12 ElementForce(const ElementRest& rest, const Eigen::Matrix3d& R, const Vector12& x) {
  Vector12 f;
  ElementEnergyAndForce(rest, R, x, &f);
  return f;
}

// R K_ij R^T of the isotropic element (BuildElementRest's C is isotropic) from its shape
// gradients: block (i, j) is V (lambda c_i c_j^T + mu c_j c_i^T + mu (b_i . b_j) I) with
// c_i = R b_i, a third of the products of rotating K's blocks.
Matrix12 WarpedStiffness(const ElementRest& rest, const Eigen::Matrix3d& R) {
  Eigen::Matrix<double, 4, 3> b;
  b.bottomRows<3>() = rest.dm_inv;
  b.row(0) = -(rest.dm_inv.row(0) + rest.dm_inv.row(1) + rest.dm_inv.row(2));
  const Eigen::Matrix<double, 4, 3> c = b * R.transpose();  // row i: (R b_i)^T
  const Eigen::Matrix4d dots = b * b.transpose();
  const double Vmu = rest.volume * rest.mu, Vlambda = rest.volume * rest.lambda;
  Matrix12 out;
  for (int i = 0; i < 4; ++i) {
    for (int j = i; j < 4; ++j) {
      Eigen::Matrix3d block = Vlambda * c.row(i).transpose() * c.row(j);
      block.noalias() += Vmu * c.row(j).transpose() * c.row(i);
      block.diagonal().array() += Vmu * dots(i, j);
      out.block<3, 3>(3 * i, 3 * j) = block;
      if (j != i) out.block<3, 3>(3 * j, 3 * i) = block.transpose();
    }
  }
  return out;
}

Eigen::Matrix<double, 6, 3> ElementResidualJacobianBlock(const ElementRest& rest,
                                                         const Eigen::Matrix3d& R, int i) {
  return ElementResidualMatrix(rest).block<6, 3>(0, 3 * i) * R.transpose();
}

Matrix6x12 ElementResidualJacobian(const ElementRest& rest, const Eigen::Matrix3d& R) {
  const Matrix6x12 S = ElementResidualMatrix(rest);
  Matrix6x12 J;
  for (int i = 0; i < 4; ++i) J.block<6, 3>(0, 3 * i) = S.block<6, 3>(0, 3 * i) * R.transpose();
  return J;
}

Vector6 ElementStress(const ElementRest& rest, const Eigen::Matrix3d& R, const Vector12& x) {
  return HookeMatrix(rest) * (StrainDisplacement(rest) * RotatedDisplacement(rest, R, x));
}

void ElasticModel::Build(const TetMesh& mesh, ElasticModelType type,
                         const ObjectMaterial& material) {
  Build(mesh, material.model == MaterialModel::kNeoHookean ? ElasticModelType::kNeoHookean : type,
        material.material, material.regions);
  nodal_volume_ = type_ == ElasticModelType::kNeoHookean && material.nodal_volume;
}

void ElasticModel::Build(const TetMesh& mesh, ElasticModelType type,
                         const Material& default_material,
                         const std::vector<std::pair<int, Material>>& material_per_region) {
  type_ = type;
  nodal_volume_ = false;
  default_material_ = default_material;
  material_per_region_ = material_per_region;
  tets_ = mesh.tets;
  rest_.assign(mesh.num_tets(), ElementRest());
  rotations_.assign(mesh.num_tets(), Eigen::Matrix3d::Identity());
  std::vector<int> all(mesh.num_tets());
  for (int e = 0; e < mesh.num_tets(); ++e) all[e] = e;
  RebuildElements(mesh, all);
}

void ElasticModel::RebuildElements(const TetMesh& mesh, const std::vector<int>& elements) {
  if (tets_.rows() != mesh.tets.rows()) {
    tets_ = mesh.tets;
    rest_.resize(mesh.num_tets());
    rotations_.resize(mesh.num_tets(), Eigen::Matrix3d::Identity());
  }
  for (int e : elements) {
    tets_.row(e) = mesh.tets.row(e);
    Material material = default_material_;
    for (const auto& rm : material_per_region_) {
      if (e < mesh.region.size() && rm.first == mesh.region(e)) material = rm.second;
    }
    Eigen::Matrix<double, 3, 4> X;
    for (int k = 0; k < 4; ++k) X.col(k) = mesh.rest.row(mesh.tets(e, k)).transpose();
    rest_[e] = BuildElementRest(X, material);
    rotations_[e].setIdentity();
  }
}

void ElasticModel::RemapElements(const TetMesh& mesh, const std::vector<int>& old_element,
                                 const std::vector<int>& touched) {
  std::vector<ElementRest> rest(old_element.size());
  std::vector<Eigen::Matrix3d> rotations(old_element.size());
  for (size_t i = 0; i < old_element.size(); ++i) {
    rest[i] = rest_[old_element[i]];
    rotations[i] = rotations_[old_element[i]];
  }
  rest_ = std::move(rest);
  rotations_ = std::move(rotations);
  tets_ = mesh.tets;
  RebuildElements(mesh, touched);
}

Vector12 ElasticModel::Gather(const Vertices& x, int e) const {
  Vector12 xe;
  for (int k = 0; k < 4; ++k) xe.segment<3>(3 * k) = x.row(tets_(e, k)).transpose();
  return xe;
}

void ElasticModel::UpdateRotations(const Vertices& x) {
  if (type_ == ElasticModelType::kLinear) return;
  const int n = num_elements();
  // A team only from 1024 elements on: below, its start costs more than the polar steps
  // (docs/notes/2026-11-29-threads.md).
  ParallelFor(0, n, 512, [&](int64_t e) {
    Eigen::Matrix<double, 3, 4> xe;
    for (int k = 0; k < 4; ++k) xe.col(k) = x.row(tets_(e, k)).transpose();
    // Warm-started from the rotation before: a few Newton steps instead of an SVD.
    rotations_[e] = PolarRotation(DeformationGradient(xe, rest_[e].dm_inv), rotations_[e]);
  });
}

double ElasticModel::Energy(const Vertices& x) const {
  double total = 0.0;
  Vector12 unused;
  for (int e = 0; e < num_elements(); ++e) {
    total += type_ == ElasticModelType::kNeoHookean
                 ? NeoHookeanEnergyAndForce(rest_[e], NeoHookeanKappa(rest_[e], false), 0.0,
                                            Gather(x, e), &unused)
                 : ElementEnergy(rest_[e], rotations_[e], Gather(x, e));
  }
  return total;
}

void ElasticModel::AddGradient(const Vertices& x, Vertices* gradient) const {
  for (int e = 0; e < num_elements(); ++e) {
    Vector12 f;
    if (type_ == ElasticModelType::kNeoHookean) {
      NeoHookeanEnergyAndForce(rest_[e], NeoHookeanKappa(rest_[e], false), 0.0, Gather(x, e), &f);
    } else {
      f = ElementForce(rest_[e], rotations_[e], Gather(x, e));
    }
    for (int k = 0; k < 4; ++k) gradient->row(tets_(e, k)) -= f.segment<3>(3 * k).transpose();
  }
}

void ElasticModel::AddStiffnessTriplets(std::vector<Eigen::Triplet<double>>* triplets) const {
  triplets->reserve(triplets->size() + 144 * static_cast<size_t>(num_elements()));
  for (int e = 0; e < num_elements(); ++e) {
    const Matrix12 K = WarpedStiffness(rest_[e], rotations_[e]);
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        const int ra = 3 * tets_(e, a), cb = 3 * tets_(e, b);
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) triplets->emplace_back(ra + i, cb + j, K(3 * a + i, 3 * b + j));
      }
    }
  }
}

SignedSvd SignedSingularValueDecomposition(const Eigen::Matrix3d& F) {
  SignedSvd out;
  if (!F.allFinite()) return out;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  out.U = svd.matrixU();
  out.V = svd.matrixV();
  out.sigma = svd.singularValues();
  // As PolarRotation: a reflection in U or V moves to the smallest singular value.
  if (out.U.determinant() < 0) {
    out.U.col(2) *= -1.0;
    out.sigma(2) *= -1.0;
  }
  if (out.V.determinant() < 0) {
    out.V.col(2) *= -1.0;
    out.sigma(2) *= -1.0;
  }
  return out;
}

double ElementEnergyAndForce(const ElementRest& rest, const Eigen::Matrix3d& R,
                             const Vector12& x, Vector12* force) {
  const Vector12 u = RotatedDisplacement(rest, R, x);
  // K u = V L^T C L u from the shape gradients b_i, as ElasticElement::Normal: the small strain
  // e = sym(sum_i u_i b_i^T), the stress P = 2 mu e + lambda tr(e) I, and (K u)_i = V P b_i.
  const Eigen::Matrix<double, 3, 4> b = ShapeGradients(rest);
  Eigen::Matrix3d e = Eigen::Map<const Eigen::Matrix<double, 3, 4>>(u.data()) * b.transpose();
  e = (0.5 * (e + e.transpose())).eval();
  Eigen::Matrix3d P = 2.0 * rest.mu * e;
  P.diagonal().array() += rest.lambda * e.trace();
  Vector12 ku;
  Eigen::Map<Eigen::Matrix<double, 3, 4>>(ku.data()) = rest.volume * P * b;
  for (int i = 0; i < 4; ++i) force->segment<3>(3 * i) = -R * ku.segment<3>(3 * i);
  return 0.5 * u.dot(ku);
}

}  // namespace femreg
