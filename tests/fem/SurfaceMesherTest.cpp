// Surface mesher (thesis §4.5.1): cuts, excisions and Z-plasties meshed with
// triangles and quadrilaterals, checked against areas, counts and angles
// worked out by hand, plus hundreds of random cuts and the bad inputs a
// surgeon can draw.

#include "fem/SurfaceMesher.h"

#include <sstream>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <random>

using namespace caps::fem;

namespace {

constexpr double kPi = std::numbers::pi;
double rad(double degrees)
{
  return degrees * kPi / 180.0;
}
double deg(double radians)
{
  return radians * 180.0 / kPi;
}
bool contains(const std::string& text, const std::string& part)
{
  return text.find(part) != std::string::npos;
}

void report(const char* name, const SurfaceMesherResult& r)
{
  const SurfaceMeshQuality& q = r.quality;
  std::printf("[%s] %d vertices, %d triangles (%d from stage 1), %d quads, %d/%d layers, reach %.2f mm, "
              "angles %.1f..%.1f deg, max aspect %.2f, area %.2f mm2%s%s\n",
              name, q.vertexCount, q.triangleCount, r.stageOneTriangles, q.quadCount, r.layersBuilt, r.layersPlanned,
              r.reach, deg(q.minAngle), deg(q.maxAngle), q.maxAspectRatio, q.meshArea, r.message.empty() ? "" : "; ",
              r.message.c_str());
  ::testing::Test::RecordProperty(std::string(name) + "_minAngleDeg", std::to_string(deg(q.minAngle)));
  ::testing::Test::RecordProperty(std::string(name) + "_maxAspect", std::to_string(q.maxAspectRatio));
}

std::string problems(const SurfaceMeshQuality& q)
{
  std::string text;
  for (const auto& p : q.problems)
    text += p + "\n";
  return text;
}

/// Distance from p to the polygon through @a loop (closed).
double distanceToLoop(const ChartPoint& p, const std::vector<ChartPoint>& loop)
{
  double best = 1e300;
  for (std::size_t i = 0; i < loop.size(); ++i)
  {
    const ChartPoint a = loop[i], b = loop[(i + 1) % loop.size()], ab = b - a;
    const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * ab - p).norm());
  }
  return best;
}

/// Interior angle of triangle corner @a k.
double cornerAngle(const SurfaceMesh& mesh, const std::vector<int>& polygon, std::size_t k)
{
  const std::size_t n = polygon.size();
  const ChartPoint p = mesh.vertices[polygon[k]];
  const ChartPoint a = mesh.vertices[polygon[(k + 1) % n]] - p, b = mesh.vertices[polygon[(k + n - 1) % n]] - p;
  return std::acos(a.dot(b) / (a.norm() * b.norm()));
}

} // namespace

TEST(SurfaceMesher, HoleLoopFromCutPathFollowsFigure411)
{
  const std::vector<ChartPoint> path = {{0, 0}, {5, 0}, {10, 2}, {15, 2}};
  const HoleLoop hole = holeLoopFromCutPath(path);
  // p0 p1 p2 p3 p2' p1'
  ASSERT_EQ(hole.points.size(), 6u);
  EXPECT_EQ(hole.pathIndex, (std::vector<int>{0, 1, 2, 3, 2, 1}));
  EXPECT_EQ(hole.points[4], path[2]);
  EXPECT_EQ(hole.points[5], path[1]);
  EXPECT_EQ(holeLoopFromCutPath({{0, 0}, {5, 0}}).points.size(), 2u);
  EXPECT_THROW(holeLoopFromCutPath({{0, 0}}), std::invalid_argument);

  const RefinedCutPath refined = refineCutPath({{0, 0}, {10, 0}, {10, 3}}, 4.0);
  // 10 mm -> 3 parts, 3 mm -> 1 part.
  ASSERT_EQ(refined.points.size(), 5u);
  EXPECT_EQ(refined.originalIndex, (std::vector<int>{0, 3, 4}));
  EXPECT_NEAR(refined.points[1].x(), 10.0 / 3, 1e-12);
}

