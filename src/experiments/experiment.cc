#include "femreg/experiment.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "femreg/ground_truth.h"
#include "femreg/point_cloud.h"
#include "femreg/synth.h"
#include "femreg/tracker.h"

namespace fs = std::filesystem;

namespace femreg {

namespace {

std::vector<std::string> FilesWithExtension(const fs::path& dir, const std::set<std::string>& exts) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (e.is_regular_file() && exts.count(e.path().extension().string())) out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());  // frame_NNNN: zero padded
  return out;
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", v);
  return buf;
}

}  // namespace

Status LoadDataset(const std::string& dir, Dataset* dataset, int max_frames) {
  dataset->dir = dir;
  dataset->name = fs::path(dir).filename().string();
  if (dataset->name.empty()) dataset->name = fs::path(dir).parent_path().filename().string();
  Status status = LoadScene((fs::path(dir) / "scene.yaml").string(), &dataset->scene);
  if (!status.ok()) return status;
  dataset->clouds = FilesWithExtension(fs::path(dir) / "clouds", {".pcd", ".ply", ".xyz", ".txt"});
  dataset->truth = FilesWithExtension(fs::path(dir) / "ground_truth", {".csv"});
  if (dataset->clouds.empty()) return Status::Error(dir + "/clouds: no clouds");
  if (dataset->truth.size() < dataset->clouds.size()) {
    return Status::Error(dir + "/ground_truth: " + std::to_string(dataset->truth.size()) +
                         " frames for " + std::to_string(dataset->clouds.size()) + " clouds");
  }
  if (max_frames > 0 && static_cast<int>(dataset->clouds.size()) > max_frames) {
    dataset->clouds.resize(static_cast<size_t>(max_frames));
  }
  dataset->truth.resize(dataset->clouds.size());
  return Status::Ok();
}

Outcome RunSetting(const Dataset& dataset, const Setting& setting,
                   const std::function<void(int, int)>& progress) {
  Outcome out;
  out.setting = setting.name;
  Scene scene = dataset.scene;
  if (setting.apply) setting.apply(&scene);
  // The dataset's own meshes: the ground truth is given at their vertices.
  std::vector<TetMesh> reference(scene.objects.size());
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    Status status = LoadObjectMesh(dataset.scene, static_cast<int>(i), &reference[i]);
    if (!status.ok()) {
      out.error = status.message();
      return out;
    }
  }
  if (setting.resolution != 1.0) {
    for (ObjectSpec& o : scene.objects) {
      MeshGeneratorSpec& g = o.generate;
      if (g.shape == MeshGeneratorSpec::Shape::kNone) {
        out.error = "mesh resolution can only change for generated meshes (object '" + o.name + "')";
        return out;
      }
      auto scale = [&](int n) { return std::max(1, static_cast<int>(std::lround(n * setting.resolution))); };
      g.cells = Eigen::Vector3i(scale(g.cells.x()), scale(g.cells.y()), scale(g.cells.z()));
      g.radial_cells = scale(g.radial_cells);
      g.axial_cells = scale(g.axial_cells);
    }
  }
  std::string error;
  if (!scene.registration.IsValid(&error)) {
    out.error = error;
    return out;
  }
  std::unique_ptr<Tracker> tracker;
  Status status = Tracker::Create(scene, &tracker);
  if (!status.ok()) {
    out.error = status.message();
    return out;
  }
  // Where the reference vertices sit in the tracked meshes.
  std::vector<EmbeddedPoints> embedded(scene.objects.size());
  int reference_vertices = 0;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    embedded[i] = EmbedPoints(tracker->mesh(static_cast<int>(i)), reference[i].rest);
    reference_vertices += reference[i].num_vertices();
    out.vertices += tracker->mesh(static_cast<int>(i)).num_vertices();
    out.elements += tracker->mesh(static_cast<int>(i)).num_tets();
  }

  std::vector<double> ms, solve_ms, corr_ms;
  double seen_sum = 0, seen_sq = 0, hidden_sum = 0, hidden_sq = 0;
  int seen_n = 0, hidden_n = 0;
  const int total = static_cast<int>(dataset.clouds.size());
  for (int f = 0; f < total; ++f) {
    PointCloud cloud;
    Status read = ReadPointCloud(dataset.clouds[f], &cloud);
    if (!read.ok()) cloud = PointCloud();
    GroundTruthFrame truth;
    status = ReadGroundTruthFrame(dataset.truth[f], &truth);
    if (!status.ok() || truth.positions.rows() != reference_vertices) {
      out.error = status.ok() ? dataset.truth[f] + ": " + std::to_string(truth.positions.rows()) +
                                    " vertices, the scene has " + std::to_string(reference_vertices)
                              : status.message();
      return out;
    }
    FrameSummary summary;
    tracker->Track(cloud, &summary);
    if (summary.IsSolutionUsable()) ++out.usable;
    ms.push_back(summary.time.total * 1e3);
    solve_ms.push_back(summary.time.solve * 1e3);
    corr_ms.push_back(summary.time.correspondences * 1e3);
    Vertices at_reference(reference_vertices, 3);
    int offset = 0;
    for (size_t i = 0; i < scene.objects.size(); ++i) {
      const Vertices p = InterpolateEmbedded(tracker->mesh(static_cast<int>(i)),
                                             tracker->vertices(static_cast<int>(i)), embedded[i]);
      at_reference.middleRows(offset, p.rows()) = p;
      offset += static_cast<int>(p.rows());
    }
    for (int v = 0; v < reference_vertices; ++v) {
      const double e = (at_reference.row(v) - truth.positions.row(v)).norm();
      out.all_max = std::max(out.all_max, e);
      if (truth.visible[static_cast<size_t>(v)]) {
        seen_sum += e;
        seen_sq += e * e;
        ++seen_n;
      } else {
        hidden_sum += e;
        hidden_sq += e * e;
        ++hidden_n;
      }
    }
    if (progress) progress(f + 1, total);
  }
  out.frames = total;
  out.median_ms = Median(ms);
  double sum = 0;
  for (double m : ms) sum += m;
  out.mean_ms = ms.empty() ? 0 : sum / ms.size();
  out.median_solve_ms = Median(solve_ms);
  out.median_correspondences_ms = Median(corr_ms);
  out.seen_mean = seen_n ? seen_sum / seen_n : 0;
  out.hidden_mean = hidden_n ? hidden_sum / hidden_n : 0;
  out.seen_rms = seen_n ? std::sqrt(seen_sq / seen_n) : 0;
  out.hidden_rms = hidden_n ? std::sqrt(hidden_sq / hidden_n) : 0;
  out.all_mean = (seen_n + hidden_n) ? (seen_sum + hidden_sum) / (seen_n + hidden_n) : 0;
  return out;
}

