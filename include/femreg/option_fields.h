// femreg/option_fields.h - the registration options' field tables (femreg/field_table.h):
// each member of CameraOptions, PreprocessOptions, DataTermOptions, WeightOptions,
// ForceOptions, FreeSpaceOptions, SolverOptions and RegistrationOptions described once, with
// its scene key, range, Python name and docstring (docs/dev/adding-an-option.md).
#ifndef FEMREG_OPTION_FIELDS_H_
#define FEMREG_OPTION_FIELDS_H_

#include <array>
#include <sstream>
#include <string>
#include <type_traits>

#include "femreg/field_table.h"
#include "femreg/registration.h"

namespace femreg {

template <>
struct EnumValues<RobustLoss> {
  static constexpr std::array<RobustLoss, 4> kAll = {RobustLoss::kHuber, RobustLoss::kCauchy,
                                                     RobustLoss::kTukey, RobustLoss::kNone};
};
template <>
struct EnumValues<DataMetric> {
  static constexpr std::array<DataMetric, 2> kAll = {DataMetric::kPointToPoint,
                                                     DataMetric::kPointToPlane};
};
template <>
struct EnumValues<Regularizer> {
  static constexpr std::array<Regularizer, 4> kAll = {Regularizer::kCorotational, Regularizer::kLinear,
                                                      Regularizer::kMassSpring, Regularizer::kNone};
};
template <>
struct EnumValues<InitialPose> {
  static constexpr std::array<InitialPose, 2> kAll = {InitialPose::kGiven, InitialPose::kAuto};
};
template <>
struct EnumValues<SolverBackend> {
  static constexpr std::array<SolverBackend, 2> kAll = {SolverBackend::kCeres, SolverBackend::kFast};
};
template <>
struct EnumValues<TrustRegion> {
  static constexpr std::array<TrustRegion, 2> kAll = {TrustRegion::kLevenbergMarquardt,
                                                      TrustRegion::kDogleg};
};
template <>
struct EnumValues<LinearSolver> {
  static constexpr std::array<LinearSolver, 2> kAll = {LinearSolver::kSparseNormalCholesky,
                                                       LinearSolver::kConjugateGradients};
};
template <>
struct EnumValues<Preconditioner> {
  static constexpr std::array<Preconditioner, 3> kAll = {Preconditioner::kAuto, Preconditioner::kFactor,
                                                         Preconditioner::kMultigrid};
};

// The tables. kSection is the struct's key under `registration:` (and in provenance).
// `enabled` has no row: a scene enables the camera by having the section, and a camera is
// written in full (the parser and writer say so by hand; Python and provenance add it).
template <>
struct OptionFields<CameraOptions> {
  static constexpr const char* kSection = "camera";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = CameraOptions;
    v(&S::position, FieldInfo("position").Finite());
    v(&S::target, FieldInfo("target").Finite());
    v(&S::up, FieldInfo("up").Finite());
    v(&S::fx, FieldInfo("fx").Above(0));
    v(&S::fy, FieldInfo("fy").Above(0));
    v(&S::cx, FieldInfo("cx").Finite());
    v(&S::cy, FieldInfo("cy").Finite());
    v(&S::width, FieldInfo("width").Above(0));
    v(&S::height, FieldInfo("height").Above(0));
  }
};

