// The femreg Python module (pybind11): scenes, meshes, materials and options; the Tracker
// with numpy in and out; the forward solve; the mesh, cloud and depth-image readers and
// writers. Every femreg::Status error becomes femreg.Error with the C++ message; a wrong
// array shape or an unknown option name is a ValueError.
//
// The per-frame path (Tracker.track): a C-contiguous float64 (N, 3) array is read in place
// and copied once into the tracker's cloud buffer (femreg::PointCloud owns its points);
// the GIL is released while the frame is solved; the result is one (V, 3) copy of the
// vertices (the tracker overwrites its own next frame).
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/io.h"
#include "femreg/mesh.h"
#include "femreg/point_cloud.h"
#include "femreg/registration.h"
#include "femreg/scene.h"
#include "femreg/tracker.h"
#include "femreg/version.h"

namespace py = pybind11;

namespace femreg {
namespace python {
namespace {

// Raised for every femreg::Status error (registered as femreg.Error, a RuntimeError).
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

void Check(const Status& status) {
  if (!status.ok()) throw Error(status.message());
}

using DoubleArray = py::array_t<double, py::array::forcecast>;

// An (N, 3) float array as Vertices; `what` names the argument in the ValueError.
void CopyRows3(const DoubleArray& array, const char* what, Vertices* out) {
  if (array.ndim() != 2 || array.shape(1) != 3) {
    std::string shape = "(";
    for (py::ssize_t i = 0; i < array.ndim(); ++i) {
      shape += (i ? ", " : "") + std::to_string(array.shape(i));
    }
    throw py::value_error(std::string(what) + ": expected an (N, 3) array, got shape " + shape +
                          (array.ndim() == 1 ? ",)" : ")"));
  }
  const py::ssize_t n = array.shape(0);
  out->resize(n, 3);
  if (n == 0) return;
  // Vertices is row-major: a C-contiguous array is one memcpy.
  if (array.flags() & py::array::c_style) {
    std::memcpy(out->data(), array.data(), static_cast<size_t>(n) * 3 * sizeof(double));
  } else {
    auto a = array.unchecked<2>();
    for (py::ssize_t i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) (*out)(i, k) = a(i, k);
    }
  }
}

py::array_t<double> ToArray(const Vertices& v) {
  py::array_t<double> out({static_cast<py::ssize_t>(v.rows()), static_cast<py::ssize_t>(3)});
  if (v.rows() > 0) {
    std::memcpy(out.mutable_data(), v.data(), static_cast<size_t>(v.rows()) * 3 * sizeof(double));
  }
  return out;
}

template <typename Enum>
Enum EnumFromString(const std::string& s, const char* field, const std::vector<Enum>& all) {
  Enum v;
  if (!FromString(s, &v)) {
    std::string names;
    for (Enum e : all) names += (names.empty() ? "" : ", ") + std::string(ToString(e));
    throw py::value_error(std::string(field) + ": unknown value '" + s + "' (use " + names + ")");
  }
  return v;
}

// Binds an enum field of a struct as a string property.
template <typename Class, typename Struct, typename Enum>
void EnumProperty(Class& cls, const char* name, Enum Struct::*field, const char* qualified,
                  std::vector<Enum> all, const char* doc) {
  cls.def_property(
      name, [field](const Struct& s) { return std::string(ToString(s.*field)); },
      [field, qualified, all](Struct& s, const std::string& v) {
        s.*field = EnumFromString(v, qualified, all);
      },
      doc);
}

py::dict EnergyDict(const EnergyTerms& e) {
  py::dict d;
  d["data"] = e.data;
  d["elastic"] = e.elastic;
  d["temporal"] = e.temporal;
  d["anchor"] = e.anchor;
  d["collision"] = e.collision;
  d["load"] = e.load;
  d["equilibrium"] = e.equilibrium;
  d["total"] = e.total();
  return d;
}

py::dict SummaryDict(const FrameSummary& s) {
  py::dict d;
  d["frame"] = s.frame;
  d["backend"] = ToString(s.backend);
  d["termination"] = ToString(s.termination);
  d["message"] = s.message;
  d["usable"] = s.IsSolutionUsable();
  d["cloud_points"] = s.cloud_points;
  d["nonfinite_dropped"] = s.nonfinite_dropped;
  d["points_used"] = s.points_used;
  d["initial_energy"] = EnergyDict(s.initial);
  d["final_energy"] = EnergyDict(s.final);
  d["outer_iterations"] = s.outer_iterations;
  d["inner_iterations"] = s.inner_iterations;
  d["model_to_cloud"] = s.model_to_cloud;
  d["cloud_to_model"] = s.cloud_to_model;
  d["rejected"] = s.rejected;
  d["occluded_points"] = s.occluded_points;
  d["rms_residual"] = s.rms_residual;
  d["contacts"] = s.contacts;
  d["object_contacts"] = s.object_contacts;
  d["obstacle_contacts"] = s.obstacle_contacts;
  d["max_penetration"] = s.max_penetration;
  d["min_gap"] = s.min_gap;
  py::list forces;  // per object pair and obstacle: other = -1 - i for obstacle i
  for (const ContactForce& f : s.contact_forces) {
    forces.append(py::dict(py::arg("object") = f.object, py::arg("other") = f.other, py::arg("contacts") = f.contacts,
                           py::arg("force") = Eigen::Vector3d(f.force), py::arg("friction") = Eigen::Vector3d(f.friction)));
  }
  d["contact_forces"] = forces;
  d["force"] = Eigen::Vector3d(s.force);
  d["torque"] = Eigen::Vector3d(s.torque);
  py::dict t;
  t["preprocess"] = s.time.preprocess;
  t["prealign"] = s.time.prealign;
  t["rotations"] = s.time.rotations;
  t["correspondences"] = s.time.correspondences;
  t["build"] = s.time.build;
  t["solve"] = s.time.solve;
  t["collision"] = s.time.collision;
  t["fracture"] = s.time.fracture;
  t["total"] = s.time.total;
  d["time_s"] = t;
  py::list iterations;
  for (const OuterIteration& it : s.iterations) {
    py::dict r;
    r["iteration"] = it.iteration;
    r["energy_before"] = EnergyDict(it.before);
    r["energy_after"] = EnergyDict(it.after);
    r["model_to_cloud"] = it.model_to_cloud;
    r["cloud_to_model"] = it.cloud_to_model;
    r["rejected"] = it.rejected;
    r["inner_iterations"] = it.inner_iterations;
    r["contacts"] = it.contacts;
    r["rms_residual"] = it.rms_residual;
    r["time_s"] = it.time_s;
    iterations.append(r);
  }
  d["iterations"] = iterations;
  py::list fractures;
  for (const FractureEvent& f : s.fractures) {
    py::dict r;
    r["frame"] = f.frame;
    r["object"] = f.object;
    r["iteration"] = f.iteration;
    r["node"] = f.node;
    r["original_node"] = f.original_node;
    r["normal"] = std::vector<double>{f.normal.x(), f.normal.y(), f.normal.z()};
    r["measure"] = f.measure;
    r["toughness"] = f.toughness;
    r["removed_elements"] = f.removed_elements;
    fractures.append(r);
  }
  d["fractures"] = fractures;
  d["report"] = s.BriefReport();
  return d;
}

// An (H, W) integer array as a RawDepthImage (values in depth units, 0 = no return).
void ToRawDepth(const py::array_t<uint16_t, py::array::forcecast>& depth, RawDepthImage* image) {
  if (depth.ndim() != 2) throw py::value_error("depth: expected an (H, W) array of depth units");
  image->height = static_cast<int>(depth.shape(0));
  image->width = static_cast<int>(depth.shape(1));
  image->values.resize(static_cast<size_t>(depth.size()));
  auto d = depth.unchecked<2>();
  size_t i = 0;
  for (py::ssize_t v = 0; v < depth.shape(0); ++v) {
    for (py::ssize_t u = 0; u < depth.shape(1); ++u) image->values[i++] = d(v, u);
  }
}

// An optional (H, W) mask (non-zero = keep) as flags.
bool ToKeep(const py::object& mask, const RawDepthImage& image, std::vector<uint8_t>* keep) {
  if (mask.is_none()) return false;
  auto m = mask.cast<py::array_t<uint8_t, py::array::forcecast>>();
  if (m.ndim() != 2 || m.shape(0) != image.height || m.shape(1) != image.width) {
    throw py::value_error("mask: expected an (H, W) array the size of the depth image (" +
                          std::to_string(image.height) + ", " + std::to_string(image.width) + ")");
  }
  keep->resize(static_cast<size_t>(m.size()));
  auto a = m.unchecked<2>();
  size_t i = 0;
  for (py::ssize_t v = 0; v < m.shape(0); ++v) {
    for (py::ssize_t u = 0; u < m.shape(1); ++u) (*keep)[i++] = a(v, u) != 0;
  }
  return true;
}

DepthImageOptions MakeDepthOptions(double depth_scale, double min_depth, double max_depth,
                                   int pixel_stride) {
  DepthImageOptions o;
  o.depth_scale = depth_scale;
  o.min_depth = min_depth;
  o.max_depth = max_depth;
  o.pixel_stride = pixel_stride;
  std::string why;
  if (!o.IsValid(&why)) throw py::value_error(why);
  return o;
}

// A scene and the tracker built from it, with a cloud buffer reused frame after frame.
class PyTracker {
 public:
  explicit PyTracker(std::unique_ptr<Tracker> tracker) : tracker_(std::move(tracker)) {}

