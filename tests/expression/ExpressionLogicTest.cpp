// The Expression module's logic without a window: how the sliders mix
// (a = clamp(Σ w_e A_e + o, 0, 1)), how an expression's muscle names map to
// the fitted muscles, saving expressions in the scene as undoable edits
// (a new one too), and what the face model's input says when the scene
// lacks something. Expected numbers are worked out here by hand.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstring>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "SampleFace.h"
#include "TestPaths.h"
#include "modules/expression/ExpressionLogic.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "modules/volumes/CommandLine.h"
#include "report/DemoScene.h"
#include "scene/ExpressionNode.h"
#include "scene/LandmarksNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/SceneBundle.h"
#include "scene/VolumeNode.h"

namespace caps {
namespace {

using expression::ExpressionDefinition;
using expression::FittedMuscle;

Eigen::VectorXd vec(std::initializer_list<double> values)
{
  Eigen::VectorXd v(Eigen::Index(values.size()));
  Eigen::Index i = 0;
  for (double x : values)
    v[i++] = x;
  return v;
}

void expectVector(const Eigen::VectorXd& actual, std::initializer_list<double> expected, double tolerance = 1e-15)
{
  ASSERT_EQ(actual.size(), Eigen::Index(expected.size()));
  Eigen::Index i = 0;
  for (double x : expected)
  {
    EXPECT_NEAR(actual[i], x, tolerance) << "muscle " << i;
    ++i;
  }
}

FittedMuscle muscle(const std::string& id, const std::string& definition)
{
  FittedMuscle m;
  m.id = id;
  m.definition = definition;
  return m;
}

/// Two bilateral muscles and a midline one, as fitMuscleSet names them.
std::vector<FittedMuscle> someMuscles()
{
  return {muscle("zygomaticus_major_left", "zygomaticus_major"), muscle("zygomaticus_major_right", "zygomaticus_major"),
          muscle("risorius_left", "risorius"), muscle("risorius_right", "risorius"),
          muscle("orbicularis_oris_upper", "orbicularis_oris_upper")};
}

std::vector<std::string> savedNames(const ExpressionLogic& logic)
{
  std::vector<std::string> names;
  for (const ExpressionNode* n : logic.savedExpressions())
    names.push_back(n->name());
  return names;
}

// --- Mixing (ExpressionLogic.h's file comment) -------------------------------

TEST(ExpressionMix, OneExpressionAtFullWeightIsThatExpression)
{
  const Eigen::VectorXd smile = vec({0.2, 0.5, 0.0, 1.0});
  const Eigen::VectorXd frown = vec({0.7, 0.0, 0.9, 0.3});
  const Eigen::VectorXd a = expression::mixActivations({smile, frown}, {1.0, 0.0}, Eigen::VectorXd::Zero(4));
  EXPECT_EQ(a, smile);
}

TEST(ExpressionMix, ExpressionsAndMuscleOffsetsAdd)
{
  const Eigen::VectorXd e1 = vec({0.2, 0.5, 0.0, 0.1});
  const Eigen::VectorXd e2 = vec({0.3, 0.0, 0.4, 0.1});
  // 0.5 e1 + e2 = (0.1 + 0.3, 0.25, 0.4, 0.05 + 0.1).
  expectVector(expression::mixActivations({e1, e2}, {0.5, 1.0}, Eigen::VectorXd::Zero(4)), {0.4, 0.25, 0.4, 0.15});
  // e1 + offsets (0.1, 0, 0.2, 0.3).
  expectVector(expression::mixActivations({e1}, {1.0}, vec({0.1, 0.0, 0.2, 0.3})), {0.3, 0.5, 0.2, 0.4});
  // No expression: the muscle sliders alone.
  expectVector(expression::mixActivations({}, {}, vec({0.1, 0.0, 0.2, 0.3})), {0.1, 0.0, 0.2, 0.3});
}

TEST(ExpressionMix, NoMuscleGoesBeyondRestOrFullContraction)
{
  const Eigen::VectorXd e1 = vec({0.8, 0.5, 0.6});
  const Eigen::VectorXd e2 = vec({0.7, 0.0, 0.0});
  // (0.8 + 0.7 + 0.2, 0.5 - 0.9, 0.6 + 0.2) = (1.7, -0.4, 0.8) → (1, 0, 0.8).
  expectVector(expression::mixActivations({e1, e2}, {1.0, 1.0}, vec({0.2, -0.9, 0.2})), {1.0, 0.0, 0.8});
}

TEST(ExpressionMix, MismatchedSizesThrow)
{
  const Eigen::VectorXd e = vec({0.5, 0.5});
  EXPECT_THROW(expression::mixActivations({e}, {1.0, 0.5}, Eigen::VectorXd::Zero(2)), std::invalid_argument);
  EXPECT_THROW(expression::mixActivations({e, e}, {1.0}, Eigen::VectorXd::Zero(2)), std::invalid_argument);
  EXPECT_THROW(expression::mixActivations({e}, {1.0}, Eigen::VectorXd::Zero(3)), std::invalid_argument);
}

// --- Expressions on the fitted muscles ---------------------------------------

TEST(ExpressionActivations, ADefinitionIdMeansBothSidesAFittedIdOne)
{
  const ExpressionDefinition e{
    "test",
    "Test",
    "",
    {{"zygomaticus_major", 0.7}, {"risorius_left", 0.4}, {"orbicularis_oris_upper", 1.0}, {"no_such_muscle", 0.5}}};
  expectVector(expression::expressionActivations(e, someMuscles()), {0.7, 0.7, 0.4, 0.0, 1.0});
}

TEST(ExpressionActivations, TheLaterEntryWins)
{
  const ExpressionDefinition oneSideLess{"a", "A", "", {{"zygomaticus_major", 1.0}, {"zygomaticus_major_left", 0.3}}};
  expectVector(expression::expressionActivations(oneSideLess, someMuscles()), {0.3, 1.0, 0.0, 0.0, 0.0});
  const ExpressionDefinition bothSidesAfter{
    "b", "B", "", {{"zygomaticus_major_left", 0.3}, {"zygomaticus_major", 1.0}}};
  expectVector(expression::expressionActivations(bothSidesAfter, someMuscles()), {1.0, 1.0, 0.0, 0.0, 0.0});
}

TEST(ExpressionActivations, ASavedExpressionNamesFittedMusclesAndTheOthersAreReported)
{
  // Saved expressions hold fitted ids only: a definition id is unknown there.
  const std::map<std::string, double> saved{
    {"zygomaticus_major_left", 0.6}, {"risorius", 0.5}, {"orbicularis_oris_upper", 0.25}, {"unknown_x", 0.2}};
  std::vector<std::string> unknown;
  expectVector(expression::expressionActivations(saved, someMuscles(), &unknown), {0.6, 0.0, 0.0, 0.0, 0.25});
  EXPECT_EQ(unknown, (std::vector<std::string>{"risorius", "unknown_x"}));
  // Without a list to report to, the same activations.
  expectVector(expression::expressionActivations(saved, someMuscles()), {0.6, 0.0, 0.0, 0.0, 0.25});
}

TEST(ExpressionActivations, TheBuiltInExpressionsNameMusclesOfTheDefaultSet)
{
  const expression::MuscleSet set = expression::readMuscleSet(expression::defaultMuscleSetPath());
  std::vector<std::string> names;
  for (const ExpressionDefinition& e : expression::builtInExpressions())
  {
    EXPECT_FALSE(e.muscles.empty()) << e.name;
    EXPECT_EQ(std::count(names.begin(), names.end(), e.name), 0) << e.name << " twice";
    names.push_back(e.name);
    for (const auto& [id, activation] : e.muscles)
    {
      EXPECT_NE(set.find(id), nullptr) << e.name << " names " << id << ", which " << set.file << " does not have";
      EXPECT_GT(activation, 0.0) << e.name << " " << id;
      EXPECT_LE(activation, 1.0) << e.name << " " << id;
    }
  }
  for (const char* name : {"smile", "frown", "pucker", "fig_5_15", "fig_5_16", "fig_5_17", "fig_5_18"})
    EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
}

// --- Saved expressions in the scene ------------------------------------------

TEST(SavedExpression, ANewOneIsOneUndoableEdit)
{
  Scene scene;
  ExpressionLogic logic(scene);
  ExpressionNode& saved =
    logic.saveExpression("grin", "default",
                         {{"zygomaticus_major_left", 0.8},
                          {"risorius_right", 1.7},                  // clamped to 1
                          {"depressor_labii_inferioris_left", 0.0}, // zeros left out
                          {"temporalis_left", -0.2},
                          {"corrugator_supercilii_left", std::numeric_limits<double>::quiet_NaN()}},
                         "a test grin");
  const NodeId id = saved.id();
  const std::map<std::string, double> expected{{"zygomaticus_major_left", 0.8}, {"risorius_right", 1.0}};
  EXPECT_EQ(saved.name(), "grin");
  EXPECT_EQ(saved.muscleSet(), "default");
  EXPECT_EQ(saved.description(), "a test grin");
  EXPECT_EQ(saved.activations(), expected);
  EXPECT_EQ(savedNames(logic), std::vector<std::string>{"grin"});
  EXPECT_EQ(logic.savedExpression("grin"), &saved);
  ASSERT_TRUE(scene.undoStack().canUndo());
  EXPECT_EQ(scene.undoStack().undoLabel(), "Save expression grin");

  // Undo: the expression is gone from the scene, the list and by name.
  ASSERT_TRUE(scene.undoStack().undo());
  EXPECT_TRUE(scene.nodesOfType(NodeType::Expression).empty());
  EXPECT_TRUE(logic.savedExpressions().empty());
  EXPECT_EQ(logic.savedExpression("grin"), nullptr);
  EXPECT_FALSE(scene.undoStack().canUndo());

  // Redo: back, as it was.
  ASSERT_TRUE(scene.undoStack().redo());
  ASSERT_NE(logic.savedExpression("grin"), nullptr);
  const ExpressionNode& back = *logic.savedExpression("grin");
  EXPECT_EQ(back.id(), id);
  EXPECT_EQ(back.activations(), expected);
  EXPECT_EQ(back.description(), "a test grin");
  EXPECT_EQ(back.muscleSet(), "default");

  // Undo again, then save another: the first is out of the scene for good.
  ASSERT_TRUE(scene.undoStack().undo());
  EXPECT_EQ(scene.node(id), nullptr) << "an undone expression is out of the scene";
  logic.saveExpression("pout", "default", {{"orbicularis_oris_lower", 0.5}}, "");
  EXPECT_EQ(savedNames(logic), std::vector<std::string>{"pout"});
  EXPECT_EQ(scene.nodesOfType(NodeType::Expression).size(), 1u);
  EXPECT_FALSE(scene.undoStack().canRedo());
  ASSERT_TRUE(scene.undoStack().undo());
  EXPECT_TRUE(logic.savedExpressions().empty());
  EXPECT_TRUE(scene.nodesOfType(NodeType::Expression).empty());
}

TEST(SavedExpression, OverwritingChangesItAndUndoRestoresTheOldActivations)
{
  Scene scene;
  ExpressionLogic logic(scene);
  const NodeId id = logic.saveExpression("grin", "default", {{"zygomaticus_major_left", 0.5}}, "first").id();
  const std::size_t entries = scene.undoStack().size();
  ExpressionNode& changed =
    logic.saveExpression("grin", "other", {{"risorius_right", 0.25}, {"risorius_left", 2.0}}, "second");
  EXPECT_EQ(changed.id(), id);
  EXPECT_EQ(scene.nodesOfType(NodeType::Expression).size(), 1u);
  EXPECT_EQ(changed.activations(), (std::map<std::string, double>{{"risorius_left", 1.0}, {"risorius_right", 0.25}}));
  EXPECT_EQ(changed.description(), "second");
  EXPECT_EQ(changed.muscleSet(), "other");
  EXPECT_EQ(scene.undoStack().size(), entries + 1); // one edit for the three fields
  EXPECT_EQ(scene.undoStack().undoLabel(), "Change expression grin");

  ASSERT_TRUE(scene.undoStack().undo());
  ASSERT_EQ(logic.savedExpression("grin"), &changed);
  EXPECT_EQ(changed.activations(), (std::map<std::string, double>{{"zygomaticus_major_left", 0.5}}));
  EXPECT_EQ(changed.description(), "first");
  EXPECT_EQ(changed.muscleSet(), "default");
  ASSERT_TRUE(scene.undoStack().redo());
  EXPECT_EQ(changed.activations(), (std::map<std::string, double>{{"risorius_left", 1.0}, {"risorius_right", 0.25}}));
}

TEST(SavedExpression, AnEmptyNameIsRefusedAndChangesNothing)
{
  Scene scene;
  ExpressionLogic logic(scene);
  try
  {
    logic.saveExpression("", "default", {{"risorius_left", 0.5}}, "");
    FAIL() << "saved without a name";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("name"), std::string::npos) << e.what();
  }
  EXPECT_EQ(scene.size(), 0u);
  EXPECT_FALSE(scene.undoStack().canUndo());
}

TEST(SavedExpression, AllAtRestIsSavedWithNoActivations)
{
  Scene scene;
  ExpressionLogic logic(scene);
  const ExpressionNode& rest = logic.saveExpression("rest", "default", {{"risorius_left", 0.0}}, "");
  EXPECT_TRUE(rest.activations().empty());
  EXPECT_EQ(savedNames(logic), std::vector<std::string>{"rest"});
}

TEST(SavedExpression, TheyAreListedInTheOrderTheyWereFirstSaved)
{
  Scene scene;
  ExpressionLogic logic(scene);
  for (const char* name : {"b", "a", "c"})
    logic.saveExpression(name, "default", {{"risorius_left", 0.5}}, "");
  logic.saveExpression("a", "default", {{"risorius_left", 0.75}}, "changed");
  EXPECT_EQ(savedNames(logic), (std::vector<std::string>{"b", "a", "c"}));
  EXPECT_EQ(logic.savedExpression("a")->activation("risorius_left"), 0.75);
  EXPECT_EQ(logic.savedExpression("d"), nullptr);
}

TEST(SavedExpression, AnUndoneOneStaysGoneThroughSavingAndLoadingTheScene)
{
  Scene scene;
  ExpressionLogic logic(scene);
  logic.saveExpression("kept", "default", {{"risorius_left", 0.5}}, "");
  logic.saveExpression("undone", "default", {{"risorius_right", 0.5}}, "");
  ASSERT_TRUE(scene.undoStack().undo());
  const auto bundle = test::scratchFolder() / "expressions.caps";
  saveSceneBundle(scene, bundle);
  Scene loaded;
  loadSceneBundle(loaded, bundle);
  ExpressionLogic reloaded(loaded);
  EXPECT_EQ(savedNames(reloaded), std::vector<std::string>{"kept"});
  EXPECT_EQ(reloaded.savedExpression("kept")->activations(), (std::map<std::string, double>{{"risorius_left", 0.5}}));
}

// --- The sample face of the other tests --------------------------------------

/// Bit for bit, NaN where NaN.
void expectSameMap(const seg::RangeMap& actual, const seg::RangeMap& expected, const char* what)
{
  EXPECT_TRUE(actual.frame() == expected.frame()) << what;
  ASSERT_EQ(actual.values().size(), expected.values().size()) << what;
  std::size_t differ = 0;
  for (std::size_t k = 0; k < actual.values().size(); ++k)
  {
    const float a = actual.values()[k], b = expected.values()[k];
    if (std::isnan(a) != std::isnan(b) || (!std::isnan(a) && std::memcmp(&a, &b, sizeof a) != 0))
      ++differ;
  }
  EXPECT_EQ(differ, 0u) << what << ": samples that differ";
}

// sampleFace() reads the maps from the demo scene instead of building them
// from the CT in every test process (about 12 s each): this is the one test
// that builds them, as RangeMapLogic::run does with its default parameters,
// to hold it to being the same face.
TEST(SampleFace, TheDemoScenesMapsAreTheSampleCtsMapsWithDefaultParameters)
{
  RangeMapOutput computed;
  Scene scene;
  RangeMapLogic logic(scene);
  std::ostringstream messages;
  VolumeNode* volume = cli::loadCt(logic, test::sampleCt(), seg::CtReadOptions{}, messages);
  ASSERT_NE(volume, nullptr) << messages.str();
  logic.run(*volume, RangeMapLogic::Parameters{}, {}, &computed);
  expectSameMap(test::sampleFace().maps.skin, computed.skin, "skin");
  expectSameMap(test::sampleFace().maps.bone, computed.bone, "bone");
  EXPECT_GE(test::sampleFace().landmarks.landmarks.size(), 6u);
}

// --- The face model's input from the scene -----------------------------------

/// A range map node on a cylinder of radius @a r about the z axis.
RangeMapNode& addCylinder(Scene& scene, const std::string& role, float r)
{
  auto* node = scene.add<RangeMapNode>();
  node->setName(role + " range");
  node->setRole(role);
  node->setAxis(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  node->setZRange(-60.0, 60.0);
  node->setValues(Eigen::MatrixXf::Constant(64, 32, r));
  return *node;
}

std::string modelInputError(const ExpressionLogic& logic)
{
  try
  {
    logic.modelInput();
  }
  catch (const std::invalid_argument& e)
  {
    return e.what();
  }
  return "(no error)";
}

TEST(ExpressionModelInput, WithoutRangeMapsItSaysToBuildThem)
{
  Scene scene;
  ExpressionLogic logic(scene);
  const std::string none = modelInputError(logic);
  EXPECT_NE(none.find("no skin range map"), std::string::npos) << none;
  EXPECT_NE(none.find("Range maps module"), std::string::npos) << none;

  addCylinder(scene, "skin", 80.0f);
  const std::string noBone = modelInputError(logic);
  EXPECT_NE(noBone.find("no bone range map"), std::string::npos) << noBone;
  EXPECT_NE(noBone.find("Range maps module"), std::string::npos) << noBone;
}

TEST(ExpressionModelInput, OnAFaceWithoutFeaturesItSaysWhichLandmarksToPlace)
{
  Scene scene;
  ExpressionLogic logic(scene);
  addCylinder(scene, "skin", 80.0f);
  addCylinder(scene, "bone", 72.0f);
  const std::string error = modelInputError(logic);
  EXPECT_NE(error.find("landmarks"), std::string::npos) << error;
  EXPECT_NE(error.find("place them"), std::string::npos) << error;
}

TEST(ExpressionModelInput, TheDemoSceneGivesItsMapsItsCtAndTheUsersLandmarks)
{
  Scene scene;
  loadSceneBundle(scene, test::reportDemoFolder() / "sample.caps");
  ExpressionLogic logic(scene);
  const expression::ExpressionModelInput automatic = logic.modelInput();
  const RangeMapNode* skinNode = nullptr;
  for (Node* n : scene.nodesOfType(NodeType::RangeMap))
    if (static_cast<RangeMapNode*>(n)->role() == "skin")
      skinNode = static_cast<RangeMapNode*>(n);
  ASSERT_NE(skinNode, nullptr);
  ASSERT_EQ(automatic.skin.nTheta(), skinNode->values().rows());
  ASSERT_EQ(automatic.skin.nZ(), skinNode->values().cols());
  for (int i : {0, 100, 300})
    for (int j : {10, 128, 200})
    {
      const float expected = skinNode->values()(i, j);
      if (std::isnan(expected))
        EXPECT_TRUE(std::isnan(automatic.skin.at(i, j)));
      else
        EXPECT_EQ(automatic.skin.at(i, j), expected) << i << ", " << j;
    }
  EXPECT_FALSE(automatic.bone.empty());
  EXPECT_EQ(automatic.landmarkSource, "placed automatically");
  const auto volumes = scene.nodesOfType(NodeType::Volume);
  ASSERT_FALSE(volumes.empty());
  EXPECT_EQ(automatic.ct.GetPointer(), static_cast<VolumeNode*>(volumes.front())->image());

  // The user's nasion, 4 mm up the axis from the automatic one, replaces it.
  const auto nasion = std::find_if(automatic.landmarks.begin(), automatic.landmarks.end(),
                                   [](const seg::Landmark& l) { return l.name == "nasion"; });
  ASSERT_NE(nasion, automatic.landmarks.end());
  const seg::CylindricalFrame& frame = automatic.skin.frame();
  const double r = automatic.skin.sample(nasion->theta, nasion->z + 4.0);
  ASSERT_TRUE(std::isfinite(r));
  const Eigen::Vector3d mine = frame.toWorld(r, nasion->theta, nasion->z + 4.0);
  auto* marks = scene.add<LandmarksNode>();
  marks->setLandmarks({{"nasion", {mine.x(), mine.y(), mine.z()}}});
  const expression::ExpressionModelInput own = logic.modelInput();
  EXPECT_EQ(own.landmarkSource, "1 placed by you, the others automatically");
  EXPECT_EQ(own.landmarks.size(), automatic.landmarks.size());
  const auto moved =
    std::find_if(own.landmarks.begin(), own.landmarks.end(), [](const seg::Landmark& l) { return l.name == "nasion"; });
  ASSERT_NE(moved, own.landmarks.end());
  EXPECT_NEAR(moved->theta, nasion->theta, 1e-9);
  EXPECT_NEAR(moved->z, nasion->z + 4.0, 1e-9);
}

} // namespace
} // namespace caps
