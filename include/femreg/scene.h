// femreg/scene.h - a scene: objects, materials, boundary conditions, loads, the observation
// and solver settings, anchors and the effects that are on. Read from YAML.
#ifndef FEMREG_SCENE_H_
#define FEMREG_SCENE_H_

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "femreg/collision_spec.h"
#include "femreg/field_table.h"
#include "femreg/fem.h"
#include "femreg/forward.h"
#include "femreg/fracture.h"
#include "femreg/mesh.h"
#include "femreg/registration.h"
#include "femreg/status.h"
#include "femreg/synth.h"

namespace femreg {

// A set of vertices chosen by a box, by the side of a plane or by an index list.
struct VertexSelection {
  enum class Kind { kAll, kBox, kPlane, kIndices };
  Kind kind = Kind::kAll;
  Eigen::Vector3d box_min = Eigen::Vector3d::Zero(), box_max = Eigen::Vector3d::Zero();
  // Plane: vertices with (p - plane_point) . plane_normal >= -tolerance.
  Eigen::Vector3d plane_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d plane_normal = Eigen::Vector3d::UnitZ();
  double tolerance = 1e-9;  // m, added around boxes and planes
  std::vector<int> indices;
  std::string where;        // "scene.yaml:12 (boundary[0].select)" for messages
};

// Evaluates a selection on `positions` (the object's rest positions in the scene frame).
// An empty result is an error naming selection.where.
Status SelectVertices(const VertexSelection& selection, const Vertices& positions,
                      std::vector<int>* vertices);

// A mesh made by a generator of io.h instead of read from a file.
struct MeshGeneratorSpec {
  enum class Shape {
    kNone,      // no generator: the object reads mesh_path
    kBox,       // MakeBox(size, cells, origin)
    kCylinder,  // MakeCylinder(radius, length, radial_cells, axial_cells), along +z
    kSphere,    // MakeSphere(radius, radial_cells), centred at the origin
  };
  Shape shape = Shape::kNone;
  Eigen::Vector3d size = Eigen::Vector3d::Ones();     // box edge lengths (m)
  Eigen::Vector3i cells = Eigen::Vector3i::Ones();    // box cells per axis
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();   // box corner with the smallest coordinates
  double radius = 0.5;                                // cylinder, sphere (m)
  double length = 1.0;                                // cylinder (m)
  int radial_cells = 4;                               // cylinder, sphere
  int axial_cells = 8;                                // cylinder
};
const char* ToString(MeshGeneratorSpec::Shape shape);

struct ObjectSpec {
  std::string name;
  std::string mesh_path;  // resolved against the scene file's folder; empty when generated
  MeshGeneratorSpec generate;  // used when generate.shape != kNone
  double scale = 1.0;     // applied to the mesh file's coordinates (e.g. 0.001 for mm)
  // Initial pose: x = R(rotation) * scale * X_file + translation; the rest shape is the
  // posed one.
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();  // axis * angle (rad)
  Material material;
  std::vector<std::pair<int, Material>> region_materials;  // region id -> material
  // material.model: the constitutive law of all its elements; material.volume: nodal
  // (neo-Hookean only; simulate, calibrate): the volumetric energy on the vertices (fem.h).
  // Set: the element is chosen (by the file, simulate --model, or ChooseForwardElements and
  // ChooseRegistrationElements for a nearly incompressible object), and no automatic choice
  // replaces it. Unset: hooke with element volumes, open to the automatic choice.
  std::optional<MaterialModel> model;
  std::optional<MaterialVolume> volume;
  bool ElementChosen() const { return model.has_value() || volume.has_value(); }
  MaterialModel Model() const { return model.value_or(MaterialModel::kHooke); }
  bool NodalVolume() const { return volume == MaterialVolume::kNodal; }
  // The above as the FEM layer takes them.
  ObjectMaterial Materials() const;
  // Fracture toughness (Pa): a node breaks when its fracture measure exceeds it; used when
  // effects.fracture is on; 0 = unbreakable.
  double toughness = 0.0;
  std::vector<std::pair<int, double>> region_toughness;  // region id -> toughness (Pa)
  int label = -1;          // cloud points with this label belong to it; -1 = none
  // A fine triangle surface (.ply, .obj, .stl; resolved against the scene file's folder)
  // carried by the mesh's tetrahedra, in the mesh file's coordinates (the object's scale and
  // pose apply): the data terms act on it (Tracker::SetEmbeddedSurface). Empty: none.
  std::string surface_path;
};

// An object's own values beside its name, mesh or generator, materials, regions and surface,
// which are read and written by hand (a region's toughness is the toughness row). The element
// rows sit in the `material` group beside the material's own keys (Material's table).
template <>
struct OptionFields<ObjectSpec> {
  static constexpr const char* kSection = "objects";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = ObjectSpec;
    v(&S::scale, FieldInfo("scale").Above(0).Doc("applied to the mesh file's coordinates (0.001 for mm)"));
    v(&S::translation, FieldInfo("translation").In("pose").Doc("initial pose: translation (m)"));
    v(&S::rotation, FieldInfo("rotation").In("pose").Doc("initial pose: rotation, axis * angle (rad)"));
    v(&S::model, FieldInfo("model").In("material").Python("material_model").Doc("the elements' law; unset: hooke"));
    v(&S::volume, FieldInfo("volume").In("material").Python("material_volume").Doc("nodal: neo_hookean's volumetric energy on the vertices"));
    v(&S::toughness, FieldInfo("toughness").AtLeast(0).After().Doc("fracture toughness (Pa); 0 = unbreakable"));
    v(&S::label, FieldInfo("label").AtLeast(-1).After().Doc("cloud points with this label are its own; -1 = none"));
  }
};