  py::array_t<double> Track(const DoubleArray& points, const py::object& normals,
                            const py::object& labels, int object) {
    CheckObject(object);
    CopyRows3(points, "points", &cloud_.points);
    if (normals.is_none()) {
      cloud_.normals.resize(0, 3);
    } else {
      CopyRows3(normals.cast<DoubleArray>(), "normals", &cloud_.normals);
      if (cloud_.normals.rows() != cloud_.points.rows()) {
        throw py::value_error("normals: " + std::to_string(cloud_.normals.rows()) +
                              " rows for " + std::to_string(cloud_.points.rows()) + " points");
      }
    }
    if (labels.is_none()) {
      cloud_.labels.resize(0);
    } else {
      auto l = labels.cast<py::array_t<int, py::array::forcecast>>();
      if (l.ndim() != 1 || l.shape(0) != static_cast<py::ssize_t>(cloud_.points.rows())) {
        throw py::value_error("labels: expected " + std::to_string(cloud_.points.rows()) +
                              " labels (one per point)");
      }
      cloud_.labels = Eigen::Map<const Eigen::VectorXi>(l.data(), l.shape(0));
    }
    return TrackCloud(cloud_, object);
  }

  py::array_t<double> TrackCloud(const PointCloud& cloud, int object) {
    CheckObject(object);
    Status status;
    {
      py::gil_scoped_release release;
      status = tracker_->Track(cloud, &summary_);
    }
    Check(status);
    return ToArray(tracker_->vertices(object));
  }

