// Material from data: a bracketing grid and a golden-section search over one material
// parameter, each value scored by the robust distance of the observed clouds to the
// simulated equilibrium's surface (femreg/calibration.h).
#include "femreg/calibration.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <limits>
#include <sstream>
#include <utility>

#include "femreg/fem.h"
#include "geometry/nearest.h"
#include "parallel/stopwatch.h"

namespace femreg {
namespace {

using Clock = std::chrono::steady_clock;

bool IsModulus(CalibrationParameter p) { return p != CalibrationParameter::kPoissonRatio; }

// The search variable t: ln E for a modulus, nu itself for the Poisson ratio.
double ToT(CalibrationParameter p, double value) { return IsModulus(p) ? std::log(value) : value; }
double FromT(CalibrationParameter p, double t) { return IsModulus(p) ? std::exp(t) : t; }

// The value the scene has now.
double SceneValue(const Scene& scene, const CalibrationOptions& options) {
  const ObjectSpec& o = scene.objects[options.object];
  switch (options.parameter) {
    case CalibrationParameter::kYoungsModulus:
      return o.material.youngs_modulus;
    case CalibrationParameter::kPoissonRatio:
      return o.material.poisson_ratio;
    case CalibrationParameter::kRegionYoungsModulus:
      for (const auto& r : o.region_materials) {
        if (r.first == options.region) return r.second.youngs_modulus;
      }
      return o.material.youngs_modulus;
  }
  return 0.0;
}

double Huber(double d, double scale) {
  return d <= scale ? 0.5 * d * d : scale * (d - 0.5 * scale);
}

// Huber up to reach, then a logarithmic tail with the same slope there: a far point still
// tells a nearer shape from a farther one, where the cap makes the misfit flat away from the
// fit. The grid ranks by it; the fit itself ignores points beyond reach (other objects).
double FarMisfit(double d, double scale, double reach) {
  if (d <= reach) return Huber(d, scale);
  return Huber(reach, scale) + std::min(reach, scale) * reach * std::log(d / reach);
}

// What one value scored, with the per-cloud inlier fractions for the overlap check.
struct Score {
  CalibrationSample sample;
  std::vector<double> cloud_inliers;  // per cloud, fraction within max_distance
  Vertices x;                         // the equilibrium (warm starts)
  bool converged = false;
  std::string forward_message;
};

class Search {
 public:
  Search(const Scene& scene, const std::vector<PointCloud>& clouds,
         const CalibrationOptions& options, const TetMesh& mesh, const ForwardProblem& problem)
      : scene_(scene), clouds_(clouds), options_(options), mesh_(mesh), problem_(problem) {}

  // Solves and scores the value at t; warm-started from the evaluated t nearest to it.
  Score Evaluate(double t, bool grid) {
    const auto start = Clock::now();
    Score score;
    const double value = FromT(options_.parameter, t);
    const Scene s = ApplyCalibration(scene_, options_, value);
    const ObjectSpec& spec = s.objects[options_.object];
    ElasticModel model;
    model.Build(mesh_, s.forward.Model(), spec.Materials());
    TetMesh mesh = mesh_;
    ForwardOptions forward = s.forward;
    forward.verbose = false;
    const Score* nearest = nullptr;
    if (options_.warm_start) {
      for (const Score& other : done_) {
        if (!other.converged) continue;
        const double ot = ToT(options_.parameter, other.sample.value);
        if (nearest == nullptr ||
            std::abs(ot - t) < std::abs(ToT(options_.parameter, nearest->sample.value) - t)) {
          nearest = &other;
        }
      }
    }
    ForwardSummary fs;
    int newton = 0;
    if (nearest != nullptr) {
      mesh.x = nearest->x;
      ForwardOptions warm = forward;
      warm.load_steps = 1;
      const Status status = SolveQuasiStatic(problem_, warm, &model, &mesh, &fs);
      newton += fs.NumNewtonIterations();
      score.converged = status.ok() && fs.termination == ForwardTermination::kConverged;
    }
    if (!score.converged) {  // cold: from rest with the scene's load steps
      mesh.x = mesh_.rest;
      fs = ForwardSummary();
      const Status status = SolveQuasiStatic(problem_, forward, &model, &mesh, &fs);
      newton += fs.NumNewtonIterations();
      score.converged = status.ok() && fs.termination == ForwardTermination::kConverged;
      score.forward_message = status.ok() ? fs.message : status.message();
    }
    score.x = mesh.x;
    CalibrationSample& c = score.sample;
    c.value = value;
    c.grid = grid;
    c.newton_iterations = newton;
    Scoring(mesh, &score);
    c.time_s = Seconds(start);
    if (options_.verbose) {
      std::printf("  %s %-10.6g  objective %.4e  mean %.3f mm  rms %.3f mm  inliers %.1f%%  "
                  "Newton %d  %.2f s%s\n",
                  grid ? "grid  " : "golden", value, c.objective, c.mean_distance * 1e3,
                  c.rms_distance * 1e3, 100 * c.inlier_fraction, newton, c.time_s,
                  score.converged ? "" : "  (not converged)");
      std::fflush(stdout);
    }
    done_.push_back(score);
    return score;
  }

