// Reproducible plans: a plan as the operations that made it,
// applied again to the same skin, gives the same plan and the same
// prediction bit for bit; every bad input of the issue is refused by the
// operation that brings it, with the plan kept as it was; plan files that are
// not plan files are refused naming what is wrong; the CT's content hash sees
// voxels and geometry, not file names.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>

#include <gtest/gtest.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>

#include "planning/AnalyticSkins.h"
#include "TestPaths.h"
#include "modules/incision/IncisionLogic.h"
#include "planning/PlanRecipe.h"
#include "planning/PlanSimulation.h"
#include "scene/PlanNode.h"
#include "scene/Scene.h"
#include "scene/SceneError.h"
#include "segmentation/CtReader.h"

namespace fs = std::filesystem;

namespace caps::planning {
namespace {

using test::degree;

using Phantom = test::CylinderPhantom;
const Phantom& phantom()
{
  return test::cylinderPhantom();
}

const ProcedureLibrary& library()
{
  return test::shippedProcedures();
}

const SkinPoint zCentre{0.3, -8.0};

PlaceProcedure placeZ()
{
  return {"z-plasty", zCentre, {{"central_length", 12.0}, {"limb_angle", 60.0 * degree}}};
}

/// Cut point i of a plan in its chart (mm).
ChartPoint chartPoint(const IncisionPlan& plan, int i)
{
  return plan.chart(phantom().skin).fromNormalized(plan.cutPath()[std::size_t(i)]);
}

Eigen::Vector2d normalised(const IncisionPlan& plan, const ChartPoint& p)
{
  return plan.chart(phantom().skin).toNormalized(p);
}

/// The direction away from cut point i's twin on the left side of the cut
/// (the skin lies left of the loop): the mean of the two limbs' left normals.
ChartPoint leftOfCut(const IncisionPlan& plan, int i)
{
  const auto left = [](const ChartPoint& d) { return ChartPoint(-d.y(), d.x()).normalized(); };
  const ChartPoint a = chartPoint(plan, i - 1), b = chartPoint(plan, i), c = chartPoint(plan, i + 1);
  return (left(b - a) + left(c - b)).normalized();
}

/// Place, move p2 by 1 mm along the axis, offset p1's left side by 0.75 mm.
PlanRecipe zRecipe()
{
  PlanRecipe recipe;
  recipe.softwareVersion = softwareVersion();
  recipe.operations.push_back(placeZ());
  const IncisionPlan placed = applyRecipe(recipe, phantom().skin, library());
  recipe.operations.push_back(MoveCutPoint{2, normalised(placed, chartPoint(placed, 2) + ChartPoint(0.0, 1.0))});
  recipe.operations.push_back(OffsetBorderPoint{1, 0.75 * leftOfCut(placed, 1)});
  return recipe;
}

void expectSamePlan(const IncisionPlan& a, const IncisionPlan& b)
{
  EXPECT_EQ(a.procedure(), b.procedure());
  EXPECT_EQ(a.generator(), b.generator());
  EXPECT_EQ(a.parameters(), b.parameters());
  EXPECT_EQ(a.cutPath(), b.cutPath()); // Eigen ==: exact
  EXPECT_EQ(a.centre().theta, b.centre().theta);
  EXPECT_EQ(a.centre().z, b.centre().z);
  EXPECT_EQ(a.borderOffsets(), b.borderOffsets());
  EXPECT_EQ(a.writtenSutures(), b.writtenSutures());
  EXPECT_EQ(a.underminedRegions(), b.underminedRegions()); // exact
}

/// The message of the RecipeError an operation throws, or a test failure.
std::string refusal(const IncisionPlan& plan, const PlanOperation& operation, int number, int* at = nullptr,
                    const seg::RangeMap& skin = phantom().skin, const ProcedureLibrary& procedures = library())
{
  try
  {
    applyOperation(plan, operation, number, skin, procedures);
  }
  catch (const RecipeError& e)
  {
    if (at)
      *at = e.operation();
    std::printf("[refused] %s\n", e.what()); // what the surgeon reads, for the log
    return e.what();
  }
  ADD_FAILURE() << describe(operation) << " was accepted";
  return {};
}

bool contains(const std::string& text, const std::string& part)
{
  return text.find(part) != std::string::npos;
}

std::string readFile(const fs::path& file)
{
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

} // namespace

TEST(PlanRecipe, OperationsDoWhatThePlanApiDoes)
{
  const PlanRecipe recipe = zRecipe();
  const IncisionPlan replayed = applyRecipe(recipe, phantom().skin, library());

  const auto& place = std::get<PlaceProcedure>(recipe.operations[0]);
  IncisionPlan direct = library().find("z-plasty")->place(phantom().skin, place.at, place.values);
  const auto& move = std::get<MoveCutPoint>(recipe.operations[1]);
  direct.moveCutPoint(move.point, move.thetaZN);
  const auto& offset = std::get<OffsetBorderPoint>(recipe.operations[2]);
  direct.offsetBorderPoint(offset.vertex, offset.offset);
  expectSamePlan(replayed, direct);
  EXPECT_TRUE(replayed.isExcision());
  EXPECT_EQ(describe(recipe.operations[1]), "move cut point 2");
}

TEST(PlanRecipe, AppliedTwiceGivesTheSamePlanAndPredictionBitForBit)
{
  const PlanRecipe recipe = zRecipe();
  // The second time through plan.json's text, as a replay reads it.
  const PlanRecipe read = recipeFromJson(nlohmann::json::parse(recipeToJson(recipe).dump(2)));
  EXPECT_EQ(recipeToJson(read), recipeToJson(recipe));
  const IncisionPlan first = applyRecipe(recipe, phantom().skin, library());
  const IncisionPlan again = applyRecipe(read, phantom().skin, library());
  expectSamePlan(first, again);

  SimulationOptions options;
  options.elementSize = 2.5;
  options.regionRadius = 15.0;
  options.threads = 2;
  const PlanPrediction a = simulatePlan(phantom().skin, phantom().bone, first, options);
  const PlanPrediction b = simulatePlan(phantom().skin, phantom().bone, again, options);
  ASSERT_EQ(a.displacements.size(), b.displacements.size());
  EXPECT_EQ(
    std::memcmp(a.displacements.data(), b.displacements.data(), std::size_t(a.displacements.size()) * sizeof(double)),
    0);
  EXPECT_GT(a.displacements.cwiseAbs().maxCoeff(), 1.0); // the flaps moved: not a trivial match
}

// The skin's pre-tension a prediction carried goes into plan.json and back
// (N/mm, to the last bit); a file without it was made on slack skin; an
// impossible one is refused naming the field.
TEST(PlanRecipe, ThePreTensionIsKeptAndChecked)
{
  PlanRecipe recipe = zRecipe();
  recipe.elementSize = 2.0;
  recipe.preTension = std::array<double, 2>{0.0113, 0.0047};
  const nlohmann::json written = recipeToJson(recipe);
  ASSERT_TRUE(written["simulation"].contains("preTension"));
  const PlanRecipe read = recipeFromJson(nlohmann::json::parse(written.dump(2)));
  ASSERT_TRUE(read.preTension);
  EXPECT_EQ((*read.preTension)[0], 0.0113);
  EXPECT_EQ((*read.preTension)[1], 0.0047);
  nlohmann::json slack = written;
  slack["simulation"].erase("preTension");
  EXPECT_FALSE(recipeFromJson(slack).preTension);
  nlohmann::json wrong = written;
  wrong["simulation"]["preTension"]["acrossLines"] = -1.0;
  try
  {
    (void)recipeFromJson(wrong);
    ADD_FAILURE() << "a negative tension was read";
  }
  catch (const RecipeError& e)
  {
    EXPECT_NE(std::string(e.what()).find("preTension"), std::string::npos) << e.what();
  }
}

TEST(PlanRecipe, SetParameterPlacesTheProcedureAgainAtTheSameCentre)
{
  RecordedPlan recorded;
  recorded.apply(placeZ(), phantom().skin, library());
  recorded.apply(OffsetBorderPoint{1, 0.5 * leftOfCut(recorded.plan(), 1)}, phantom().skin, library());
  recorded.apply(SetParameter{"limb_angle", 45.0 * degree}, phantom().skin, library());
  auto values = placeZ().values;
  values["limb_angle"] = 45.0 * degree;
  const IncisionPlan expected = library().find("z-plasty")->place(phantom().skin, zCentre, values);
  expectSamePlan(recorded.plan(), expected);
  EXPECT_FALSE(recorded.plan().isExcision()); // the template drew the cut afresh
  EXPECT_EQ(recorded.recipe().operations.size(), 3u);

  int at = -1;
  const std::string unknown = refusal(recorded.plan(), SetParameter{"limb_length", 10.0}, 4, &at);
  EXPECT_EQ(at, 4);
  EXPECT_TRUE(contains(unknown, "operation 4 (set parameter limb_length)")) << unknown;
  EXPECT_TRUE(contains(unknown, "central_length")) << "lists the parameters there are: " << unknown;
  const std::string range = refusal(recorded.plan(), SetParameter{"limb_angle", 120.0 * degree}, 4);
  EXPECT_TRUE(contains(range, "outside its range")) << range;
}

TEST(PlanRecipe, ARefusedOperationKeepsThePlanAsItWas)
{
  RecordedPlan recorded(std::string(64, 'a'));
  recorded.apply(placeZ(), phantom().skin, library());
  const IncisionPlan before = recorded.plan();
  const PlanRecipe recipeBefore = recorded.recipe();
  // p3 moved through the middle of limb 0: limbs 0 and 2 cross.
  const ChartPoint middle = 0.5 * (chartPoint(before, 0) + chartPoint(before, 1));
  const ChartPoint through = chartPoint(before, 2) + 2.0 * (middle - chartPoint(before, 2));
  const MoveCutPoint crossing{3, normalised(before, through)};
  try
  {
    recorded.apply(crossing, phantom().skin, library());
    ADD_FAILURE() << "a move that makes limbs cross was accepted";
  }
  catch (const RecipeError& e)
  {
    EXPECT_EQ(e.operation(), 2);
    EXPECT_TRUE(contains(e.what(), "operation 2 (move cut point 3): limb 0 (cut points 0–1) crosses limb 2"))
      << e.what();
    EXPECT_TRUE(contains(e.what(), "a cut may not cross itself")) << e.what();
  }
  expectSamePlan(recorded.plan(), before);
  EXPECT_EQ(recipeToJson(recorded.recipe()), recipeToJson(recipeBefore));
  // applyOperation() works on a copy: the plan it was given is untouched.
  IncisionPlan given = before;
  refusal(given, crossing, 2);
  expectSamePlan(given, before);
}

TEST(PlanRecipe, BadInputIsRefusedByTheOperationThatBringsIt)
{
  const IncisionPlan placed = library().find("z-plasty")->place(phantom().skin, zCentre, placeZ().values);

  // A path leaving the scanned region (z from -100 to 100 mm).
  const Eigen::Vector2d top(placed.cutPath()[0].x(), 1.05);
  std::string m = refusal(placed, MoveCutPoint{0, top}, 2);
  EXPECT_TRUE(contains(m, "operation 2 (move cut point 0): cut point 0")) << m;
  EXPECT_TRUE(contains(m, "is outside the scanned region")) << m;
  EXPECT_TRUE(contains(m, "move it")) << "says what to do: " << m;
  m = refusal(IncisionPlan(), PlaceProcedure{"z-plasty", {0.3, 96.0}, placeZ().values}, 1);
  EXPECT_TRUE(contains(m, "operation 1 (place z-plasty)")) << m;
  EXPECT_TRUE(contains(m, "outside the scanned region")) << m;

  // Points too close together: p1 0.2 mm from p2.
  const ChartPoint p2 = chartPoint(placed, 2);
  const ChartPoint towards = (chartPoint(placed, 1) - p2).normalized();
  m = refusal(placed, MoveCutPoint{1, normalised(placed, p2 + 0.2 * towards)}, 3);
  EXPECT_TRUE(contains(m, "operation 3 (move cut point 1): cut points 1 and 2 are 0.2 mm apart, closer than 0.5 mm"))
    << m;
  EXPECT_TRUE(contains(m, "move one of them or delete it")) << m;

  // Points and border points that do not exist; an end of the cut has no twin.
  m = refusal(placed, MoveCutPoint{7, placed.cutPath()[0]}, 2);
  EXPECT_TRUE(contains(m, "cut point 7 does not exist: the cut has 4 points")) << m;
  m = refusal(placed, OffsetBorderPoint{9, {0.0, 1.0}}, 2);
  EXPECT_TRUE(contains(m, "border point 9 does not exist")) << m;
  m = refusal(placed, OffsetBorderPoint{0, {0.0, 1.0}}, 2);
  EXPECT_TRUE(contains(m, "is an end of the cut")) << m;
  // An offset to the wrong side swaps the excision's sides.
  m = refusal(placed, OffsetBorderPoint{1, -2.0 * leftOfCut(placed, 1)}, 2);
  EXPECT_TRUE(contains(m, "operation 2 (offset border point 1)")) << m;
  // Nothing to move before a procedure is placed; numbers that are not numbers.
  m = refusal(IncisionPlan(), MoveCutPoint{0, {0.0, 0.0}}, 1);
  EXPECT_TRUE(contains(m, "there is no cut yet; a plan starts by placing a procedure")) << m;
  m = refusal(placed, MoveCutPoint{1, {std::nan(""), 0.0}}, 2);
  EXPECT_TRUE(contains(m, "not a number")) << m;
  // A procedure that does not exist.
  m = refusal(IncisionPlan(), PlaceProcedure{"face-lift", zCentre, {}}, 1);
  EXPECT_TRUE(contains(m, "operation 1 (place face-lift): there is no procedure 'face-lift' (there are: ")) << m;
  EXPECT_TRUE(contains(m, "z-plasty")) << m;
  EXPECT_THROW(applyRecipe(PlanRecipe{}, phantom().skin, library()), RecipeError);
}

TEST(PlanRecipe, AProcedureWithInconsistentSuturesIsLeftOutAndSaysWhy)
{
  const fs::path folder = test::scratchFolder();
  fs::copy_file(test::proceduresFolder() / "z-plasty.procedure", folder / "z-plasty.procedure");
  // A Z whose third suture sews border edge (0,1) a second time.
  std::string text = readFile(test::proceduresFolder() / "z-plasty.procedure");
  text.replace(text.find("procedure = z-plasty"), 20, "procedure = lopsided-z");
  text.replace(text.find("suture = ((0,1),(3,4))"), 22, "suture = ((0,1),(2,3))");
  std::ofstream(folder / "lopsided-z.procedure") << text;

  Scene scene;
  IncisionLogic logic(scene);
  const ProcedureLibrary& procedures = logic.reloadProcedures(folder);
  ASSERT_EQ(procedures.procedures().size(), 1u);
  ASSERT_EQ(procedures.errors().size(), 1u);
  PlanRecipe recipe;
  recipe.operations.push_back(PlaceProcedure{"lopsided-z", zCentre, {}});
  try
  {
    logic.applyRecipe(recipe, phantom().skin);
    ADD_FAILURE() << "a procedure with inconsistent sutures was placed";
  }
  catch (const RecipeError& e)
  {
    const std::string m = e.what();
    EXPECT_EQ(e.operation(), 1);
    EXPECT_TRUE(contains(m, "there is no procedure 'lopsided-z' (there are: z-plasty)")) << m;
    EXPECT_TRUE(contains(m, "lopsided-z.procedure:")) << "names the file: " << m;
    EXPECT_TRUE(contains(m, "is already sewn by suture")) << "says what is wrong: " << m;
    EXPECT_TRUE(contains(m, "fix the file")) << m;
  }
  EXPECT_THROW(logic.placeProcedure("lopsided-z", phantom().skin, zCentre), std::invalid_argument);
}

TEST(PlanRecipe, HolesInTheSkinMapAreRefusedUnderTheCutAndUnderTheMesh)
{
  // A patch without skin (NaN) 6 to 14 mm right of the Z's centre, and one
  // under the Z's own central limb.
  const auto withHole = [](double uFrom, double uTo, double vFrom, double vTo) {
    seg::RangeMap skin = test::cylinderSkin(80.0);
    const auto& f = skin.frame();
    for (int j = 0; j < skin.nZ(); ++j)
      for (int i = 0; i < skin.nTheta(); ++i)
      {
        const double u = 80.0 * seg::CylindricalFrame::wrapTheta(f.indexToTheta(i) - zCentre.theta);
        const double v = f.indexToZ(j) - zCentre.z;
        if (u >= uFrom && u <= uTo && v >= vFrom && v <= vTo)
          skin.at(i, j) = std::numeric_limits<float>::quiet_NaN();
      }
    return skin;
  };
  // Under the central limb (from u = -6 to 6 mm), beside the centre.
  const seg::RangeMap underLimb = withHole(2.0, 4.0, -1.0, 1.0);
  int at = -1;
  std::string m = refusal(IncisionPlan(), placeZ(), 1, &at, underLimb);
  EXPECT_EQ(at, 1);
  EXPECT_TRUE(contains(m, "operation 1 (place z-plasty): the skin map has no surface under border edge")) << m;
  EXPECT_TRUE(contains(m, "move the cut onto measured skin")) << m;
  // Under the centre the plan is placed on.
  m = refusal(IncisionPlan(), placeZ(), 1, &at, withHole(-1.0, 1.0, -1.0, 1.0));
  EXPECT_TRUE(contains(m, "the skin map has no surface at")) << m;
  EXPECT_TRUE(contains(m, "place the plan on the measured skin")) << m;
  // A move onto the hole, from a plan placed beside it: refused, the plan kept.
  const seg::RangeMap beside = withHole(-30.0, -25.0, -2.0, 2.0);
  RecordedPlan recorded;
  recorded.apply(placeZ(), beside, library());
  const IncisionPlan before = recorded.plan();
  EXPECT_THROW(recorded.apply(MoveCutPoint{1, normalised(before, {-27.0, 0.0})}, beside, library()), RecipeError);
  expectSamePlan(recorded.plan(), before);

  const seg::RangeMap nearCut = withHole(12.0, 16.0, -2.0, 2.0);
  PlanRecipe recipe;
  recipe.operations.push_back(placeZ());
  const IncisionPlan plan = applyRecipe(recipe, nearCut, library()); // the cut itself is on skin
  SimulationOptions options;
  options.elementSize = 2.5;
  options.regionRadius = 15.0;
  try
  {
    simulatePlan(nearCut, phantom().bone, plan, options);
    ADD_FAILURE() << "a meshed region over a hole in the skin map was simulated";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_TRUE(contains(e.what(), "no surface under the meshed region")) << e.what();
    EXPECT_TRUE(contains(e.what(), "reduce the region radius or move the plan")) << e.what();
  }
}

TEST(PlanRecipe, FilesThatAreNotPlansAreRefusedNamingWhatIsWrong)
{
  const fs::path folder = test::scratchFolder();
  const PlanRecipe recipe = zRecipe();
  writeRecipe(recipe, folder / "plan.json");
  EXPECT_EQ(recipeToJson(readRecipe(folder / "plan.json")), recipeToJson(recipe));
  EXPECT_FALSE(fs::exists(folder / "plan.json.writing"));

  const auto refused = [&](const std::string& text) -> std::pair<int, std::string> {
    std::ofstream(folder / "bad.json") << text;
    try
    {
      readRecipe(folder / "bad.json");
    }
    catch (const RecipeError& e)
    {
      std::printf("[refused] %s\n", e.what());
      return {e.operation(), e.what()};
    }
    ADD_FAILURE() << "accepted: " << text;
    return {-1, {}};
  };
  auto [at, m] = refused("Operative report: Z-plasty, left cheek.");
  EXPECT_EQ(at, 0);
  EXPECT_TRUE(contains(m, "bad.json is not a plan file: it is not JSON")) << m;
  std::tie(at, m) = refused(R"({"format": "caps-scene", "formatVersion": 1, "operations": []})");
  EXPECT_TRUE(contains(m, "this is not a CAPS plan")) << m;
  std::tie(at, m) = refused(R"({"format": "caps-plan", "formatVersion": 7, "operations": []})");
  EXPECT_TRUE(contains(m, "by a newer CAPS")) << m;
  EXPECT_TRUE(contains(m, "update CAPS")) << m;
  std::tie(at, m) = refused(R"({"format": "caps-plan", "formatVersion": 1, "ctSha256": "12ab", "operations": []})");
  EXPECT_TRUE(contains(m, "64 lowercase hex digits")) << m;

  nlohmann::json j = recipeToJson(recipe);
  j["operations"][1] = {{"operation", "rotate"}, {"degrees", 15}};
  std::tie(at, m) = refused(j.dump());
  EXPECT_EQ(at, 2);
  EXPECT_TRUE(contains(m, "operation 2 is 'rotate', which this CAPS does not know; the operations are place, "
                          "move, offset, set-parameter"))
    << m;
  j = recipeToJson(recipe);
  j["operations"][1]["thetaZN"] = "left cheek";
  std::tie(at, m) = refused(j.dump());
  EXPECT_EQ(at, 2);
  EXPECT_TRUE(contains(m, "operation 2 (move): \"thetaZN\" must be two numbers")) << m;
  j = recipeToJson(recipe);
  j["operations"][2].erase("vertex");
  std::tie(at, m) = refused(j.dump());
  EXPECT_EQ(at, 3);
  EXPECT_TRUE(contains(m, "operation 3 (offset): \"vertex\" is missing")) << m;
  j = recipeToJson(recipe);
  j["operations"][0]["values"]["limb_angle"] = "sixty";
  std::tie(at, m) = refused(j.dump());
  EXPECT_TRUE(contains(m, "parameter \"limb_angle\" must be a finite number")) << m;

  // A well-formed file naming a procedure that does not exist: refused when applied.
  PlanRecipe unknown;
  unknown.operations.push_back(PlaceProcedure{"face-lift", zCentre, {}});
  writeRecipe(unknown, folder / "face-lift.json");
  try
  {
    applyRecipe(readRecipe(folder / "face-lift.json"), phantom().skin, library());
    ADD_FAILURE() << "a plan of a procedure that does not exist was made";
  }
  catch (const RecipeError& e)
  {
    EXPECT_TRUE(contains(e.what(), "there is no procedure 'face-lift'")) << e.what();
  }
  try
  {
    readRecipe(folder / "missing.json");
    ADD_FAILURE() << "a missing file was read";
  }
  catch (const RecipeError& e)
  {
    EXPECT_TRUE(contains(e.what(), "cannot read the plan file")) << e.what();
  }
}

TEST(PlanRecipe, ThePlanNodeKeepsItsRecipeAndOldScenesStillLoad)
{
  PlanRecipe recipe = zRecipe();
  recipe.ctSha256 = std::string(64, 'c');
  RecordedPlan recorded(recipe.ctSha256);
  for (const auto& o : recipe.operations)
    recorded.apply(o, phantom().skin, library());
  PlanNode node;
  node.setName("left cheek");
  IncisionLogic::writePlan(recorded.plan(), node);
  IncisionLogic::writeRecipe(recorded.recipe(), node);
  PlanNode back;
  back.fromJson(nlohmann::json::parse(node.toJson().dump()));
  const auto read = IncisionLogic::readRecipe(back);
  ASSERT_TRUE(read.has_value());
  EXPECT_EQ(recipeToJson(*read), recipeToJson(recorded.recipe()));
  EXPECT_EQ(read->ctSha256, recipe.ctSha256);
  EXPECT_EQ(read->softwareVersion, softwareVersion());
  expectSamePlan(applyRecipe(*read, phantom().skin, library()), IncisionLogic::readPlan(back));
  EXPECT_EQ(read->elementSize, 0.0); // not recorded: no "simulation" in the node
  EXPECT_TRUE(back.simulation().is_null());

  // How the prediction was made (element size, cut depth) goes with it, so
  // a report predicts the same.
  PlanRecipe withSimulation = recorded.recipe();
  withSimulation.elementSize = 2.5;
  withSimulation.cutLayers = 2;
  IncisionLogic::writeRecipe(withSimulation, node);
  PlanNode again;
  again.fromJson(nlohmann::json::parse(node.toJson().dump()));
  const auto readAgain = IncisionLogic::readRecipe(again);
  ASSERT_TRUE(readAgain.has_value());
  EXPECT_EQ(readAgain->elementSize, 2.5);
  EXPECT_EQ(readAgain->cutLayers, 2);
  EXPECT_THROW(node.setSimulation(nlohmann::json::array()), SceneError);
  IncisionLogic::writeRecipe(recorded.recipe(), node);

  // A plan saved before plans kept their recipe: no recipe, the plan reads.
  nlohmann::json old = node.toJson();
  for (const char* key : {"operations", "ctSha256", "softwareVersion"})
    old.erase(key);
  PlanNode oldNode;
  oldNode.fromJson(old);
  EXPECT_FALSE(IncisionLogic::readRecipe(oldNode).has_value());
  expectSamePlan(IncisionLogic::readPlan(oldNode), recorded.plan());

  // A hand-edited operation is refused naming the plan and the operation.
  nlohmann::json edited = node.toJson();
  edited["operations"][1]["operation"] = "twist";
  PlanNode editedNode;
  editedNode.fromJson(edited);
  try
  {
    IncisionLogic::readRecipe(editedNode);
    ADD_FAILURE() << "an unknown operation in the scene was accepted";
  }
  catch (const RecipeError& e)
  {
    EXPECT_EQ(e.operation(), 2);
    EXPECT_TRUE(contains(e.what(), "plan 'left cheek': operation 2 is 'twist'")) << e.what();
  }
  EXPECT_THROW(node.setOperations(nlohmann::json::object()), SceneError);
}

TEST(PlanRecipe, UnderminedRegionsGoThroughPlanJsonTheSceneAndAReplayBitForBit)
{
  // The Z recipe, a region drawn, cleared, two drawn again, a parameter set.
  PlanRecipe recipe = zRecipe();
  const IncisionPlan z = applyRecipe(recipe, phantom().skin, library());
  auto region = [&](double u, double v) {
    UnderminedRegion r;
    for (const ChartPoint& p :
         {ChartPoint(u - 4.1, v - 2.3), ChartPoint(u + 3.7, v - 2.9), ChartPoint(u + 0.3, v + 3.3)})
      r.push_back(normalised(z, p));
    return r;
  };
  recipe.operations.push_back(UndermineRegion{region(0.0, 12.0)});
  recipe.operations.push_back(ClearUndermining{});
  recipe.operations.push_back(UndermineRegion{region(-6.0, 11.0)});
  recipe.operations.push_back(UndermineRegion{region(7.0, -10.0)});
  recipe.operations.push_back(SetParameter{"limb_angle", 55.0 * degree});
  EXPECT_EQ(describe(recipe.operations[3]), "undermine a region of 3 points");

  const nlohmann::json written = recipeToJson(recipe);
  EXPECT_EQ(written["operations"][3]["operation"], "undermine");
  EXPECT_EQ(written["operations"][3]["region"].size(), 3u);
  EXPECT_EQ(written["operations"][3]["region"][0].size(), 2u);
  EXPECT_EQ(written["operations"][4], nlohmann::json({{"operation", "clear-undermining"}}));
  EXPECT_EQ(written["formatVersion"], 1);
  const PlanRecipe read = recipeFromJson(nlohmann::json::parse(written.dump(2)));
  EXPECT_EQ(recipeToJson(read), written);
  EXPECT_EQ(std::get<UndermineRegion>(read.operations[5]).region,
            std::get<UndermineRegion>(recipe.operations[5]).region);

  const IncisionPlan first = applyRecipe(recipe, phantom().skin, library());
  const IncisionPlan again = applyRecipe(read, phantom().skin, library());
  expectSamePlan(first, again);
  // The clear dropped the first; setting a parameter kept the other two.
  ASSERT_EQ(first.underminedRegions().size(), 2u);
  EXPECT_EQ(first.underminedRegions()[0], std::get<UndermineRegion>(recipe.operations[5]).region);
  EXPECT_EQ(first.parameters().at("limb_angle"), 55.0 * degree);
  // Placing a procedure starts afresh, regions too.
  EXPECT_TRUE(applyOperation(first, placeZ(), 9, phantom().skin, library()).underminedRegions().empty());

  SimulationOptions options;
  options.elementSize = 2.5;
  options.regionRadius = 15.0;
  options.threads = 2;
  const PlanPrediction a = simulatePlan(phantom().skin, phantom().bone, first, options);
  const PlanPrediction b = simulatePlan(phantom().skin, phantom().bone, again, options);
  EXPECT_FALSE(a.continuum.underminedNodes.empty());
  EXPECT_EQ(a.continuum.underminedNodes, b.continuum.underminedNodes);
  ASSERT_EQ(a.displacements.size(), b.displacements.size());
  EXPECT_EQ(
    std::memcmp(a.displacements.data(), b.displacements.data(), std::size_t(a.displacements.size()) * sizeof(double)),
    0);

  // The scene keeps them through the recipe.
  RecordedPlan recorded(std::string(64, 'd'));
  for (const auto& o : recipe.operations)
    recorded.apply(o, phantom().skin, library());
  PlanNode node;
  node.setName("right cheek");
  IncisionLogic::writePlan(recorded.plan(), node);
  IncisionLogic::writeRecipe(recorded.recipe(), node);
  PlanNode back;
  back.fromJson(nlohmann::json::parse(node.toJson().dump()));
  expectSamePlan(IncisionLogic::readPlan(back), first);

  // A hand-edited region is refused naming the operation and the point.
  nlohmann::json bad = written;
  bad["operations"][5]["region"][1] = nlohmann::json::array({0.1});
  try
  {
    recipeFromJson(bad);
    ADD_FAILURE() << "a region point of one number was accepted";
  }
  catch (const RecipeError& e)
  {
    EXPECT_EQ(e.operation(), 6);
    EXPECT_TRUE(contains(e.what(), "operation 6 (undermine): point 1 of \"region\" must be two numbers")) << e.what();
  }
  bad["operations"][5].erase("region");
  EXPECT_THROW(recipeFromJson(bad), RecipeError);
}

// A cut drawn by hand along the points a simple excision's template makes is
// sewn exactly as the template's procedure file writes it (its sutures are
// the straight closure), and goes through the plan file unchanged.
TEST(PlanRecipe, ACutDrawnByHandIsSewnStraightBackTogether)
{
  const ProcedureTemplate* simple = library().find("simple-excision");
  ASSERT_NE(simple, nullptr);
  const IncisionPlan templated = simple->place(phantom().skin, zCentre, {{"length", 16.0}});
  ASSERT_EQ(templated.pointCount(), 4);
  PlanRecipe recipe;
  recipe.softwareVersion = softwareVersion();
  recipe.operations.push_back(DrawCut{templated.cutPath()});
  const IncisionPlan drawn = applyRecipe(recipe, phantom().skin, library());
  EXPECT_TRUE(drawn.procedure().empty());
  EXPECT_EQ(drawn.cutPath(), templated.cutPath());
  EXPECT_EQ(drawn.writtenSutures(), templated.writtenSutures());
  EXPECT_EQ(drawn.sutures().size(), templated.sutures().size());
  EXPECT_EQ(describe(recipe.operations[0]), "draw a cut of 4 points");
  // The chart is centred on the middle of the points: the template's centre
  // is the middle of its symmetric cut.
  EXPECT_NEAR(drawn.centre().theta, templated.centre().theta, 1e-9);
  EXPECT_NEAR(drawn.centre().z, templated.centre().z, 1e-9);
  // Offsets make it an excision like the template's.
  PlanRecipe excision = recipe;
  const std::vector<ChartPoint> offsets = templated.borderOffsets();
  for (int v = 0; v < int(offsets.size()); ++v)
    if (offsets[std::size_t(v)].norm() > 0.0)
      excision.operations.push_back(OffsetBorderPoint{v, offsets[std::size_t(v)]});
  EXPECT_TRUE(applyRecipe(excision, phantom().skin, library()).isExcision() || !templated.isExcision());
  // Through JSON and back: the same operations, the same plan.
  const PlanRecipe read = recipeFromJson(recipeToJson(excision));
  ASSERT_EQ(read.operations.size(), excision.operations.size());
  EXPECT_EQ(operationToJson(read.operations[0]), operationToJson(excision.operations[0]));
  expectSamePlan(applyRecipe(read, phantom().skin, library()), applyRecipe(excision, phantom().skin, library()));
  // Too few points, or a point that is not a number, are refused.
  EXPECT_TRUE(contains(refusal(IncisionPlan(), DrawCut{{templated.cutPath()[0]}}, 1), "at least 2 points"));
  EXPECT_TRUE(contains(
    refusal(IncisionPlan(), DrawCut{{templated.cutPath()[0], Eigen::Vector2d(std::nan(""), 0.0)}}, 1), "not a number"));
  // Straight closure of 3 points: ((0,1),(0,3)) and ((1,2),(3,2)).
  const std::vector<SutureEdges> three = straightClosureSutures(3);
  ASSERT_EQ(three.size(), 2u);
  EXPECT_EQ(three[0], (SutureEdges{{0, 1}, {0, 3}}));
  EXPECT_EQ(three[1], (SutureEdges{{1, 2}, {3, 2}}));
}

TEST(CtContentHash, TheSameScanReadTwiceUnderOtherNamesHashesTheSame)
{
  // The sample series copied under other names, listed in the opposite order.
  const fs::path copy = test::scratchFolder() / "renamed";
  fs::create_directories(copy);
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(test::sampleCt()))
    if (entry.path().extension() == ".dcm")
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  for (std::size_t k = 0; k < files.size(); ++k)
    fs::copy_file(files[k], copy / ("slice-" + std::to_string(files.size() - k) + ".dcm"));
  const seg::CtVolume original = seg::readCtVolume(test::sampleCt());
  const std::string hash = ctContentHash(original.image);
  EXPECT_EQ(hash.size(), 64u);
  EXPECT_EQ(hash.find_first_not_of("0123456789abcdef"), std::string::npos) << hash;
  EXPECT_EQ(ctContentHash(seg::readCtVolume(copy).image), hash);
  EXPECT_EQ(ctContentHash(original.image), hash); // and hashing twice is the same

