// The options tables (femreg/option_fields.h): each covers every member of its struct (the
// top level's, every member but its sections); every
// field, set alone to a value other than its default, is written by the scene writer and
// read back by the parser unchanged; and a value out of a field's range fails, both in
// IsValid and in a scene file, with the field's name (and there the file and line).
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <type_traits>
#include <utility>

#include "femreg/option_fields.h"
#include "femreg/scene.h"
#include "member_count.h"

namespace femreg {
namespace {

using testing_tables::ExpectSameFields;
using testing_tables::FieldCount;
using testing_tables::MemberCount;
using testing_tables::OtherValue;

TEST(OptionFields, EveryMemberHasARow) {
  EXPECT_EQ(FieldCount<DataTermOptions>(), MemberCount<DataTermOptions>());
  EXPECT_EQ(FieldCount<WeightOptions>(), MemberCount<WeightOptions>());
  EXPECT_EQ(FieldCount<SolverOptions>(), MemberCount<SolverOptions>());
  EXPECT_EQ(FieldCount<ForceOptions>(), MemberCount<ForceOptions>());
  EXPECT_EQ(FieldCount<FreeSpaceOptions>(), MemberCount<FreeSpaceOptions>());
  EXPECT_EQ(FieldCount<CameraOptions>() + 1, MemberCount<CameraOptions>());  // + enabled
  EXPECT_EQ(FieldCount<PreprocessOptions>() + 2, MemberCount<PreprocessOptions>());  // + crop, mask_dir
  // The top level: its own values, and its seven sections (camera ... free_space).
  EXPECT_EQ(FieldCount<RegistrationOptions>() + 7, MemberCount<RegistrationOptions>());
}


// What else a field needs to take effect on its own (the cross-field rules of the parser,
// the writer and IsValid).
void AllowAlone(const std::string& field, RegistrationOptions* o) {
  if (field == "weights.data_per_area") o->weights.data = -1;  // per-area weighting selected
  if (field == "solver.trust_region" || field == "solver.linear_solver") {
    o->solver.backend = SolverBackend::kCeres;  // Ceres' settings
  }
  if (field == "forces.friction") o->forces.pushing_only = true;
  if (field.rfind("camera.", 0) == 0) o->camera.enabled = true;  // a scene's camera is on
  if (field.rfind("preprocess.crop.", 0) == 0) o->preprocess.crop = true;  // the group is the switch
  if (field == "preprocess.normals.neighbors") o->preprocess.normal_neighbors = 8;  // 0 or >= 3
}

const char kObject[] = "objects: [{generate: {shape: box, size: [1, 0.1, 0.1], cells: [4, 1, 1]}}]\n";

// `section` gives the options struct within RegistrationOptions.
template <class Options, class Section>
void ExpectEachFieldRoundTrips(Section section) {
  int fields = 0;
  OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
    ++fields;
    const std::string field = FieldName<Options>(f);
    Scene scene;
    ASSERT_TRUE(ParseScene(kObject, "box.yaml", ".", &scene).ok());
    Options& o = section(scene.registration);
    const auto d = o.*member;
    o.*member = OtherValue(f, d);
    ASSERT_NE(o.*member, d) << field;
    AllowAlone(field, &scene.registration);
    std::string error;
    ASSERT_TRUE(scene.registration.IsValid(&error)) << field << ": " << error;

    const std::string yaml = SceneToYaml(scene);
    EXPECT_NE(yaml.find(std::string(f.key) + ": "), std::string::npos) << field << " not written:\n"
                                                                      << yaml;
    Scene read;
    const Status status = ParseScene(yaml, "written.yaml", ".", &read);
    ASSERT_TRUE(status.ok()) << field << ": " << status.message() << "\n" << yaml;
    ExpectSameFields(o, section(read.registration), field);
  });
  EXPECT_EQ(fields, static_cast<int>(FieldCount<Options>()));
}

TEST(OptionFields, EachFieldRoundTripsThroughTheSceneFile) {
  ExpectEachFieldRoundTrips<DataTermOptions>([](RegistrationOptions& r) -> auto& { return r.data; });
  ExpectEachFieldRoundTrips<WeightOptions>([](RegistrationOptions& r) -> auto& { return r.weights; });
  ExpectEachFieldRoundTrips<SolverOptions>([](RegistrationOptions& r) -> auto& { return r.solver; });
  ExpectEachFieldRoundTrips<ForceOptions>([](RegistrationOptions& r) -> auto& { return r.forces; });
  ExpectEachFieldRoundTrips<FreeSpaceOptions>([](RegistrationOptions& r) -> auto& { return r.free_space; });
  ExpectEachFieldRoundTrips<CameraOptions>([](RegistrationOptions& r) -> auto& { return r.camera; });
  ExpectEachFieldRoundTrips<PreprocessOptions>([](RegistrationOptions& r) -> auto& { return r.preprocess; });
  ExpectEachFieldRoundTrips<RegistrationOptions>([](RegistrationOptions& r) -> auto& { return r; });
}

// A value the field's range refuses, as a number and as YAML: below a lower bound, above an
// upper one, else (finite only) NaN.
double OutOfRange(const FieldInfo& f) {
  if (f.has_min) return f.min_open ? f.min : f.min - 1;
  if (f.has_max) return f.max_open ? f.max : f.max + 1;
  return std::nan("");
}

