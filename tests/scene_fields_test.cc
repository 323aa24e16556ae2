// The tables of the scene's sections beside the registration (femreg/field_table.h): a
// material's, the forward solve's, collision's, fracture's, synth's and its sensor's, and
// those of the lists' entries: objects, anchors, collision pairs and obstacles, synth's motion
// tracks and bodies. Each covers every member of its struct but those named as read by hand; every
// field, set alone to a value other than its default, is written by the scene writer and read
// back by the parser unchanged; and a value out of a field's range fails, in IsValid (where
// the struct has one) and in a scene file, with the field's name (there with the file, line
// and key path). tests/option_fields_test.cc does the same for the registration's tables.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>

#include "femreg/collision_spec.h"
#include "femreg/fem.h"
#include "femreg/field_table.h"
#include "femreg/forward.h"
#include "femreg/fracture.h"
#include "femreg/scene.h"
#include "femreg/synth.h"
#include "member_count.h"

namespace femreg {
namespace {

using testing_tables::ExpectSameFields;
using testing_tables::FieldCount;
using testing_tables::MemberCount;
using testing_tables::OtherValue;

TEST(SceneFields, EveryMemberHasARowOrIsNamedAsReadByHand) {
  EXPECT_EQ(FieldCount<Material>(), MemberCount<Material>());
  // + min_step, tangent, watchdog_steps, num_threads, verbose: the program's, no scene keys.
  EXPECT_EQ(FieldCount<ForwardOptions>() + 5, MemberCount<ForwardOptions>());
  // + pairs, obstacles: lists of entries.
  EXPECT_EQ(FieldCount<CollisionSpec>() + 2, MemberCount<CollisionSpec>());
  // + toughness, region_toughness (the objects'), min_piece_fraction (no scene key).
  EXPECT_EQ(FieldCount<FractureOptions>() + 3, MemberCount<FractureOptions>());
  // + camera (registration.camera), artefacts (SynthArtefactKeys).
  EXPECT_EQ(FieldCount<DepthSensorOptions>() + 2, MemberCount<DepthSensorOptions>());
  // + name, keyframes.
  EXPECT_EQ(FieldCount<SynthBodySpec>() + 2, MemberCount<SynthBodySpec>());
  // + enabled, the ground truth's four (mesh_path, generate, material, ground_truth_where),
  // sensor, motion, bodies, the four of the artefacts table (occluder_*, leave_*),
  // source_name.
  EXPECT_EQ(FieldCount<SynthSpec>() + 13, MemberCount<SynthSpec>());
  // + name, mesh_path, generate, material, region_materials, region_toughness, surface_path.
  EXPECT_EQ(FieldCount<ObjectSpec>() + 7, MemberCount<ObjectSpec>());
  // + name, object, selection, translations, rotations, centre.
  EXPECT_EQ(FieldCount<AnchorSpec>() + 6, MemberCount<AnchorSpec>());
  // + first, second (the objects).
  EXPECT_EQ(FieldCount<CollisionPair>() + 2, MemberCount<CollisionPair>());
  // + name, kind, plane_point, plane_normal, box_size, mesh_path, surface, objects, keyframes.
  EXPECT_EQ(FieldCount<ObstacleSpec>() + 9, MemberCount<ObstacleSpec>());
  // + name, selection, has_centre, centre, keyframes.
  EXPECT_EQ(FieldCount<MotionTrackSpec>() + 5, MemberCount<MotionTrackSpec>());
}

// FieldOf finds a member's row when the code compiles (a member without one does not compile:
// CTest field_of_needs_a_row).
TEST(SceneFields, FieldOfFindsTheRowWhenItCompiles) {
  static_assert(HasRow(&ObjectSpec::rotation) && HasRow(&ObjectSpec::toughness));
  static_assert(!HasRow(&ObjectSpec::name) && !HasRow(&ObjectSpec::material));
  constexpr FieldInfo rotation = FieldOf<&ObjectSpec::rotation>();
  EXPECT_STREQ(rotation.key, "rotation");
  EXPECT_STREQ(rotation.group, "pose");
  EXPECT_EQ(FieldName<ObjectSpec>(FieldOf<&ObjectSpec::toughness>()), "objects.toughness");
  // An object's element: two rows in the material group.
  static_assert(HasRow(&ObjectSpec::model) && HasRow(&ObjectSpec::volume));
  EXPECT_EQ(FieldName<ObjectSpec>(FieldOf<&ObjectSpec::volume>()), "objects.material.volume");
}

// One object, a camera and a synth section with a track and a body, so that every section
// can be set.
const char kBase[] =
    "objects:\n"
    "  - generate: {shape: box, size: [1, 0.1, 0.1], cells: [4, 1, 1]}\n"
    "registration:\n"
    "  camera: {position: [0, 0, 2], target: [0, 0, 0], up: [0, 1, 0]}\n"
    "synth:\n"
    "  ground_truth: {refinement: 2}\n"
    "  motion: [{select: {all: true}, keyframes: [{frame: 0}]}]\n"
    "  bodies: [{box: {min: [0, 0, 0.2], max: [0.1, 0.1, 0.3]}}]\n";
// Two objects with an anchor, a pair and an obstacle (whose frictions are left unset: the
// round trip sets them to 0, a frictionless pair that is not the collision's default).
const char kBaseLists[] =
    "objects:\n"
    "  - {name: a, generate: {shape: box, size: [1, 0.1, 0.1], cells: [4, 1, 1]}}\n"
    "  - {name: b, generate: {shape: box, size: [1, 0.1, 0.1], cells: [4, 1, 1]}}\n"
    "anchors: [{object: a, select: {all: true}}]\n"
    "collision:\n"
    "  pairs: [{objects: [a, b]}]\n"
    "  obstacles: [{plane: {point: [0, 0, 0], normal: [0, 0, 1]}}]\n";

// What else a field needs to be set on its own (the parser's rules across keys).
void AllowAlone(const std::string& field, Scene* scene) {
  if (field == "synth.sanity_check") scene->synth.refinement = 1;  // a sanity check has no ground_truth
  if (field.rfind("synth.background.", 0) == 0) scene->synth.background = true;  // the group's switch
}

template <class Options>
void ExpectEachFieldRoundTrips(Options& (*section)(Scene&), const char* base_text = kBase) {
  int fields = 0;
  OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
    ++fields;
    const std::string field = FieldName<Options>(f);
    Scene scene;
    const Status base = ParseScene(base_text, "base.yaml", ".", &scene);
    ASSERT_TRUE(base.ok()) << base.message();
    Options& o = section(scene);
    const auto d = o.*member;
    o.*member = OtherValue(f, d);
    ASSERT_NE(o.*member, d) << field;
    AllowAlone(field, &scene);
    std::string error;
    EXPECT_TRUE(CheckFieldRanges(o, &error)) << field << ": " << error;

    const std::string yaml = SceneToYaml(scene);
    EXPECT_NE(yaml.find(std::string(f.key) + ": "), std::string::npos) << field << " not written:\n" << yaml;
    Scene read;
    const Status status = ParseScene(yaml, "written.yaml", ".", &read);
    ASSERT_TRUE(status.ok()) << field << ": " << status.message() << "\n" << yaml;
    ExpectSameFields(o, section(read), field);
  });
  EXPECT_EQ(fields, static_cast<int>(FieldCount<Options>()));
}