// Why an object's element cannot be built, a check across its rows beside their ranges
// ("'nodal' needs 'model: neo_hookean' (...)", of material.volume); "" when it can. The scene
// parser and the Python module both ask it.
std::string ObjectElementError(const ObjectSpec& object);

struct BoundaryConditionSpec {
  enum class Type { kClamp, kDisplacement };
  std::string object;  // object name; may be empty when the scene has one object
  VertexSelection selection;
  Type type = Type::kClamp;
  Eigen::Vector3d displacement = Eigen::Vector3d::Zero();  // m, for kDisplacement
};

struct LoadSpec {
  std::string object;
  VertexSelection selection;
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // N, the total, spread evenly
};

// Where external forces may act in equilibrium registration (registration.forces.region):
// the selected vertices of the object's free surface.
struct ForceRegionSpec {
  std::string object;
  VertexSelection selection;
};

// Vertices held by a gripper or a support during registration.
struct AnchorSpec {
  std::string name;
  std::string object;
  VertexSelection selection;
  bool hard = false;     // hard: vertices fixed at the targets; soft: a penalty
  double weight = 0.0;   // soft anchors; 0 = weights.anchor
  // Per-frame translation of the anchored set from its rest position; a frame beyond the
  // list uses the last entry; an empty list holds the set at rest.
  std::vector<Eigen::Vector3d> translations;
  // Optional per-frame rotation (axis * angle, rad; as many as translations) about `centre`
  // (m), applied before the translation: a gripper that turns.
  std::vector<Eigen::Vector3d> rotations;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
};

// An anchor's own values beside its name, object, selection and trajectory (translations,
// rotations and their centre), which are read and written by hand.
template <>
struct OptionFields<AnchorSpec> {
  static constexpr const char* kSection = "anchors";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = AnchorSpec;
    v(&S::hard, FieldInfo("hard").Doc("vertices fixed at the targets; false: a penalty"));
    v(&S::weight, FieldInfo("weight").AtLeast(0).Doc("a soft anchor's weight; 0 = weights.anchor"));
  }
};

struct EffectsSpec {
  bool fracture = false;
  bool collision = false;
  // effects.fracture as a map: the limits and crossing tolerance (toughness is per object).
  FractureOptions fracture_options;
};

