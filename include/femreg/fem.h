// femreg/fem.h - linear tetrahedral FEM: isotropic material, per-element rest data, the
// corotational element (docs/theory/corotational.md) and the small-strain linear element.
#ifndef FEMREG_FEM_H_
#define FEMREG_FEM_H_

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <string>
#include <utility>
#include <vector>

#include "femreg/field_table.h"
#include "femreg/mesh.h"

namespace femreg {

struct Material {
  double youngs_modulus = 1.0e5;  // E, Pa; > 0
  double poisson_ratio = 0.3;     // nu; in (-1, 0.5)
  double density = 1000.0;        // kg/m^3; > 0
  bool IsValid(std::string* error) const;
};

// A material's keys (an object's `material:`, a region's, synth's ground truth's).
template <>
struct OptionFields<Material> {
  static constexpr const char* kSection = "";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = Material;
    v(&S::youngs_modulus, FieldInfo("youngs_modulus").Above(0).Doc("E (Pa)"));
    v(&S::poisson_ratio, FieldInfo("poisson_ratio").Above(-1).Below(0.5).Doc("nu, in (-1, 0.5)"));
    v(&S::density, FieldInfo("density").Above(0).Doc("kg/m^3"));
  }
};

// The constitutive law of an object's elements.
enum class MaterialModel {
  kHooke,       // linear elasticity: the corotational (or small-strain linear) element
  kNeoHookean,  // the stable neo-Hookean element (below): large strain, nu -> 0.5
};
const char* ToString(MaterialModel model);
bool FromString(const std::string& name, MaterialModel* model);
template <>
struct EnumValues<MaterialModel> {
  static constexpr std::array<MaterialModel, 2> kAll = {MaterialModel::kHooke, MaterialModel::kNeoHookean};
};

// Where an object's volumetric energy lives: in each element, or on the vertices' volumes
// (ObjectMaterial::nodal_volume below; neo-Hookean only).
enum class MaterialVolume { kElement, kNodal };
const char* ToString(MaterialVolume volume);
bool FromString(const std::string& name, MaterialVolume* volume);
template <>
struct EnumValues<MaterialVolume> {
  static constexpr std::array<MaterialVolume, 2> kAll = {MaterialVolume::kElement, MaterialVolume::kNodal};
};

// The materials of one object: one for every element, or per region (the mesh's element
// tags) with a default for the regions not listed.
struct ObjectMaterial {
  Material material;                              // elements of regions not listed
  std::vector<std::pair<int, Material>> regions;  // region id -> material
  MaterialModel model = MaterialModel::kHooke;    // one law for the whole object
  // kNeoHookean only: the volumetric energy on the vertices' volumes (a quarter of each
  // element around a vertex) instead of each element's, against the locking of linear
  // tetrahedra as nu -> 0.5 (see NodalVolume below). The forward solve only.
  bool nodal_volume = false;
  ObjectMaterial() = default;
  ObjectMaterial(const Material& m) : material(m) {}  // NOLINT: one material everywhere
  // The material of an element of `region`.
  const Material& ForRegion(int region) const;
  // Every material valid (Material::IsValid); the error names it ("regions[2] (region 5):
  // poisson_ratio ...").
  bool IsValid(std::string* error) const;
};

enum class ElasticModelType {
  kCorotational,  // R K (R^T x - X): rotation-invariant, for large rotations
  kLinear,        // K (x - X): small-strain linear FEM, for comparison
  kNeoHookean,    // the stable neo-Hookean element (below); rotations kept for fracture
};
const char* ToString(ElasticModelType type);
bool FromString(const std::string& name, ElasticModelType* type);
template <>
struct EnumValues<ElasticModelType> {
  static constexpr std::array<ElasticModelType, 3> kAll = {ElasticModelType::kCorotational, ElasticModelType::kLinear,
                                                           ElasticModelType::kNeoHookean};
};

using Matrix6x12 = Eigen::Matrix<double, 6, 12>;
using Matrix12 = Eigen::Matrix<double, 12, 12>;
using Vector12 = Eigen::Matrix<double, 12, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

// Isotropic Hooke matrix in Voigt order (xx, yy, zz, yz, xz, xy) acting on engineering
// shear strains (gamma = 2 eps).
Matrix6 IsotropicElasticity(double youngs_modulus, double poisson_ratio);

