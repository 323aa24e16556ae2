#include "femreg/experiment.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "femreg/ground_truth.h"
#include "femreg/point_cloud.h"
#include "femreg/synth.h"
#include "femreg/tracker.h"
#include "parallel/threads.h"

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

Status LoadDataset(const std::string& dir, Dataset* dataset, int max_frames,
                   const std::vector<SceneOverride>& overrides) {
  dataset->dir = dir;
  dataset->name = fs::path(dir).filename().string();
  if (dataset->name.empty()) dataset->name = fs::path(dir).parent_path().filename().string();
  Status status =
      LoadSceneWithOverrides((fs::path(dir) / "scene.yaml").string(), overrides, &dataset->scene);
  if (!status.ok()) return status;
  dataset->clouds = FilesWithExtension(fs::path(dir) / "clouds", {".pcd", ".ply", ".xyz", ".txt"});
  dataset->truth = FilesWithExtension(fs::path(dir) / "ground_truth", {".csv"});
  // Fracture sequences keep per-piece positions and events beside the frames.
  dataset->truth.erase(std::remove_if(dataset->truth.begin(), dataset->truth.end(),
                                      [](const std::string& f) {
                                        const std::string n = fs::path(f).filename().string();
                                        return n == "events.csv" ||
                                               (n.size() > 11 &&
                                                n.compare(n.size() - 11, 11, "_pieces.csv") == 0);
                                      }),
                       dataset->truth.end());
  if (dataset->clouds.empty()) return Status::Error(dir + "/clouds: no clouds");
  if (max_frames > 0 && static_cast<int>(dataset->clouds.size()) > max_frames) {
    dataset->clouds.resize(static_cast<size_t>(max_frames));
  }
  // No ground truth (a recording): time, residuals and convergence only.
  if (dataset->truth.empty()) return Status::Ok();
  if (dataset->truth.size() < dataset->clouds.size()) {
    return Status::Error(dir + "/ground_truth: " + std::to_string(dataset->truth.size()) +
                         " frames for " + std::to_string(dataset->clouds.size()) +
                         " clouds (remove the folder to run without ground truth)");
  }
  dataset->truth.resize(dataset->clouds.size());
  return Status::Ok();
}

Outcome RunSetting(const Dataset& dataset, const Setting& setting,
                   const std::function<void(int, int)>& progress) {
  Outcome out;
  out.setting = setting.name;
  out.has_truth = dataset.has_truth();
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

  std::vector<double> ms, solve_ms, corr_ms, residual;
  double outer_sum = 0.0;
  double seen_sum = 0, seen_sq = 0, hidden_sum = 0, hidden_sq = 0;
  int seen_n = 0, hidden_n = 0;
  const int total = static_cast<int>(dataset.clouds.size());
  for (int f = 0; f < total; ++f) {
    PointCloud cloud;
    Status read = ReadPointCloud(dataset.clouds[f], &cloud);
    if (!read.ok()) cloud = PointCloud();
    GroundTruthFrame truth;
    if (out.has_truth) {
      status = ReadGroundTruthFrame(dataset.truth[f], &truth);
      if (!status.ok() || truth.positions.rows() != reference_vertices) {
        out.error = status.ok() ? dataset.truth[f] + ": " + std::to_string(truth.positions.rows()) +
                                      " vertices, the scene has " + std::to_string(reference_vertices)
                                : status.message();
        return out;
      }
    }
    FrameSummary summary;
    tracker->Track(cloud, &summary);
    if (summary.IsSolutionUsable()) ++out.usable;
    if (summary.termination == TerminationType::kConverged) ++out.converged;
    outer_sum += summary.outer_iterations;
    if (summary.points_used > 0) residual.push_back(summary.rms_residual);
    ms.push_back(summary.time.total * 1e3);
    solve_ms.push_back(summary.time.solve * 1e3);
    corr_ms.push_back(summary.time.correspondences * 1e3);
    if (!out.has_truth) {
      if (progress) progress(f + 1, total);
      continue;
    }
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
  out.mean_outer_iterations = total > 0 ? outer_sum / total : 0.0;
  out.median_rms_residual = Median(residual);
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
  // Frames per second on one thread and on all of them (the baseline runs on the scene's
  // solver.threads, by default all).
  const int all = ResolveThreadCount(0);
  s.push_back({"1 thread", {{"threads", "1"}}, [](Scene* sc) { sc->registration.solver.num_threads = 1; }, 1.0});
  s.push_back({"all threads (" + std::to_string(all) + ")", {{"threads", std::to_string(all)}},
               [all](Scene* sc) { sc->registration.solver.num_threads = all; }, 1.0});
  for (double res : {0.5, 0.75, 1.5}) {
    s.push_back({"resolution x" + Num(res), {{"resolution", Num(res)}}, nullptr, res});
  }
  for (int outer : {1, 2, 3, 5, 8, 12}) {
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
  if (r.solver.backend == SolverBackend::kFast) {
    s.push_back({"Ceres back end", {{"backend", "ceres"}},
                 [](Scene* sc) { sc->registration.solver.backend = SolverBackend::kCeres; }, 1.0});
    s.push_back({"Ceres, 1 thread", {{"backend", "ceres"}, {"threads", "1"}},
                 [](Scene* sc) {
                   sc->registration.solver.backend = SolverBackend::kCeres;
                   sc->registration.solver.num_threads = 1;
                 },
                 1.0});
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
                       o.model = MaterialModel::kHooke;  // this element at this nu
                       o.volume.reset();                 // the corotational element's own volume
                     }
                   },
                   1.0});
    }
  }
  return s;
}