Material& ObjectMaterial0(Scene& s) { return s.objects[0].material; }
ForwardOptions& Forward(Scene& s) { return s.forward; }
CollisionSpec& Collision(Scene& s) { return s.collision; }
FractureOptions& Fracture(Scene& s) { return s.effects.fracture_options; }
DepthSensorOptions& Sensor(Scene& s) { return s.synth.sensor; }
SynthSpec& Synth(Scene& s) { return s.synth; }
SynthBodySpec& Body0(Scene& s) { return s.synth.bodies[0]; }
MotionTrackSpec& Track0(Scene& s) { return s.synth.motion[0]; }
ObjectSpec& Object0(Scene& s) { return s.objects[0]; }
AnchorSpec& Anchor0(Scene& s) { return s.anchors[0]; }
CollisionPair& Pair0(Scene& s) { return s.collision.pairs[0]; }
ObstacleSpec& Obstacle0(Scene& s) { return s.collision.obstacles[0]; }

TEST(SceneFields, EachFieldRoundTripsThroughTheSceneFile) {
  ExpectEachFieldRoundTrips(&ObjectMaterial0);
  ExpectEachFieldRoundTrips(&Forward);
  ExpectEachFieldRoundTrips(&Collision);
  ExpectEachFieldRoundTrips(&Fracture);
  ExpectEachFieldRoundTrips(&Sensor);
  ExpectEachFieldRoundTrips(&Synth);
  ExpectEachFieldRoundTrips(&Body0);
  ExpectEachFieldRoundTrips(&Track0);
  ExpectEachFieldRoundTrips(&Object0, kBaseLists);
  ExpectEachFieldRoundTrips(&Anchor0, kBaseLists);
  ExpectEachFieldRoundTrips(&Pair0, kBaseLists);
  ExpectEachFieldRoundTrips(&Obstacle0, kBaseLists);
}

