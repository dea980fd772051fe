// The tension across a closed wound per centimetre of wound line and per
// stitch (planning::WoundTension) on the cylinder phantom (skin r = 80 mm
// over bone r = 70 mm): named as the procedure names its lines, zero where
// nothing is pulled together, largest where an ellipse is widest, and the
// same number as the mesh is refined while the force at one node is not.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "AnalyticSkins.h"
#include "planning/PlanRecipe.h"
#include "planning/PlanSimulation.h"
#include "planning/WoundTension.h"

namespace caps::planning {
namespace {

IncisionPlan ellipsePlan()
{
  const auto& phantom = test::cylinderPhantom();
  return test::shippedProcedure("elliptical-excision")
    .place(phantom.skin, {0.0, 0.0}, {{"length", 24.0}, {"ratio", 3.0}, {"axis_angle", 0.0}});
}

PlanPrediction solved(const IncisionPlan& plan, double elementSize)
{
  const auto& phantom = test::cylinderPhantom();
  SimulationOptions options = test::phantomSimulationOptions();
  options.elementSize = elementSize;
  options.threads = 2;
  return simulatePlan(phantom.skin, phantom.bone, plan, options);
}

TEST(WoundTension, TheZPlastysLinesAreTheLimbsTheProcedureNames)
{
  const auto& phantom = test::cylinderPhantom();
  const IncisionPlan plan = test::shippedProcedure("z-plasty").place(phantom.skin, {0.0, 0.0});
  const PlanPrediction p = solved(plan, 2.0);
  const WoundTension t = woundTension(p, plan, 5.0);
  ASSERT_EQ(t.lines.size(), 3u);
  EXPECT_EQ(t.lines[0].name, "the first limb");
  EXPECT_EQ(t.lines[1].name, "the second limb");
  EXPECT_EQ(t.lines[2].name, "the new central limb");
  for (const WoundLineTension& l : t.lines)
  {
    // Each line closes one 20 mm limb: on the skin after the closure it is
    // a limb's length give or take the stretch of the transposition.
    EXPECT_GT(l.length, 14.0) << l.name;
    EXPECT_LT(l.length, 32.0) << l.name;
    EXPECT_GT(l.perCentimetre, 0.0) << l.name;
    EXPECT_GE(l.peakPerCentimetre, l.perCentimetre - 1e-12) << l.name;
    EXPECT_NEAR(l.perStitch, 0.5 * l.perCentimetre, 1e-12) << l.name;
    EXPECT_EQ(l.stitches, int(std::lround(l.length / 5.0))) << l.name;
  }
  EXPECT_THROW(woundTension(p, plan, 0.0), std::invalid_argument);
  EXPECT_THROW(woundTension(p, ellipsePlan()), std::invalid_argument);
}

TEST(WoundTension, ACutSewnStraightBackHoldsNoTension)
{
  // Nothing is pulled together: every suture joins two points that were
  // one before the cut, so no force holds the wound.
  IncisionPlan plan({{-0.04, 0.0}, {0.0, 0.0}, {0.04, 0.0}}, {0.0, 0.0});
  plan.setSutures(straightClosureSutures(3), {"the cut", "the cut"});
  const PlanPrediction p = solved(plan, 2.0);
  const WoundTension t = woundTension(p, plan);
  ASSERT_EQ(t.lines.size(), 1u);
  EXPECT_EQ(t.lines[0].name, "the cut");
  EXPECT_GT(t.lines[0].length, 10.0);
  EXPECT_LT(t.lines[0].perCentimetre, 1e-9);
}

TEST(WoundTension, AnEllipsesClosureIsOneLineAsSymmetricAsTheEllipse)
{
  // The ellipse and its mesh are mirror symmetric about its minor axis:
  // the piece from p(k) to p(k+1) is held as hard as its mirror image.
  const IncisionPlan plan = ellipsePlan();
  const PlanPrediction p = solved(plan, 2.0);
  const WoundTension t = woundTension(p, plan);
  ASSERT_EQ(t.lines.size(), 1u);
  const WoundLineTension& line = t.lines[0];
  EXPECT_EQ(line.name, "the closure line");
  ASSERT_EQ(line.sutures.size(), 8u);
  ASSERT_EQ(line.piecePerCentimetre.size(), 8u);
  for (std::size_t k = 0; k < 8; ++k)
  {
    std::printf("[ tension ] piece %zu: %.4f N/cm\n", k, line.piecePerCentimetre[k]);
    EXPECT_GT(line.piecePerCentimetre[k], 0.0);
    EXPECT_NEAR(line.piecePerCentimetre[k], line.piecePerCentimetre[7 - k], 1e-6 * line.peakPerCentimetre) << k;
  }
  EXPECT_DOUBLE_EQ(line.peakPerCentimetre,
                   *std::max_element(line.piecePerCentimetre.begin(), line.piecePerCentimetre.end()));
  EXPECT_EQ(t.peakLine, "the closure line");
  EXPECT_DOUBLE_EQ(t.peakPerStitch, line.peakPerCentimetre * 0.4);
}

TEST(WoundTension, TheTensionPerCentimetreSettlesAsTheMeshIsRefined)
{
  const IncisionPlan plan = ellipsePlan();
  std::vector<double> perCm, peakPerCm, largestNode;
  for (double size : {2.0, 1.4, 1.0})
  {
    const PlanPrediction p = solved(plan, size);
    const WoundTension t = woundTension(p, plan);
    perCm.push_back(t.lines.at(0).perCentimetre);
    peakPerCm.push_back(t.peakPerCentimetre);
    largestNode.push_back(p.closure.largest);
    std::printf("[ tension ] element %.1f mm: %.4f N/cm (peak %.4f N/cm), largest node force %.4f N\n", size,
                perCm.back(), peakPerCm.back(), largestNode.back());
  }
  const auto change = [](const std::vector<double>& v, std::size_t k) { return std::abs(v[k + 1] - v[k]) / v[k + 1]; };
  // The tension settles: its last change is small and smaller than the first.
  EXPECT_LT(change(perCm, 1), 0.06);
  EXPECT_LT(change(perCm, 1), change(perCm, 0) + 1e-3);
  EXPECT_LT(change(peakPerCm, 1), 0.08);
}

} // namespace
} // namespace caps::planning