std::vector<Setting> DefaultBenchSweep(const Scene& base) {
  const RegistrationOptions& r = base.registration;
  std::vector<Setting> s;
  s.push_back({"baseline", {}, nullptr, 1.0});
  for (double res : {0.5, 0.75, 1.5}) {
    s.push_back({"resolution x" + Num(res), {{"resolution", Num(res)}}, nullptr, res});
  }
  for (int outer : {1, 2, 3, 8, 12}) {
    if (outer == r.solver.max_outer_iterations) continue;
    s.push_back({"outer " + std::to_string(outer), {{"max_outer_iterations", std::to_string(outer)}},
                 [outer](Scene* sc) { sc->registration.solver.max_outer_iterations = outer; }, 1.0});
  }
  for (int inner : {2, 5, 25}) {
    if (inner == r.solver.max_inner_iterations) continue;
    s.push_back({"inner " + std::to_string(inner), {{"max_inner_iterations", std::to_string(inner)}},
                 [inner](Scene* sc) { sc->registration.solver.max_inner_iterations = inner; }, 1.0});
  }
  for (int stride : {2, 4, 8}) {
    s.push_back({"cloud stride " + std::to_string(stride), {{"cloud_stride", std::to_string(stride)}},
                 [stride](Scene* sc) { sc->registration.data.cloud_stride = stride; }, 1.0});
  }
  if (r.solver.backend != SolverBackend::kFast) {
    s.push_back({"fast back end", {{"backend", "fast"}},
                 [](Scene* sc) { sc->registration.solver.backend = SolverBackend::kFast; }, 1.0});
    s.push_back({"fast, outer 3", {{"backend", "fast"}, {"max_outer_iterations", "3"}},
                 [](Scene* sc) {
                   sc->registration.solver.backend = SolverBackend::kFast;
                   sc->registration.solver.max_outer_iterations = 3;
                 },
                 1.0});
    s.push_back({"fast, resolution x0.5", {{"backend", "fast"}, {"resolution", "0.5"}},
                 [](Scene* sc) { sc->registration.solver.backend = SolverBackend::kFast; }, 0.5});
  }
  s.push_back({"conjugate gradients", {{"linear_solver", "conjugate_gradients"}},
               [](Scene* sc) {
                 sc->registration.solver.backend = SolverBackend::kCeres;
                 sc->registration.solver.linear_solver = LinearSolver::kConjugateGradients;
                 sc->registration.solver.trust_region = TrustRegion::kLevenbergMarquardt;
               },
               1.0});
  s.push_back({"dogleg", {{"trust_region", "dogleg"}},
               [](Scene* sc) {
                 sc->registration.solver.backend = SolverBackend::kCeres;
                 sc->registration.solver.trust_region = TrustRegion::kDogleg;
                 sc->registration.solver.linear_solver = LinearSolver::kSparseNormalCholesky;
               },
               1.0});
  for (double w : {0.1, 0.3, 3.0, 10.0}) {
    s.push_back({"elastic weight x" + Num(w), {{"elastic_weight", Num(w * r.weights.elastic)}},
                 [w](Scene* sc) { sc->registration.weights.elastic *= w; }, 1.0});
  }
  for (double e : {0.2, 5.0}) {
    s.push_back({"E x" + Num(e), {{"youngs_modulus_factor", Num(e)}},
                 [e](Scene* sc) {
                   for (ObjectSpec& o : sc->objects) o.material.youngs_modulus *= e;
                 },
                 1.0});
  }
  return s;
}

