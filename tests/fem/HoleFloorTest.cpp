// The floor of an incision's hole (fem/HoleFloor): touching twins merged,
// the enclosed area triangulated with the loop's own vertices. Checked
// against the shoelace area of the loop, Euler's count (a simple polygon of
// n vertices has n - 2 triangles), the loop's edges each used once and the
// Delaunay empty-circle property, which is computed here independently.

#include "fem/HoleFloor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <stdexcept>
#include <utility>

namespace caps::fem {
namespace {

double signedArea(const ChartPoint& a, const ChartPoint& b, const ChartPoint& c)
{
  return 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
}

double shoelace(const std::vector<ChartPoint>& loop)
{
  double sum = 0.0;
  for (std::size_t i = 0; i < loop.size(); ++i)
    sum += loop[i].x() * loop[(i + 1) % loop.size()].y() - loop[i].y() * loop[(i + 1) % loop.size()].x();
  return 0.5 * sum;
}

SurfaceMesh holeOnly(const std::vector<ChartPoint>& loop)
{
  SurfaceMesh m;
  m.vertices = loop;
  m.holeVertexCount = int(loop.size());
  return m;
}

struct FloorCheck
{
  double area = 0.0;
  double smallestArea = INFINITY;
  int interiorEdges = 0;
};

/// Area and orientation of the triangles; every directed edge used once;
/// interior edges met from both sides are locally Delaunay (the opposite
/// vertex is not inside the circumcircle, computed from its centre).
FloorCheck checkFloor(const SurfaceMesh& m, const HoleFloor& floor)
{
  FloorCheck out;
  std::map<std::pair<int, int>, int> directed;
  for (std::size_t t = 0; t < floor.triangles.size(); ++t)
  {
    const auto& tri = floor.triangles[t];
    const double a =
      signedArea(m.vertices[std::size_t(tri[0])], m.vertices[std::size_t(tri[1])], m.vertices[std::size_t(tri[2])]);
    EXPECT_GT(a, 0.0) << "triangle " << t << " is not counter-clockwise";
    out.area += a;
    out.smallestArea = std::min(out.smallestArea, a);
    for (int k = 0; k < 3; ++k)
    {
      const std::pair<int, int> e{tri[std::size_t(k)], tri[std::size_t((k + 1) % 3)]};
      EXPECT_EQ(directed.count(e), 0u) << "edge used twice in one direction";
      directed[e] = tri[std::size_t((k + 2) % 3)];
    }
  }
  for (const auto& [e, opposite] : directed)
  {
    const auto back = directed.find({e.second, e.first});
    if (back == directed.end() || e.first > e.second)
      continue;
    ++out.interiorEdges;
    // Circumcentre of (a, b, c) by the perpendicular bisectors.
    const ChartPoint a = m.vertices[std::size_t(e.first)], b = m.vertices[std::size_t(e.second)],
                     c = m.vertices[std::size_t(opposite)], d = m.vertices[std::size_t(back->second)];
    const double den = 2.0 * (a.x() * (b.y() - c.y()) + b.x() * (c.y() - a.y()) + c.x() * (a.y() - b.y()));
    const ChartPoint centre(
      (a.squaredNorm() * (b.y() - c.y()) + b.squaredNorm() * (c.y() - a.y()) + c.squaredNorm() * (a.y() - b.y())) / den,
      (a.squaredNorm() * (c.x() - b.x()) + b.squaredNorm() * (a.x() - c.x()) + c.squaredNorm() * (b.x() - a.x())) /
        den);
    const double radius = (a - centre).norm();
    EXPECT_GE((d - centre).norm(), radius * (1.0 - 1e-9))
      << "edge (" << e.first << ", " << e.second << ") is not Delaunay";
  }
  return out;
}

TEST(HoleFloorTest, ASlitHasTwinsAndNoFloor)
{
  // Cut path (-10,0) (0,0) (10,0): loop 0, 1, 2, 1' with 1' on 1.
  const SurfaceMesh m = holeOnly({{-10, 0}, {0, 0}, {10, 0}, {0, 0}});
  const HoleFloor floor = holeFloor(m);
  EXPECT_EQ(floor.representative, (std::vector<int>{0, 1, 2, 1}));
  EXPECT_TRUE(floor.triangles.empty());
}

TEST(HoleFloorTest, AnEllipseIsCoveredByNMinusTwoTriangles)
{
  // A lens (excision, §4.4.4) of 2 * 15 + 2 loop vertices, clockwise like a hole loop.
  std::vector<ChartPoint> loop;
  const int inner = 15;
  loop.push_back({-20, 0});
  for (int i = 1; i <= inner; ++i)
  {
    const double u = -20.0 + 40.0 * i / (inner + 1);
    loop.push_back({u, 4.0 * std::sqrt(1.0 - u * u / 400.0)});
  }
  loop.push_back({20, 0});
  for (int i = inner; i >= 1; --i)
    loop.push_back({loop[std::size_t(i)].x(), -loop[std::size_t(i)].y()});
  const SurfaceMesh m = holeOnly(loop);
  const HoleFloor floor = holeFloor(m);
  ASSERT_EQ(floor.triangles.size(), loop.size() - 2);
  const FloorCheck check = checkFloor(m, floor);
  EXPECT_NEAR(check.area, std::abs(shoelace(loop)), 1e-12 * std::abs(shoelace(loop)));
  EXPECT_EQ(check.interiorEdges, int(loop.size()) - 3);
}

TEST(HoleFloorTest, ABoxWithPointsAlongItsSidesKeepsThemAll)
{
  // A 12 x 6 mm box excision refined every 1 mm: 32 loop vertices, 28 of
  // them collinear with their neighbours.
  std::vector<ChartPoint> loop;
  for (int i = 0; i < 12; ++i)
    loop.push_back({-6.0 + i, 3.0});
  for (int i = 0; i < 6; ++i)
    loop.push_back({6.0, 3.0 - i});
  for (int i = 0; i < 12; ++i)
    loop.push_back({6.0 - i, -3.0});
  for (int i = 0; i < 6; ++i)
    loop.push_back({-6.0, -3.0 + i});
  const SurfaceMesh m = holeOnly(loop);
  const HoleFloor floor = holeFloor(m);
  ASSERT_EQ(floor.triangles.size(), loop.size() - 2);
  const FloorCheck check = checkFloor(m, floor);
  EXPECT_NEAR(check.area, 72.0, 1e-12);
  EXPECT_GT(check.smallestArea, 0.1); // no sliver along the straight sides
}

TEST(HoleFloorTest, TouchingTwinsSplitTheHoleIntoTwoParts)
{
  // Path (-20,0) (-10,0) (0,0) (10,0) (20,0); the twins of -10 and 10 are
  // offset ±3 mm, those of 0 are not: two lenses meeting at (0, 0).
  const std::vector<ChartPoint> loop = {{-20, 0}, {-10, 3}, {0, 0}, {10, 3}, {20, 0}, {10, -3}, {0, 0}, {-10, -3}};
  const SurfaceMesh m = holeOnly(loop);
  const HoleFloor floor = holeFloor(m);
  EXPECT_EQ(floor.representative, (std::vector<int>{0, 1, 2, 3, 4, 5, 2, 7}));
  ASSERT_EQ(floor.triangles.size(), 4u); // two quadrilaterals
  const FloorCheck check = checkFloor(m, floor);
  EXPECT_NEAR(check.area, 2.0 * 60.0, 1e-12); // each a rhombus of diagonals 20 and 6
  for (const auto& t : floor.triangles)
    for (int v : t)
      EXPECT_NE(v, 6) << "the twin of a touching point is replaced by its representative";
}

TEST(HoleFloorTest, RandomStarShapedHolesAreTriangulatedExactly)
{
  std::mt19937 random(7);
  std::uniform_real_distribution<double> radius(3.0, 12.0);
  for (int trial = 0; trial < 20; ++trial)
  {
    const int n = 5 + trial * 3;
    std::vector<ChartPoint> loop;
    for (int i = 0; i < n; ++i)
    {
      const double angle = -2.0 * std::numbers::pi * i / n; // clockwise, as a hole loop runs
      const double r = radius(random);
      loop.push_back({r * std::cos(angle), r * std::sin(angle)});
    }
    const SurfaceMesh m = holeOnly(loop);
    const HoleFloor floor = holeFloor(m);
    ASSERT_EQ(floor.triangles.size(), std::size_t(n - 2)) << "trial " << trial;
    const FloorCheck check = checkFloor(m, floor);
    EXPECT_NEAR(check.area, std::abs(shoelace(loop)), 1e-11 * std::abs(shoelace(loop))) << "trial " << trial;
  }
}

TEST(HoleFloorTest, ALoopCrossingItselfIsRefused)
{
  // A bow tie: the hole loop crosses itself.
  const SurfaceMesh m = holeOnly({{0, 0}, {10, 10}, {10, 0}, {0, 10}, {-5, 5}});
  EXPECT_THROW(holeFloor(m), std::invalid_argument);
}

} // namespace
} // namespace caps::fem
