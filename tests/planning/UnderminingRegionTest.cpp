// Undermined regions the surgeon draws on the skin (thesis
// §3.2.2, §3.2.4 item 2) on the cylinder phantom (skin r = 80 mm, bone
// r = 70 mm): a region releases exactly the bone nodes of the surface
// vertices inside it, counted here with a winding number (the library uses
// a crossing test) and nothing else; regions and the default band add up;
// a region across the θ = ±π seam is one region; a region far from the
// wound eases the closure less than one beside it; bad regions are refused
// by the operation that brings them, the plan kept as it was; the display
// is 1 over the region and 0 away from it.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <vtkDataArray.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>

#include "AnalyticSkins.h"
#include "planning/PlanDisplay.h"
#include "planning/PlanRecipe.h"
#include "planning/PlanSimulation.h"
#include "planning/Undermining.h"

namespace caps::planning {
namespace {

using test::pi;

using Phantom = test::CylinderPhantom;
const Phantom& phantom()
{
  return test::cylinderPhantom();
}
const ProcedureLibrary& library()
{
  return test::shippedProcedures();
}

/// The symmetric ellipse of PlanSimulationTest: 24 mm, 3:1, along θ, centred at (θ, 0).
PlaceProcedure placeEllipse(double theta = 0.0)
{
  return {"elliptical-excision", {theta, 0.0}, {{"length", 24.0}, {"ratio", 3.0}, {"axis_angle", 0.0}}};
}

/// A polygon drawn in the plan's chart (mm), stored as the plan stores it (θn, zn).
UnderminedRegion regionFromChart(const IncisionPlan& plan, const std::vector<ChartPoint>& chartPolygon)
{
  const SkinChart chart = plan.chart(phantom().skin);
  UnderminedRegion region;
  for (const auto& p : chartPolygon)
    region.push_back(chart.toNormalized(p));
  return region;
}

/// A region back in the chart, point by point through the chart's own
/// conversion (not the library's unwrapping along the border).
std::vector<ChartPoint> chartPolygon(const IncisionPlan& plan, const UnderminedRegion& region)
{
  const SkinChart chart = plan.chart(phantom().skin);
  std::vector<ChartPoint> polygon;
  for (const auto& p : region)
    polygon.push_back(chart.fromNormalized(p));
  return polygon;
}

/// Winding number of a closed polygon about p: the turns of the ray from p
/// to a point walking its border (0 outside, ±1 inside a simple polygon).
int windingNumber(const std::vector<ChartPoint>& polygon, const ChartPoint& p)
{
  double angle = 0.0;
  for (std::size_t k = 0; k < polygon.size(); ++k)
  {
    const ChartPoint a = polygon[k] - p, b = polygon[(k + 1) % polygon.size()] - p;
    angle += std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
  }
  return int(std::lround(angle / (2.0 * pi)));
}

double distanceToBorder(const std::vector<ChartPoint>& polygon, const ChartPoint& p)
{
  double d = 1e300;
  for (std::size_t k = 0; k < polygon.size(); ++k)
  {
    const ChartPoint a = polygon[k], b = polygon[(k + 1) % polygon.size()];
    const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    d = std::min(d, (p - (a + t * (b - a))).norm());
  }
  return d;
}

/// A non-convex pentagon above the wound (the ellipse spans |u| ≤ 12, |v| ≤ 4 mm).
std::vector<ChartPoint> besideTheWound()
{
  return {{-7.31, 5.17}, {8.93, 5.41}, {6.07, 13.29}, {0.53, 8.87}, {-6.11, 12.73}};
}

SimulationOptions options(double underminingWidth = 0.0)
{
  SimulationOptions o = test::phantomSimulationOptions();
  o.underminingWidth = underminingWidth;
  return o;
}

/// The plan's bone nodes the mesher should release for undermined vertex
/// flags: each flagged vertex's, and each edge's between two flagged ones.
std::vector<int> releasedFor(const PlanPrediction& p, const std::vector<bool>& flagged)
{
  std::vector<int> nodes;
  for (std::size_t v = 0; v < flagged.size(); ++v)
    if (flagged[v])
      nodes.push_back(p.continuum.vertexColumns[v].back());
  for (std::size_t e = 0; e < p.continuum.edges.size(); ++e)
    if (flagged[std::size_t(p.continuum.edges[e][0])] && flagged[std::size_t(p.continuum.edges[e][1])])
      nodes.push_back(p.continuum.edgeColumns[e].back());
  std::sort(nodes.begin(), nodes.end());
  return nodes;
}

/// Surface vertices inside any of the plan's regions, by winding number;
/// fails when a vertex lies too near a border to say.
std::vector<bool> insideByWinding(const IncisionPlan& plan, const PlanPrediction& p)
{
  std::vector<bool> inside(p.surface.mesh.vertices.size(), false);
  for (const auto& region : plan.underminedRegions())
  {
    const std::vector<ChartPoint> polygon = chartPolygon(plan, region);
    for (std::size_t v = 0; v < inside.size(); ++v)
    {
      const ChartPoint& x = p.surface.mesh.vertices[v];
      EXPECT_GT(distanceToBorder(polygon, x), 1e-6) << "vertex " << v << " on a region's border: move the region";
      inside[v] = inside[v] || windingNumber(polygon, x) != 0;
    }
  }
  return inside;
}

std::vector<bool> flagsOf(const std::vector<char>& flags)
{
  std::vector<bool> out;
  for (char f : flags)
    out.push_back(f != 0);
  return out;
}

IncisionPlan planWith(const std::vector<std::vector<ChartPoint>>& regions, double theta = 0.0)
{
  RecordedPlan recorded;
  recorded.apply(placeEllipse(theta), phantom().skin, library());
  for (const auto& r : regions)
    recorded.apply(UndermineRegion{regionFromChart(recorded.plan(), r)}, phantom().skin, library());
  return recorded.plan();
}

bool contains(const std::string& text, const std::string& part)
{
  return text.find(part) != std::string::npos;
}

} // namespace

TEST(UnderminingRegion, ReleasesExactlyTheBoneNodesOfTheVerticesInsideIt)
{
  const IncisionPlan plain = planWith({});
  const IncisionPlan plan = planWith({besideTheWound()});
  ASSERT_EQ(plan.underminedRegions().size(), 1u);
  const PlanPrediction none = simulatePlan(phantom().skin, phantom().bone, plain, options());
  const PlanPrediction p = simulatePlan(phantom().skin, phantom().bone, plan, options());

  // The same mesh and sutures: only the supports change.
  ASSERT_EQ(p.continuum.mesh.nodes, none.continuum.mesh.nodes);
  EXPECT_EQ(p.continuum.boneNodes, none.continuum.boneNodes);
  EXPECT_TRUE(none.continuum.underminedNodes.empty());

  const std::vector<bool> inside = insideByWinding(plan, p);
  const long count = std::count(inside.begin(), inside.end(), true);
  const std::vector<int> expected = releasedFor(p, inside);
  std::printf("[undermined region] %ld of %zu surface vertices inside, %zu of %zu bone nodes released\n", count,
              inside.size(), expected.size(), p.continuum.boneNodes.size());
  EXPECT_GT(count, 10); // a region a few elements across, not a trivial match
  EXPECT_EQ(flagsOf(p.underminedVertices), inside);
  EXPECT_EQ(flagsOf(underminedRegionVertices(p.surface.mesh, plan, plan.chart(phantom().skin))), inside);
  EXPECT_EQ(p.continuum.underminedNodes, expected);
  std::vector<int> stillFixed;
  std::set_difference(none.continuum.fixedNodes.begin(), none.continuum.fixedNodes.end(), expected.begin(),
                      expected.end(), std::back_inserter(stillFixed));
  EXPECT_EQ(p.continuum.fixedNodes, stillFixed);
  std::printf("[undermined region] wound %.3g mm wide, %.3g mm after closure (%.3g without the region)\n",
              p.maxSutureGapBefore, p.maxSutureGap, none.maxSutureGap);
  EXPECT_LT(p.maxSutureGap, 1e-9);
  // The freed skin slides over the bone.
  double slide = 0.0;
  for (int node : p.continuum.underminedNodes)
    slide = std::max(slide, p.displacements.segment<3>(3 * node).norm());
  EXPECT_GT(slide, 1e-3);
}

TEST(UnderminingRegion, RegionsAndTheBandAddUp)
{
  // Two overlapping regions, one reaching into the band along the wound.
  const std::vector<ChartPoint> second = {{3.3, -15.1}, {14.7, -14.9}, {14.9, -3.1}, {9.1, -2.3}};
  const std::vector<ChartPoint> overlapping = {{10.2, -17.3}, {18.7, -16.9}, {18.1, -9.7}};
  const IncisionPlan regions = planWith({besideTheWound(), second, overlapping});
  const double width = 3.0;
  const PlanPrediction band = simulatePlan(phantom().skin, phantom().bone, planWith({}), options(width));
  const PlanPrediction both = simulatePlan(phantom().skin, phantom().bone, regions, options(width));
  ASSERT_EQ(both.continuum.mesh.nodes, band.continuum.mesh.nodes);

  const std::vector<bool> inside = insideByWinding(regions, both);
  std::vector<bool> expected(inside.size());
  long inBand = 0, inRegions = 0, inBoth = 0;
  for (std::size_t v = 0; v < inside.size(); ++v)
  {
    expected[v] = inside[v] || band.underminedVertices[v] != 0;
    inBand += band.underminedVertices[v] != 0;
    inRegions += inside[v];
    inBoth += inside[v] && band.underminedVertices[v] != 0;
  }
  std::printf("[undermined union] band %ld vertices, regions %ld, both %ld, union %ld\n", inBand, inRegions, inBoth,
              long(std::count(expected.begin(), expected.end(), true)));
  EXPECT_GT(inBoth, 0);         // they overlap: the union is not a sum
  EXPECT_GT(inRegions, inBoth); // and the regions reach beyond the band
  EXPECT_EQ(flagsOf(both.underminedVertices), expected);
  EXPECT_EQ(both.continuum.underminedNodes, releasedFor(both, expected));
  EXPECT_GT(both.continuum.underminedNodes.size(), band.continuum.underminedNodes.size());
}

TEST(UnderminingRegion, ARegionAcrossTheSeamIsOneRegion)
{
  // The plan at the back of the head: θ = ±π runs 1.6 mm right of its centre.
  const double theta = pi - 0.02;
  const std::vector<ChartPoint> across = {{-6.13, 5.29}, {9.71, 5.13}, {8.87, 12.61}, {-5.33, 11.93}};
  const IncisionPlan plan = planWith({across}, theta);
  const UnderminedRegion& stored = plan.underminedRegions().front();
  // Stored on both sides of the seam: θn near +1 and near -1.
  EXPECT_GT(std::max_element(stored.begin(), stored.end(), [](auto& a, auto& b) { return a.x() < b.x(); })->x(), 0.95);
  EXPECT_LT(std::min_element(stored.begin(), stored.end(), [](auto& a, auto& b) { return a.x() < b.x(); })->x(), -0.95);

  const PlanPrediction p = simulatePlan(phantom().skin, phantom().bone, plan, options());
  const std::vector<bool> inside = insideByWinding(plan, p);
  long count = 0, rightOfSeam = 0;
  for (std::size_t v = 0; v < inside.size(); ++v)
    if (inside[v])
    {
      ++count;
      rightOfSeam += p.surface.mesh.vertices[v].x() > 0.02 * 80.0;
    }
  std::printf("[undermined across the seam] %ld vertices inside, %ld beyond θ = π\n", count, rightOfSeam);
  EXPECT_GT(rightOfSeam, 5);
  EXPECT_GT(count - rightOfSeam, 5);
  EXPECT_EQ(flagsOf(p.underminedVertices), inside);
  EXPECT_EQ(p.continuum.underminedNodes, releasedFor(p, inside));
}

TEST(UnderminingRegion, AFarRegionEasesTheClosureLessThanOneBesideTheWound)
{
  // The same 10 × 6 mm rectangle beside the wound and out at the rim.
  auto rectangle = [](double u, double v) {
    return std::vector<ChartPoint>{
      {u - 5.03, v - 3.07}, {u + 5.01, v - 3.03}, {u + 4.97, v + 2.93}, {u - 4.99, v + 3.01}};
  };
  const PlanPrediction none = simulatePlan(phantom().skin, phantom().bone, planWith({}), options());
  // Out at the rim: where the mesh ends along u beside the wound.
  double rim = 0.0;
  for (const ChartPoint& x : none.surface.mesh.vertices)
    if (std::abs(x.y() - 7.6) < 3.0)
      rim = std::max(rim, x.x());
  const PlanPrediction near = simulatePlan(phantom().skin, phantom().bone, planWith({rectangle(0.0, 7.6)}), options());
  const PlanPrediction far =
    simulatePlan(phantom().skin, phantom().bone, planWith({rectangle(rim - 4.0, 7.6)}), options());
  const double f0 = none.closure.magnitudeSum, fNear = near.closure.magnitudeSum, fFar = far.closure.magnitudeSum;
  std::printf("[undermined region] closure force %.6g N; a region beside the wound %.6g N (%zu bone nodes "
              "released), the same at the rim (u = %.3g mm) %.6g N (%zu released)\n",
              f0, fNear, near.continuum.underminedNodes.size(), rim - 4.0, fFar, far.continuum.underminedNodes.size());
  ASSERT_FALSE(near.continuum.underminedNodes.empty());
  ASSERT_FALSE(far.continuum.underminedNodes.empty());
  EXPECT_LT(fNear, f0);
  EXPECT_LE(fFar, f0 * (1 + 1e-9));
  EXPECT_LT(f0 - fFar, 0.2 * (f0 - fNear));
  // Displacements at the wound's skin hardly notice the far region.
  double change = 0.0, largest = 0.0;
  for (int v = 0; v < none.skin.holeVertexCount; ++v)
  {
    const int node = none.skin.nodes[std::size_t(v)];
    change =
      std::max(change, (far.displacements.segment<3>(3 * node) - none.displacements.segment<3>(3 * node)).norm());
    largest = std::max(largest, none.displacements.segment<3>(3 * node).norm());
  }
  std::printf("[undermined region] at the wound the far region moves the skin by %.3g mm of %.3g mm\n", change,
              largest);
  EXPECT_LT(change, 0.02 * largest);
}

TEST(UnderminingRegion, BadRegionsAreRefusedAndThePlanKeptAsItWas)
{
  RecordedPlan recorded(std::string(64, 'b'));
  recorded.apply(placeEllipse(), phantom().skin, library());
  recorded.apply(UndermineRegion{regionFromChart(recorded.plan(), besideTheWound())}, phantom().skin, library());
  const IncisionPlan before = recorded.plan();
  const std::string recipeBefore = recipeToJson(recorded.recipe()).dump();

  auto refused = [&](const UnderminedRegion& region, const std::string& expected) {
    try
    {
      recorded.apply(UndermineRegion{region}, phantom().skin, library());
      ADD_FAILURE() << "accepted a region that should say: " << expected;
    }
    catch (const RecipeError& e)
    {
      std::printf("[refused] %s\n", e.what());
      EXPECT_EQ(e.operation(), 3);
      EXPECT_TRUE(
        contains(e.what(), "operation 3 (undermine a region of " + std::to_string(region.size()) + " points): "))
        << e.what();
      EXPECT_TRUE(contains(e.what(), expected)) << e.what();
    }
    EXPECT_EQ(recorded.plan().underminedRegions(), before.underminedRegions());
    EXPECT_EQ(recorded.plan().cutPath(), before.cutPath());
    EXPECT_EQ(recipeToJson(recorded.recipe()).dump(), recipeBefore);
  };
  const IncisionPlan& plan = before;
  refused(regionFromChart(plan, {{0, 6}, {5, 6}}), "at least 3 points on the skin; this one has 2");
  refused({}, "at least 3 points on the skin; this one has 0");
  // A bow tie: edges 0 and 2 cross.
  refused(regionFromChart(plan, {{0, 6}, {6, 12}, {6.5, 6.2}, {0.3, 12.5}}),
          "edge 0 (points 0–1) and edge 2 (points 2–3) of the region cross or touch");
  // A point beyond the scanned z range (-100 to 100 mm) and a point that is not a number.
  UnderminedRegion off = regionFromChart(plan, {{0, 6}, {5, 6}, {5, 10}});
  off[2].y() = 1.02;
  refused(off, "point 2 of the region");
  refused(off, "is outside the scanned region (z from -100 to 100 mm)");
  off[2].y() = std::nan("");
  refused(off, "point 2 of the region is not a number");
  // Points on one line: no area; a repeated point; a border folding back
  // along itself touches an edge that is not its neighbour.
  refused(regionFromChart(plan, {{0, 6}, {3, 7.5}, {6, 9}}), "the region has no area");
  refused(regionFromChart(plan, {{0, 6}, {5, 6}, {5, 6}, {5, 10}}),
          "points 1 and 2 of the region are at the same place");
  refused(regionFromChart(plan, {{0, 6}, {6, 6}, {3, 6}, {3, 10}}), "of the region cross or touch");
  // Round the head: three steps of 0.7π, 0.7π and 0.6π, each the short way.
  refused({{-0.9, 0.1}, {-0.2, 0.1}, {0.5, 0.15}}, "goes all the way round the head");

  // A hole in the skin map under a point.
  seg::RangeMap holed = phantom().skin;
  const SkinChart chart = plan.chart(phantom().skin);
  const SkinPoint at = chart.fromChart({3.0, 8.0});
  holed.at(int(std::lround(holed.frame().thetaToIndex(at.theta))), int(std::lround(holed.frame().zToIndex(at.z)))) =
    std::nanf("");
  try
  {
    applyOperation(plan, UndermineRegion{regionFromChart(plan, {{0, 6}, {6, 6}, {3, 8}})}, 3, holed, library());
    ADD_FAILURE() << "a region over a hole in the skin map was accepted";
  }
  catch (const RecipeError& e)
  {
    std::printf("[refused] %s\n", e.what());
    EXPECT_TRUE(contains(e.what(), "the skin map has no surface under point 2 of the region")) << e.what();
  }

  // Nothing to undermine before there is a plan.
  EXPECT_THROW(
    applyOperation(IncisionPlan(), UndermineRegion{before.underminedRegions().front()}, 1, phantom().skin, library()),
    RecipeError);
  // What was refused left nothing behind; clearing works and is recorded.
  recorded.apply(ClearUndermining{}, phantom().skin, library());
  EXPECT_TRUE(recorded.plan().underminedRegions().empty());
  EXPECT_EQ(describe(recorded.recipe().operations.back()), "clear undermining");
}

TEST(UnderminingRegion, TheDisplayIsOneOverTheRegionAndZeroAwayFromIt)
{
  const IncisionPlan plan = planWith({besideTheWound()});
  const PlanPrediction p = simulatePlan(phantom().skin, phantom().bone, plan, options());
  const PlanDisplay d = buildPlanDisplay(p, phantom().skin);
  ASSERT_EQ(d.undermined.size(), std::size_t(d.surface.vertexCount()));

  // A display vertex lies on the skin face of one element, over one polygon
  // of the surface mesh: 1 when the region holds every corner of that
  // polygon, 0 when it holds none (the face's nodes then all carry 0), a
  // ramp between. Winding numbers again.
  const std::vector<ChartPoint> polygon = chartPolygon(plan, plan.underminedRegions().front());
  std::vector<bool> vertexInside(p.surface.mesh.vertices.size());
  for (std::size_t v = 0; v < vertexInside.size(); ++v)
    vertexInside[v] = windingNumber(polygon, p.surface.mesh.vertices[v]) != 0;
  int inside = 0, outside = 0, ramp = 0;
  const SkinChart chart = plan.chart(phantom().skin);
  const seg::CylindricalFrame& frame = phantom().skin.frame();
  double farthestTinted = 0.0; // from the region, outside it
  for (Eigen::Index v = 0; v < d.surface.vertexCount(); ++v)
  {
    const double u = d.undermined[std::size_t(v)];
    ASSERT_GE(u, 0.0);
    ASSERT_LE(u, 1.0);
    const auto& corners =
      p.surface.mesh
        .polygons[std::size_t(p.continuum.elementPolygon[std::size_t(d.surface.bodyPoints()[std::size_t(v)].element)])];
    const long in = std::count_if(corners.begin(), corners.end(), [&](int c) { return vertexInside[std::size_t(c)]; });
    if (in == long(corners.size()))
    {
      ++inside;
      EXPECT_NEAR(u, 1.0, 1e-12) << "vertex " << v;
    }
    else if (in == 0)
    {
      ++outside;
      EXPECT_EQ(u, 0.0) << "vertex " << v;
    }
    else
      ramp += u > 0.0 && u < 1.0;
    if (u > 0.0)
    {
      const seg::CylindricalPoint c = frame.toCylindrical(d.surface.undeformedPositions().col(v));
      const ChartPoint x = chart.toChart({c.theta, c.z});
      if (windingNumber(polygon, x) == 0)
        farthestTinted = std::max(farthestTinted, distanceToBorder(polygon, x));
    }
  }
  std::printf("[undermined display] %d display vertices over polygons inside the region, %d outside, %d on the ramp; "
              "tinted at most %.3g mm outside the region\n",
              inside, outside, ramp, farthestTinted);
  EXPECT_GT(inside, 50);
  EXPECT_GT(outside, 1000);
  EXPECT_GT(ramp, 0);
  EXPECT_LT(farthestTinted, 6.0); // the elements beside the wound are 2–4 mm

  // In the polydata: the array, and the colour tinted blue over the region only.
  vtkSmartPointer<vtkPolyData> poly = planDisplayPolyData(d, 1.0);
  vtkDataArray* undermined = poly->GetPointData()->GetArray("undermined");
  vtkDataArray* colour = poly->GetPointData()->GetArray("skin_colour");
  vtkDataArray* shade = poly->GetPointData()->GetArray("skin_shade");
  ASSERT_NE(undermined, nullptr);
  ASSERT_NE(colour, nullptr);
  ASSERT_NE(shade, nullptr);
  EXPECT_STREQ(poly->GetPointData()->GetScalars()->GetName(), "skin_colour");
  int tinted = 0;
  for (vtkIdType v = 0; v < poly->GetNumberOfPoints(); ++v)
  {
    EXPECT_EQ(undermined->GetComponent(v, 0), d.undermined[std::size_t(v)]);
    if (d.undermined[std::size_t(v)] == 0.0)
      for (int k = 0; k < 3; ++k)
        EXPECT_EQ(colour->GetComponent(v, k), shade->GetComponent(v, k));
    else if (d.undermined[std::size_t(v)] == 1.0)
    {
      // Grey skin (no colour map) pulled towards the blue tint.
      EXPECT_GT(colour->GetComponent(v, 2), shade->GetComponent(v, 2));
      EXPECT_LT(colour->GetComponent(v, 0), shade->GetComponent(v, 0));
      ++tinted;
    }
  }
  EXPECT_GT(tinted, 50);
}

} // namespace caps::planning