// `crop` and `mask_dir` have no rows: a scene crops by having the `crop` group (with both
// bounds), and the masks' folder is a path relative to the scene file (the parser, writer,
// Python and provenance say so by hand).
template <>
struct OptionFields<PreprocessOptions> {
  static constexpr const char* kSection = "preprocess";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = PreprocessOptions;
    v(&S::scale, FieldInfo("scale").Above(0).Doc("Points (and normals, viewpoint) scaled first: 0.001 for mm."));
    v(&S::translation, FieldInfo("translation").In("transform").Finite().Doc("m, after the rotation"));
    v(&S::rotation, FieldInfo("rotation").In("transform").Finite().Doc("axis * angle (rad)"));
    v(&S::crop_min, FieldInfo("min").In("crop").Python("crop_min").Finite());
    v(&S::crop_max, FieldInfo("max").In("crop").Python("crop_max").Finite());
    v(&S::plane_distance,
      FieldInfo("distance").In("plane").Required().Python("plane_distance").AtLeast(0).Doc("m; the dominant plane's points removed; 0 = off"));
    v(&S::plane_iterations, FieldInfo("iterations").In("plane").Python("plane_iterations").AtLeast(1));
    v(&S::voxel_size, FieldInfo("voxel_size").AtLeast(0).Doc("m; 0 = no downsampling"));
    v(&S::auto_voxel, FieldInfo("auto_voxel").AtLeast(0).Note("(0 = off)").Doc("in mean surface edges; 0 = off"));
    v(&S::auto_voxel_min_ratio, FieldInfo("auto_voxel_min_ratio").AtLeast(0));
    v(&S::flying_pixels, FieldInfo("flying_pixels")
                             .AtLeast(0)
                             .Note("(sigmas of the depth's noise; 0 = off)")
                             .Doc("Flying pixels: points between surfaces that no surface around them predicts "
                                  "within this many sigmas of the depth's noise (from the image's second differences), with a "
                                  "camera (registration.preprocess.flying_pixels; 0 = off)"));
    v(&S::depth_offset, FieldInfo("depth_offset")
                            .Doc("Take off each frame's common depth offset (flicker), measured on the static "
                                 "plane preprocess.plane removes, with a camera (registration.preprocess.depth_offset)"));
    v(&S::outlier_neighbors, FieldInfo("neighbors").In("outliers").Python("outlier_neighbors").AtLeast(0));
    v(&S::outlier_stddev, FieldInfo("stddev").In("outliers").Python("outlier_stddev").Above(0));
    v(&S::normal_neighbors, FieldInfo("neighbors").In("normals").Python("normal_neighbors").AtLeast(0));
  }
};

template <>
struct OptionFields<DataTermOptions> {
  static constexpr const char* kSection = "data";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = DataTermOptions;
    v(&S::model_to_cloud, FieldInfo("model_to_cloud"));
    v(&S::cloud_to_model, FieldInfo("cloud_to_model"));
    v(&S::max_distance, FieldInfo("max_distance").Finite());
    v(&S::loss, FieldInfo("loss").Doc("robust loss: huber, cauchy, tukey or none"));
    v(&S::loss_scale, FieldInfo("loss_scale").Above(0));
    v(&S::metric, FieldInfo("metric").Doc("point_to_point or point_to_plane"));
    v(&S::visibility, FieldInfo("visibility"));
    v(&S::cloud_stride, FieldInfo("cloud_stride").AtLeast(1));
    v(&S::auto_visibility, FieldInfo("auto_visibility"));
    v(&S::reciprocity, FieldInfo("reciprocity").AtLeast(0).Note("(0 = off)"));
    v(&S::hold_pairs_after, FieldInfo("hold_pairs_after").AtLeast(0).Note("(0 = never held)"));
    v(&S::occluders, FieldInfo("occluders"));
    v(&S::occluder_margin, FieldInfo("occluder_margin").Above(0));
    v(&S::max_strain_step, FieldInfo("max_strain_step").AtLeast(0).Note("(0 = off)"));
    v(&S::min_points, FieldInfo("min_points").AtLeast(0));
    v(&S::min_points_per_surface_vertex, FieldInfo("min_points_per_surface_vertex").AtLeast(0));
    v(&S::lost_coverage, FieldInfo("lost_coverage").AtLeast(0).AtMost(1).Note("(0 = never lost)"));
  }
};

template <>
struct OptionFields<WeightOptions> {
  static constexpr const char* kSection = "weights";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = WeightOptions;
    // data and data_per_area: which one a scene sets selects the weighting (the parser and
    // writer handle the pair; < 0 data means per area).
    v(&S::data, FieldInfo("data").Finite());
    v(&S::data_per_area, FieldInfo("data_per_area").AtLeast(0));
    v(&S::model_to_cloud_share, FieldInfo("model_to_cloud_share").AtLeast(0));
    v(&S::model_to_cloud_area_cap, FieldInfo("model_to_cloud_area_cap").AtLeast(0).Note("(0: no cap)"));
    v(&S::model_to_cloud_balance, FieldInfo("model_to_cloud_balance"));
    v(&S::elastic, FieldInfo("elastic").AtLeast(0));
    v(&S::barrier, FieldInfo("barrier").AtLeast(0).Note("(0 = off)"));
    v(&S::barrier_volume, FieldInfo("barrier_volume").Above(0).Below(1));
    v(&S::temporal, FieldInfo("temporal").AtLeast(0));
    v(&S::anchor, FieldInfo("anchor").AtLeast(0));
  }
};