// A straight cut 20 mm long, 5 points: a zero-area slit. Both ends turn by
// 180° and get two corner squares each; every later layer mitres the 90°
// corners, so each rim is a rectangle round the cut.
TEST(SurfaceMesher, StraightCutGivesRectangularLayers)
{
  std::vector<ChartPoint> path;
  for (int i = 0; i < 5; ++i)
    path.push_back({5.0 * i, 0});
  SurfaceMesherOptions options;
  options.firstLayerThickness = 2.0;
  options.layerGrowth = 1.25;
  options.layerCount = 3;
  const SurfaceMesherResult r = meshAroundHole(holeLoopFromCutPath(path), options);
  report("slit", r);
  ASSERT_TRUE(r.quality.valid()) << problems(r.quality);
  EXPECT_FALSE(r.stoppedEarly);
  EXPECT_EQ(r.layersBuilt, 3);
  EXPECT_EQ(r.stageOneTriangles, 0);
  EXPECT_EQ(r.quality.triangleCount, 0);
  // Layer 1: 8 edge quads + 2 x 2 corner quads; the border then has 16
  // vertices and each later layer one quad per border edge.
  EXPECT_EQ(r.quality.quadCount, 12 + 16 + 16);
  const double reach = 2.0 * (1 + 1.25 + 1.25 * 1.25);
  EXPECT_NEAR(r.reach, reach, 1e-12);
  const double area = (20 + 2 * reach) * (2 * reach);
  EXPECT_NEAR(r.quality.outerArea, area, 1e-9);
  EXPECT_NEAR(r.quality.meshArea, area, 1e-9);
  EXPECT_NEAR(r.quality.holeArea, 0.0, 1e-12);
  // Squares and 45°/135° mitred corner quads.
  EXPECT_NEAR(deg(r.quality.minAngle), 45.0, 1e-9);
  EXPECT_NEAR(deg(r.quality.maxAngle), 135.0, 1e-9);
  EXPECT_EQ(r.mesh.holeVertexCount, 8);
  for (int i = 0; i < 8; ++i)
    EXPECT_EQ(r.mesh.vertices[i], holeLoopFromCutPath(path).points[i]);
  EXPECT_EQ(r.mesh.outerBorder.size(), 16u);
}

TEST(SurfaceMesher, TwoPointCut)
{
  SurfaceMesherOptions options;
  options.layerCount = 1;
  options.firstLayerThickness = 4.0;
  const SurfaceMesherResult r = meshAroundHole(holeLoopFromCutPath({{0, 0}, {10, 0}}), options);
  report("two-point cut", r);
  ASSERT_TRUE(r.quality.valid()) << problems(r.quality);
  EXPECT_EQ(r.quality.quadCount, 2 + 2 * 2);
  EXPECT_NEAR(r.quality.meshArea, 18.0 * 8.0, 1e-9);
}

