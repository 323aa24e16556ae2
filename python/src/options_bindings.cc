// Python bindings: Material and the registration options (the scene file's `registration:`
// keys), enum fields as strings. The structs' fields come from their tables
// (femreg/field_table.h, DefFields), and Material's constructor too (DefFieldsInit).
#include <string>

#include "bindings.h"
#include "femreg/fem.h"
#include "femreg/registration.h"

namespace femreg {
namespace python {

void BindOptions(py::module_& m) {
  // ---- materials and options ------------------------------------------------------------
  // A Material's values are checked when set, as its constructor checks them: a scene
  // object's material (scene.object(...).material, changed in place) is otherwise first
  // checked when a tracker is built from the scene.
  auto material = py::class_<Material>(m, "Material", "Isotropic linear elastic material (SI units).");
  DefFieldsInit(material, "Material", +[](const Material& mat, std::string* why) { return mat.IsValid(why); });
  DefCheckedFields(material, +[](const Material& mat, const std::string&, std::string* why) {
    if (mat.IsValid(why)) return true;
    *why = "Material: " + *why;
    return false;
  });

  auto camera = py::class_<CameraOptions>(m, "CameraOptions",
                                          "The camera: pose (position, target, up) and pinhole intrinsics.");
  camera.def(py::init<>()).def_readwrite("enabled", &CameraOptions::enabled);
  DefFields(camera);

  auto preprocess = py::class_<PreprocessOptions>(m, "PreprocessOptions");
  preprocess.def(py::init<>())
      .def_readwrite("crop", &PreprocessOptions::crop, "Keep the points within [crop_min, crop_max] only.")
      .def_readwrite("mask_dir", &PreprocessOptions::mask_dir,
                     "Depth frames' masks, mask_dir/<frame name>.png (registration.preprocess."
                     "mask_dir; read_depth_frame(..., mask_dir=...) applies them)");
  DefFields(preprocess);

  auto data = py::class_<DataTermOptions>(m, "DataTermOptions");
  data.def(py::init<>());
  DefFields(data);

  auto forces = py::class_<ForceOptions>(m, "ForceOptions",
                                         "Equilibrium registration: external forces estimated every frame "
                                         "(the scene's registration.forces).");
  forces.def(py::init<>());
  DefFields(forces);

  auto free_space = py::class_<FreeSpaceOptions>(m, "FreeSpaceOptions",
                                                 "Free space: surface vertices in front of the observed depth "
                                                 "(the scene's registration.free_space).");
  free_space.def(py::init<>());
  DefFields(free_space);

  auto weights = py::class_<WeightOptions>(m, "WeightOptions");
  weights.def(py::init<>());
  DefFields(weights);

  auto solver = py::class_<SolverOptions>(m, "SolverOptions");
  solver.def(py::init<>());
  DefFields(solver);
  // The scene key's name too (solver.threads), beside the C++ member's (num_threads).
  solver.def_readwrite("threads", &SolverOptions::num_threads, "The same as num_threads (the scene's solver.threads)");

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
      .def("validate",
           [](const RegistrationOptions& o) {
             std::string why;
             if (!o.IsValid(&why)) throw py::value_error("RegistrationOptions: " + why);
           },
           "Raises ValueError naming the first bad field.");
  DefFields(options);
}

}  // namespace python
}  // namespace femreg