template <>
struct OptionFields<ForceOptions> {
  static constexpr const char* kSection = "forces";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = ForceOptions;
    v(&S::estimate, FieldInfo("estimate"));
    v(&S::when_occluded, FieldInfo("when_occluded"));
    v(&S::when_occluded_pushing_only, FieldInfo("when_occluded_pushing_only"));
    v(&S::weight, FieldInfo("weight").Above(0));
    v(&S::adaptive_weight, FieldInfo("adaptive_weight"));
    v(&S::misfit_ratio, FieldInfo("misfit_ratio").Above(1));
    v(&S::sparsity, FieldInfo("sparsity").AtLeast(0));
    v(&S::pushing_only, FieldInfo("pushing_only"));
    v(&S::friction, FieldInfo("friction").Finite().Note("(< 0: no bound)"));
    v(&S::balance, FieldInfo("balance").AtLeast(1));
  }
};

template <>
struct OptionFields<FreeSpaceOptions> {
  static constexpr const char* kSection = "free_space";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = FreeSpaceOptions;
    v(&S::enabled, FieldInfo("enabled"));
    v(&S::tolerance, FieldInfo("tolerance").Above(0).Note("(m)"));
    v(&S::weight, FieldInfo("weight").Above(0).Note("(N/m per vertex; enabled: false turns it off)"));
  }
};

template <>
struct OptionFields<SolverOptions> {
  static constexpr const char* kSection = "solver";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = SolverOptions;
    v(&S::backend, FieldInfo("backend").Doc("ceres or fast"));
    v(&S::max_outer_iterations, FieldInfo("max_outer_iterations").AtLeast(1));
    v(&S::max_inner_iterations, FieldInfo("max_inner_iterations").AtLeast(1));
    v(&S::relative_energy_tolerance, FieldInfo("relative_energy_tolerance").AtLeast(0));
    v(&S::inner_tolerance, FieldInfo("inner_tolerance").AtLeast(0));
    v(&S::step_tolerance,
      FieldInfo("step_tolerance").AtLeast(0).Note("(a fraction of the mean edge length)"));
    v(&S::bulk_step_tolerance,
      FieldInfo("bulk_step_tolerance").AtLeast(0).Note("(a fraction of the mean edge length; 0 = off)"));
    v(&S::stiff_restart_volume,
      FieldInfo("stiff_restart_volume").Finite().Below(1).Note("(a fraction of each element's volume at the frame's start; 0 = off; < 0: automatic, 0.1 with the forces estimated, else off)"));
    v(&S::max_pcg_iterations, FieldInfo("max_pcg_iterations").AtLeast(0).Note("(0: factorize every step)"));
    v(&S::preconditioner,
      FieldInfo("preconditioner")
          .Doc("fast back end: auto (multigrid where the sparse factor would fill in), factor or multigrid"));
    v(&S::time_budget_s, FieldInfo("time_budget_s").AtLeast(0).Note("(0 = none)"));
    // Ceres' own settings: written only with backend ceres, refused beside backend fast.
    v(&S::trust_region, FieldInfo("trust_region").Doc("Ceres only"));
    v(&S::linear_solver, FieldInfo("linear_solver").Doc("Ceres only"));
    v(&S::num_threads, FieldInfo("threads")
                           .Python("num_threads")
                           .AtLeast(0)
                           .Note("(0: the cores other processes leave free, per frame)"));
    v(&S::predict_motion, FieldInfo("predict_motion"));
    v(&S::backtrack, FieldInfo("backtrack"));
    v(&S::cut_reversals, FieldInfo("cut_reversals"));
    v(&S::hold_hidden_turns,
      FieldInfo("hold_hidden_turns").Doc("Outer iterations leave out turns of free objects that their surface does not show."));
    v(&S::rigid_prealign, FieldInfo("rigid_prealign"));
    v(&S::rigid_iterations, FieldInfo("rigid_iterations").AtLeast(0));
  }
};

// The top level's own values; each section (camera, preprocess, data, weights, solver,
// forces, free_space) is a struct of its own, with its own table where it has one.
template <>
struct OptionFields<RegistrationOptions> {
  static constexpr const char* kSection = "";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = RegistrationOptions;
    v(&S::regularizer, FieldInfo("regularizer").Doc("corotational, linear, mass_spring or none"));
    v(&S::loads, FieldInfo("loads").Doc("The scene's gravity and loads act in the registration energy."));
    v(&S::initial_pose, FieldInfo("initial_pose")
                            .Doc("given (the meshes as given) or auto (a global search on the first frame "
                                 "when the given pose explains the cloud badly)"));
  }
};

}  // namespace femreg

#endif  // FEMREG_OPTION_FIELDS_H_