// Rest data of one element, built once per topology: what the kernels read every step, in
// 192 bytes. The element's matrices (L, C, K, S below) are formed from it where a kernel
// needs them: stored, they took 2.8 kB an element (1 GB for a 70k-vertex mesh), and the
// fields read every step lay three cache lines apart
// (docs/notes/2026-12-01-element-rest-size.md).
struct ElementRest {
  Eigen::Matrix3d dm_inv;  // inverse of D_m = [X1-X0, X2-X0, X3-X0]
  double volume = 0.0;     // rest volume V_e (> 0)
  double lambda = 0.0;     // the material's Lame parameters (isotropic): lambda ...
  double mu = 0.0;         // ... and the shear modulus
  Vector12 X;              // rest positions [X0; X1; X2; X3]
};

// The element's strain-displacement matrix L (eps = L u, u = [u0; u1; u2; u3], Voigt order
// and engineering shears as IsotropicElasticity), from its shape gradients.
Matrix6x12 StrainDisplacement(const ElementRest& rest);
// Its Hooke matrix C: IsotropicElasticity's, from lambda and mu.
Matrix6 HookeMatrix(const ElementRest& rest);
// Its stiffness K = V_e L^T C L (12 by 12).
Matrix12 ElementStiffness(const ElementRest& rest);
// The residual's matrix S = sqrt(V_e) C^(1/2) L (C^(1/2) the symmetric square root), so that
// S^T S = K.
Matrix6x12 ElementResidualMatrix(const ElementRest& rest);

// X: 3 by 4 rest positions (columns are the vertices).
ElementRest BuildElementRest(const Eigen::Matrix<double, 3, 4>& X, const Material& material);

// Rotation of the polar decomposition F = R S through an SVD, with the sign fix of
// Irving et al. 2004 so that det R = +1 also for inverted and flat F (S then has a
// negative or zero entry). Always finite for finite F.
Eigen::Matrix3d PolarRotation(const Eigen::Matrix3d& F);
// The same rotation (to round-off), found by Newton's method on SO(3) from `start` (e.g. the
// element's rotation at the previous step): R maximizes tr(R^T F) over rotations, which is
// the rotation above, also for inverted and flat F. Two or three 3x3 steps from a close
// start instead of an SVD; falls back to the SVD when the start is far or F is near the
// inverted tie (two equal singular values with the sign on one of them).
Eigen::Matrix3d PolarRotation(const Eigen::Matrix3d& F, const Eigen::Matrix3d& start);

// Deformation gradient F = D_s D_m^-1 of an element at positions x (3 by 4).
Eigen::Matrix3d DeformationGradient(const Eigen::Matrix<double, 3, 4>& x,
                                    const Eigen::Matrix3d& dm_inv);

// Per-element kernels. x: the element's current positions stacked as a 12-vector.
// R is the element rotation (identity for the linear model).
// u_r = R^T x - X (per vertex), residual r = S u_r (6), energy 0.5 |r|^2,
// force on the vertices f = -R K u_r (12), warped stiffness R K R^T (12 by 12).
Vector6 ElementResidual(const ElementRest& rest, const Eigen::Matrix3d& R, const Vector12& x);
double ElementEnergy(const ElementRest& rest, const Eigen::Matrix3d& R, const Vector12& x);
Vector12 ElementForce(const ElementRest& rest, const Eigen::Matrix3d& R, const Vector12& x);
Matrix12 WarpedStiffness(const ElementRest& rest, const Eigen::Matrix3d& R);
// The residual's Jacobian with R held fixed: S blockdiag(R^T) (6 by 12).
Matrix6x12 ElementResidualJacobian(const ElementRest& rest, const Eigen::Matrix3d& R);
// Its block of vertex i (0..3): S_i R^T (6 by 3), S_i the columns 3i..3i+2 of S.
Eigen::Matrix<double, 6, 3> ElementResidualJacobianBlock(const ElementRest& rest,
                                                         const Eigen::Matrix3d& R, int i);
// Corotational stress in the element's unrotated frame, Voigt: C L u_r
// (docs/theory/fracture.md#detection).
Vector6 ElementStress(const ElementRest& rest, const Eigen::Matrix3d& R, const Vector12& x);