  void CheckObject(int object) const {
    if (object < 0 || object >= tracker_->num_objects()) {
      throw py::index_error("object " + std::to_string(object) + ": the tracker has " +
                            std::to_string(tracker_->num_objects()) + " object(s)");
    }
  }

  // A depth image through the tracker's camera (options().camera).
  py::array_t<double> TrackDepth(const py::array_t<uint16_t, py::array::forcecast>& depth,
                                 const py::object& mask, double depth_scale, double min_depth,
                                 double max_depth, int pixel_stride, int object) {
    CheckObject(object);
    const DepthImageOptions options = MakeDepthOptions(depth_scale, min_depth, max_depth, pixel_stride);
    ToRawDepth(depth, &depth_);
    std::vector<uint8_t> keep;
    const bool masked = ToKeep(mask, depth_, &keep);
    Check(BackProjectDepth(depth_, tracker_->options().camera, options, masked ? &keep : nullptr,
                           &cloud_));
    return TrackCloud(cloud_, object);
  }

  Tracker& tracker() { return *tracker_; }
  const FrameSummary& summary() const { return summary_; }

 private:
  std::unique_ptr<Tracker> tracker_;
  PointCloud cloud_;  // reused: no allocation when the cloud size does not change
  RawDepthImage depth_;
  FrameSummary summary_;
};

py::dict ForwardSummaryDict(const ForwardSummary& s) {
  py::dict d;
  d["termination"] = ToString(s.termination);
  d["converged"] = s.termination == ForwardTermination::kConverged;
  d["message"] = s.message;
  d["iterations"] = s.NumNewtonIterations();
  d["load_steps"] = static_cast<int>(s.load_steps.size());
  d["free_dofs"] = s.num_free_dofs;
  d["initial_residual"] = s.initial_residual_norm;
  d["final_residual"] = s.final_residual_norm;
  d["final_energy"] = s.final_energy;
  d["max_displacement"] = s.max_displacement;
  d["inverted_elements"] = s.inverted_elements;
  d["time_s"] = s.total_time_s;
  d["report"] = s.BriefReport();
  return d;
}

int ObjectIndex(const Scene& scene, const py::object& object) {
  const int n = static_cast<int>(scene.objects.size());
  if (py::isinstance<py::str>(object)) {
    const std::string name = object.cast<std::string>();
    for (int i = 0; i < n; ++i) {
      if (scene.objects[i].name == name) return i;
    }
    std::string names;
    for (const ObjectSpec& o : scene.objects) names += (names.empty() ? "" : ", ") + o.name;
    throw py::value_error("object '" + name + "': the scene has no such object (objects: " +
                          names + ")");
  }
  const int i = object.cast<int>();
  if (i < 0 || i >= n) {
    throw py::index_error("object " + std::to_string(i) + ": the scene has " + std::to_string(n) +
                          " object(s)");
  }
  return i;
}

}  // namespace

}  // namespace python
}  // namespace femreg