template <class Options>
void ExpectRangesNamed(Options RegistrationOptions::*section) {
  const std::string name = OptionFields<Options>::kSection;
  int checked = 0;
  OptionFields<Options>::Visit([&](auto member, const FieldInfo& f) {
    if (!f.checked()) return;
    ++checked;
    const double bad = OutOfRange(f);
    ASSERT_FALSE(f.InRange(bad)) << f.key;
    const std::string field = FieldName<Options>(f);

    RegistrationOptions o;
    using T = std::decay_t<decltype(o.*section.*member)>;
    constexpr bool kVector = std::is_same_v<T, Eigen::Vector3d>;
    if constexpr (kVector) {
      (o.*section).*member = Eigen::Vector3d::Constant(bad);
    } else {
      (o.*section).*member = static_cast<T>(bad);
    }
    std::string error;
    EXPECT_FALSE(o.IsValid(&error)) << field;
    EXPECT_EQ(error.rfind(field + " must be ", 0), 0u) << error;

    std::string text = std::isnan(bad) ? ".nan" : std::to_string(bad);
    if (std::is_same_v<T, int>) text = std::to_string(static_cast<int>(bad));
    if (kVector) text = "[" + text + ", 0, 0]";
    // A grouped field inside its group, beside what the group needs (a crop's other bound).
    std::string entry = std::string(f.key) + ": " + text;
    if (f.group != nullptr) {
      std::string beside;
      if (std::string(f.group) == "crop") beside = std::string(", ") + (std::string(f.key) == "min" ? "max" : "min") + ": [1, 1, 1]";
      if (std::string(f.group) == "plane" && std::string(f.key) != "distance") beside = ", distance: 0.01";
      entry = std::string(f.group) + ": {" + entry + beside + "}";
    }
    Scene scene;
    const Status status = ParseScene(std::string(kObject) + "registration:\n  " + name + ": {" + entry + "}\n",
                                     "bad.yaml", ".", &scene);
    ASSERT_FALSE(status.ok()) << field << " = " << text;
    // A vector's bad number is named by its index: "registration.camera.up[0]: must be ...".
    const std::string named = "bad.yaml:3: registration." + field + (kVector ? "" : ": must be ");
    EXPECT_EQ(status.message().rfind(named, 0), 0u) << status.message();
  });
  EXPECT_GT(checked, 0);
}

TEST(OptionFields, OutOfRangeValuesNameTheField) {
  ExpectRangesNamed(&RegistrationOptions::data);
  ExpectRangesNamed(&RegistrationOptions::weights);
  ExpectRangesNamed(&RegistrationOptions::solver);
  ExpectRangesNamed(&RegistrationOptions::forces);
  ExpectRangesNamed(&RegistrationOptions::free_space);
  ExpectRangesNamed(&RegistrationOptions::camera);
  ExpectRangesNamed(&RegistrationOptions::preprocess);
}

// The messages as IsValid wrote them before the tables, word for word.
TEST(OptionFields, MessagesKeepTheirWording) {
  RegistrationOptions o;
  std::string error;
  o.weights.barrier_volume = 1;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "weights.barrier_volume must be in (0, 1) (got 1)");
  o = RegistrationOptions();
  o.data.lost_coverage = 2;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "data.lost_coverage must be in [0, 1] (0 = never lost) (got 2)");
  o = RegistrationOptions();
  o.solver.num_threads = -1;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "solver.threads must be >= 0 (0: the cores other processes leave free, per frame) (got -1)");
  o = RegistrationOptions();
  o.forces.friction = std::nan("");
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "forces.friction must be finite (< 0: no bound) (got nan)");
  // Friction bounds pushing forces: those of forces.pushing_only, or of the frames that
  // forces.when_occluded switches (when_occluded_pushing_only), which forces.estimate leaves out.
  o = RegistrationOptions();
  o.forces.friction = 0.5;
  EXPECT_TRUE(o.IsValid(&error)) << error;
  o.forces.when_occluded_pushing_only = false;
  EXPECT_FALSE(o.IsValid(&error));
  o.forces.when_occluded_pushing_only = true;
  o.forces.estimate = true;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("set forces.pushing_only too"), std::string::npos) << error;
  o.forces.pushing_only = true;
  EXPECT_TRUE(o.IsValid(&error)) << error;
  o = RegistrationOptions();
  o.free_space.weight = 0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "free_space.weight must be > 0 (N/m per vertex; enabled: false turns it off) (got 0)");
  o = RegistrationOptions();
  o.weights.data = o.weights.elastic = o.weights.temporal = 0;  // a rule across fields
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "weights data, elastic and temporal must not all be 0 (got 0, 0, 0)");
  o = RegistrationOptions();
  o.camera.up = Eigen::Vector3d(0, std::nan(""), 0);
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "camera.up must be finite (got [0, nan, 0])");
  o = RegistrationOptions();
  o.camera.height = 0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "camera.height must be > 0 (got 0)");
  o = RegistrationOptions();
  o.preprocess.flying_pixels = -1;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "preprocess.flying_pixels must be >= 0 (sigmas of the depth's noise; 0 = off) (got -1)");
  o = RegistrationOptions();
  o.preprocess.outlier_neighbors = -1;  // a grouped field: its group in the name
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(error, "preprocess.outliers.neighbors must be >= 0 (got -1)");
}

}  // namespace
}  // namespace femreg
