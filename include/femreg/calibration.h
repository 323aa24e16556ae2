// femreg/calibration.h - material from data: fits an object's Young's modulus (or its
// Poisson ratio, or one region's Young's modulus) so that the quasi-static equilibrium of a
// scene under its loads and boundary conditions matches observed point clouds.
//
// The misfit of a value is the mean over the observed points of a robust (Huber, truncated
// at max_distance) function of each point's distance to the simulated surface. The search is
// a bracketing grid (ranking by the same with a logarithmic tail beyond max_distance
// instead of the cap) over the interval (log-spaced for a modulus) followed by a golden-section
// search inside the bracket around the grid's best sample; every forward solve is warm-started
// from the equilibrium of the nearest value evaluated before.
#ifndef FEMREG_CALIBRATION_H_
#define FEMREG_CALIBRATION_H_

#include <array>
#include <string>
#include <vector>

#include "femreg/forward.h"
#include "femreg/registration.h"
#include "femreg/scene.h"
#include "femreg/status.h"

namespace femreg {

enum class CalibrationParameter {
  kYoungsModulus,        // the object's E (every region that does not set its own)
  kPoissonRatio,         // the object's nu (likewise)
  kRegionYoungsModulus,  // the E of one region (CalibrationOptions::region)
};
const char* ToString(CalibrationParameter parameter);
// "E", "nu", "region_E" (also "youngs_modulus", "poisson_ratio").
bool FromString(const std::string& name, CalibrationParameter* parameter);
template <>
struct EnumValues<CalibrationParameter> {
  static constexpr std::array<CalibrationParameter, 3> kAll = {
      CalibrationParameter::kYoungsModulus, CalibrationParameter::kPoissonRatio,
      CalibrationParameter::kRegionYoungsModulus};
};

struct CalibrationOptions {
  CalibrationParameter parameter = CalibrationParameter::kYoungsModulus;
  int object = 0;   // index of the scene object whose material is fitted
  int region = -1;  // kRegionYoungsModulus: the region id (must be in the mesh)
  // Search interval. 0 = automatic: E / 10 .. E * 10 around the scene's value for a
  // modulus, 0 .. 0.495 for nu.
  double lower = 0.0;
  double upper = 0.0;
  // Samples of the bracketing grid over [lower, upper] (log-spaced for a modulus, >= 3).
  // Their misfits are the curve calibration.json and misfit.png show.
  int grid_samples = 9;
  // Golden-section stops when the bracket is narrower than this: in ln E for a modulus
  // (1e-3 = 0.1 %), in nu for the Poisson ratio.
  double tolerance = 1e-3;
  int max_evaluations = 40;  // forward solves in all (grid included)
  // Robust distance: Huber with this scale (m), each point's distance capped at
  // max_distance (m): farther points (outliers, other objects) add a constant. The grid
  // ranks values by the misfit with a logarithmic tail beyond max_distance instead, so
  // that shapes far from the fit still differ (CalibrationSample::far_objective).
  double loss_scale = 0.002;
  double max_distance = 0.02;
  // At the fit, at least this fraction of the points of every cloud must lie within
  // max_distance of the simulated surface; fewer is an error (the cloud does not overlap
  // the object).
  double min_overlap = 0.5;
  bool warm_start = true;  // start each forward solve from the nearest evaluated equilibrium
  bool verbose = false;    // one line per evaluation on stdout
  bool IsValid(std::string* error) const;  // names the field
};

// The options calibration.json records (its "options" block), by the names of femreg
// calibrate's flags where they have one. The ranges are IsValid's, which checks them together.
template <>
struct OptionFields<CalibrationOptions> {
  static constexpr const char* kSection = "";  // command-line options, not a scene section
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = CalibrationOptions;
    v(&S::parameter, FieldInfo("parameter").Doc("E, nu or region_E"));
    v(&S::object, FieldInfo("object").AtLeast(0).Doc("index of the scene object whose material is fitted"));
    v(&S::region, FieldInfo("region").Doc("region_E: the region id"));
    v(&S::lower, FieldInfo("lower").Finite().Doc("search interval's lower end; 0 = automatic"));
    v(&S::upper, FieldInfo("upper").Finite().Doc("search interval's upper end; 0 = automatic"));
    v(&S::grid_samples, FieldInfo("grid_samples").AtLeast(3).Doc("samples of the bracketing grid"));
    v(&S::tolerance, FieldInfo("tolerance").Above(0).Doc("golden section's bracket width (ln E, or nu)"));
    v(&S::max_evaluations, FieldInfo("max_evaluations").Doc("forward solves in all"));
    v(&S::loss_scale, FieldInfo("loss_scale").Above(0).Note("m").Doc("Huber scale of the distance (m)"));
    v(&S::max_distance, FieldInfo("max_distance").Above(0).Note("m").Doc("distance cap (m): farther points are outliers"));
    v(&S::min_overlap, FieldInfo("min_overlap").AtLeast(0).AtMost(1).Doc("fraction of each cloud within max_distance at the fit"));
    v(&S::warm_start, FieldInfo("warm_start").Doc("start each solve from the nearest equilibrium"));
  }
};