// A value the field's range refuses: below a lower bound, above an upper one, else NaN.
double OutOfRange(const FieldInfo& f) {
  if (f.has_min) return f.min_open ? f.min : f.min - 1;
  if (f.has_max) return f.max_open ? f.max : f.max + 1;
  return std::nan("");
}

// Where a section's keys go in a scene file: the text around "KEY: VALUE", and the line and
// key path the parser names it by.
struct Place {
  std::string before, after;
  int line;
  std::string path;
};

// The struct's own check where it has one (IsValid), else the table's ranges alone.
template <class Options>
bool Valid(const Options& o, std::string* error) {
  if constexpr (std::is_same_v<Options, Material> || std::is_same_v<Options, ForwardOptions> ||
                std::is_same_v<Options, CollisionSpec> || std::is_same_v<Options, FractureOptions> ||
                std::is_same_v<Options, DepthSensorOptions>) {
    return o.IsValid(error);
  } else {
    return CheckFieldRanges(o, error);
  }
}

template <class Options>
void ExpectRangesNamed(const Place& place) {
  int checked = 0;
  OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
    if (!f.checked()) return;
    ++checked;
    const double bad = OutOfRange(f);
    ASSERT_FALSE(f.InRange(bad)) << f.key;
    const std::string field = FieldName<Options>(f);

    Options o;
    using Field = std::decay_t<decltype(o.*member)>;
    using T = typename FieldType<Field>::Value;  // an optional's value: checked when set
    std::string error;
    if constexpr (std::is_arithmetic_v<T> && !std::is_unsigned_v<T>) {  // a seed cannot hold -1; the scene file can
      if constexpr (FieldType<Field>::kOptional) {
        EXPECT_TRUE(Valid(o, &error)) << field << " unset: " << error;
      }
      o.*member = static_cast<T>(bad);
      EXPECT_FALSE(Valid(o, &error)) << field;
      EXPECT_EQ(error.rfind(field + " must be ", 0), 0u) << error;
    }

    std::string text = std::isnan(bad) ? ".nan" : std::to_string(bad);
    if (std::is_integral_v<T>) text = std::to_string(static_cast<int>(bad));
    std::string entry = std::string(f.key) + ": " + text;
    if (f.group != nullptr) entry = std::string(f.group) + ": {" + entry + "}";
    Scene scene;
    const std::string yaml = place.before + entry + place.after;
    const Status status = ParseScene(yaml, "bad.yaml", ".", &scene);
    ASSERT_FALSE(status.ok()) << field << " = " << text << "\n" << yaml;
    const std::string named =
        "bad.yaml:" + std::to_string(place.line) + ": " + place.path + "." + f.path() + ": must be ";
    EXPECT_EQ(status.message().rfind(named, 0), 0u) << status.message();
  });
  EXPECT_GT(checked, 0);
}

