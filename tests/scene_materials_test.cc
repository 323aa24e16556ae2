// Material ranges are checked by Material::IsValid alone; the scene parser puts its message at
// the file, line and key path of the value that broke it, for an object's material and for a
// region's.
#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

#include "femreg/fem.h"
#include "femreg/scene.h"

namespace femreg {
namespace {

// Line numbers matter below.
const char kScene[] =
    "objects:\n"                                                          // 1
    "  - name: block\n"                                                   // 2
    "    generate: {shape: box, size: [0.1, 0.1, 0.1], cells: [2, 2, 2]}\n"  // 3
    "    material:\n"                                                     // 4
    "      youngs_modulus: 1e5\n"                                         // 5
    "      poisson_ratio: 0.3\n"                                          // 6
    "      density: 1000\n"                                               // 7
    "    regions:\n"                                                      // 8
    "      2:\n"                                                          // 9
    "        youngs_modulus: 1e6\n"                                       // 10
    "        poisson_ratio: 0.4\n"                                        // 11
    "        density: 500\n";                                             // 12

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

std::string ParseError(const std::string& text) {
  Scene scene;
  const Status status = ParseScene(text, "materials.yaml", ".", &scene);
  EXPECT_FALSE(status.ok()) << "expected an error for:\n" << text;
  return status.message();
}

TEST(SceneMaterials, ValidMaterialsAndRegionsParse) {
  Scene scene;
  const Status status = ParseScene(kScene, "materials.yaml", ".", &scene);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(scene.objects.size(), 1u);
  EXPECT_EQ(scene.objects[0].material.youngs_modulus, 1e5);
  ASSERT_EQ(scene.objects[0].region_materials.size(), 1u);
  EXPECT_EQ(scene.objects[0].region_materials[0].first, 2);
  EXPECT_EQ(scene.objects[0].region_materials[0].second.youngs_modulus, 1e6);
  EXPECT_EQ(scene.objects[0].region_materials[0].second.density, 500);
}

struct BadValue {
  std::string from, to;  // the edit of kScene
  std::string expected;  // the whole location and message
};

TEST(SceneMaterials, BadValuesNameFileLineAndKey) {
  const std::vector<BadValue> cases = {
      {"youngs_modulus: 1e5", "youngs_modulus: 0",
       "materials.yaml:5: objects[0].material.youngs_modulus: must be > 0 (got 0)"},
      {"youngs_modulus: 1e5", "youngs_modulus: -2e3",
       "materials.yaml:5: objects[0].material.youngs_modulus: must be > 0 (got -2000)"},
      {"poisson_ratio: 0.3", "poisson_ratio: 0.5",
       "materials.yaml:6: objects[0].material.poisson_ratio: must be in (-1, 0.5) (got 0.5)"},
      {"poisson_ratio: 0.3", "poisson_ratio: -1",
       "materials.yaml:6: objects[0].material.poisson_ratio: must be in (-1, 0.5) (got -1)"},
      {"density: 1000", "density: 0",
       "materials.yaml:7: objects[0].material.density: must be > 0 (got 0)"},
      // A region's material: its own key path and line.
      {"youngs_modulus: 1e6", "youngs_modulus: -1",
       "materials.yaml:10: objects[0].regions.2.youngs_modulus: must be > 0 (got -1)"},
      {"poisson_ratio: 0.4", "poisson_ratio: 0.75",
       "materials.yaml:11: objects[0].regions.2.poisson_ratio: must be in (-1, 0.5) (got 0.75)"},
      {"density: 500", "density: -3",
       "materials.yaml:12: objects[0].regions.2.density: must be > 0 (got -3)"},
  };
  for (const BadValue& c : cases) {
    EXPECT_EQ(ParseError(Replace(kScene, c.from, c.to)), c.expected);
  }
}

// The parser's words are IsValid's: a material with the same bad value gives the same
// constraint, named after the field.
TEST(SceneMaterials, MessagesAreMaterialIsValids) {
  Material m;
  m.poisson_ratio = 0.75;
  std::string error;
  ASSERT_FALSE(m.IsValid(&error));
  EXPECT_EQ(error, "poisson_ratio must be in (-1, 0.5) (got 0.75)");
  const std::string message = ParseError(Replace(kScene, "poisson_ratio: 0.3", "poisson_ratio: 0.75"));
  EXPECT_NE(message.find("poisson_ratio: " + error.substr(std::string("poisson_ratio ").size())),
            std::string::npos)
      << message;
  // Library callers get the same checks (the parser refuses non-finite numbers itself).
  m = Material();
  m.youngs_modulus = std::numeric_limits<double>::infinity();
  ASSERT_FALSE(m.IsValid(&error));
  EXPECT_EQ(error, "youngs_modulus must be > 0 (got inf)");
}

// A region that sets one value inherits the others from the object's material.
TEST(SceneMaterials, RegionInheritsTheObjectsMaterial) {
  const std::string text = Replace(Replace(kScene, "        poisson_ratio: 0.4\n", ""),
                                   "        density: 500\n", "");
  Scene scene;
  const Status status = ParseScene(text, "materials.yaml", ".", &scene);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(scene.objects[0].region_materials.size(), 1u);
  const Material& region = scene.objects[0].region_materials[0].second;
  EXPECT_EQ(region.youngs_modulus, 1e6);
  EXPECT_EQ(region.poisson_ratio, 0.3);
  EXPECT_EQ(region.density, 1000);
}

// material.model and material.volume: parsed, checked against each other, written back.
TEST(SceneMaterials, ModelAndVolume) {
  Scene scene;
  ASSERT_TRUE(ParseScene(kScene, "materials.yaml", ".", &scene).ok());
  EXPECT_EQ(scene.objects[0].Model(), MaterialModel::kHooke);
  EXPECT_FALSE(scene.objects[0].NodalVolume());
  const std::string text = Replace(kScene, "      density: 1000\n",
                                   "      density: 1000\n      model: neo_hookean\n      volume: nodal\n");
  ASSERT_TRUE(ParseScene(text, "materials.yaml", ".", &scene).ok());
  EXPECT_EQ(scene.objects[0].Model(), MaterialModel::kNeoHookean);
  EXPECT_TRUE(scene.objects[0].NodalVolume());
  const ObjectMaterial m = scene.objects[0].Materials();
  EXPECT_EQ(m.model, MaterialModel::kNeoHookean);
  EXPECT_TRUE(m.nodal_volume);
  EXPECT_EQ(m.regions.size(), 1u);
  // Written and read back.
  Scene again;
  ASSERT_TRUE(ParseScene(SceneToYaml(scene), "again.yaml", ".", &again).ok()) << SceneToYaml(scene);
  EXPECT_EQ(again.objects[0].Model(), MaterialModel::kNeoHookean);
  EXPECT_TRUE(again.objects[0].NodalVolume());

  EXPECT_EQ(ParseError(Replace(kScene, "      density: 1000\n", "      density: 1000\n      model: neohooke\n")),
            "materials.yaml:8: objects[0].material.model: unknown value 'neohooke' (one of: hooke, "
            "neo_hookean)");
  EXPECT_EQ(ParseError(Replace(kScene, "      density: 1000\n", "      density: 1000\n      volume: nodal\n")),
            "materials.yaml:8: objects[0].material.volume: 'nodal' needs 'model: neo_hookean' (the "
            "nodal volume is the neo-Hookean element's remedy for locking)");
  // A model the file wrote is the row that breaks the rule, not the volume it cannot take.
  EXPECT_EQ(ParseError(Replace(kScene, "      density: 1000\n",
                               "      density: 1000\n      volume: nodal\n      model: hooke\n")),
            "materials.yaml:9: objects[0].material.model: 'nodal' needs 'model: neo_hookean' (the "
            "nodal volume is the neo-Hookean element's remedy for locking)");
  EXPECT_EQ(ParseError(Replace(kScene, "      density: 1000\n", "      density: 1000\n      volume: nodl\n")),
            "materials.yaml:8: objects[0].material.volume: unknown value 'nodl' (did you mean 'nodal'? one of: "
            "element, nodal)");
  // The element's rows are the material group's keys beside the material's own.
  EXPECT_EQ(ParseError(Replace(kScene, "      density: 1000\n", "      density: 1000\n      volme: nodal\n")),
            "materials.yaml:8: objects[0].material.volme: unknown key (did you mean 'volume'?)");

  // volume: element alone chooses the element (hooke), as model: hooke does, and stays chosen.
  const std::string element = Replace(kScene, "      density: 1000\n", "      density: 1000\n      volume: element\n");
  ASSERT_TRUE(ParseScene(element, "materials.yaml", ".", &scene).ok());
  EXPECT_TRUE(scene.objects[0].ElementChosen());
  EXPECT_EQ(scene.objects[0].Model(), MaterialModel::kHooke);
  ASSERT_TRUE(ParseScene(SceneToYaml(scene), "again.yaml", ".", &again).ok()) << SceneToYaml(scene);
  EXPECT_TRUE(again.objects[0].ElementChosen()) << SceneToYaml(scene);
  EXPECT_FALSE(again.objects[0].NodalVolume());
}

// Nearly incompressible objects get the nodal-volume neo-Hookean element for forward solves
// unless the scene chose an element; a chosen hooke survives being written and read back.
TEST(SceneMaterials, NearlyIncompressibleChoosesTheNodalVolume) {
  Scene scene;
  ASSERT_TRUE(ParseScene(kScene, "materials.yaml", ".", &scene).ok());
  EXPECT_TRUE(ChooseForwardElements(&scene).empty());  // nu 0.3 and 0.4: unchanged
  EXPECT_EQ(scene.objects[0].Model(), MaterialModel::kHooke);

  const std::string soft = Replace(kScene, "        poisson_ratio: 0.4\n", "        poisson_ratio: 0.49\n");
  ASSERT_TRUE(ParseScene(soft, "materials.yaml", ".", &scene).ok());
  EXPECT_FALSE(scene.objects[0].ElementChosen());
  const std::vector<std::string> lines = ChooseForwardElements(&scene);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("block: nu 0.49 >= 0.45"), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("model: hooke"), std::string::npos) << lines[0];
  EXPECT_EQ(scene.objects[0].Model(), MaterialModel::kNeoHookean);
  EXPECT_TRUE(scene.objects[0].NodalVolume());
  EXPECT_TRUE(ChooseForwardElements(&scene).empty());  // already chosen: no second line