  const std::vector<Score>& done() const { return done_; }

 private:
  void Scoring(const TetMesh& mesh, Score* score) const {
    CalibrationSample& c = score->sample;
    const std::vector<double> none;
    double objective = 0.0, far = 0.0, sum = 0.0, sum2 = 0.0;
    long inliers = 0, total = 0;
    SurfaceIndex surface(mesh.x, mesh.surface);
    for (const PointCloud& cloud : clouds_) {
      long cloud_in = 0;
      for (int i = 0; i < cloud.size(); ++i) {
        const double d = std::sqrt(surface.Closest(cloud.points.row(i).transpose()).squared_distance);
        objective += Huber(std::min(d, options_.max_distance), options_.loss_scale);
        far += FarMisfit(d, options_.loss_scale, options_.max_distance);
        if (d <= options_.max_distance) {
          ++cloud_in;
          sum += d;
          sum2 += d * d;
        }
      }
      inliers += cloud_in;
      total += cloud.size();
      score->cloud_inliers.push_back(cloud.size() ? double(cloud_in) / cloud.size() : 0.0);
    }
    c.objective = total ? objective / total : 0.0;
    c.far_objective = total ? far / total : 0.0;
    c.mean_distance = inliers ? sum / inliers : 0.0;
    c.rms_distance = inliers ? std::sqrt(sum2 / inliers) : 0.0;
    c.inlier_fraction = total ? double(inliers) / total : 0.0;
  }