// femreg synth: the ground truth simulation, the virtual sensor and the motion script
// (the scene's `synth:` section; see datasets/README.md).
// A keyframe of a rigid motion: at `frame` the set is rotated by `rotation` (axis * angle,
// rad) about its centre and then moved by `translation` (m), both from rest. Between
// keyframes both are interpolated linearly; before the first and after the last one they
// are held.
struct MotionKeyframe {
  int frame = 0;
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();
};
// The interpolated translation and rotation vector at `frame`.
void InterpolateKeyframes(const std::vector<MotionKeyframe>& keyframes, int frame,
                          Eigen::Vector3d* translation, Eigen::Vector3d* rotation);

// Vertices of the simulated mesh moved rigidly from rest (a gripper, a clamp that moves).
struct MotionTrackSpec {
  enum class Anchor { kNone, kHard, kSoft };
  std::string name;
  VertexSelection selection;        // on the simulated (ground truth) mesh's rest positions
  bool has_centre = false;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // default: the selection's centroid
  std::vector<MotionKeyframe> keyframes;
  // The robot knows this gripper: the tracking scene gets an anchor that follows the track
  // (a rotating track's anchor turns about its centre, which it must then give).
  Anchor anchor = Anchor::kNone;
};
const char* ToString(MotionTrackSpec::Anchor anchor);
bool FromString(const std::string& name, MotionTrackSpec::Anchor* anchor);
template <>
struct EnumValues<MotionTrackSpec::Anchor> {
  static constexpr std::array<MotionTrackSpec::Anchor, 3> kAll = {
      MotionTrackSpec::Anchor::kNone, MotionTrackSpec::Anchor::kHard, MotionTrackSpec::Anchor::kSoft};
};

// A track's own value beside its name, selection, centre and keyframes (read and written by
// hand).
template <>
struct OptionFields<MotionTrackSpec> {
  static constexpr const char* kSection = "synth.motion";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    v(&MotionTrackSpec::anchor, FieldInfo("anchor").Doc("hard or soft: the tracking scene gets an anchor that follows it"));
  }
};

// A rigid box rendered with the object (a tool, an occluder): never part of the ground
// truth. Keyframes translate it (rotation is not supported for bodies).
struct SynthBodySpec {
  std::string name;
  Eigen::Vector3d box_min = Eigen::Vector3d::Zero(), box_max = Eigen::Vector3d::Zero();
  std::vector<MotionKeyframe> keyframes;
  bool in_cloud = false;   // its pixels return points (false: masked, it only hides)
  // Pressed along -z into the object: the object's top surface vertices under the box's
  // footprint are moved down to its bottom face (prescribed displacement, not a contact
  // solve).
  bool press = false;
  double contact_tolerance = 1e-3;  // m: how far below the highest vertex the patch reaches
};

// A body's keys beside its name and keyframes (read and written by hand); its box is
// required (min < max in every coordinate, checked where it is read).
template <>
struct OptionFields<SynthBodySpec> {
  static constexpr const char* kSection = "synth.bodies";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = SynthBodySpec;
    v(&S::box_min, FieldInfo("min").In("box").Required().Python("box_min").Doc("the box's corner with the smallest coordinates (m)"));
    v(&S::box_max, FieldInfo("max").In("box").Required().Python("box_max").Doc("the box's opposite corner (m)"));
    v(&S::in_cloud, FieldInfo("in_cloud").After().Doc("its pixels return points (false: masked, it only hides)"));
    v(&S::press, FieldInfo("press").After().Doc("pressed along -z into the object"));
    v(&S::contact_tolerance, FieldInfo("contact_tolerance").After().AtLeast(0).Doc("m: how far below the highest vertex the patch reaches"));
  }
};