PYBIND11_MODULE(_femreg, m) {
  using namespace femreg;           // NOLINT
  using namespace femreg::python;   // NOLINT
  m.doc() = "femreg: physics-regularized non-rigid registration of tetrahedral meshes to "
            "point clouds (C++ core, pybind11 bindings).";
  // The library's version (CMakeLists.txt's project() line): femreg.__version__.
  m.attr("__version__") = femreg::Version();

  static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      error(e.what());
    }
  });

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
      .def_readwrite("occluders", &DataTermOptions::occluders)
      .def_readwrite("occluder_margin", &DataTermOptions::occluder_margin);
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

  // ---- meshes ---------------------------------------------------------------------------
  py::class_<TetMesh>(m, "Mesh", "A tetrahedral mesh; arrays are read-only views of it.")
      .def_property_readonly("rest", [](const TetMesh& t) -> const Vertices& { return t.rest; },
                             py::return_value_policy::reference_internal, "#V by 3 rest positions")
      .def_property_readonly("x", [](const TetMesh& t) -> const Vertices& { return t.x; },
                             py::return_value_policy::reference_internal,
                             "#V by 3 current positions")
      .def_property_readonly("tets", [](const TetMesh& t) -> const Tets& { return t.tets; },
                             py::return_value_policy::reference_internal, "#T by 4 vertex indices")
      .def_property_readonly("surface", [](const TetMesh& t) -> const Triangles& { return t.surface; },
                             py::return_value_policy::reference_internal,
                             "#F by 3 boundary triangles, counter-clockwise seen from outside")
      .def_property_readonly("region", [](const TetMesh& t) -> const Eigen::VectorXi& { return t.region; },
                             py::return_value_policy::reference_internal, "#T region ids")
      .def_property_readonly("mass", [](const TetMesh& t) -> const Eigen::VectorXd& { return t.mass; },
                             py::return_value_policy::reference_internal, "#V lumped masses (kg)")
      .def_property_readonly("surface_vertices", [](const TetMesh& t) { return t.surface_vertices; })
      .def_property_readonly("num_vertices", &TetMesh::num_vertices)
      .def_property_readonly("num_tets", &TetMesh::num_tets)
      .def("set_positions",
           [](TetMesh& t, const DoubleArray& x) {
             Vertices v;
             CopyRows3(x, "positions", &v);
             if (v.rows() != t.rest.rows()) {
               throw py::value_error("positions: " + std::to_string(v.rows()) + " rows for " +
                                     std::to_string(t.rest.rows()) + " vertices");
             }
             t.x = v;
           },
           py::arg("positions"), "Sets the current positions x (#V by 3).")
      .def("__repr__", [](const TetMesh& t) {
        return "<femreg.Mesh " + std::to_string(t.num_vertices()) + " vertices, " +
               std::to_string(t.num_tets()) + " tetrahedra>";
      });

  m.def("read_mesh",
        [](const std::string& path) {
          TetMesh mesh;
          Check(ReadTetMesh(path, &mesh));
          return mesh;
        },
        py::arg("path"),
        "Reads a tetrahedral mesh (Gmsh, TetGen, MEDIT, VTK legacy, VTU; by content).");
  m.def("mesh_from_arrays",
        [](const DoubleArray& vertices, const py::array_t<int, py::array::forcecast>& tets) {
          TetMesh mesh;
          CopyRows3(vertices, "vertices", &mesh.rest);
          if (tets.ndim() != 2 || tets.shape(1) != 4) {
            throw py::value_error("tets: expected a (T, 4) integer array");
          }
          auto t = tets.unchecked<2>();
          mesh.tets.resize(tets.shape(0), 4);
          for (py::ssize_t i = 0; i < tets.shape(0); ++i) {
            for (int k = 0; k < 4; ++k) mesh.tets(i, k) = t(i, k);
          }
          Check(FinalizeMesh(&mesh, "mesh_from_arrays"));
          return mesh;
        },
        py::arg("vertices"), py::arg("tets"),
        "A mesh from (V, 3) positions and (T, 4) vertex indices; checked and oriented.");
  m.def("make_box",
        [](const Eigen::Vector3d& size, const Eigen::Vector3i& cells, const Eigen::Vector3d& origin) {
          if ((cells.array() < 1).any() || (size.array() <= 0).any()) {
            throw py::value_error("make_box: size must be > 0 and cells >= 1");
          }
          return MakeBox(size, cells.x(), cells.y(), cells.z(), origin);
        },
        py::arg("size"), py::arg("cells"), py::arg("origin") = Eigen::Vector3d::Zero(),
        "A box [origin, origin + size] of cells[0] * cells[1] * cells[2] cubes, 6 tets each.");
  m.def("write_vtu",
        [](const std::string& path, const TetMesh& mesh, const py::object& positions,
           const py::dict& fields) {
          Vertices x = mesh.x;
          if (!positions.is_none()) CopyRows3(positions.cast<DoubleArray>(), "positions", &x);
          if (x.rows() != mesh.rest.rows()) {
            throw py::value_error("positions: " + std::to_string(x.rows()) + " rows for " +
                                  std::to_string(mesh.rest.rows()) + " vertices");
          }
          std::vector<MeshField> out;
          for (const auto& [key, value] : fields) {
            MeshField f;
            f.name = key.cast<std::string>();
            auto a = value.cast<DoubleArray>();
            const py::ssize_t rows = a.shape(0);
            const py::ssize_t cols = a.ndim() == 1 ? 1 : a.shape(1);
            if (a.ndim() > 2 || (cols != 1 && cols != 3) ||
                (rows != mesh.num_vertices() && rows != mesh.num_tets())) {
              throw py::value_error("fields['" + f.name +
                                    "']: expected one row per vertex or per element with 1 "
                                    "or 3 columns");
            }
            f.per_cell = rows != mesh.num_vertices();
            f.values.resize(rows, cols);
            auto u = a.unchecked();
            for (py::ssize_t i = 0; i < rows; ++i) {
              for (py::ssize_t k = 0; k < cols; ++k) {
                f.values(i, k) = a.ndim() == 1 ? a.at(i) : a.at(i, k);
              }
            }
            (void)u;
            out.push_back(std::move(f));
          }
          Check(WriteVtu(path, mesh, x, out));
        },
        py::arg("path"), py::arg("mesh"), py::arg("positions") = py::none(),
        py::arg("fields") = py::dict(),
        "Writes the mesh at `positions` (default mesh.x) as VTU with point or cell fields "
        "({name: (V,) / (V, 3) / (T,) / (T, 3) array}); atomic.");
  m.def("write_ply_surface",
        [](const std::string& path, const TetMesh& mesh, const py::object& positions) {
          Vertices x = mesh.x;
          if (!positions.is_none()) CopyRows3(positions.cast<DoubleArray>(), "positions", &x);
          if (x.rows() != mesh.rest.rows()) throw py::value_error("positions: wrong row count");
          Check(WritePlySurface(path, mesh, x));
        },
        py::arg("path"), py::arg("mesh"), py::arg("positions") = py::none(),
        "Writes the boundary surface as ASCII PLY; atomic.");
  m.def("write_obj_surface",
        [](const std::string& path, const TetMesh& mesh, const py::object& positions) {
          Vertices x = mesh.x;
          if (!positions.is_none()) CopyRows3(positions.cast<DoubleArray>(), "positions", &x);
          if (x.rows() != mesh.rest.rows()) throw py::value_error("positions: wrong row count");
          Check(WriteObjSurface(path, mesh, x));
        },
        py::arg("path"), py::arg("mesh"), py::arg("positions") = py::none(),
        "Writes the boundary surface as OBJ; atomic.");

  // ---- point clouds ---------------------------------------------------------------------
  py::class_<PointCloud>(m, "PointCloud", "Points (metres, scene frame), optional normals and labels.")
      .def(py::init([](const DoubleArray& points, const py::object& normals) {
             PointCloud c;
             CopyRows3(points, "points", &c.points);
             if (!normals.is_none()) {
               CopyRows3(normals.cast<DoubleArray>(), "normals", &c.normals);
               if (c.normals.rows() != c.points.rows()) {
                 throw py::value_error("normals: one row per point expected");
               }
             }
             return c;
           }),
           py::arg("points"), py::arg("normals") = py::none())
      .def_property_readonly("points", [](const PointCloud& c) -> const Vertices& { return c.points; },
                             py::return_value_policy::reference_internal)
      .def_property_readonly("normals",
                             [](py::object self) -> py::object {
                               const PointCloud& c = self.cast<const PointCloud&>();
                               if (!c.has_normals()) return py::none();
                               return py::cast(c.normals, py::return_value_policy::reference_internal, self);
                             })
      .def_property_readonly("labels",
                             [](py::object self) -> py::object {
                               const PointCloud& c = self.cast<const PointCloud&>();
                               if (!c.has_labels()) return py::none();
                               return py::cast(c.labels, py::return_value_policy::reference_internal, self);
                             })
      .def("__len__", &PointCloud::size)
      .def("__repr__", [](const PointCloud& c) {
        return "<femreg.PointCloud " + std::to_string(c.size()) + " points" +
               (c.has_normals() ? ", normals" : "") + (c.has_labels() ? ", labels" : "") + ">";
      });

  m.def("read_point_cloud",
        [](const std::string& path) {
          PointCloud cloud;
          int dropped = 0;
          SensorPose sensor;
          Check(ReadPointCloud(path, &cloud, &dropped, &sensor));
          py::dict info;
          info["nonfinite_dropped"] = dropped;
          info["viewpoint_known"] = sensor.known;
          info["viewpoint"] = Eigen::Vector3d(sensor.origin);
          return py::make_tuple(std::move(cloud), info);
        },
        py::arg("path"),
        "Reads a PCD, PLY or x y z [nx ny nz] text cloud. Returns (PointCloud, info) where "
        "info has nonfinite_dropped, viewpoint_known and viewpoint (the PCD VIEWPOINT origin).");
  m.def("write_point_cloud",
        [](const std::string& path, const DoubleArray& points, const py::object& normals) {
          PointCloud c;
          CopyRows3(points, "points", &c.points);
          if (!normals.is_none()) {
            CopyRows3(normals.cast<DoubleArray>(), "normals", &c.normals);
            if (c.normals.rows() != c.points.rows()) {
              throw py::value_error("normals: one row per point expected");
            }
          }
          Check(WritePointCloud(path, c));
        },
        py::arg("path"), py::arg("points"), py::arg("normals") = py::none(),
        "Writes a binary PCD (with normals when given); atomic.");

  // ---- depth images --------------------------------------------------------------------
  m.def("read_depth_png",
        [](const std::string& path) {
          RawDepthImage image;
          Check(ReadDepthPng(path, &image));
          py::array_t<uint16_t> out({static_cast<py::ssize_t>(image.height),
                                     static_cast<py::ssize_t>(image.width)});
          std::memcpy(out.mutable_data(), image.values.data(), image.values.size() * sizeof(uint16_t));
          return out;
        },
        py::arg("path"), "A 16-bit greyscale PNG as an (H, W) uint16 array.");
  m.def("write_depth_png",
        [](const std::string& path, const py::array_t<uint16_t, py::array::forcecast>& depth) {
          RawDepthImage image;
          ToRawDepth(depth, &image);
          Check(WriteDepthPng(path, image));
        },
        py::arg("path"), py::arg("depth"), "Writes an (H, W) array as a 16-bit PNG; atomic.");
  m.def("depth_to_points",
        [](const py::array_t<uint16_t, py::array::forcecast>& depth, const CameraOptions& camera,
           const py::object& mask, double depth_scale, double min_depth, double max_depth,
           int pixel_stride) {
          RawDepthImage image;
          ToRawDepth(depth, &image);
          std::vector<uint8_t> keep;
          const bool masked = ToKeep(mask, image, &keep);
          PointCloud cloud;
          Check(BackProjectDepth(image, camera,
                                 MakeDepthOptions(depth_scale, min_depth, max_depth, pixel_stride),
                                 masked ? &keep : nullptr, &cloud));
          return ToArray(cloud.points);
        },
        py::arg("depth"), py::arg("camera"), py::arg("mask") = py::none(),
        py::arg("depth_scale") = 0.001, py::arg("min_depth") = 0.0, py::arg("max_depth") = 0.0,
        py::arg("pixel_stride") = 1,
        "Back-projects an (H, W) depth image (depth units, 0 = no return) through the camera: "
        "(N, 3) points in the scene frame.");
  m.def("read_depth_frame",
        [](const std::string& path, const CameraOptions& camera, double depth_scale,
           double min_depth, double max_depth, int pixel_stride, const std::string& mask_dir) {
          DepthImageOptions options = MakeDepthOptions(depth_scale, min_depth, max_depth, pixel_stride);
          options.mask_dir = mask_dir;
          PointCloud cloud;
          Check(ReadDepthFrame(path, camera, options, &cloud));
          return cloud;
        },
        py::arg("path"), py::arg("camera"), py::arg("depth_scale") = 0.001,
        py::arg("min_depth") = 0.0, py::arg("max_depth") = 0.0, py::arg("pixel_stride") = 1,
        py::arg("mask_dir") = "",
        "A depth PNG frame back-projected through the camera (and masked by mask_dir/NAME.png "
        "when mask_dir is given): a PointCloud.");

  // ---- scenes ---------------------------------------------------------------------------
  py::class_<Scene>(m, "Scene", "A scene file: objects, materials, camera, registration settings.")
      .def_readonly("path", &Scene::path)
      .def_readonly("description", &Scene::description)
      .def_readwrite("registration", &Scene::registration,
                     "RegistrationOptions, changed in place (scene.registration.solver.backend = \"fast\")")
      .def_property_readonly("object_names",
                             [](const Scene& s) {
                               std::vector<std::string> names;
                               for (const ObjectSpec& o : s.objects) names.push_back(o.name);
                               return names;
                             })
      .def("material",
           [](const Scene& s, const py::object& object) {
             return s.objects[ObjectIndex(s, object)].material;
           },
           py::arg("object") = 0, "The object's material (by index or name).")
      .def("load_mesh",
           [](const Scene& s, const py::object& object) {
             TetMesh mesh;
             Check(LoadObjectMesh(s, ObjectIndex(s, object), &mesh));
             return mesh;
           },
           py::arg("object") = 0,
           "The object's mesh with the scene's scale and pose applied, and its masses.")
      .def("to_yaml", [](const Scene& s) { return SceneToYaml(s); })
      .def("__repr__", [](const Scene& s) {
        return "<femreg.Scene '" + s.path + "', " + std::to_string(s.objects.size()) + " object(s)>";
      });
  m.def("load_scene",
        [](const std::string& path) {
          Scene scene;
          Check(LoadScene(path, &scene));
          return scene;
        },
        py::arg("path"), "Reads and validates a scene file (YAML).");
  m.def("parse_scene",
        [](const std::string& text, const std::string& base_dir) {
          Scene scene;
          Check(ParseScene(text, "<string>", base_dir, &scene));
          return scene;
        },
        py::arg("text"), py::arg("base_dir") = ".",
        "A scene from YAML text; relative mesh paths resolve against base_dir.");

  // ---- the tracker ----------------------------------------------------------------------
  py::class_<PyTracker>(m, "Tracker",
                        "Registers the scene's meshes to one point cloud per call.")
      .def(py::init([](const Scene& scene) {
             std::unique_ptr<Tracker> t;
             Check(Tracker::Create(scene, &t));
             return std::make_unique<PyTracker>(std::move(t));
           }),
           py::arg("scene"), "A tracker for every object of a scene (femreg.load_scene).")
      .def(py::init([](const std::vector<TetMesh>& meshes, const std::vector<Material>& materials,
                       const RegistrationOptions& options) {
             if (materials.size() != meshes.size()) {
               throw py::value_error("materials: " + std::to_string(materials.size()) +
                                     " for " + std::to_string(meshes.size()) + " meshes");
             }
             std::vector<ObjectMaterial> object_materials(materials.begin(), materials.end());
             std::unique_ptr<Tracker> t;
             Check(Tracker::Create(meshes, object_materials, options, &t));
             return std::make_unique<PyTracker>(std::move(t));
           }),
           py::arg("meshes"), py::arg("materials"), py::arg("options") = RegistrationOptions(),
           "A tracker for meshes built in code (their x is the initial shape), one Material "
           "per mesh.")
      .def("track", &PyTracker::Track, py::arg("points"), py::arg("normals") = py::none(),
           py::arg("labels") = py::none(), py::arg("object") = 0,
           "Registers to one cloud: points (N, 3) in metres, scene frame; optional normals "
           "(N, 3) and labels (N,). Returns object `object`'s (V, 3) vertices (a copy); the "
           "frame summary is in `summary`. Bad data is reported there, never raised.")
      .def("track_depth", &PyTracker::TrackDepth, py::arg("depth"), py::arg("mask") = py::none(),
           py::arg("depth_scale") = 0.001, py::arg("min_depth") = 0.0, py::arg("max_depth") = 0.0,
           py::arg("pixel_stride") = 1, py::arg("object") = 0,
           "Registers to a depth image: depth (H, W) integer depth units (0 = no return), "
           "back-projected through the scene's camera (registration.camera); optional mask "
           "(H, W), non-zero = keep. Returns the (V, 3) vertices like track().")
      .def("track_cloud", &PyTracker::TrackCloud, py::arg("cloud"), py::arg("object") = 0,
           "track() for a femreg.PointCloud (e.g. from read_point_cloud or a depth image).")
      .def_property_readonly("summary",
                             [](const PyTracker& t) { return SummaryDict(t.summary()); },
                             "The last frame's summary as a dict.")
      .def_property_readonly("full_report",
                             [](const PyTracker& t) { return t.summary().FullReport(); })
      .def_property_readonly("num_objects", [](PyTracker& t) { return t.tracker().num_objects(); })
      .def_property_readonly("frame", [](PyTracker& t) { return t.tracker().frame(); },
                             "frames tracked so far")
      .def("vertices",
           [](PyTracker& t, int object) {
             t.CheckObject(object);
             return ToArray(t.tracker().vertices(object));
           },
           py::arg("object") = 0, "(V, 3) current positions (a copy).")
      .def("external_forces",
           [](PyTracker& t, int object) {
             t.CheckObject(object);
             return ToArray(t.tracker().external_forces(object));
           },
           py::arg("object") = 0,
           "(V, 3) the external force on each vertex in the last frame (N): the estimated ones "
           "(registration.forces.estimate) and the contacts', zero at clamps and anchors; "
           "without forces.estimate, the data term's pull.")
      .def("mesh",
           [](PyTracker& t, int object) {
             t.CheckObject(object);
             return t.tracker().mesh(object);
           },
           py::arg("object") = 0, "A copy of the object's mesh (rest data, topology, x).")
      .def("vertex_residuals",
           [](PyTracker& t, int object) {
             t.CheckObject(object);
             return Eigen::VectorXd(t.tracker().vertex_residuals(object));
           },
           py::arg("object") = 0,
           "(V,) distance (m) to the nearest cloud point in the last frame; NaN inside.")
      .def("vertex_observed",
           [](PyTracker& t, int object) {
             t.CheckObject(object);
             const std::vector<char>& o = t.tracker().vertex_observed(object);
             py::array_t<bool> out(static_cast<py::ssize_t>(o.size()));
             for (size_t i = 0; i < o.size(); ++i) out.mutable_at(i) = o[i] != 0;
             return out;
           },
           py::arg("object") = 0, "(V,) whether each vertex had a data partner last frame.")
      .def("set_vertices",
           [](PyTracker& t, int object, const DoubleArray& x) {
             t.CheckObject(object);
             Vertices v;
             CopyRows3(x, "x", &v);
             Check(t.tracker().SetVertices(object, v));
           },
           py::arg("object"), py::arg("x"),
           "Puts the object's vertices at x and forgets the motion so far.")
      .def("add_anchor",
           [](PyTracker& t, const std::string& name, int object, const std::vector<int>& vertices,
              bool hard, double weight) {
             Check(t.tracker().AddAnchor(name, object, vertices, hard, weight));
           },
           py::arg("name"), py::arg("object"), py::arg("vertices"), py::arg("hard") = true,
           py::arg("weight") = 0.0)
      .def("set_anchor_targets",
           [](PyTracker& t, const std::string& name, const DoubleArray& targets) {
             Vertices v;
             CopyRows3(targets, "targets", &v);
             Check(t.tracker().SetAnchorTargets(name, v));
           },
           py::arg("name"), py::arg("targets"))
      .def("set_anchor_trajectory",
           [](PyTracker& t, const std::string& name, const DoubleArray& translations,
              const std::optional<DoubleArray>& rotations, const std::array<double, 3>& centre) {
             Vertices tr;
             CopyRows3(translations, "translations", &tr);
             std::vector<Eigen::Vector3d> tv;
             for (Eigen::Index i = 0; i < tr.rows(); ++i) tv.push_back(tr.row(i).transpose());
             if (!rotations) {
               Check(t.tracker().SetAnchorTrajectory(name, tv));
               return;
             }
             Vertices rot;
             CopyRows3(*rotations, "rotations", &rot);
             std::vector<Eigen::Vector3d> rv;
             for (Eigen::Index i = 0; i < rot.rows(); ++i) rv.push_back(rot.row(i).transpose());
             Check(t.tracker().SetAnchorTrajectory(name, tv, rv, Eigen::Vector3d(centre[0], centre[1], centre[2])));
           },
           py::arg("name"), py::arg("translations"), py::arg("rotations") = py::none(),
           py::arg("centre") = std::array<double, 3>{0, 0, 0},
           "Moves the anchored set by translations[frame] (F, 3) from where it was added, after "
           "turning it by rotations[frame] (axis * angle, rad) about centre.")
      .def("set_external_loads",
           [](PyTracker& t, int object, const std::array<double, 3>& gravity,
              const std::optional<std::vector<int>>& vertices, const std::optional<DoubleArray>& forces) {
             t.CheckObject(object);
             std::vector<std::pair<int, Eigen::Vector3d>> nodal;
             if (vertices.has_value() != forces.has_value()) {
               throw py::value_error("set_external_loads: give vertices and forces together");
             }
             if (vertices) {
               Vertices f;
               CopyRows3(*forces, "forces", &f);
               if (static_cast<Eigen::Index>(vertices->size()) != f.rows()) {
                 throw py::value_error("set_external_loads: one force row per vertex");
               }
               for (size_t i = 0; i < vertices->size(); ++i) {
                 nodal.emplace_back((*vertices)[i], f.row(static_cast<Eigen::Index>(i)).transpose());
               }
             }
             Check(t.tracker().SetExternalLoads(object, Eigen::Vector3d(gravity[0], gravity[1], gravity[2]), nodal));
           },
           py::arg("object"), py::arg("gravity"), py::arg("vertices") = py::none(), py::arg("forces") = py::none(),
           "Gravity (m/s^2, on the lumped masses) and nodal forces (N) in the registration energy.")
      .def_property_readonly("options", [](PyTracker& t) { return t.tracker().options(); });

  // ---- forward simulation ---------------------------------------------------------------
  m.def("simulate",
        [](const Scene& scene, const py::object& object, const std::string& model,
           int load_steps, int max_iterations, const std::string& tangent, int threads) {
          const int index = ObjectIndex(scene, object);
          ElasticModelType model_type = scene.forward_model;
          if (!model.empty() && !FromString(model, &model_type)) {
            throw py::value_error("model: use corotational or linear (got '" + model + "')");
          }
          ForwardOptions forward = scene.forward;
          if (load_steps > 0) forward.load_steps = load_steps;
          if (max_iterations > 0) forward.max_iterations = max_iterations;
          if (!tangent.empty() && !FromString(tangent, &forward.tangent)) {
            throw py::value_error("tangent: use full, projected or warped (got '" + tangent + "')");
          }
          forward.num_threads = threads;
          TetMesh mesh;
          Check(LoadObjectMesh(scene, index, &mesh));
          ForwardProblem problem;
          Check(BuildForwardProblem(scene, index, mesh, &problem));
          ForwardSummary summary;
          Status status;
          {
            py::gil_scoped_release release;
            ElasticModel elastic;
            elastic.Build(mesh, model_type, scene.objects[index].Materials());
            status = SolveQuasiStatic(problem, forward, &elastic, &mesh, &summary);
          }
          Check(status);
          py::dict result = ForwardSummaryDict(summary);
          result["object"] = scene.objects[index].name;
          result["vertices"] = ToArray(mesh.x);
          result["mesh"] = std::move(mesh);
          return result;
        },
        py::arg("scene"), py::arg("object") = 0, py::arg("model") = "",
        py::arg("load_steps") = 0, py::arg("max_iterations") = 0, py::arg("tangent") = "",
        py::arg("threads") = 0,
        "The quasi-static equilibrium of one object under the scene's clamps, prescribed "
        "displacements, loads and gravity (femreg simulate). Returns a dict: vertices (V, 3), "
        "mesh (at the result), converged, termination, message, iterations, residuals, ... "
        "A solve that does not converge is reported there (converged False), not raised.");

}