Status SelectSettings(const std::vector<Setting>& sweep, const std::vector<std::string>& selectors,
                      std::vector<Setting>* selected, std::vector<int>* indices) {
  std::vector<char> pick(sweep.size(), 0);
  for (const std::string& sel : selectors) {
    int found = -1;
    for (size_t i = 0; i < sweep.size() && found < 0; ++i) {
      if (sweep[i].name == sel) found = static_cast<int>(i);
    }
    if (found < 0 && !sel.empty() &&
        std::all_of(sel.begin(), sel.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); })) {
      const long index = sel.size() > 9 ? -1 : std::stol(sel);
      if (index < 0 || index >= static_cast<long>(sweep.size())) {
        return Status::Error("--setting " + sel + ": the sweep has settings 0 to " +
                             std::to_string(static_cast<long>(sweep.size()) - 1));
      }
      found = static_cast<int>(index);
    }
    if (found < 0) {
      // Every name, for the message: the sweep is short and names are easier to copy than to guess.
      std::string names;
      for (const Setting& s : sweep) names += (names.empty() ? "'" : ", '") + s.name + "'";
      return Status::Error("--setting '" + sel + "': no such setting (run --list-settings; the "
                           "sweep has " + names + ")");
    }
    pick[static_cast<size_t>(found)] = 1;
  }
  selected->clear();
  indices->clear();
  for (size_t i = 0; i < sweep.size(); ++i) {
    if (!pick[i]) continue;
    selected->push_back(sweep[i]);
    indices->push_back(static_cast<int>(i));
  }
  return Status::Ok();
}

namespace {
// What a Pareto front trades against time: the vertex error, or the residual without truth.
double Inaccuracy(const Outcome& o) { return o.has_truth ? o.all_mean : o.median_rms_residual; }
}  // namespace

std::vector<int> ParetoFront(const std::vector<Outcome>& outcomes) {
  std::vector<int> front;
  for (size_t i = 0; i < outcomes.size(); ++i) {
    if (!outcomes[i].error.empty()) continue;
    bool dominated = false;
    for (size_t j = 0; j < outcomes.size() && !dominated; ++j) {
      if (i == j || !outcomes[j].error.empty()) continue;
      const double ej = Inaccuracy(outcomes[j]), ei = Inaccuracy(outcomes[i]);
      const bool no_worse = outcomes[j].median_ms <= outcomes[i].median_ms && ej <= ei;
      const bool better = outcomes[j].median_ms < outcomes[i].median_ms || ej < ei;
      dominated = no_worse && better;
    }
    if (!dominated) front.push_back(static_cast<int>(i));
  }
  return front;
}