struct SynthSpec {
  bool enabled = false;      // the scene has a synth section
  int frames = 30;
  uint64_t seed = 1;
  bool sanity_check = false; // ground truth made with the tracked mesh and material
  // Ground truth mesh: the object's generator refined, or a mesh file or generator of its
  // own (with the object's scale and pose); the material overrides the object's.
  int refinement = 1;
  std::string mesh_path;
  MeshGeneratorSpec generate;
  Material material;
  std::string ground_truth_where;  // "synth.yaml:12 (synth.ground_truth)" for messages
  DepthSensorOptions sensor;       // sensor.camera is registration.camera
  bool background = false;         // a square table quad
  Eigen::Vector3d background_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d background_normal = Eigen::Vector3d::UnitZ();
  double background_size = 1.0;    // m, edge length
  std::vector<MotionTrackSpec> motion;
  std::vector<SynthBodySpec> bodies;
  // Artefacts of the sequence (the sensor's own are in sensor.artefacts). Occluder: a
  // sphere of this radius (m; 0 = none) between the camera and the object, standoff (m)
  // nearer than the object's nearest vertex, crossing the object's view from left to right
  // once over the sequence; its points are in the clouds (a hand in the mask).
  double occluder_radius = 0.0;
  double occluder_standoff = 0.03;
  // The object leaves the view: for leave_frames frames from leave_start (-1: a third of
  // the way in) the camera returns none of its points; the ground truth keeps its shape,
  // every vertex unseen.
  int leave_frames = 0;
  int leave_start = -1;
  std::string source_name;         // the scene file's name, for the outputs
};

// The `synth:` section's own values, the ground truth's refinement and the background. The
// rest of ground_truth (mesh, generate, material), the sensor, motion, bodies and artefacts
// are read and written by hand, the sensor, tracks and bodies through their own tables, the
// artefacts through SynthArtefactKeys.
template <>
struct OptionFields<SynthSpec> {
  static constexpr const char* kSection = "synth";
  template <class Visitor>
  static constexpr void Visit(Visitor&& v) {
    using S = SynthSpec;
    v(&S::frames, FieldInfo("frames").AtLeast(1).Doc("frames to simulate"));
    v(&S::seed, FieldInfo("seed").AtLeast(0).Doc("the sensor noise's seed"));
    v(&S::sanity_check, FieldInfo("sanity_check").Doc("ground truth made with the tracked mesh and material"));
    v(&S::refinement, FieldInfo("refinement").In("ground_truth").AtLeast(1).Doc("the object's generator with cells * refinement"));
    v(&S::background, FieldInfo("background").SwitchesGroup().After().Doc("a square table quad in view"));
    v(&S::background_point, FieldInfo("point").In("background").After().Python("background_point").Doc("a point of the table (m)"));
    v(&S::background_normal, FieldInfo("normal").In("background").After().Python("background_normal").Doc("the table's normal"));
    v(&S::background_size, FieldInfo("size").In("background").After().Above(0).Python("background_size").Doc("m, edge length"));
  }
};

// The artefacts of synth by name, as the scene's `synth.artefacts` map and `femreg synth
// --artefact` write them: NAME: {KEY: value, ...}. An artefact's first key is its strength
// and switches it on (0 = off; for grazing_holes a lower angle is stronger).
struct SynthArtefactKey {
  const char* artefact;  // "flying_pixels"
  const char* key;       // "fraction"
  double realistic;      // what `--artefact NAME` and `--artefact all` set
  double min, max;       // the valid range
  bool integer;
  double (*get)(const SynthSpec&);
  void (*set)(SynthSpec*, double);
};
const std::vector<SynthArtefactKey>& SynthArtefactKeys();
// Applies "NAME" (every key of NAME at its realistic value), "NAME=STRENGTH" (the first
// key), "NAME.KEY=VALUE" or "all" (every artefact at its realistic values).
Status SetSynthArtefact(const std::string& spec, SynthSpec* synth);
// One key of one artefact ("" = its strength), range-checked.
Status SetSynthArtefactValue(const std::string& artefact, const std::string& key, double value,
                             SynthSpec* synth);
// The switched-on artefacts with their values ("flying_pixels fraction 0.5 jump 0.02;
// ..."); "" when none is on.
std::string SynthArtefactSummary(const SynthSpec& synth);

struct Scene {
  std::string path;  // the file it was read from ("" when built in code)
  std::string description;  // free text (the file's `description:`)
  std::vector<ObjectSpec> objects;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  // m/s^2
  std::vector<BoundaryConditionSpec> boundary_conditions;
  std::vector<LoadSpec> loads;
  ForwardOptions forward;  // forward: (with the objects' element, forward.model)
  RegistrationOptions registration;
  std::vector<AnchorSpec> anchors;
  std::vector<ForceRegionSpec> force_regions;  // registration.forces.region; empty: every free surface vertex
  EffectsSpec effects;
  // Pairs, penalty and obstacles; used when effects.collision is on (an empty pair list
  // then means every pair of objects).
  CollisionSpec collision;
  SynthSpec synth;  // femreg synth; synth.enabled when the file has a synth section
};