// Elliptical excision: a 30 mm cut whose two sides are opened into a lens of
// half-width 4 mm (§4.4.4), meshed out to 20 mm.
TEST(SurfaceMesher, EllipticalExcision)
{
  const int n = 11;
  const double a = 15, b = 4;
  std::vector<ChartPoint> path;
  for (int i = 0; i < n; ++i)
    path.push_back({-a + 2 * a * i / (n - 1), 0});
  HoleLoop hole = holeLoopFromCutPath(path);
  auto width = [&](double u) { return b * std::sqrt(std::max(0.0, 1 - (u / a) * (u / a))); };
  // Left of the cut (+v) for the first copies, right (-v) for the twins.
  for (int i = 1; i < n - 1; ++i)
    hole.points[i].y() += width(hole.points[i].x());
  for (std::size_t i = n; i < hole.points.size(); ++i)
    hole.points[i].y() -= width(hole.points[i].x());
  // Independent hole area: trapezoids of the full width 2 w(u).
  double holeArea = 0;
  for (int i = 0; i + 1 < n; ++i)
    holeArea += (width(path[i].x()) + width(path[i + 1].x())) * (path[i + 1].x() - path[i].x());

  SurfaceMesherOptions options;
  options.regionRadius = 20;
  const SurfaceMesherResult r = meshAroundHole(hole, options);
  report("excision", r);
  ASSERT_TRUE(r.quality.valid()) << problems(r.quality);
  EXPECT_FALSE(r.stoppedEarly);
  EXPECT_EQ(r.stageOneTriangles, 0); // the lens is convex
  EXPECT_NEAR(r.quality.holeArea, holeArea, 1e-9);
  EXPECT_NEAR(r.quality.meshArea, r.quality.outerArea - holeArea, 1e-6);
  EXPECT_NEAR(r.reach, 20.0, 1e-9);
  // The rim lies about 20 mm from the hole: mitres and corner kites reach
  // further, merged or split points (chord midpoints) a little less far.
  for (int id : r.mesh.outerBorder)
  {
    const double d = distanceToLoop(r.mesh.vertices[id], hole.points);
    EXPECT_GT(d, 0.9 * 20);
    EXPECT_LT(d, 1.75 * 20);
  }
  EXPECT_GE(deg(r.quality.minAngle), 15.0);
}

// Z-plasty of Fig. 4.11/4.13: central limb (0,0)-(10,0), limbs of 10 mm at
// 60°. Stage 1 adds the two equilateral triangles in the 60° corners
// (Fig. 4.13's 1 and 2), leaving a rhombus; one stage-2 pass adds 4 edge
// quads and a corner quad at each 120° turn (3-8).
TEST(SurfaceMesher, ZPlastyFigure413)
{
  const double h = 10 * std::sqrt(3.0) / 2;
  const std::vector<ChartPoint> path = {{5, h}, {0, 0}, {10, 0}, {5, -h}};
  SurfaceMesherOptions options;
  options.layerCount = 1;
  options.firstLayerThickness = 3.0;
  const SurfaceMesherResult r = meshAroundHole(holeLoopFromCutPath(path), options);
  report("z-plasty 1 layer", r);
  ASSERT_TRUE(r.quality.valid()) << problems(r.quality);
  EXPECT_EQ(r.stageOneTriangles, 2);
  EXPECT_EQ(r.quality.triangleCount, 2);
  EXPECT_EQ(r.quality.quadCount, 6);
  for (const auto& polygon : r.mesh.polygons)
    if (polygon.size() == 3)
    {
      for (std::size_t k = 0; k < 3; ++k)
        EXPECT_NEAR(deg(cornerAngle(r.mesh, polygon, k)), 60.0, 1e-9);
    }
  // Offset of a convex polygon (area A, perimeter P) by l with mitred corners:
  // A + P l + l² Σ tan(turn/2); a corner kite has the mitre's area.
  const double l = 3, rhombus = 100 * std::sin(rad(60));
  const double expected = rhombus + 40 * l + l * l * 2 * (std::tan(rad(30)) + std::tan(rad(60)));
  EXPECT_NEAR(r.quality.outerArea, expected, 1e-9);
  EXPECT_NEAR(r.quality.meshArea, expected, 1e-9);

  options.layerCount = 4;
  options.firstLayerThickness = 0;
  options.regionRadius = 25;
  const SurfaceMesherResult wide = meshAroundHole(holeLoopFromCutPath(refineCutPath(path, 2.5).points), options);
  report("z-plasty 25 mm", wide);
  ASSERT_TRUE(wide.quality.valid()) << problems(wide.quality);
  EXPECT_FALSE(wide.stoppedEarly);
  // With 2.5 mm points each 60° corner is filled by a fan of triangles, the
  // same number in both (the Z is point-symmetric).
  EXPECT_GE(wide.stageOneTriangles, 2);
  EXPECT_EQ(wide.stageOneTriangles % 2, 0);
  EXPECT_NEAR(wide.reach, 25.0, 1e-9);
}