  // One voxel one HU brighter, a spacing, an origin or a direction changed:
  // another CT (changed in place and put back: the sample is 150 MB).
  vtkImageData* changed = original.image;
  vtkDataArray* voxels = changed->GetPointData()->GetScalars();
  const vtkIdType middle = voxels->GetNumberOfTuples() / 2;
  voxels->SetComponent(middle, 0, voxels->GetComponent(middle, 0) + 1.0);
  EXPECT_NE(ctContentHash(changed), hash);
  voxels->SetComponent(middle, 0, voxels->GetComponent(middle, 0) - 1.0);
  EXPECT_EQ(ctContentHash(changed), hash);
  double spacing[3];
  changed->GetSpacing(spacing);
  changed->SetSpacing(spacing[0], spacing[1], spacing[2] * 1.0000001);
  EXPECT_NE(ctContentHash(changed), hash);
  changed->SetSpacing(spacing);
  double origin[3];
  changed->GetOrigin(origin);
  changed->SetOrigin(origin[0] + 0.5, origin[1], origin[2]);
  EXPECT_NE(ctContentHash(changed), hash);
  changed->SetOrigin(origin);
  changed->SetDirectionMatrix(-1, 0, 0, 0, -1, 0, 0, 0, 1);
  EXPECT_NE(ctContentHash(changed), hash);
  changed->SetDirectionMatrix(1, 0, 0, 0, 1, 0, 0, 0, 1);
  EXPECT_THROW(ctContentHash(vtkSmartPointer<vtkImageData>::New()), std::invalid_argument);
}

// The model a prediction was made with, and how it checked out, are in
// plan.json: the model so a replay solves the same way, the check so anyone
// can read how far to trust the prediction without running CAPS.
TEST(PlanRecipe, KeepsTheTissueModelAndThePredictionCheck)
{
  PlanRecipe recipe;
  recipe.ctSha256 = std::string(64, 'e');
  recipe.operations.push_back(placeZ());
  recipe.elementSize = 2.0;
  const nlohmann::json linear = recipeToJson(recipe);
  EXPECT_FALSE(linear["simulation"].contains("model")) << "the linear model is what older files mean";
  EXPECT_FALSE(linear.contains("prediction"));
  EXPECT_EQ(recipeFromJson(linear).model, TissueModel::LinearElastic);

  recipe.model = TissueModel::LargeDeformation;
  SimulationOptions options;
  options.elementSize = 2.5;
  options.regionRadius = 15.0;
  options.model = recipe.model;
  const PlanPrediction p =
    simulatePlan(phantom().skin, phantom().bone, applyRecipe(recipe, phantom().skin, library()), options);
  recipe.prediction = p.check;
  const nlohmann::json written = recipeToJson(recipe);
  EXPECT_EQ(written["simulation"]["model"], "large-deformation");
  EXPECT_EQ(written["prediction"]["model"], "large-deformation");
  EXPECT_EQ(written["prediction"]["admissible"], p.check.admissible());
  EXPECT_EQ(written["prediction"]["minDetF"].get<double>(), p.check.deformation.minDetF);
  EXPECT_GT(written["prediction"]["skinTrianglesChecked"].get<int>(), 0) << "the skin was checked for crossings";
  EXPECT_EQ(written["prediction"]["skinCrossings"].get<int>(), p.check.skinCrossings.crossingPairs);
  EXPECT_EQ(written["prediction"]["meshElements"].get<int>(), int(p.continuum.mesh.elements.size()));
  EXPECT_EQ(written["prediction"]["meshMinScaledJacobian"].get<double>(), p.check.mesh.minScaledJacobian);
  const PlanRecipe read = recipeFromJson(nlohmann::json::parse(written.dump(2)));
  EXPECT_EQ(read.model, TissueModel::LargeDeformation);
  ASSERT_TRUE(read.prediction);
  EXPECT_EQ(read.prediction->increments, p.check.increments);
  EXPECT_EQ(read.prediction->converged, p.check.converged);
  EXPECT_EQ(recipeToJson(read), written);
  EXPECT_EQ(read.prediction->loosePathStoppedAt, p.check.loosePathStoppedAt);
  EXPECT_EQ(read.prediction->mesh.worstJacobianAt, p.check.mesh.worstJacobianAt);

  nlohmann::json bad = written;
  bad["prediction"]["meshWorstScaledJacobianAt"] = {1.0, 2.0};
  try
  {
    recipeFromJson(bad);
    ADD_FAILURE() << "a point with two coordinates was accepted";
  }
  catch (const RecipeError& e)
  {
    EXPECT_TRUE(contains(e.what(), "[x, y, z]")) << e.what();
  }
  bad = written;
  bad["simulation"]["model"] = "nonlinear";
  try
  {
    recipeFromJson(bad);
    ADD_FAILURE() << "an unknown tissue model was accepted";
  }
  catch (const RecipeError& e)
  {
    EXPECT_TRUE(contains(e.what(), "\"linear\" or \"large-deformation\"")) << e.what();
  }
}

} // namespace caps::planning