  const std::string hooke = Replace(soft, "      density: 1000\n", "      density: 1000\n      model: hooke\n");
  ASSERT_TRUE(ParseScene(hooke, "materials.yaml", ".", &scene).ok());
  EXPECT_TRUE(scene.objects[0].ElementChosen());
  EXPECT_TRUE(ChooseForwardElements(&scene).empty());
  EXPECT_EQ(scene.objects[0].Model(), MaterialModel::kHooke);
  Scene again;
  ASSERT_TRUE(ParseScene(SceneToYaml(scene), "again.yaml", ".", &again).ok());
  EXPECT_TRUE(ChooseForwardElements(&again).empty()) << SceneToYaml(scene);

  const std::string linear = soft + "forward: {model: linear}\n";
  ASSERT_TRUE(ParseScene(linear, "materials.yaml", ".", &scene).ok());
  EXPECT_TRUE(ChooseForwardElements(&scene).empty());
  EXPECT_FALSE(scene.objects[0].NodalVolume());

  // forward.model: corotational is a choice too, kept and written back.
  const std::string corotational = soft + "forward: {model: corotational}\n";
  ASSERT_TRUE(ParseScene(corotational, "materials.yaml", ".", &scene).ok());
  Scene written;
  ASSERT_TRUE(ParseScene(SceneToYaml(scene), "written.yaml", ".", &written).ok()) << SceneToYaml(scene);
  EXPECT_EQ(written.forward.model, ElasticModelType::kCorotational);
  EXPECT_TRUE(ChooseForwardElements(&written).empty());
  EXPECT_EQ(written.objects[0].Model(), MaterialModel::kHooke);
}

// Registration's default is the neo-Hookean element with nu capped in its elastic term (the
// nodal volume is 3-5x the time there and no more accurate), unless the scene chose the
// element or a regularizer other than corotational, or estimates forces (nu as given).
TEST(SceneMaterials, NearlyIncompressibleRegistrationCapsNu) {
  const std::string soft = Replace(kScene, "      poisson_ratio: 0.3\n", "      poisson_ratio: 0.49\n");
  Scene scene;
  ASSERT_TRUE(ParseScene(soft, "materials.yaml", ".", &scene).ok());
  const std::vector<std::string> lines = ChooseRegistrationElements(&scene);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("nu 0.35"), std::string::npos) << lines[0];
  EXPECT_EQ(scene.objects[0].Model(), MaterialModel::kNeoHookean);
  EXPECT_FALSE(scene.objects[0].NodalVolume());
  EXPECT_EQ(scene.objects[0].material.poisson_ratio, kRegistrationPoissonRatio);
  EXPECT_EQ(scene.objects[0].region_materials[0].second.poisson_ratio, kRegistrationPoissonRatio);
  EXPECT_TRUE(ChooseRegistrationElements(&scene).empty());  // once