// The elastic energy of a whole mesh: rest data per element, rotations, and assembly.
class ElasticModel {
 public:
  // material_per_region: region id -> material; elements of unlisted regions use
  // default_material.
  void Build(const TetMesh& mesh, ElasticModelType type, const Material& default_material,
             const std::vector<std::pair<int, Material>>& material_per_region = {});
  // An object whose material.model is kNeoHookean gets that element whatever `type` says
  // (type picks between the Hooke elements).
  void Build(const TetMesh& mesh, ElasticModelType type, const ObjectMaterial& material);
  // Rebuilds the rest data of the listed elements only (after a topology change).
  void RebuildElements(const TetMesh& mesh, const std::vector<int>& elements);
  // After elements were removed or renumbered (fracture): element i of `mesh` was element
  // old_element[i]; its rest data and rotation move along, and only `touched` (new indices)
  // are rebuilt.
  void RemapElements(const TetMesh& mesh, const std::vector<int>& old_element,
                     const std::vector<int>& touched);

  // Recomputes R_e from positions (identity for the linear model).
  void UpdateRotations(const Vertices& x);

  // With the current rotations held fixed (the neo-Hookean model: its element form, without
  // the nodal volume, which only the forward solve has).
  double Energy(const Vertices& x) const;
  // Adds the energy gradient (= -force) to gradient (#V by 3).
  void AddGradient(const Vertices& x, Vertices* gradient) const;
  // Adds the warped stiffness R K R^T (the Gauss-Newton Hessian) as (row, col, value)
  // triplets over 3 #V dofs (the Hooke models; for the neo-Hookean one its stiffness at rest).
  void AddStiffnessTriplets(std::vector<Eigen::Triplet<double>>* triplets) const;

  ElasticModelType type() const { return type_; }
  // kNeoHookean: the volumetric energy on the vertices (ObjectMaterial::nodal_volume).
  bool nodal_volume() const { return nodal_volume_; }
  int num_elements() const { return static_cast<int>(rest_.size()); }
  const ElementRest& rest(int e) const { return rest_[e]; }
  const Eigen::Matrix3d& rotation(int e) const { return rotations_[e]; }
  const Tets& tets() const { return tets_; }
  Vector12 Gather(const Vertices& x, int e) const;

 private:
  ElasticModelType type_ = ElasticModelType::kCorotational;
  bool nodal_volume_ = false;
  Material default_material_;
  std::vector<std::pair<int, Material>> material_per_region_;
  Tets tets_;
  std::vector<ElementRest> rest_;
  std::vector<Eigen::Matrix3d> rotations_;
};

// ---------------------------------------------------------------------------------------
// The consistent corotational tangent (used by the forward solve).
//
// The element energy E_e(x) = 0.5 u^T K u with u = R(x)^T x - X is V_e psi(F) with
// psi(F) = mu |S - I|^2 + lambda/2 tr(S - I)^2 for F = R S (C isotropic, as
// IsotropicElasticity builds it). ElementForce's f = -R K u is its exact negative gradient
// (the dR terms cancel), but the warped stiffness R K R^T is not its Hessian: it leaves out
// dR/dx, which is why Newton on R K R^T converges only linearly. In the signed SVD
// F = U diag(sigma) V^T the Hessian of psi is the warped one plus, along the three twist
// directions T_ij = U (e_i e_j^T - e_j e_i^T) V^T / sqrt(2) (where R K R^T is zero), the
// eigenvalues
//     g_ij = 2 mu + 2 (lambda tr(S - I) - 2 mu) / (sigma_i + sigma_j),
// which follow from dR = U W V^T, W_ij = (A_ij - A_ji) / (sigma_i + sigma_j), A = U^T dF V
// (equivalently dR = R [w]x with (tr(S) I - S) w = axial(R^T dF - dF^T R)). g_ij < 0 under
// compression (sigma_i + sigma_j < 2 at small tr(S - I)), so the exact tangent can be
// indefinite.

// F = U diag(sigma) V^T with U, V proper rotations, |sigma| sorted decreasing, and the sign
// of det F on sigma(2) (Irving et al. 2004, as PolarRotation): R = U V^T is PolarRotation(F)
// and S = V diag(sigma) V^T.
struct SignedSvd {
  Eigen::Matrix3d U = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d V = Eigen::Matrix3d::Identity();
  Eigen::Vector3d sigma = Eigen::Vector3d::Ones();
};
SignedSvd SignedSingularValueDecomposition(const Eigen::Matrix3d& F);