namespace {
// The fixed columns after the parameters, in order.
const char* const kCsvColumns[] = {
    "vertices", "elements", "frames", "usable", "median_ms", "mean_ms", "median_solve_ms",
    "median_correspondences_ms", "err_mean_mm", "err_seen_mean_mm", "err_hidden_mean_mm",
    "err_seen_rms_mm", "err_hidden_rms_mm", "err_max_mm", "converged", "mean_outer_iterations",
    "median_rms_residual_mm", "setting_index", "pareto", "error"};

std::string Quoted(std::string text) {
  std::replace(text.begin(), text.end(), '"', '\'');
  std::replace(text.begin(), text.end(), '\n', ' ');
  return "\"" + text + "\"";
}

// One CSV line into fields ("..." quoted, "" inside a quoted field is a quote).
std::vector<std::string> SplitCsvLine(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        fields.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        fields.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else if (c != '\r') {
      fields.back() += c;
    }
  }
  return fields;
}
}  // namespace

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
  for (const char* c : kCsvColumns) os << "," << c;
  os << "\n";
  char buf[512];
  for (size_t i = 0; i < outcomes.size(); ++i) {
    const Outcome& o = outcomes[i];
    os << Quoted(o.setting);
    for (const auto& k : keys) {
      std::string v;
      for (const auto& p : settings[i].parameters) {
        if (p.first == k) v = p.second;
      }
      os << "," << v;
    }
    const bool on_front = std::find(front.begin(), front.end(), static_cast<int>(i)) != front.end();
    std::snprintf(buf, sizeof(buf), ",%d,%d,%d,%d,%.3f,%.3f,%.3f,%.3f", o.vertices, o.elements,
                  o.frames, o.usable, o.median_ms, o.mean_ms, o.median_solve_ms,
                  o.median_correspondences_ms);
    os << buf;
    if (o.has_truth) {
      std::snprintf(buf, sizeof(buf), ",%.4f,%.4f,%.4f,%.4f,%.4f,%.4f", o.all_mean * 1e3,
                    o.seen_mean * 1e3, o.hidden_mean * 1e3, o.seen_rms * 1e3, o.hidden_rms * 1e3,
                    o.all_max * 1e3);
      os << buf;
    } else {
      os << ",,,,,,";  // no ground truth: not measured
    }
    std::snprintf(buf, sizeof(buf), ",%d,%.3f,%.5f,%d,%d", o.converged, o.mean_outer_iterations,
                  o.median_rms_residual * 1e3, o.setting_index, on_front ? 1 : 0);
    os << buf << "," << Quoted(o.error) << "\n";
  }
  return os.str();
}

