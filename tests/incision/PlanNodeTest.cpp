// A plan in the scene: everything an IncisionPlan is goes into a PlanNode,
// through the scene's JSON, and back; the plan read back predicts the same
// displacements bit for bit (on a phantom).

#include <gtest/gtest.h>

#include "planning/AnalyticSkins.h"
#include "modules/incision/IncisionLogic.h"
#include "planning/PlanSimulation.h"
#include "scene/PlanNode.h"
#include "scene/SceneError.h"

namespace caps::planning {
namespace {

/// The plan read from a node after a trip through the scene's JSON, as a
/// saved bundle keeps it.
IncisionPlan throughJson(const PlanNode& node)
{
  PlanNode copy;
  copy.fromJson(nlohmann::json::parse(node.toJson().dump()));
  return IncisionLogic::readPlan(copy);
}

} // namespace

TEST(PlanNode, EveryProcedureRoundTripsThroughTheScene)
{
  const seg::RangeMap skin = test::cylinderSkin(80.0);
  for (const ProcedureTemplate& t : test::shippedProcedures().procedures())
  {
    IncisionPlan plan = t.place(skin, {-1.2, 12.5});
    if (plan.pointCount() > 2)
      plan.offsetBorderPoint(1, {0.0, 0.75}); // an excision on the first inner point
    PlanNode node;
    IncisionLogic::writePlan(plan, node);
    const IncisionPlan back = throughJson(node);
    EXPECT_EQ(back.procedure(), plan.procedure()) << t.id();
    EXPECT_EQ(back.generator(), plan.generator()) << t.id();
    EXPECT_EQ(back.parameters(), plan.parameters()) << t.id();
    EXPECT_EQ(back.cutPath(), plan.cutPath()) << t.id();
    EXPECT_EQ(back.centre().theta, plan.centre().theta) << t.id();
    EXPECT_EQ(back.centre().z, plan.centre().z) << t.id();
    EXPECT_EQ(back.borderOffsets(), plan.borderOffsets()) << t.id();
    EXPECT_EQ(back.writtenSutures(), plan.writtenSutures()) << t.id();
    // Every shipped procedure names its wound lines, and they come back.
    ASSERT_EQ(plan.woundLineNames().size(), plan.writtenSutures().size()) << t.id();
    for (const std::string& name : plan.woundLineNames())
      EXPECT_FALSE(name.empty()) << t.id();
    EXPECT_EQ(back.woundLineNames(), plan.woundLineNames()) << t.id();
    EXPECT_GT(plan.underminingBand(), 0.0) << t.id();
    EXPECT_EQ(back.underminingBand(), plan.underminingBand()) << t.id();
    EXPECT_EQ(back.cutDepth(), plan.cutDepth()) << t.id();
    ASSERT_EQ(back.sutures().size(), plan.sutures().size()) << t.id();
    for (std::size_t k = 0; k < plan.sutures().size(); ++k)
    {
      EXPECT_EQ(back.sutures()[k].a, plan.sutures()[k].a) << t.id();
      EXPECT_EQ(back.sutures()[k].b, plan.sutures()[k].b) << t.id();
    }
  }
}

TEST(PlanNode, APlanReadBackPredictsTheSameBitForBit)
{
  const seg::RangeMap skin = test::cylinderSkin(80.0), bone = test::cylinderSkin(70.0);
  const IncisionPlan plan =
    test::shippedProcedure("z-plasty")
      .place(skin, {0.3, -8.0}, {{"central_length", 12.0}, {"limb_angle", 60.0 * test::degree}});
  SimulationOptions options;
  options.elementSize = 2.5;
  options.regionRadius = 15.0;
  options.threads = 2;
  const PlanPrediction first = simulatePlan(skin, bone, plan, options);
  PlanNode node;
  IncisionLogic::writePlan(plan, node);
  const PlanPrediction again = simulatePlan(skin, bone, throughJson(node), options);
  ASSERT_EQ(again.displacements.size(), first.displacements.size());
  EXPECT_TRUE((again.displacements.array() == first.displacements.array()).all());
  EXPECT_GT(first.displacements.cwiseAbs().maxCoeff(), 1.0); // the flaps moved: not a trivial match
}

TEST(PlanNode, AHandEditedNodeThatDoesNotFitIsRefused)
{
  const seg::RangeMap skin = test::cylinderSkin(80.0);
  const IncisionPlan z = test::shippedProcedure("z-plasty").place(skin, {0.0, 0.0});
  PlanNode offsets;
  offsets.setName("left cheek");
  IncisionLogic::writePlan(z, offsets);
  offsets.setBorderOffsets({{0.0, 1.0}}); // one offset for a loop of six points
  try
  {
    IncisionLogic::readPlan(offsets);
    ADD_FAILURE() << "offsets that do not fit were accepted";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("left cheek"), std::string::npos) << e.what();
  }
  PlanNode sutures;
  IncisionLogic::writePlan(z, sutures);
  sutures.setSutures({{0, 1, 0, 9}}); // vertex 9 is not on the border
  EXPECT_THROW(IncisionLogic::readPlan(sutures), std::invalid_argument);
  PlanNode names;
  IncisionLogic::writePlan(z, names);
  EXPECT_THROW(names.setWoundLineNames({"the first limb"}), SceneError); // three sutures
  nlohmann::json edited = names.toJson();
  edited["woundLineNames"] = {"the first limb", 2, "the new central limb"};
  PlanNode read;
  EXPECT_THROW(read.fromJson(edited), SceneError);
}

} // namespace caps::planning