// Below this sigma_i + sigma_j the derivative of the rotation is undefined (an element
// collapsed to a line, or inverted with sigma_i = -sigma_j): that twist mode keeps the
// warped stiffness' zero.
constexpr double kMinTwistSingularSum = 1e-6;

enum class TangentProjection {
  kNone,                    // the exact Hessian of the element energy (may be indefinite)
  kPositiveSemiDefinite,    // negative twist eigenvalues clamped to 0: the nearest PSD
                            // matrix in the element's own eigenbasis
};

// What CorotationalTangent did, for statistics.
struct ElementTangentInfo {
  int negative_modes = 0;    // twist eigenvalues g_ij < 0 (clamped under kPositiveSemiDefinite)
  int degenerate_modes = 0;  // twist modes with sigma_i + sigma_j < kMinTwistSingularSum
  double min_eigenvalue = 0.0;  // min g_ij before projection (Pa), 0 when all degenerate
};

// The element's consistent stiffness d^2 E_e / dx^2 = -d f_e / dx (12 by 12, symmetric) at
// positions x, with R = R(x) recomputed from x (not the model's stored rotation):
// WarpedStiffness(rest, R) + V_e sum_ij g_ij b_ij b_ij^T with b_ij = dF/dx^T : T_ij.
// rotation, if not null: R(x) = U V^T of the same decomposition (PolarRotation's, to round-off).
// start, if not null: a rotation near R(x) (e.g. the element's held rotation), for Newton's
// polar rotation and a closed-form symmetric eigensolver in place of the SVD (the SVD where
// the start is too far for Newton); the same tangent to 1e-9 of its largest entry.
Matrix12 CorotationalTangent(const ElementRest& rest, const Vector12& x,
                             TangentProjection projection,
                             ElementTangentInfo* info = nullptr, Eigen::Matrix3d* rotation = nullptr,
                             const Eigen::Matrix3d* start = nullptr);

// CorotationalTangent's exact tangent (TangentProjection::kNone) as its 16 3x3 blocks (block
// (a, b) at blocks[4 a + b]), in closed form from F and its polar rotation R, without the
// eigendecomposition: with c_a = R grad N_a and M = tr(S) I - S (S = R^T F), the warped
// stiffness plus V [c_a]x^T (mu I + (lambda tr(S - I) - 2 mu) R M^-1 R^T) [c_b]x, since
// dR = R [w]x with M w = axial(R^T dF - dF^T R). False, nothing written, unless M is surely
// well inside the positive definite cone (its pivots at least 1e-4 of F's largest entry, and
// det M / tr(adj M), a lower bound of its smallest eigenvalue, at least kMinTwistSingularSum):
// near a collapse CorotationalTangent decides, as it drops a twist mode there.
bool CorotationalTangentBlocks(const ElementRest& rest, const Eigen::Matrix3d& F, const Eigen::Matrix3d& R,
                               Eigen::Matrix3d* blocks);

// Energy 0.5 u^T K u and force f = -R K u (12) of an element in one pass (u = R^T x - X
// formed once); same values as ElementEnergy and ElementForce.
double ElementEnergyAndForce(const ElementRest& rest, const Eigen::Matrix3d& R,
                             const Vector12& x, Vector12* force);