// A cut 4 mm below the top of the scanned range: layers flatten against the
// bound and keep growing elsewhere.
TEST(SurfaceMesher, StopsAtChartBound)
{
  std::vector<ChartPoint> path;
  for (int i = 0; i < 7; ++i)
    path.push_back({3.0 * i, 0.3 * std::sin(i)});
  SurfaceMesherOptions options;
  options.regionRadius = 15;
  options.vMax = 4.0;
  options.vMin = -6.0;
  const SurfaceMesherResult r = meshAroundHole(holeLoopFromCutPath(path), options);
  report("chart bound", r);
  ASSERT_TRUE(r.quality.valid()) << problems(r.quality);
  EXPECT_FALSE(r.stoppedEarly);
  EXPECT_TRUE(r.reachedChartBound);
  EXPECT_PRED2(contains, r.message, "scanned range");
  int onTop = 0, onBottom = 0;
  for (const ChartPoint& p : r.mesh.vertices)
  {
    EXPECT_LE(p.y(), 4.0);
    EXPECT_GE(p.y(), -6.0);
    onTop += p.y() == 4.0;
    onBottom += p.y() == -6.0;
  }
  EXPECT_GT(onTop, 2);
  EXPECT_GT(onBottom, 2);
  // Sideways the mesh still reaches 15 mm past the cut's ends.
  double uMin = 0, uMax = 0;
  for (const ChartPoint& p : r.mesh.vertices)
    uMin = std::min(uMin, p.x()), uMax = std::max(uMax, p.x());
  EXPECT_LE(uMin, -15.0 + 1e-9);
  EXPECT_GE(uMax, 18.0 + 15.0 - 1e-9);

  options.vMax = 0.5;
  try
  {
    meshAroundHole(holeLoopFromCutPath(path), options);
    FAIL() << "expected a refusal";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_PRED2(contains, e.what(), "top of the scanned range");
  }
}

TEST(SurfaceMesher, RefusesBadIncisions)
{
  auto message = [](const HoleLoop& hole) -> std::string {
    try
    {
      meshAroundHole(hole);
    }
    catch (const std::invalid_argument& e)
    {
      return e.what();
    }
    return "(accepted)";
  };
  // A path that crosses itself between points 0-1 and 3-4.
  EXPECT_PRED2(contains, message(holeLoopFromCutPath({{0, 0}, {10, 0}, {10, 5}, {5, 5}, {5, -5}})),
               "crosses itself near point 3");
  EXPECT_PRED2(contains, message(holeLoopFromCutPath({{0, 0}, {5, 0}, {5.1, 0}, {10, 0}})),
               "point 1 and point 2 are 0.1 mm apart: move them apart (at least 1.0 mm)");
  EXPECT_PRED2(contains, message(holeLoopFromCutPath({{0, 0}, {10, 0}, {0, 1}})), "turns back too sharply at point 1");
  EXPECT_PRED2(contains, message(holeLoopFromCutPath({{0, 0}, {10, 0}, {10, 5}, {0.5, 0.5}, {0.5, 10}})), "passes");
  HoleLoop wrongWay = holeLoopFromCutPath({{0, 0}, {5, 0}, {10, 0}});
  wrongWay.points[1].y() = -2; // the left copy moved to the right
  wrongWay.points[3].y() = 2;
  EXPECT_PRED2(contains, message(wrongWay), "wrong way");
  EXPECT_PRED2(contains, message(holeLoopFromCutPath({{0, 0}, {2, 0}, {40, 0}})), "unevenly spaced");
}