Status ReadOutcomesCsv(const std::string& path, std::vector<Setting>* settings,
                       std::vector<Outcome>* outcomes) {
  settings->clear();
  outcomes->clear();
  std::ifstream in(path);
  if (!in) return Status::Error(path + ": cannot open");
  std::string line;
  if (!std::getline(in, line)) return Status::Error(path + ":1: empty file, expected a bench/compare CSV");
  const std::vector<std::string> header = SplitCsvLine(line);
  std::map<std::string, size_t> column;
  for (size_t i = 0; i < header.size(); ++i) column[header[i]] = i;
  if (header.empty() || header[0] != "setting") {
    return Status::Error(path + ":1: not a bench/compare CSV (the first column is not 'setting')");
  }
  for (const char* c : kCsvColumns) {
    if (!column.count(c)) {
      return Status::Error(path + ":1: column '" + std::string(c) +
                           "' is missing (written by an older femreg? rerun the setting)");
    }
  }
  const size_t first_fixed = column["vertices"];
  int line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line == "\r") continue;
    const std::vector<std::string> f = SplitCsvLine(line);
    const std::string where = path + ":" + std::to_string(line_number) + ": ";
    if (f.size() != header.size()) {
      return Status::Error(where + std::to_string(f.size()) + " fields, the header has " +
                           std::to_string(header.size()));
    }
    auto number = [&](const char* name, double* value) -> Status {
      const std::string& text = f[column[name]];
      char* end = nullptr;
      *value = std::strtod(text.c_str(), &end);
      if (text.empty() || end != text.c_str() + text.size()) {
        return Status::Error(where + name + ": not a number ('" + text.substr(0, 40) + "')");
      }
      return Status::Ok();
    };
    Setting s;
    Outcome o;
    s.name = o.setting = f[0];
    for (size_t k = 1; k < first_fixed; ++k) {
      if (!f[k].empty()) s.parameters.push_back({header[k], f[k]});
    }
    o.error = f[column["error"]];
    double v = 0.0;
    Status st;
    struct IntField { const char* name; int* target; };
    for (const IntField& i : {IntField{"vertices", &o.vertices}, IntField{"elements", &o.elements},
                              IntField{"frames", &o.frames}, IntField{"usable", &o.usable},
                              IntField{"converged", &o.converged},
                              IntField{"setting_index", &o.setting_index}}) {
      if (!(st = number(i.name, &v)).ok()) return st;
      *i.target = static_cast<int>(v);
    }
    struct RealField { const char* name; double* target; double scale; };
    for (const RealField& r : {RealField{"median_ms", &o.median_ms, 1.0},
                               RealField{"mean_ms", &o.mean_ms, 1.0},
                               RealField{"median_solve_ms", &o.median_solve_ms, 1.0},
                               RealField{"median_correspondences_ms", &o.median_correspondences_ms, 1.0},
                               RealField{"mean_outer_iterations", &o.mean_outer_iterations, 1.0},
                               RealField{"median_rms_residual_mm", &o.median_rms_residual, 1e-3}}) {
      if (!(st = number(r.name, r.target)).ok()) return st;
      *r.target *= r.scale;
    }
    o.has_truth = !f[column["err_mean_mm"]].empty();
    if (o.has_truth) {
      for (const RealField& r : {RealField{"err_mean_mm", &o.all_mean, 1e-3},
                                 RealField{"err_seen_mean_mm", &o.seen_mean, 1e-3},
                                 RealField{"err_hidden_mean_mm", &o.hidden_mean, 1e-3},
                                 RealField{"err_seen_rms_mm", &o.seen_rms, 1e-3},
                                 RealField{"err_hidden_rms_mm", &o.hidden_rms, 1e-3},
                                 RealField{"err_max_mm", &o.all_max, 1e-3}}) {
        if (!(st = number(r.name, r.target)).ok()) return st;
        *r.target *= r.scale;
      }
    }
    settings->push_back(s);
    outcomes->push_back(o);
  }
  return Status::Ok();
}

Status MergeOutcomes(const std::vector<std::vector<Setting>>& shard_settings,
                     const std::vector<std::vector<Outcome>>& shard_outcomes,
                     std::vector<Setting>* settings, std::vector<Outcome>* outcomes) {
  std::vector<std::pair<Setting, Outcome>> rows;
  for (size_t k = 0; k < shard_outcomes.size(); ++k) {
    for (size_t i = 0; i < shard_outcomes[k].size(); ++i) {
      const Outcome& o = shard_outcomes[k][i];
      for (const auto& r : rows) {
        if (r.second.setting == o.setting &&
            (o.setting_index < 0 || r.second.setting_index == o.setting_index)) {
          return Status::Error("setting '" + o.setting + "' is in two shards");
        }
      }
      // One table compares like with like: the same frames, with or without ground truth.
      for (const auto& r : rows) {
        if (!o.error.empty() || !r.second.error.empty()) continue;
        if (r.second.frames != o.frames || r.second.has_truth != o.has_truth) {
          return Status::Error("setting '" + o.setting + "' ran " + std::to_string(o.frames) +
                               " frames " + (o.has_truth ? "with" : "without") +
                               " ground truth, setting '" + r.second.setting + "' " +
                               std::to_string(r.second.frames) + " frames " +
                               (r.second.has_truth ? "with" : "without") +
                               " (shards of different runs?)");
        }
      }
      rows.push_back({shard_settings[k][i], o});
    }
  }
  std::stable_sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) {
    return a.second.setting_index < b.second.setting_index;
  });
  settings->clear();
  outcomes->clear();
  for (auto& r : rows) {
    settings->push_back(std::move(r.first));
    outcomes->push_back(std::move(r.second));
  }
  return Status::Ok();
}

}  // namespace femreg