  const Scene& scene_;
  const std::vector<PointCloud>& clouds_;
  const CalibrationOptions& options_;
  const TetMesh& mesh_;
  const ForwardProblem& problem_;
  std::vector<Score> done_;
};

std::string Num(double v) {
  std::ostringstream os;
  os << std::setprecision(6) << v;
  return os.str();
}

// Least-squares parabola J = c0 + c1 s + c2 s^2 in s = t - t0 through the samples; false
// when fewer than 3 distinct t.
bool FitParabola(const std::vector<std::pair<double, double>>& tj, double t0, Eigen::Vector3d* c) {
  if (tj.size() < 3) return false;
  Eigen::MatrixXd A(tj.size(), 3);
  Eigen::VectorXd b(tj.size());
  for (size_t i = 0; i < tj.size(); ++i) {
    const double s = tj[i].first - t0;
    A.row(static_cast<Eigen::Index>(i)) << 1.0, s, s * s;
    b(static_cast<Eigen::Index>(i)) = tj[i].second;
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  if (qr.rank() < 3) return false;
  *c = qr.solve(b);
  return true;
}

}  // namespace

const char* ToString(CalibrationParameter p) {
  switch (p) {
    case CalibrationParameter::kYoungsModulus: return "E";
    case CalibrationParameter::kPoissonRatio: return "nu";
    case CalibrationParameter::kRegionYoungsModulus: return "region_E";
  }
  return "?";
}

bool FromString(const std::string& name, CalibrationParameter* p) {
  if (name == "E" || name == "youngs_modulus") {
    *p = CalibrationParameter::kYoungsModulus;
  } else if (name == "nu" || name == "poisson_ratio") {
    *p = CalibrationParameter::kPoissonRatio;
  } else if (name == "region_E") {
    *p = CalibrationParameter::kRegionYoungsModulus;
  } else {
    return false;
  }
  return true;
}

const char* ToString(CalibrationTermination t) {
  switch (t) {
    case CalibrationTermination::kNotRun: return "not_run";
    case CalibrationTermination::kConverged: return "converged";
    case CalibrationTermination::kMaxEvaluations: return "max_evaluations";
    case CalibrationTermination::kAtBound: return "at_bound";
    case CalibrationTermination::kUnobservable: return "unobservable";
    case CalibrationTermination::kNoOverlap: return "no_overlap";
    case CalibrationTermination::kForwardFailed: return "forward_failed";
    case CalibrationTermination::kInvalidInput: return "invalid_input";
  }
  return "?";
}

bool CalibrationOptions::IsValid(std::string* error) const {
  // Each field's own range by its table (femreg/calibration.h); the rules across fields here.
  if (!CheckFieldRanges(*this, error)) return false;
  auto fail = [error](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (parameter == CalibrationParameter::kRegionYoungsModulus && region < 0) {
    return fail("region: a region id (>= 0) is needed to fit region_E");
  }
  if (IsModulus(parameter)) {
    if (lower < 0) return fail("lower: a modulus bound must be > 0, or 0 for automatic (got " + Num(lower) + ")");
    if (upper < 0) return fail("upper: a modulus bound must be > 0, or 0 for automatic (got " + Num(upper) + ")");
  } else {
    if (lower != 0 && !(lower > -1 && lower < 0.5)) return fail("lower: nu must be in (-1, 0.5) (got " + Num(lower) + ")");
    if (upper != 0 && !(upper > -1 && upper < 0.5)) return fail("upper: nu must be in (-1, 0.5) (got " + Num(upper) + ")");
  }
  if (lower != 0 && upper != 0 && !(lower < upper)) {
    return fail("lower: must be < upper (got " + Num(lower) + " and " + Num(upper) + ")");
  }
  if (max_evaluations < grid_samples) {
    return fail("max_evaluations: must be >= grid_samples (" + std::to_string(grid_samples) + "; got " +
                std::to_string(max_evaluations) + ")");
  }
  return true;
}

std::string CalibrationSummary::BriefReport() const {
  std::ostringstream os;
  os << std::setprecision(4) << "calibration " << ToString(termination) << ": " << ToString(parameter)
     << " = " << value << " (scene " << initial_value << ")";
  if (sigma_t > 0) {
    os << ", 1-sigma [" << value_low << ", " << value_high << "]";
  }
  os << ", mean distance " << mean_distance * 1e3 << " mm (rms " << rms_distance * 1e3
     << " mm, " << 100 * inlier_fraction << "% of " << num_points << " points within reach), "
     << evaluations << " forward solves, " << newton_iterations << " Newton iterations, "
     << total_time_s << " s";
  return os.str();
}

bool CalibrationSummary::IsSolutionUsable() const {
  return termination == CalibrationTermination::kConverged ||
         termination == CalibrationTermination::kMaxEvaluations;
}

Scene ApplyCalibration(const Scene& scene, const CalibrationOptions& options, double value) {
  Scene s = scene;
  ObjectSpec& o = s.objects[options.object];
  switch (options.parameter) {
    case CalibrationParameter::kYoungsModulus:
      o.material.youngs_modulus = value;
      break;
    case CalibrationParameter::kPoissonRatio:
      o.material.poisson_ratio = value;
      break;
    case CalibrationParameter::kRegionYoungsModulus: {
      bool found = false;
      for (auto& r : o.region_materials) {
        if (r.first == options.region) {
          r.second.youngs_modulus = value;
          found = true;
        }
      }
      if (!found) {
        Material m = o.material;
        m.youngs_modulus = value;
        o.region_materials.push_back({options.region, m});
      }
      break;
    }
  }
  return s;
}

std::vector<double> DistancesToSurface(const TetMesh& mesh, const Vertices& points) {
  SurfaceIndex surface(mesh.x, mesh.surface);
  std::vector<double> d(static_cast<size_t>(points.rows()));
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    d[static_cast<size_t>(i)] = std::sqrt(surface.Closest(points.row(i).transpose()).squared_distance);
  }
  return d;
}

Status SolveSceneObject(const Scene& given, int object, TetMesh* mesh, ForwardSummary* out) {
  Scene scene = given;
  ChooseForwardElements(&scene);  // as Calibrate does
  if (object < 0 || object >= static_cast<int>(scene.objects.size())) {
    return Status::Error("object " + std::to_string(object) + ": the scene has " +
                         std::to_string(scene.objects.size()) + " object(s)");
  }
  Status status = LoadObjectMesh(scene, object, mesh);
  ForwardProblem problem;
  if (status.ok()) status = BuildForwardProblem(scene, object, *mesh, &problem);
  if (!status.ok()) return status;
  const ObjectSpec& spec = scene.objects[object];
  ElasticModel model;
  model.Build(*mesh, scene.forward.Model(), spec.Materials());
  ForwardSummary summary;
  status = SolveQuasiStatic(problem, scene.forward, &model, mesh, &summary);
  if (out) *out = summary;
  if (!status.ok()) return status;
  if (summary.termination != ForwardTermination::kConverged) {
    return Status::Error(spec.name + ": the forward solve did not converge (" +
                         ToString(summary.termination) + "): " + summary.message);
  }
  return Status::Ok();
}

Status Calibrate(const Scene& given, const std::vector<PointCloud>& observed,
                 const CalibrationOptions& options, CalibrationSummary* summary,
                 const std::vector<std::string>& names) {
  const auto start = Clock::now();
  Scene scene = given;
  ChooseForwardElements(&scene);  // the element simulate would use (the command logs it)
  *summary = CalibrationSummary();
  summary->parameter = options.parameter;
  auto invalid = [&](const std::string& message) {
    summary->termination = CalibrationTermination::kInvalidInput;
    summary->message = message;
    return Status::Error(message);
  };
  std::string error;
  if (!options.IsValid(&error)) return invalid("calibration options: " + error);
  if (options.object >= static_cast<int>(scene.objects.size())) {
    return invalid("object " + std::to_string(options.object) + ": the scene has " +
                   std::to_string(scene.objects.size()) + " object(s)");
  }
  auto cloud_name = [&](size_t i) {
    return i < names.size() ? names[i] : "cloud " + std::to_string(i);
  };
  if (observed.empty()) return invalid("no observed cloud");
  for (size_t i = 0; i < observed.size(); ++i) {
    if (observed[i].size() == 0) return invalid(cloud_name(i) + ": the cloud has no point");
    if (!observed[i].points.allFinite()) return invalid(cloud_name(i) + ": non-finite coordinates");
    summary->num_points += observed[i].size();
  }

  TetMesh mesh;
  Status status = LoadObjectMesh(scene, options.object, &mesh);
  ForwardProblem problem;
  if (status.ok()) status = BuildForwardProblem(scene, options.object, mesh, &problem);
  if (!status.ok()) return invalid(status.message());
  const ObjectSpec& spec = scene.objects[options.object];
  const std::string where = (scene.path.empty() ? std::string("scene") : scene.path) +
                            ": object " + spec.name;
  if (options.parameter == CalibrationParameter::kRegionYoungsModulus) {
    bool found = false;
    for (int e = 0; e < mesh.num_tets() && !found; ++e) found = mesh.region(e) == options.region;
    if (!found) return invalid(where + ": the mesh has no element in region " + std::to_string(options.region));
  }

  // Observability. Forces (gravity on a mass, nodal loads) deform the object by an amount
  // that depends on E; prescribed displacements alone give a shape that does not depend on
  // a single modulus (scaling E scales the stresses only), but does on nu and on the ratio
  // of regions' moduli.
  double force = 0.0;
  if (problem.gravity.norm() > 0 && mesh.mass.size() > 0) force += problem.gravity.norm() * mesh.mass.sum();
  for (const auto& l : problem.nodal_loads) force += l.second.norm();
  double displaced = 0.0;
  for (const auto& p : problem.prescribed) displaced = std::max(displaced, p.second.norm());
  bool regions_differ = false;
  for (const auto& r : spec.region_materials) {
    regions_differ = regions_differ || r.second.youngs_modulus != spec.material.youngs_modulus;
  }
  const bool observable =
      force > 0 || (displaced > 0 && (options.parameter != CalibrationParameter::kYoungsModulus || regions_differ));
  if (!observable) {
    summary->termination = CalibrationTermination::kUnobservable;
    summary->message =
        where + ": nothing in the scene deforms the object by an amount that depends on " +
        ToString(options.parameter) +
        (displaced > 0 ? " (prescribed displacements alone give the same shape for every E)"
                       : " (no gravity, no loads)") +
        ": add the load the object was under when the cloud was taken (gravity: [0, 0, -9.81], "
        "or loads:)";
    summary->total_time_s = Seconds(start);
    return Status::Ok();
  }

  // The interval.
  const double initial = SceneValue(scene, options);
  summary->initial_value = initial;
  double lower = options.lower, upper = options.upper;
  if (IsModulus(options.parameter)) {
    if (lower == 0) lower = initial / 10;
    if (upper == 0) upper = initial * 10;
  } else {
    if (lower == 0 && options.lower == 0) lower = 0.0;
    if (upper == 0) upper = 0.495;
  }
  if (!(lower < upper)) {
    return invalid("the search interval is empty: [" + Num(lower) + ", " + Num(upper) + "]");
  }
  summary->lower = lower;
  summary->upper = upper;
  const CalibrationParameter p = options.parameter;
  const double t_lo = ToT(p, lower), t_hi = ToT(p, upper);

  Search search(scene, observed, options, mesh, problem);
  auto finish = [&](CalibrationTermination termination, const std::string& message) {
    summary->termination = termination;
    summary->message = message;
    for (const Score& s : search.done()) {
      summary->samples.push_back(s.sample);
      summary->newton_iterations += s.sample.newton_iterations;
      summary->forward_time_s += s.sample.time_s;
    }
    summary->evaluations = static_cast<int>(search.done().size());
    summary->total_time_s = Seconds(start);
    return Status::Ok();
  };

  // 1. The bracketing grid, from the stiff end (small deformation, the easiest start) to the
  // soft one, each solve warm-started from the one before.
  const int n = options.grid_samples;
  std::vector<double> grid_t(n);
  for (int i = 0; i < n; ++i) grid_t[i] = t_lo + (t_hi - t_lo) * i / (n - 1);
  std::vector<Score> grid(n);
  const bool stiff_last = !IsModulus(p);  // nu: no stiff end; go up
  for (int k = 0; k < n; ++k) {
    const int i = stiff_last ? k : n - 1 - k;
    grid[i] = search.Evaluate(grid_t[i], true);
  }
  int best = -1;
  for (int i = 0; i < n; ++i) {
    if (!grid[i].converged) continue;
    if (best < 0 || grid[i].sample.far_objective < grid[best].sample.far_objective) best = i;
  }
  if (best < 0) {
    return finish(CalibrationTermination::kForwardFailed,
                  where + ": no forward solve of the grid converged (e.g. at " + ToString(p) + " = " +
                      Num(grid[0].sample.value) + ": " + grid[0].forward_message +
                      "); try more forward.load_steps or a narrower interval");
  }
  for (size_t c = 0; c < observed.size(); ++c) {
    if (grid[best].cloud_inliers[c] < options.min_overlap) {
      return finish(
          CalibrationTermination::kNoOverlap,
          cloud_name(c) + ": only " + Num(100 * grid[best].cloud_inliers[c]) +
              "% of its points lie within max_distance (" + Num(options.max_distance * 1e3) +
              " mm) of the simulated " + spec.name + " at best (" + ToString(p) + " = " +
              Num(grid[best].sample.value) + "; at least " + Num(100 * options.min_overlap) +
              "% needed): the cloud does not overlap the object. Is it in the scene's frame "
              "and in metres, and cropped to the object?");
    }
  }
  auto set_best = [&](const Score& s) {
    summary->value = s.sample.value;
    summary->objective = s.sample.objective;
    summary->mean_distance = s.sample.mean_distance;
    summary->rms_distance = s.sample.rms_distance;
    summary->inlier_fraction = s.sample.inlier_fraction;
  };
  set_best(grid[best]);
  if (best == 0 || best == n - 1) {
    return finish(CalibrationTermination::kAtBound,
                  where + ": the best fit is at the " + (best == 0 ? "lower" : "upper") +
                      " end of the search interval (" + ToString(p) + " = " +
                      Num(grid[best].sample.value) + " in [" + Num(lower) + ", " + Num(upper) +
                      "]): the true value may lie beyond it; widen the interval (--lower/--upper)"
                      " or check the scene's loads and the cloud's units");
  }

  // 2. Golden section inside [t_{best-1}, t_{best+1}].
  const double kInvPhi = (std::sqrt(5.0) - 1) / 2;
  double a = grid_t[best - 1], b = grid_t[best + 1];
  double x1 = b - kInvPhi * (b - a), x2 = a + kInvPhi * (b - a);
  Score f1 = search.Evaluate(x1, false), f2 = search.Evaluate(x2, false);
  auto value_of = [](const Score& s) {
    return s.converged ? s.sample.objective : std::numeric_limits<double>::infinity();
  };
  bool converged = false;
  while (true) {
    if (b - a < options.tolerance) {
      converged = true;
      break;
    }
    if (static_cast<int>(search.done().size()) >= options.max_evaluations) break;
    if (value_of(f1) < value_of(f2)) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - kInvPhi * (b - a);
      f1 = search.Evaluate(x1, false);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + kInvPhi * (b - a);
      f2 = search.Evaluate(x2, false);
    }
  }
  const Score* fit = nullptr;  // the best inside the grid's bracket
  for (const Score& s : search.done()) {
    const double t = ToT(p, s.sample.value);
    if (t < grid_t[best - 1] - 1e-12 || t > grid_t[best + 1] + 1e-12) continue;
    if (s.converged && (fit == nullptr || s.sample.objective < fit->sample.objective)) fit = &s;
  }
  set_best(*fit);