  const std::string chosen = Replace(soft, "      density: 1000\n", "      density: 1000\n      model: neo_hookean\n");
  ASSERT_TRUE(ParseScene(chosen, "materials.yaml", ".", &scene).ok());
  EXPECT_TRUE(ChooseRegistrationElements(&scene).empty());
  EXPECT_EQ(scene.objects[0].material.poisson_ratio, 0.49);

  ASSERT_TRUE(ParseScene(soft + "registration: {regularizer: linear}\n", "materials.yaml", ".", &scene).ok());
  EXPECT_TRUE(ChooseRegistrationElements(&scene).empty());
  EXPECT_EQ(scene.objects[0].Model(), MaterialModel::kHooke);

  const std::string forces = soft + "registration: {solver: {backend: fast}, forces: {estimate: true}}\n";
  ASSERT_TRUE(ParseScene(forces, "materials.yaml", ".", &scene).ok());
  const std::vector<std::string> given = ChooseRegistrationElements(&scene);
  ASSERT_EQ(given.size(), 1u);
  EXPECT_NE(given[0].find("as given"), std::string::npos) << given[0];
  EXPECT_EQ(scene.objects[0].Model(), MaterialModel::kNeoHookean);
  EXPECT_EQ(scene.objects[0].material.poisson_ratio, 0.49);
}

}  // namespace
}  // namespace femreg