// One forward solve of the search.
struct CalibrationSample {
  double value = 0.0;      // the parameter (Pa for a modulus)
  double objective = 0.0;  // mean robust loss (m^2): what the search minimizes
  // The same with Huber(D) + min(D, scale) D ln(d / D) for a distance d beyond D =
  // max_distance (m^2): what the bracketing grid ranks by.
  double far_objective = 0.0;
  double mean_distance = 0.0;  // m, mean over the points within max_distance
  double rms_distance = 0.0;   // m, likewise
  double inlier_fraction = 0.0;  // points within max_distance, over all clouds
  int newton_iterations = 0;
  double time_s = 0.0;
  bool grid = false;       // a sample of the bracketing grid (else of the golden section)
};

enum class CalibrationTermination {
  kNotRun,
  kConverged,      // the bracket shrank below the tolerance
  kMaxEvaluations, // stopped at max_evaluations; value is the best sample
  kAtBound,        // the best value is at an end of the search interval: widen it
  kUnobservable,   // the scene has no load that deforms the object for this parameter
  kNoOverlap,      // an observed cloud does not overlap the simulated object
  kForwardFailed,  // a forward solve did not converge
  kInvalidInput,
};
const char* ToString(CalibrationTermination termination);

struct CalibrationSummary {
  CalibrationTermination termination = CalibrationTermination::kNotRun;
  std::string message = "Calibrate was not called.";
  CalibrationParameter parameter = CalibrationParameter::kYoungsModulus;
  double initial_value = 0.0;  // the scene's value
  double value = 0.0;          // the fit (the best sample)
  double lower = 0.0, upper = 0.0;  // the search interval used
  double objective = 0.0;      // at the fit
  double mean_distance = 0.0;  // m, at the fit (points within max_distance)
  double rms_distance = 0.0;   // m
  double inlier_fraction = 0.0;
  int num_points = 0;          // observed points, all clouds
  // The curve's width. A parabola fitted to the objective against t (ln E, or nu) through
  // the samples nearest the fit gives its curvature a (objective ~ a (t - t*)^2 + J*); with J* = sigma^2 / 2 per point and N points taken as independent,
  // one standard deviation of t is sqrt(J* / (N a)) (optimistic: residuals of neighbouring
  // points are correlated). value_low / value_high are the fit moved by it.
  double sigma_t = 0.0;
  double value_low = 0.0, value_high = 0.0;
  // The values whose RMS distance is within 10 % of the best (from the same parabola): what
  // the data can tell apart in practice.
  double width_low = 0.0, width_high = 0.0;
  std::vector<CalibrationSample> samples;  // every evaluation, in the order made
  int evaluations = 0;
  int newton_iterations = 0;  // all forward solves
  double total_time_s = 0.0;
  double forward_time_s = 0.0;
  std::string BriefReport() const;
  // The fitted value is usable (converged, or max evaluations inside the interval).
  bool IsSolutionUsable() const;
};

// Fits `options.parameter` of scene.objects[options.object] to `observed` (each cloud a view
// of the same equilibrium of the scene: its boundary conditions, loads and gravity, its
// forward options and model, nearly incompressible objects with the element
// ChooseForwardElements picks), in the scene's frame and metres. Returns an error for input
// that cannot be used (bad options, no clouds, an empty cloud, a mesh that does not load);
// a search that ran reports how it ended in summary->termination and message. `names`
// (optional, one per cloud) name the clouds in messages.
Status Calibrate(const Scene& scene, const std::vector<PointCloud>& observed,
                 const CalibrationOptions& options, CalibrationSummary* summary,
                 const std::vector<std::string>& names = {});

// The scene with the fitted value written into it (object material, or the region's).
Scene ApplyCalibration(const Scene& scene, const CalibrationOptions& options, double value);

// The equilibrium of scene.objects[object] (rest positions posed; x solved; the element as
// Calibrate chooses it), for tools and tests. forward_summary may be null.
Status SolveSceneObject(const Scene& scene, int object, TetMesh* mesh,
                        ForwardSummary* forward_summary = nullptr);

// Distance of each point to the surface of `mesh` at its current positions (mesh.x).
std::vector<double> DistancesToSurface(const TetMesh& mesh, const Vertices& points);

}  // namespace femreg

#endif  // FEMREG_CALIBRATION_H_