// ---------------------------------------------------------------------------------------
// The stable neo-Hookean element (Smith, de Goes and Kim, "Stable Neo-Hookean Flesh
// Simulation", 2018, in the form without the log term of Kim and Eberle, "Dynamic
// Deformables", 2022). Per unit rest volume,
//     psi(F) = mu/2 (|F|^2 - 3) - mu (J - 1) + kappa/2 (J - 1)^2,    J = det F,
// with kappa = lambda + mu: its first Piola-Kirchhoff stress
//     P = mu F + (kappa (J - 1) - mu) cof F,    cof F = J F^-T,
// is 2 mu eps + lambda tr(eps) I at small strain, so E and nu mean what they mean for the
// Hooke elements. Unlike the classical forms (log J, J^(-2/3)), psi is a polynomial in F:
// finite, and pushing back, for flat and inverted elements (J <= 0). Its Hessian,
//     d2psi/dF2 = mu I + kappa g g^T + (kappa (J - 1) - mu) H_J,   g = vec cof F,
// (H_J the Hessian of det F, vec column-major) is indefinite under compression; the
// projection clamps its negative eigenvalues (in F's 9-space, so the element matrix stays
// positive semi-definite).
//
// Linear tetrahedra lock as nu -> 0.5: one volume constraint per element is too many for
// their few degrees of freedom. With the volume averaged over the nodes (Bonet and Burton's
// average nodal pressure tetrahedron, 1998) psi splits into
//     psi_dev(F) = mu/2 (|F|^2 - 3) - mu (J - 1) + mu/6 (J - 1)^2      (kappa = mu/3),
// per element, which is mu |dev eps|^2 at small strain, and the volumetric energy
//     sum_a K_a V_a / 2 (J_a - 1)^2,   K = lambda + 2 mu / 3 (the bulk modulus),
// on the vertices: V_a a quarter of the rest volumes of the elements around vertex a, J_a
// the ratio of their current to rest volumes. The sum of the two is the element form at
// uniform strain.

using Matrix9 = Eigen::Matrix<double, 9, 9>;

// kappa of the element form (lambda + mu), and of the deviatoric part (mu / 3).
double NeoHookeanKappa(const ElementRest& rest, bool nodal_volume);
// The bulk modulus lambda + 2 mu / 3 (Pa), of the nodal volume's energy.
double BulkModulus(const ElementRest& rest);

// The shape-function gradients b_k of the element as columns (F = sum_k x_k b_k^T; b_1..b_3
// the rows of D_m^-1, b_0 = -(their sum)).
Eigen::Matrix<double, 3, 4> ShapeGradients(const ElementRest& rest);
// cof F = det(F) F^-T = dJ/dF, column by column [f1 x f2, f2 x f0, f0 x f1] (also for
// singular F).
Eigen::Matrix3d Cofactor(const Eigen::Matrix3d& F);
// det F - 1 without cancellation near F = I (in H = F - I: tr H + i2(H) + det H).
double DeterminantMinusOne(const Eigen::Matrix3d& F);
// psi(F) (per unit rest volume) and, if P is not null, dpsi/dF.
double NeoHookeanDensity(const Eigen::Matrix3d& F, double mu, double kappa, Eigen::Matrix3d* P);
// The Hessian of det F over vec F (column-major).
Matrix9 DeterminantHessian(const Eigen::Matrix3d& F);
// d2psi/dF2 plus pressure * H_J (the nodal volume's share; 0 for the element form),
// projected to positive semi-definite if asked. info: negative eigenvalues, the smallest.
Matrix9 NeoHookeanDensityHessian(const Eigen::Matrix3d& F, double mu, double kappa,
                                 double pressure, TangentProjection projection,
                                 ElementTangentInfo* info = nullptr);

// The element's energy V psi(F) and forces -V (P + pressure cof F) b_i at x (12): the
// pressure p (Pa) is the nodal volume's dE/dv_e (its energy is counted on the vertices).
double NeoHookeanEnergyAndForce(const ElementRest& rest, double kappa, double pressure,
                                const Vector12& x, Vector12* force);
// Its stiffness V B^T NeoHookeanDensityHessian B (12 by 12), B = dvec F / dx.
Matrix12 NeoHookeanTangent(const ElementRest& rest, double kappa, double pressure,
                           const Vector12& x, TangentProjection projection,
                           ElementTangentInfo* info = nullptr);
// NeoHookeanTangent without projection, as its 16 3x3 blocks (block (a, b) at blocks[4 a + b]):
// V (mu (b_a . b_b) I + kappa q_a q_b^T - (kappa (J - 1) - mu + pressure) [F (b_a x b_b)]x),
// q_a = cof(F) b_a: the determinant's second derivative contracted with two shape gradients is
// a cross product, so no 9 by 9 Hessian is formed.
void NeoHookeanTangentBlocks(const ElementRest& rest, double kappa, double pressure, const Eigen::Matrix3d& F,
                             Eigen::Matrix3d* blocks);
// dv_e/dx = V cof(F) b_i (12): the gradient of the element's current volume.
Vector12 VolumeGradient(const ElementRest& rest, const Vector12& x);

}  // namespace femreg

#endif  // FEMREG_FEM_H_