namespace caps::planning {

TEST(PlanRecipe, KeepsTheClosureAndItsTensionAndReadsFilesFromBeforeTheTension)
{
  PlanRecipe recipe;
  recipe.ctSha256 = std::string(64, 'e');
  recipe.operations.push_back(placeZ());
  recipe.elementSize = 2.0;
  SimulationOptions options;
  options.elementSize = 2.5;
  options.regionRadius = 15.0;
  const IncisionPlan plan = applyRecipe(recipe, phantom().skin, library());
  const PlanPrediction p = simulatePlan(phantom().skin, phantom().bone, plan, options);
  const WoundTension tension = woundTension(p, plan, 5.0);
  recipe.closure = closureRecordOf(p, woundSkinStress(p, 10.0), tension);
  EXPECT_EQ(recipe.closure->force, p.closure.magnitudeSum);
  EXPECT_EQ(recipe.closure->peakTensionPerCentimetre, tension.peakPerCentimetre);
  EXPECT_EQ(recipe.closure->peakForcePerStitch, tension.peakPerStitch);
  EXPECT_EQ(recipe.closure->stitchSpacing, 5.0);
  EXPECT_EQ(recipe.closure->peakTensionLine, tension.peakLine);
  // The mean over the wound is the lines' forces over their lengths.
  double across = 0.0, length = 0.0;
  for (const WoundLineTension& l : tension.lines)
  {
    across += l.acrossForce;
    length += l.length;
  }
  EXPECT_NEAR(recipe.closure->tensionPerCentimetre, 10.0 * across / length, 1e-12);

  const nlohmann::json written = recipeToJson(recipe);
  const PlanRecipe read = recipeFromJson(nlohmann::json::parse(written.dump(2)));
  ASSERT_TRUE(read.closure);
  EXPECT_EQ(read.closure->tensionPerCentimetre, recipe.closure->tensionPerCentimetre);
  EXPECT_EQ(read.closure->peakTensionLine, recipe.closure->peakTensionLine);
  EXPECT_EQ(recipeToJson(read), written);

  nlohmann::json before = written; // a plan.json from before the tension was recorded
  for (const char* key :
       {"tensionPerCentimetre", "peakTensionPerCentimetre", "peakForcePerStitch", "stitchSpacing", "peakTensionLine"})
    before["closure"].erase(key);
  const PlanRecipe old = recipeFromJson(before);
  ASSERT_TRUE(old.closure);
  EXPECT_EQ(old.closure->force, recipe.closure->force);
  EXPECT_EQ(old.closure->peakTensionPerCentimetre, 0.0);

  nlohmann::json bad = written;
  bad["closure"]["peakForcePerStitch"] = -1.0;
  try
  {
    recipeFromJson(bad);
    ADD_FAILURE() << "a negative stitch force was accepted";
  }
  catch (const RecipeError& e)
  {
    EXPECT_TRUE(contains(e.what(), "\"peakForcePerStitch\" must be a number of 0 or more")) << e.what();
  }
}

} // namespace caps::planning
