// The contact penalty for the forward solver, and merging meshes for multi-object solves.
#include "femreg/collision.h"

namespace femreg {

namespace {

// The DOFs and weights of delta = D - n . (p_a - p_b): d delta / d x_v = w_v (-n).
int Stencil(const Contact& c, int* vertex, double* weight) {
  int n = 0;
  for (int k = 0; k < 3; ++k) {
    vertex[n] = c.vertices_a[k];
    weight[n++] = c.bary_a[k];
  }
  if (!c.obstacle()) {
    for (int k = 0; k < 3; ++k) {
      vertex[n] = c.vertices_b[k];
      weight[n++] = -c.bary_b[k];
    }
  }
  return n;
}

}  // namespace

void ContactPotential::Refresh(const Vertices& x) {
  const bool stale = detections_ == 0 || detected_at_.rows() != x.rows() ||
                     world_->frame() != detected_frame_ ||
                     (x - detected_at_).rowwise().norm().maxCoeff() > 0.5 * margin_;
  if (!stale) return;
  world_->Detect(x, margin_, &contacts_);
  detected_at_ = x;
  detected_frame_ = world_->frame();
  ++detections_;
}

double ContactPotential::Evaluate(const Vertices& x, Eigen::VectorXd* gradient) const {
  double energy = 0.0;
  const double k = world_->stiffness();
  for (const Contact& c : contacts_) {
    const double delta = world_->Penetration(c, x);
    if (!(delta > 0)) continue;
    energy += 0.5 * k * delta * delta;
    if (gradient == nullptr) continue;
    int v[6];
    double w[6];
    const int n = Stencil(c, v, w);
    for (int i = 0; i < n; ++i) gradient->segment<3>(3 * v[i]) -= k * delta * w[i] * c.normal;
  }
  return energy;
}

void ContactPotential::AddHessian(const Vertices& x,
                                  std::vector<Eigen::Triplet<double>>* triplets) const {
  const double k = world_->stiffness();
  for (const Contact& c : contacts_) {
    if (!(world_->Penetration(c, x) > 0)) continue;
    int v[6];
    double w[6];
    const int n = Stencil(c, v, w);
    const Eigen::Matrix3d nn = k * c.normal * c.normal.transpose();
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int r = 0; r < 3; ++r)
          for (int s = 0; s < 3; ++s)
            triplets->emplace_back(3 * v[i] + r, 3 * v[j] + s, w[i] * w[j] * nn(r, s));
  }
}

TetMesh MergeMeshes(const std::vector<TetMesh>& meshes, std::vector<int>* offsets) {
  TetMesh merged;
  int nv = 0, nt = 0;
  offsets->clear();
  for (const TetMesh& m : meshes) {
    offsets->push_back(nv);
    nv += m.num_vertices();
    nt += m.num_tets();
  }
  merged.rest.resize(nv, 3);
  merged.x.resize(nv, 3);
  merged.mass = Eigen::VectorXd::Zero(nv);
  merged.tets.resize(nt, 4);
  merged.region.resize(nt);
  int t = 0;
  for (size_t i = 0; i < meshes.size(); ++i) {
    const TetMesh& m = meshes[i];
    const int o = (*offsets)[i];
    merged.rest.middleRows(o, m.num_vertices()) = m.rest;
    merged.x.middleRows(o, m.num_vertices()) = m.x.rows() == m.rest.rows() ? m.x : m.rest;
    if (m.mass.size() == m.num_vertices()) merged.mass.segment(o, m.num_vertices()) = m.mass;
    merged.tets.middleRows(t, m.num_tets()) = m.tets.array() + o;
    merged.region.segment(t, m.num_tets()).setConstant(static_cast<int>(i));
    t += m.num_tets();
  }
  BuildTopology(&merged);
  return merged;
}

}  // namespace femreg