const char kObject[] = "objects: [{generate: {shape: box, size: [1, 0.1, 0.1], cells: [4, 1, 1]}}]\n";
const char kSynth[] =
    "objects: [{generate: {shape: box, size: [1, 0.1, 0.1], cells: [4, 1, 1]}}]\n"
    "registration:\n"
    "  camera: {position: [0, 0, 2], target: [0, 0, 0], up: [0, 1, 0]}\n"
    "synth:\n"
    "  sanity_check: true\n";
const char kTwoObjects[] =
    "objects: [{name: a, generate: {shape: box, size: [1, 0.1, 0.1], cells: [4, 1, 1]}},\n"
    "          {name: b, generate: {shape: box, size: [1, 0.1, 0.1], cells: [4, 1, 1]}}]\n";

TEST(SceneFields, OutOfRangeValuesNameTheField) {
  ExpectRangesNamed<Material>({"objects:\n  - generate: {shape: box, size: [1, 0.1, 0.1], cells: [4, 1, 1]}\n"
                               "    material: {",
                               "}\n", 3, "objects[0].material"});
  ExpectRangesNamed<ForwardOptions>({std::string(kObject) + "forward: {", "}\n", 2, "forward"});
  ExpectRangesNamed<CollisionSpec>({std::string(kObject) + "collision: {", "}\n", 2, "collision"});
  ExpectRangesNamed<FractureOptions>({std::string(kObject) + "effects:\n  fracture: {", "}\n", 3, "effects.fracture"});
  ExpectRangesNamed<DepthSensorOptions>({std::string(kSynth) + "  sensor: {", "}\n", 6, "synth.sensor"});
  ExpectRangesNamed<SynthSpec>({std::string(kSynth) + "  ", "\n", 6, "synth"});
  ExpectRangesNamed<SynthBodySpec>(
      {std::string(kSynth) + "  bodies: [{box: {min: [0, 0, 0.2], max: [0.1, 0.1, 0.3]}, ", "}]\n", 6,
       "synth.bodies[0]"});
  ExpectRangesNamed<ObjectSpec>({"objects:\n  - generate: {shape: box, size: [1, 0.1, 0.1], cells: [4, 1, 1]}\n    ",
                                 "\n", 3, "objects[0]"});
  ExpectRangesNamed<AnchorSpec>({std::string(kObject) + "anchors: [{select: {all: true}, ", "}]\n", 2, "anchors[0]"});
  ExpectRangesNamed<CollisionPair>(
      {std::string(kTwoObjects) + "collision:\n  pairs: [{objects: [a, b], ", "}]\n", 4, "collision.pairs[0]"});
  ExpectRangesNamed<ObstacleSpec>({std::string(kObject) + "collision:\n  obstacles: [{plane: {point: [0, 0, 0], normal: [0, 0, 1]}, ",
                                   "}]\n", 3, "collision.obstacles[0]"});
}

// The messages the tables phrase, as IsValid and the parser give them.
TEST(SceneFields, MessagesNameTheKey) {
  std::string error;
  Material m;
  m.poisson_ratio = 0.5;
  EXPECT_FALSE(m.IsValid(&error));
  EXPECT_EQ(error, "poisson_ratio must be in (-1, 0.5) (got 0.5)");
  FractureOptions f;
  f.crossing_tolerance = 1;
  EXPECT_FALSE(f.IsValid(&error));
  EXPECT_EQ(error, "effects.fracture.crossing_tolerance must be in [0, 1) (got 1)");
  ForwardOptions forward;
  forward.load_steps = 0;
  EXPECT_FALSE(forward.IsValid(&error));
  EXPECT_EQ(error, "forward.load_steps must be >= 1 (got 0)");
  CollisionSpec c;
  c.friction_slip = 0;
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_EQ(error, "collision.friction_slip must be > 0 (got 0)");
  DepthSensorOptions sensor;
  sensor.grazing_angle_deg = 95;
  EXPECT_FALSE(sensor.IsValid(&error));
  EXPECT_EQ(error, "sensor.grazing_angle_deg must be in (0, 90] (got 95)");

  Scene scene;
  const Status status =
      ParseScene(std::string(kObject) + "collision: {stiffness: 1e4, friction_slip: -1}\n", "c.yaml", ".", &scene);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message(), "c.yaml:2: collision.friction_slip: must be > 0 (got -1)");
}

