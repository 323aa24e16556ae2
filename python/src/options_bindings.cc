// Python bindings: Material and the registration options (the scene file's `registration:`
// keys), enum fields as strings.
#include <string>

#include "bindings.h"
#include "femreg/fem.h"
#include "femreg/registration.h"

namespace femreg {
namespace python {

void BindOptions(py::module_& m) {
  // ---- materials and options ------------------------------------------------------------
  py::class_<Material>(m, "Material", "Isotropic linear elastic material (SI units).")
      .def(py::init([](double e, double nu, double rho) {
             Material mat;
             mat.youngs_modulus = e;
             mat.poisson_ratio = nu;
             mat.density = rho;
             std::string why;
             if (!mat.IsValid(&why)) throw py::value_error("Material: " + why);
             return mat;
           }),
           py::arg("youngs_modulus") = 1.0e5, py::arg("poisson_ratio") = 0.3,
           py::arg("density") = 1000.0)
      .def_readwrite("youngs_modulus", &Material::youngs_modulus, "E (Pa)")
      .def_readwrite("poisson_ratio", &Material::poisson_ratio, "nu, in (-1, 0.5)")
      .def_readwrite("density", &Material::density, "kg/m^3")
      .def("__repr__", [](const Material& mat) {
        return "Material(youngs_modulus=" + py::repr(py::float_(mat.youngs_modulus)).cast<std::string>() +
               ", poisson_ratio=" + py::repr(py::float_(mat.poisson_ratio)).cast<std::string>() +
               ", density=" + py::repr(py::float_(mat.density)).cast<std::string>() + ")";
      });

  py::class_<CameraOptions>(m, "CameraOptions",
                            "The camera: pose (position, target, up) and pinhole intrinsics.")
      .def(py::init<>())
      .def_readwrite("enabled", &CameraOptions::enabled)
      .def_readwrite("position", &CameraOptions::position)
      .def_readwrite("target", &CameraOptions::target)
      .def_readwrite("up", &CameraOptions::up)
      .def_readwrite("fx", &CameraOptions::fx)
      .def_readwrite("fy", &CameraOptions::fy)
      .def_readwrite("cx", &CameraOptions::cx)
      .def_readwrite("cy", &CameraOptions::cy)
      .def_readwrite("width", &CameraOptions::width)
      .def_readwrite("height", &CameraOptions::height);

  py::class_<PreprocessOptions>(m, "PreprocessOptions")
      .def(py::init<>())
      .def_readwrite("crop", &PreprocessOptions::crop)
      .def_readwrite("crop_min", &PreprocessOptions::crop_min)
      .def_readwrite("crop_max", &PreprocessOptions::crop_max)
      .def_readwrite("voxel_size", &PreprocessOptions::voxel_size)
      .def_readwrite("outlier_neighbors", &PreprocessOptions::outlier_neighbors)
      .def_readwrite("outlier_stddev", &PreprocessOptions::outlier_stddev)
      .def_readwrite("normal_neighbors", &PreprocessOptions::normal_neighbors)
      .def_readwrite("plane_distance", &PreprocessOptions::plane_distance)
      .def_readwrite("plane_iterations", &PreprocessOptions::plane_iterations)
      .def_readwrite("mask_dir", &PreprocessOptions::mask_dir,
                     "Depth frames' masks, mask_dir/<frame name>.png (registration.preprocess."
                     "mask_dir; read_depth_frame(..., mask_dir=...) applies them)");

  auto data = py::class_<DataTermOptions>(m, "DataTermOptions");
  data.def(py::init<>())
      .def_readwrite("model_to_cloud", &DataTermOptions::model_to_cloud)
      .def_readwrite("cloud_to_model", &DataTermOptions::cloud_to_model)
      .def_readwrite("max_distance", &DataTermOptions::max_distance)
      .def_readwrite("loss_scale", &DataTermOptions::loss_scale)
      .def_readwrite("visibility", &DataTermOptions::visibility)
      .def_readwrite("auto_visibility", &DataTermOptions::auto_visibility)
      .def_readwrite("reciprocity", &DataTermOptions::reciprocity)
      .def_readwrite("cloud_stride", &DataTermOptions::cloud_stride)
      .def_readwrite("hold_pairs_after", &DataTermOptions::hold_pairs_after)
      .def_readwrite("lost_coverage", &DataTermOptions::lost_coverage)
      .def_readwrite("occluders", &DataTermOptions::occluders)
      .def_readwrite("occluder_margin", &DataTermOptions::occluder_margin)
      .def_readwrite("max_strain_step", &DataTermOptions::max_strain_step);
  EnumProperty(data, "loss", &DataTermOptions::loss, "data.loss",
               {RobustLoss::kNone, RobustLoss::kHuber, RobustLoss::kCauchy, RobustLoss::kTukey},
               "robust loss: none, huber, cauchy, tukey");
  EnumProperty(data, "metric", &DataTermOptions::metric, "data.metric",
               {DataMetric::kPointToPoint, DataMetric::kPointToPlane},
               "point_to_point or point_to_plane");

  py::class_<ForceOptions>(m, "ForceOptions",
                           "Equilibrium registration: external forces estimated every frame "
                           "(the scene's registration.forces).")
      .def(py::init<>())
      .def_readwrite("estimate", &ForceOptions::estimate)
      .def_readwrite("weight", &ForceOptions::weight)
      .def_readwrite("sparsity", &ForceOptions::sparsity)
      .def_readwrite("pushing_only", &ForceOptions::pushing_only)
      .def_readwrite("friction", &ForceOptions::friction)
      .def_readwrite("balance", &ForceOptions::balance);

  py::class_<FreeSpaceOptions>(m, "FreeSpaceOptions",
                               "Free space: surface vertices in front of the observed depth "
                               "(the scene's registration.free_space).")
      .def(py::init<>())
      .def_readwrite("enabled", &FreeSpaceOptions::enabled)
      .def_readwrite("tolerance", &FreeSpaceOptions::tolerance)
      .def_readwrite("weight", &FreeSpaceOptions::weight);

  py::class_<WeightOptions>(m, "WeightOptions")
      .def(py::init<>())
      .def_readwrite("data", &WeightOptions::data)
      .def_readwrite("data_per_area", &WeightOptions::data_per_area)
      .def_readwrite("model_to_cloud_share", &WeightOptions::model_to_cloud_share)
      .def_readwrite("model_to_cloud_area_cap", &WeightOptions::model_to_cloud_area_cap)
      .def_readwrite("model_to_cloud_balance", &WeightOptions::model_to_cloud_balance)
      .def_readwrite("elastic", &WeightOptions::elastic)
      .def_readwrite("barrier", &WeightOptions::barrier)
      .def_readwrite("barrier_volume", &WeightOptions::barrier_volume)
      .def_readwrite("temporal", &WeightOptions::temporal)
      .def_readwrite("anchor", &WeightOptions::anchor);

  auto solver = py::class_<SolverOptions>(m, "SolverOptions");
  solver.def(py::init<>())
      .def_readwrite("max_outer_iterations", &SolverOptions::max_outer_iterations)
      .def_readwrite("max_inner_iterations", &SolverOptions::max_inner_iterations)
      .def_readwrite("inner_tolerance", &SolverOptions::inner_tolerance)
      .def_readwrite("relative_energy_tolerance", &SolverOptions::relative_energy_tolerance)
      .def_readwrite("step_tolerance", &SolverOptions::step_tolerance)
      .def_readwrite("bulk_step_tolerance", &SolverOptions::bulk_step_tolerance)
      .def_readwrite("time_budget_s", &SolverOptions::time_budget_s)
      .def_readwrite("num_threads", &SolverOptions::num_threads)
      .def_readwrite("predict_motion", &SolverOptions::predict_motion)
      .def_readwrite("backtrack", &SolverOptions::backtrack)
      .def_readwrite("rigid_prealign", &SolverOptions::rigid_prealign)
      .def_readwrite("rigid_iterations", &SolverOptions::rigid_iterations);
  EnumProperty(solver, "backend", &SolverOptions::backend, "solver.backend",
               {SolverBackend::kCeres, SolverBackend::kFast}, "ceres or fast");
  EnumProperty(solver, "trust_region", &SolverOptions::trust_region, "solver.trust_region",
               {TrustRegion::kLevenbergMarquardt, TrustRegion::kDogleg}, "Ceres only");
  EnumProperty(solver, "linear_solver", &SolverOptions::linear_solver, "solver.linear_solver",
               {LinearSolver::kSparseNormalCholesky, LinearSolver::kConjugateGradients},
               "Ceres only");
  EnumProperty(solver, "preconditioner", &SolverOptions::preconditioner, "solver.preconditioner",
               {Preconditioner::kAuto, Preconditioner::kFactor, Preconditioner::kMultigrid},
               "fast back end: auto (multigrid where the sparse factor would fill in), factor or multigrid");

  auto options = py::class_<RegistrationOptions>(
      m, "RegistrationOptions",
      "Every registration setting; the fields mirror the scene file's `registration:` keys.");
  options.def(py::init<>())
      .def_readwrite("camera", &RegistrationOptions::camera)
      .def_readwrite("preprocess", &RegistrationOptions::preprocess)
      .def_readwrite("data", &RegistrationOptions::data)
      .def_readwrite("weights", &RegistrationOptions::weights)
      .def_readwrite("solver", &RegistrationOptions::solver)
      .def_readwrite("forces", &RegistrationOptions::forces)
      .def_readwrite("free_space", &RegistrationOptions::free_space)
      .def_readwrite("loads", &RegistrationOptions::loads,
                     "The scene's gravity and loads act in the registration energy.")
      .def("validate",
           [](const RegistrationOptions& o) {
             std::string why;
             if (!o.IsValid(&why)) throw py::value_error("RegistrationOptions: " + why);
           },
           "Raises ValueError naming the first bad field.");
  EnumProperty(options, "regularizer", &RegistrationOptions::regularizer, "regularizer",
               {Regularizer::kCorotational, Regularizer::kLinear, Regularizer::kMassSpring,
                Regularizer::kNone},
               "corotational, linear, mass_spring or none");
  EnumProperty(options, "initial_pose", &RegistrationOptions::initial_pose, "initial_pose",
               {InitialPose::kGiven, InitialPose::kAuto},
               "given (the meshes as given) or auto (a global search on the first frame when the "
               "given pose explains the cloud badly)");
}

}  // namespace python
}  // namespace femreg