std::vector<Setting> DefaultComparison(const Scene& base) {
  std::vector<Setting> s;
  // With no elastic term the temporal weight decides what holds the hidden parts.
  s.push_back({"data only", {{"regularizer", "none"}, {"temporal_weight", "1e-6"}},
               [](Scene* sc) {
                 sc->registration.regularizer = Regularizer::kNone;
                 sc->registration.weights.temporal = 1e-6;
               },
               1.0});
  s.push_back({"temporal only", {{"regularizer", "none"}, {"temporal_weight", "1e4"}},
               [](Scene* sc) {
                 sc->registration.regularizer = Regularizer::kNone;
                 sc->registration.weights.temporal = 1e4;
               },
               1.0});
  s.push_back({"mass-spring", {{"regularizer", "mass_spring"}},
               [](Scene* sc) { sc->registration.regularizer = Regularizer::kMassSpring; }, 1.0});
  s.push_back({"linear FEM", {{"regularizer", "linear"}},
               [](Scene* sc) { sc->registration.regularizer = Regularizer::kLinear; }, 1.0});
  const double E = base.objects.empty() ? 1e5 : base.objects[0].material.youngs_modulus;
  const double nu = base.objects.empty() ? 0.3 : base.objects[0].material.poisson_ratio;
  for (double factor : {0.2, 1.0, 5.0}) {
    for (double poisson : {0.0, nu, 0.45}) {
      if (factor != 1.0 && poisson != nu) continue;  // E at the scene's nu; nu at the scene's E
      char name[96];
      std::snprintf(name, sizeof(name), "corotational E=%g nu=%g", E * factor, poisson);
      s.push_back({name,
                   {{"regularizer", "corotational"}, {"youngs_modulus", Num(E * factor)},
                    {"poisson_ratio", Num(poisson)}},
                   [factor, poisson](Scene* sc) {
                     sc->registration.regularizer = Regularizer::kCorotational;
                     for (ObjectSpec& o : sc->objects) {
                       o.material.youngs_modulus *= factor;
                       o.material.poisson_ratio = poisson;
                     }
                   },
                   1.0});
    }
  }
  return s;
}

std::vector<int> ParetoFront(const std::vector<Outcome>& outcomes) {
  std::vector<int> front;
  for (size_t i = 0; i < outcomes.size(); ++i) {
    if (!outcomes[i].error.empty()) continue;
    bool dominated = false;
    for (size_t j = 0; j < outcomes.size() && !dominated; ++j) {
      if (i == j || !outcomes[j].error.empty()) continue;
      const bool no_worse = outcomes[j].median_ms <= outcomes[i].median_ms &&
                            outcomes[j].all_mean <= outcomes[i].all_mean;
      const bool better = outcomes[j].median_ms < outcomes[i].median_ms ||
                          outcomes[j].all_mean < outcomes[i].all_mean;
      dominated = no_worse && better;
    }
    if (!dominated) front.push_back(static_cast<int>(i));
  }
  return front;
}

std::string OutcomesCsv(const std::vector<Setting>& settings, const std::vector<Outcome>& outcomes) {
  std::vector<std::string> keys;
  for (const Setting& s : settings) {
    for (const auto& p : s.parameters) {
      if (std::find(keys.begin(), keys.end(), p.first) == keys.end()) keys.push_back(p.first);
    }
  }
  const std::vector<int> front = ParetoFront(outcomes);
  std::ostringstream os;
  os << "setting";
  for (const auto& k : keys) os << "," << k;
  os << ",vertices,elements,frames,usable,median_ms,mean_ms,median_solve_ms,"
        "median_correspondences_ms,err_mean_mm,err_seen_mean_mm,err_hidden_mean_mm,"
        "err_seen_rms_mm,err_hidden_rms_mm,err_max_mm,pareto,error\n";
  char buf[512];
  for (size_t i = 0; i < outcomes.size(); ++i) {
    const Outcome& o = outcomes[i];
    os << "\"" << o.setting << "\"";
    for (const auto& k : keys) {
      std::string v;
      for (const auto& p : settings[i].parameters) {
        if (p.first == k) v = p.second;
      }
      os << "," << v;
    }
    const bool on_front = std::find(front.begin(), front.end(), static_cast<int>(i)) != front.end();
    std::snprintf(buf, sizeof(buf), ",%d,%d,%d,%d,%.3f,%.3f,%.3f,%.3f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%d",
                  o.vertices, o.elements, o.frames, o.usable, o.median_ms, o.mean_ms,
                  o.median_solve_ms, o.median_correspondences_ms, o.all_mean * 1e3,
                  o.seen_mean * 1e3, o.hidden_mean * 1e3, o.seen_rms * 1e3, o.hidden_rms * 1e3,
                  o.all_max * 1e3, on_front ? 1 : 0);
    std::string err = o.error;
    std::replace(err.begin(), err.end(), '"', '\'');
    os << buf << ",\"" << err << "\"\n";
  }
  return os.str();
}

}  // namespace femreg
