// ExpressionNode: a named set of muscle activations saved
// in the scene bundle, undoable edits, and clear errors for bad fields.

#include <gtest/gtest.h>

#include <fstream>

#include "SceneTestUtils.h"
#include "scene/ExpressionNode.h"
#include "scene/Scene.h"
#include "scene/SceneBundle.h"
#include "scene/SceneError.h"
#include "scene/ScopedEdit.h"

namespace caps {
namespace {

using test::TempDir;

std::map<std::string, double> smile()
{
  return {{"zygomaticus_major_left", 1.0},
          {"zygomaticus_major_right", 1.0},
          {"risorius_left", 0.5},
          {"levator_labii_superioris_left", 0.125}};
}

TEST(ExpressionNode, TypeNameAndFactory)
{
  EXPECT_EQ(nodeTypeToString(NodeType::Expression), "Expression");
  EXPECT_EQ(nodeTypeFromString("Expression"), NodeType::Expression);
  EXPECT_EQ(Node::create(NodeType::Expression)->type(), NodeType::Expression);
}

TEST(ExpressionNode, RoundTripThroughTheSceneBundle)
{
  TempDir tmp;
  Scene scene;
  auto* node = scene.add<ExpressionNode>();
  node->setName("Smile");
  node->setDescription("Zygomaticus major and risorius, both sides");
  node->setMuscleSet("default");
  node->setActivations(smile());
  const NodeId id = node->id();
  EXPECT_EQ(node->activation("risorius_left"), 0.5);
  EXPECT_EQ(node->activation("temporalis_left"), 0.0);

  const auto bundle = tmp.path() / "face.caps";
  saveSceneBundle(scene, bundle);
  Scene loaded;
  loadSceneBundle(loaded, bundle);
  auto* copy = loaded.nodeAs<ExpressionNode>(id);
  ASSERT_NE(copy, nullptr);
  EXPECT_EQ(copy->name(), "Smile");
  EXPECT_EQ(copy->description(), "Zygomaticus major and risorius, both sides");
  EXPECT_EQ(copy->muscleSet(), "default");
  EXPECT_EQ(copy->activations(), smile());
}

TEST(ExpressionNode, EditsAreUndoable)
{
  Scene scene;
  auto* node = scene.add<ExpressionNode>();
  node->setName("Frown");
  node->setActivations({{"corrugator_supercilii", 0.75}});
  {
    ScopedEdit edit(scene, node->id(), "Change the frown");
    node->setActivations({{"corrugator_supercilii", 0.25}, {"depressor_labii_inferioris_left", 1.0}});
  }
  EXPECT_EQ(node->activation("corrugator_supercilii"), 0.25);
  ASSERT_TRUE(scene.undoStack().canUndo());
  scene.undoStack().undo();
  EXPECT_EQ(node->activations(), (std::map<std::string, double>{{"corrugator_supercilii", 0.75}}));
}

TEST(ExpressionNode, BadActivationsGiveClearErrors)
{
  ExpressionNode node;
  node.setName("Pucker");
  EXPECT_THROW(node.setActivations({{"orbicularis_oris_upper", 1.5}}), SceneError);
  EXPECT_THROW(node.setActivations({{"", 0.5}}), SceneError);
  try
  {
    node.fromJson(nlohmann::json::parse(R"({"activations": {"orbicularis_oris_upper": "strong"}})"));
    FAIL() << "a text activation was accepted";
  }
  catch (const SceneError& e)
  {
    EXPECT_NE(std::string(e.what()).find("orbicularis_oris_upper"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("number from 0 to 1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(node.fromJson(nlohmann::json::parse(R"({"activations": [0.5, 1]})")), SceneError);
  EXPECT_THROW(node.fromJson(nlohmann::json::parse(R"({"activations": {"orbicularis_oris_lower": -0.1}})")),
               SceneError);
  EXPECT_TRUE(node.activations().empty()); // a rejected read changes nothing
}

TEST(ExpressionNode, ADamagedBundleNamesTheNode)
{
  TempDir tmp;
  Scene scene;
  auto* node = scene.add<ExpressionNode>();
  node->setName("Sneer");
  node->setActivations({{"levator_labii_superioris_alaeque_nasi_left", 1.0}});
  const auto bundle = tmp.path() / "face.caps";
  saveSceneBundle(scene, bundle);
  // Someone edits scene.json by hand: an activation of 2.
  const auto file = bundle / "scene.json";
  std::ifstream in(file);
  nlohmann::json j = nlohmann::json::parse(in);
  in.close();
  for (auto& n : j["nodes"])
    if (n["type"] == "Expression")
      n["activations"]["levator_labii_superioris_alaeque_nasi_left"] = 2.0;
  std::ofstream(file) << j.dump();
  Scene loaded;
  try
  {
    loadSceneBundle(loaded, bundle);
    FAIL() << "an activation of 2 was accepted";
  }
  catch (const SceneError& e)
  {
    EXPECT_NE(std::string(e.what()).find("Sneer"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("from 0 (at rest) to 1"), std::string::npos) << e.what();
  }
}

} // namespace
} // namespace caps
