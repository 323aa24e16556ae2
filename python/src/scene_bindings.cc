// Python bindings: scene files (Scene, load_scene, parse_scene), their objects and the options
// of their sections beside the registration's (fields from their tables), and the forward
// solve of one scene object (simulate).
#include <string>
#include <utility>
#include <vector>

#include "bindings.h"
#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/scene.h"
#include "femreg/synth.h"

namespace femreg {
namespace python {
namespace {

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

// An object's own values as the scene parser checks them: its table's ranges, then its element
// (ObjectElementError), named by the row just set (`field`: material.model or material.volume)
// and the object.
bool ObjectValid(const ObjectSpec& object, const std::string& field, std::string* why) {
  if (!CheckFieldRanges(object, why)) return false;
  const std::string element = ObjectElementError(object);
  if (element.empty()) return true;
  const std::string model = FieldName<ObjectSpec>(FieldOf<&ObjectSpec::model>());
  *why = (field == model ? model : FieldName<ObjectSpec>(FieldOf<&ObjectSpec::volume>())) + " (object " +
         py::repr(py::str(object.name)).cast<std::string>() + "): " + element;
  return false;
}

}  // namespace

void BindScene(py::module_& m) {
  // ---- the scene's other options: their fields from their tables (DefFields) -------------
  auto forward = py::class_<ForwardOptions>(m, "ForwardOptions", "The forward solve (the scene's forward: keys).");
  forward.def(py::init<>());
  DefFields(forward);
  auto fracture = py::class_<FractureOptions>(m, "FractureOptions",
                                              "The fracture model's limits (the scene's effects.fracture keys).");
  fracture.def(py::init<>());
  DefFields(fracture);
  auto collision = py::class_<CollisionSpec>(
      m, "CollisionOptions",
      "Contacts' penalty and friction (the scene's collision: keys; its pairs and obstacles are the file's).");
  collision.def(py::init<>());
  DefFields(collision);
  auto sensor = py::class_<DepthSensorOptions>(m, "DepthSensorOptions", "femreg synth's virtual sensor (synth.sensor).");
  sensor.def(py::init<>());
  DefFields(sensor);
  auto body = py::class_<SynthBodySpec>(
      m, "SynthBody",
      "A rigid box femreg synth renders with the object (an entry of the scene's synth.bodies); "
      "its keyframes are the scene file's.");
  DefFieldsInit(body, "SynthBody");
  body.def_readwrite("name", &SynthBodySpec::name, "unique among the bodies and tracks");
  DefFields(body);
  auto synth = py::class_<SynthSpec>(m, "SynthOptions",
                                     "femreg synth's own values (the scene's synth: keys), its sensor and bodies.");
  synth.def(py::init<>())
      .def_readwrite("sensor", &SynthSpec::sensor)
      .def_readwrite("bodies", &SynthSpec::bodies,
                     "SynthBody list (synth.bodies); a copy: assign the whole list to change it");
  DefFields(synth);

  // ---- a scene's objects: their own values from their table, checked as the parser does ----
  auto object = py::class_<ObjectSpec>(
      m, "SceneObject",
      "An object of a scene (an entry of its objects:), changed in place: scene.object(\"name\"). Its "
      "values (scale, pose, material_model, material_volume, toughness, label, and its material's) "
      "are checked when set, as the scene file's are; its name, mesh and regions are the file's.");
  object.def_readonly("name", &ObjectSpec::name)
      .def_readonly("mesh", &ObjectSpec::mesh_path, "the mesh file (\"\" when generated)")
      .def_readonly("surface", &ObjectSpec::surface_path, "the embedded surface's file (\"\" for none)")
      .def_property(
          "material", py::cpp_function([](ObjectSpec& o) -> Material& { return o.material; },
                                       py::return_value_policy::reference_internal),
          [](ObjectSpec& o, const Material& material) {
            std::string why;
            if (!material.IsValid(&why)) throw py::value_error("objects.material: " + why);
            o.material = material;
          },
          "Material (material:), changed in place (each value checked when set) or assigned");
  DefCheckedFields(object, &ObjectValid);
  object.def("__repr__", [](const ObjectSpec& o) {
    return "SceneObject(name=" + py::repr(py::str(o.name)).cast<std::string>() + ", " + FieldsRepr(o) + ")";
  });

  // ---- scenes ---------------------------------------------------------------------------
  py::class_<Scene>(m, "Scene", "A scene file: objects, materials, camera, registration settings.")
      .def_readonly("path", &Scene::path)
      .def_readonly("description", &Scene::description)
      .def_readwrite("registration", &Scene::registration,
                     "RegistrationOptions, changed in place (scene.registration.solver.backend = \"fast\")")
      .def_readwrite("forward", &Scene::forward, "ForwardOptions (forward:)")
      .def_property(
          "fracture",
          py::cpp_function([](Scene& s) -> FractureOptions& { return s.effects.fracture_options; },
                           py::return_value_policy::reference_internal),
          [](Scene& s, const FractureOptions& f) { s.effects.fracture_options = f; },
          "FractureOptions (effects.fracture), changed in place; effects_fracture says whether it is on")
      .def_property(
          "effects_fracture", [](const Scene& s) { return s.effects.fracture; },
          [](Scene& s, bool on) { s.effects.fracture = on; }, "effects.fracture: on or off")
      .def_readwrite("collision", &Scene::collision, "CollisionOptions (collision:)")
      .def_readwrite("synth", &Scene::synth, "SynthOptions (synth:; synth.frames ...)")
      .def_property_readonly("object_names",
                             [](const Scene& s) {
                               std::vector<std::string> names;
                               for (const ObjectSpec& o : s.objects) names.push_back(o.name);
                               return names;
                             })
      .def_property_readonly(
          "objects",
          [](py::object self) {
            py::list list;
            for (ObjectSpec& o : self.cast<Scene&>().objects) {
              list.append(py::cast(&o, py::return_value_policy::reference_internal, self));
            }
            return list;
          },
          "SceneObject list, each changed in place (the list itself is the file's)")
      .def(
          "object",
          [](Scene& s, const py::object& object) -> ObjectSpec& { return s.objects[ObjectIndex(s, object)]; },
          py::return_value_policy::reference_internal, py::arg("object") = 0,
          "The object (by index or name) as a SceneObject, changed in place.")
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
}

void BindSimulate(py::module_& m) {
  // ---- forward simulation ---------------------------------------------------------------
  m.def("simulate",
        [](const Scene& scene, const py::object& object, const std::string& model,
           int load_steps, int max_iterations, const std::string& tangent, int threads) {
          const int index = ObjectIndex(scene, object);
          const ElasticModelType model_type =
              model.empty() ? scene.forward.Model() : EnumFromString<ElasticModelType>(model, "model");
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

}  // namespace python
}  // namespace femreg