// A value a scene may leave unset (std::optional): unset, it is not written and passes the
// checks; set, even to what the program would use without it, it is written and read back
// set (a frictionless pair under a frictional collision, a corotational model kept for a
// nearly incompressible object).
TEST(SceneFields, UnsetValuesStayUnsetAndSetOnesAreWritten) {
  Scene scene;
  ASSERT_TRUE(ParseScene(kBaseLists, "lists.yaml", ".", &scene).ok());
  EXPECT_FALSE(scene.forward.model.has_value());
  EXPECT_EQ(scene.forward.Model(), ElasticModelType::kCorotational);
  ASSERT_EQ(scene.collision.pairs.size(), 1u);
  ASSERT_EQ(scene.collision.obstacles.size(), 1u);
  EXPECT_FALSE(scene.collision.pairs[0].friction.has_value());
  EXPECT_FALSE(scene.collision.obstacles[0].friction.has_value());
  std::string error;
  EXPECT_TRUE(CheckFieldRanges(scene.collision.pairs[0], &error)) << error;
  EXPECT_TRUE(CheckFieldRanges(scene.collision.obstacles[0], &error)) << error;
  EXPECT_TRUE(scene.forward.IsValid(&error)) << error;
  std::string yaml = SceneToYaml(scene);
  EXPECT_EQ(yaml.find("friction"), std::string::npos) << yaml;
  EXPECT_EQ(yaml.find("forward"), std::string::npos) << yaml;

  scene.collision.friction = 0.5;
  scene.collision.pairs[0].friction = 0.0;
  scene.forward.model = ElasticModelType::kCorotational;
  yaml = SceneToYaml(scene);
  EXPECT_NE(yaml.find("forward: {model: corotational}"), std::string::npos) << yaml;
  Scene read;
  ASSERT_TRUE(ParseScene(yaml, "written.yaml", ".", &read).ok()) << yaml;
  EXPECT_EQ(read.forward.model, ElasticModelType::kCorotational);
  EXPECT_EQ(read.collision.friction, 0.5);
  EXPECT_EQ(read.collision.pairs[0].friction, 0.0);
  EXPECT_FALSE(read.collision.obstacles[0].friction.has_value());

  // Set out of range, it fails by its name as every other field does.
  scene.collision.obstacles[0].friction = -1.0;
  EXPECT_FALSE(CheckFieldRanges(scene.collision.obstacles[0], &error));
  EXPECT_EQ(error, "collision.obstacles.friction must be >= 0 (got -1)");
}

// forward.model is read by its row: an unknown name or key fails at its line with the same
// message as when it was read by hand.
TEST(SceneFields, ForwardModelMessages) {
  Scene scene;
  Status status = ParseScene(std::string(kObject) + "forward: {model: corotatonal}\n", "f.yaml", ".", &scene);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message(),
            "f.yaml:2: forward.model: unknown value 'corotatonal' (did you mean 'corotational'? one of: "
            "corotational, linear, neo_hookean)");
  status = ParseScene(std::string(kObject) + "forward: {modle: linear}\n", "f.yaml", ".", &scene);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message(), "f.yaml:2: forward.modle: unknown key (did you mean 'model'?)");
  status = ParseScene(std::string(kObject) + "forward: {zzz: 1}\n", "f.yaml", ".", &scene);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message(),
            "f.yaml:2: forward.zzz: unknown key (allowed: model, max_iterations, load_steps, tolerance, "
            "absolute_tolerance)");
}

}  // namespace
}  // namespace femreg