// Reads and validates a scene. Errors name the file, line and key ("scene.yaml:14: objects[0].
// material.poisson_ratio: must be in (-1, 0.5) (got 0.5)"): unknown keys, wrong types, out-of-range
// values, missing mesh files, effects not built yet.
Status LoadScene(const std::string& path, Scene* scene);
// The same from text; `source` names it in messages and relative paths resolve against
// `base_dir`.
Status ParseScene(const std::string& yaml_text, const std::string& source,
                  const std::string& base_dir, Scene* scene);

// Writes a scene as YAML that LoadScene reads back into the same Scene: every field but
// the derived ones (path, selections' `where`, synth.source_name, synth.ground_truth_where),
// and a selection's plane normal, which the reader normalizes again, to within an ulp. Only
// what differs from the defaults is written, so that written scenes stay short: an option
// at its default value is left out, and so are an effect that is off and a section at its
// defaults; what defines a thing is written in full (an object's generator, a camera, a
// plane, a selection). Numbers are written in the shortest form that reads back to the same
// double. File paths (meshes) are written relative to the scene file's folder. `comment`
// (may be empty) goes first, each of its lines as a '#' comment. The file is replaced
// atomically; errors name it. A mesh obstacle whose surface is in memory
// (ObstacleSpec::surface) has no file to name: such a scene is refused, naming the obstacle.
Status WriteScene(const Scene& scene, const std::string& path, const std::string& comment = "");
// The same as text; file paths relative to `base_dir` (the folder ParseScene will resolve
// them against; "" writes them as they are). An obstacle surface in memory is written as
// "(in memory: V vertices, T triangles)" in place of its file, which ParseScene refuses.
std::string SceneToYaml(const Scene& scene, const std::string& base_dir = "",
                        const std::string& comment = "");

// Each object's material (and its regions' materials) taken from the object of the same
// name in `from`, e.g. the scene `femreg calibrate` wrote: a fitted material used to track.
// Errors name an object `from` does not have.
Status CopyMaterials(const Scene& from, Scene* scene);

// Linear tetrahedra lock as nu -> 0.5 (one volume constraint per element is too many).
// Objects with nu >= kNearlyIncompressibleNu (their own or a region's) whose scene chose no
// element (no material.model, material.volume or forward.model) get the neo-Hookean element
// with the nodal volume (fem.h) for the forward solves of simulate and calibrate. Returns
// one line per object changed, saying so and how to override it; none when nothing changed.
constexpr double kNearlyIncompressibleNu = 0.45;
std::vector<std::string> ChooseForwardElements(Scene* scene);
// The same objects, for registration with the corotational regularizer (the default): the
// neo-Hookean element with nu capped at kRegistrationPoissonRatio in the elastic term, or
// with nu as given when registration.forces.estimate is on (the forces are the element's;
// docs/guide/materials.md). Registration takes the nodal volume only when a scene asks (it
// costs 3-5x the time there). Tracker::Create(scene) applies it.
constexpr double kRegistrationPoissonRatio = 0.35;
std::vector<std::string> ChooseRegistrationElements(Scene* scene);

// Loads (or generates) object i's mesh, applies scale and pose to rest and x, and computes
// the lumped masses from its density and region densities. Errors name the scene and the
// mesh file.
Status LoadObjectMesh(const Scene& scene, int object, TetMesh* mesh);
// Reads object `object`'s embedded surface (objects[i].surface) and poses it as its mesh
// (scale, rotation, translation). An object without one gets no rows.
Status LoadObjectSurface(const Scene& scene, int object, Vertices* vertices, Triangles* triangles);

// The forward problem of object i: boundary conditions, loads and gravity resolved to
// vertex indices on `mesh` (from LoadObjectMesh).
Status BuildForwardProblem(const Scene& scene, int object, const TetMesh& mesh,
                           ForwardProblem* problem);

}  // namespace femreg

#endif  // FEMREG_SCENE_H_