  // 3. The curve's width: a parabola through the samples inside the first bracket.
  const double t_fit = ToT(p, fit->sample.value);
  std::vector<std::pair<double, double>> tj;
  for (const Score& s : search.done()) {
    const double t = ToT(p, s.sample.value);
    if (s.converged && t >= grid_t[best - 1] - 1e-12 && t <= grid_t[best + 1] + 1e-12) {
      tj.push_back({t, s.sample.objective});
    }
  }
  Eigen::Vector3d c;
  if (FitParabola(tj, t_fit, &c) && c(2) > 0) {
    const double j_star = std::max(fit->sample.objective, 0.0);
    const double points = std::max(1.0, fit->sample.inlier_fraction * summary->num_points);
    summary->sigma_t = std::sqrt(j_star / (points * c(2)));
    summary->value_low = FromT(p, t_fit - summary->sigma_t);
    summary->value_high = FromT(p, t_fit + summary->sigma_t);
    // rms within 10 %: objective within 1.21 J* in the quadratic part of the loss.
    const double half = std::sqrt(0.21 * j_star / c(2));
    summary->width_low = FromT(p, std::max(t_fit - half, t_lo));
    summary->width_high = FromT(p, std::min(t_fit + half, t_hi));
  }
  if (converged) {
    return finish(CalibrationTermination::kConverged,
                  where + ": " + ToString(p) + " = " + Num(fit->sample.value) + " (the bracket is " +
                      Num(b - a) + (IsModulus(p) ? " in ln E" : "") + " wide)");
  }
  return finish(CalibrationTermination::kMaxEvaluations,
                where + ": stopped after " + std::to_string(options.max_evaluations) +
                    " forward solves; the bracket is still " + Num(b - a) + " wide");
}

}  // namespace femreg