// The checker itself finds overlap, inversion and gaps.
TEST(SurfaceMesher, QualityCheckFindsBrokenMeshes)
{
  SurfaceMesh mesh;
  mesh.vertices = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {2, 0}, {2, 1}};
  mesh.holeVertexCount = 0;
  mesh.polygons = {{0, 1, 2, 3}, {1, 4, 5, 2}};
  mesh.outerBorder = {0, 1, 4, 5, 2, 3};
  EXPECT_TRUE(surfaceMeshQuality(mesh).valid()) << problems(surfaceMeshQuality(mesh));
  EXPECT_NEAR(surfaceMeshQuality(mesh).meshArea, 2.0, 1e-12);

  SurfaceMesh inverted = mesh;
  inverted.polygons[1] = {1, 2, 5, 4};
  EXPECT_FALSE(surfaceMeshQuality(inverted).valid());

  SurfaceMesh overlapping = mesh;
  overlapping.vertices[4] = {0.5, 0};
  overlapping.vertices[5] = {0.5, 1};
  EXPECT_FALSE(surfaceMeshQuality(overlapping).valid());

  SurfaceMesh gap = mesh;
  gap.polygons.pop_back();
  EXPECT_FALSE(surfaceMeshQuality(gap).valid());

  SurfaceMesh sliver = mesh;
  sliver.vertices[4] = {1.05, 0}; // a 0.05 x 1 strip: aspect ratio 20
  sliver.vertices[5] = {1.05, 1};
  EXPECT_FALSE(surfaceMeshQuality(sliver).valid());
}

// Hundreds of random cuts and excisions (seeded): every mesh valid, nothing
// inverted, overlapping or sliver, full coverage.
TEST(SurfaceMesher, RandomCutPaths)
{
  std::mt19937 random(20240611);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int meshed = 0, refused = 0, stopped = 0, triangles = 0, quads = 0;
  std::map<std::string, int> refusals;
  double minAngle = kPi, maxAspect = 0;
  for (int trial = 0; trial < 400; ++trial)
  {
    const int points = 2 + int(unit(random) * 6);
    std::vector<ChartPoint> path = {{0, 0}};
    double heading = 2 * kPi * unit(random);
    for (int i = 1; i < points; ++i)
    {
      if (i > 1)
        heading += rad(-120 + 240 * unit(random));
      const double length = 2.5 + 2.5 * unit(random);
      path.push_back(path.back() + length * ChartPoint(std::cos(heading), std::sin(heading)));
    }
    HoleLoop hole = holeLoopFromCutPath(path);
    const bool excision = unit(random) < 0.4;
    if (excision)
    {
      // Open the cut: first copies to the left, twins to the right.
      for (std::size_t k = 1; k + 1 < std::size_t(points); ++k)
      {
        const ChartPoint d = (path[k + 1] - path[k - 1]).normalized();
        const ChartPoint left(-d.y(), d.x());
        hole.points[k] += 1.5 * unit(random) * left;
        hole.points[hole.points.size() - k] -= 1.5 * unit(random) * left;
      }
    }
    SurfaceMesherOptions options;
    options.regionRadius = 15;
    SurfaceMesherResult r;
    try
    {
      r = meshAroundHole(hole, options);
    }
    catch (const std::invalid_argument& e)
    {
      ++refused; // self-crossing, too close, too sharp: the surgeon is told
      const std::string why = e.what();
      ++refusals[why.substr(0, why.find(" near") == std::string::npos ? 24 : why.find(" near"))];
      continue;
    }
    ++meshed;
    std::ostringstream loopText; // (a stream: GCC 12 warns falsely on "(" + std::string)
    for (const ChartPoint& p : hole.points)
      loopText << "(" << p.x() << ", " << p.y() << ") ";
    const std::string loop = loopText.str();
    ASSERT_TRUE(r.quality.valid()) << "trial " << trial << " " << loop << ":\n" << problems(r.quality);
    EXPECT_NEAR(r.quality.meshArea, r.quality.outerArea - r.quality.holeArea, 1e-6 * r.quality.outerArea);
    if (r.stoppedEarly)
      ++stopped, std::printf("trial %d: %s\n", trial, r.message.c_str());
    triangles += r.quality.triangleCount;
    quads += r.quality.quadCount;
    minAngle = std::min(minAngle, r.quality.minAngle);
    maxAspect = std::max(maxAspect, r.quality.maxAspectRatio);
  }
  std::printf("[random] %d meshed, %d refused, %d stopped early; %d triangles, %d quads; "
              "min angle %.1f deg, max aspect %.2f\n",
              meshed, refused, stopped, triangles, quads, deg(minAngle), maxAspect);
  for (const auto& [why, count] : refusals)
    std::printf("  refused %d x: %s...\n", count, why.c_str());
  RecordProperty("meshed", meshed);
  RecordProperty("stoppedEarly", stopped);
  EXPECT_GT(meshed, 250);
  EXPECT_LT(stopped, meshed / 20);
}

// Interactive editing moves one point a little at a time; each new position
// must mesh the whole region, not stop a few layers out (a region cut short
// changes the prediction far more than the move does: on the sample's
// cheek a Z-plasty's gain went from 61 % to 81 % for a 0.5 mm move before
// short border edges were merged away). Z-plasties of 30–90° with every
// cut point moved up to 1 mm at random, meshed out to 25 and 40 mm.
TEST(SurfaceMesher, MovedZPlastyPointsStillMeshTheWholeRegion)
{
  std::mt19937 random(20261123);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int meshed = 0, stopped = 0, refused = 0;
  double minAngle = kPi, maxAspect = 0;
  for (int trial = 0; trial < 120; ++trial)
  {
    const double angle = rad(30 + 60 * (trial % 5) / 4.0), limb = 20;
    const ChartPoint a(0, 0), b(0, -limb); // central limb along -v
    std::vector<ChartPoint> path = {a + limb * ChartPoint(std::sin(angle), -std::cos(angle)), a, b,
                                    b + limb * ChartPoint(-std::sin(angle), std::cos(angle))};
    for (auto& p : path)
      p += ChartPoint(unit(random), unit(random));
    SurfaceMesherOptions options;
    options.firstLayerThickness = 2.0;
    options.regionRadius = trial % 2 ? 40 : 25;
    options.minPointSpacing = 0.8;
    SurfaceMesherResult r;
    try
    {
      r = meshAroundHole(holeLoopFromCutPath(refineCutPath(path, 2.0).points), options);
    }
    catch (const std::invalid_argument& e)
    {
      ++refused; // a 30° corner pushed sharper: limbs closer than the point spacing
      std::printf("trial %d (%.0f deg) refused: %s\n", trial, deg(angle), e.what());
      continue;
    }
    ++meshed;
    ASSERT_TRUE(r.quality.valid()) << "trial " << trial << ":\n" << problems(r.quality);
    EXPECT_NEAR(r.quality.meshArea, r.quality.outerArea - r.quality.holeArea, 1e-6 * r.quality.outerArea);
    if (r.stoppedEarly)
      ++stopped, std::printf("trial %d (%.0f deg): %s\n", trial, deg(angle), r.message.c_str());
    minAngle = std::min(minAngle, r.quality.minAngle);
    maxAspect = std::max(maxAspect, r.quality.maxAspectRatio);
  }
  std::printf("[moved Z] %d meshed, %d refused, %d stopped early; min angle %.1f deg, max aspect %.2f\n", meshed,
              refused, stopped, deg(minAngle), maxAspect);
  EXPECT_LT(refused, 6);
  // Before short border edges were merged and bent quadrilaterals split, 5
  // of these stopped early (and the sample's cheek Z at 0.5 mm); 1 still does.
  EXPECT_LE(stopped, 2);
}
