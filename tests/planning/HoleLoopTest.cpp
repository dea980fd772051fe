// The hole loop of a cut (Fig. 4.11) and its sutures (§4.4.5), for the
// thesis's examples and for every shipped procedure.

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "AnalyticSkins.h"
#include "planning/IncisionPlan.h"

using namespace caps;
using namespace caps::planning;

namespace {

std::vector<SutureEdges> thesisSimpleExcision()
{
  return {{{0, 1}, {0, 5}}, {{1, 2}, {5, 4}}, {{2, 3}, {4, 3}}};
}
std::vector<SutureEdges> thesisZPlasty()
{
  return {{{5, 0}, {5, 4}}, {{2, 1}, {2, 3}}, {{0, 1}, {3, 4}}};
}

std::set<std::set<int>> asSets(const std::vector<std::vector<int>>& classes)
{
  std::set<std::set<int>> result;
  for (const auto& c : classes)
    result.insert(std::set<int>(c.begin(), c.end()));
  return result;
}

} // namespace

TEST(HoleLoop, CutPathBecomesFig411Loop)
{
  const std::vector<ChartPoint> path = {{0, 0}, {1, 0}, {2, 1}, {3, 1}};
  const fem::HoleLoop loop = makeHoleLoop(path);
  ASSERT_EQ(loop.points.size(), 6u); // ends once, inner points twice
  EXPECT_EQ(loop.pathIndex, (std::vector<int>{0, 1, 2, 3, 2, 1}));
  for (size_t v = 0; v < loop.points.size(); ++v)
    EXPECT_EQ(loop.points[v], path[loop.pathIndex[v]]);
  EXPECT_EQ(rightSideVertex(1, 4), 5);
  EXPECT_EQ(rightSideVertex(2, 4), 4);
  EXPECT_EQ(rightSideVertex(0, 4), 0);
  EXPECT_EQ(rightSideVertex(3, 4), 3);
  EXPECT_EQ(holeLoopSize(2), 2);
  EXPECT_EQ(makeHoleLoop({{0, 0}, {1, 0}}).pathIndex, (std::vector<int>{0, 1}));
  EXPECT_THROW(makeHoleLoop({{0, 0}}), std::invalid_argument);
}

TEST(HoleLoop, OffsetsOpenTheTwinsAndTheHoleRunsClockwise)
{
  IncisionPlan plan({{0.0, 0.0}, {0.01, 0.0}, {0.02, 0.0}, {0.03, 0.0}}, {0.0, 0.0});
  plan.offsetBorderPoint(1, {0.0, 2.0});  // left side of the cut, to its left
  plan.offsetBorderPoint(5, {0.0, -2.0}); // its twin to the right
  EXPECT_TRUE(plan.isExcision());
  EXPECT_THROW(plan.offsetBorderPoint(0, {0.0, 1.0}), std::invalid_argument); // an end has no twin
  EXPECT_THROW(plan.offsetBorderPoint(6, {0.0, 1.0}), std::out_of_range);
  const auto skin = test::cylinderSkin(80.0);
  const fem::HoleLoop loop = plan.holeLoop(plan.chart(skin));
  double twiceArea = 0.0;
  for (size_t e = 0; e < loop.points.size(); ++e)
  {
    const auto& p = loop.points[e];
    const auto& q = loop.points[(e + 1) % loop.points.size()];
    twiceArea += p.x() * q.y() - p.y() * q.x();
  }
  EXPECT_LT(twiceArea, 0.0); // clockwise, skin on the left: fem/SurfaceMesh.h
  EXPECT_NO_THROW(checkPlan(plan, skin));
  plan.offsetBorderPoint(1, {0.0, -2.0});
  plan.offsetBorderPoint(5, {0.0, 2.0});
  EXPECT_THROW(checkPlan(plan, skin), std::invalid_argument); // sides swapped
}

TEST(Sutures, ThesisSimpleExcisionIsKeptAsWritten)
{
  const auto resolved = resolveSutures(6, thesisSimpleExcision());
  ASSERT_EQ(resolved.size(), 3u);
  for (size_t k = 0; k < 3; ++k)
  {
    EXPECT_EQ(resolved[k].a, thesisSimpleExcision()[k].a);
    EXPECT_EQ(resolved[k].b, thesisSimpleExcision()[k].b);
  }
  // p1 meets p1', p2 meets p2'; the ends close corners (§4.4.5).
  EXPECT_EQ(asSets(sutureClasses(6, resolved)), (std::set<std::set<int>>{{0}, {1, 5}, {2, 4}, {3}}));
}

TEST(Sutures, ThesisZPlastyMeetsFaceToFace)
{
  const auto resolved = resolveSutures(6, thesisZPlasty());
  ASSERT_EQ(resolved.size(), 3u);
  EXPECT_EQ(resolved[0].a, (std::array<int, 2>{5, 0}));
  EXPECT_EQ(resolved[0].b, (std::array<int, 2>{5, 4})); // corner at p1': p2' onto p0
  EXPECT_EQ(resolved[1].a, (std::array<int, 2>{2, 1}));
  EXPECT_EQ(resolved[1].b, (std::array<int, 2>{2, 3})); // corner at p2: p1 onto p3
  EXPECT_EQ(resolved[2].a, (std::array<int, 2>{0, 1}));
  EXPECT_EQ(resolved[2].b, (std::array<int, 2>{4, 3})); // p0 onto p2', p1 onto p3
  EXPECT_EQ(asSets(sutureClasses(6, resolved)), (std::set<std::set<int>>{{0, 4}, {1, 3}, {2}, {5}}));
}

TEST(Sutures, InconsistentSetsAreRefusedNamingTheSuture)
{
  auto message = [](int loopSize, const std::vector<SutureEdges>& s) -> std::string {
    try
    {
      resolveSutures(loopSize, s);
    }
    catch (const SutureError& e)
    {
      return std::to_string(e.suture()) + " " + e.what();
    }
    return "accepted";
  };
  EXPECT_NE(message(6, {{{0, 1}, {0, 5}}, {{1, 3}, {5, 4}}}).find("1 suture 2"), std::string::npos);
  EXPECT_NE(message(6, {{{0, 1}, {0, 5}}, {{1, 3}, {5, 4}}}).find("not a border edge"), std::string::npos);
  EXPECT_NE(message(6, {{{0, 1}, {0, 5}}, {{2, 3}, {1, 0}}}).find("already sewn by suture 1"), std::string::npos);
  EXPECT_NE(message(6, {{{0, 1}, {1, 0}}}).find("sewn to itself"), std::string::npos);
  // Sewing (0,1) to (2,3) face to face pulls 1 onto 2: edge (1,2) would vanish.
  EXPECT_NE(message(6, {{{0, 1}, {2, 3}}}).find("both ends of border edge (1,2)"), std::string::npos);
  EXPECT_NE(message(6, {{{0, 1}, {6, 7}}}).find("border points 0..5"), std::string::npos);
}

TEST(Sutures, EveryShippedProcedureClosesConsistently)
{
  const auto& library = test::shippedProcedures();
  EXPECT_TRUE(library.errors().empty()) << library.errors().front();
  struct Expected
  {
    int points, pairs, corners;
  };
  const std::map<std::string, Expected> expected = {
    {"elliptical-excision", {9, 8, 2}},
    {"simple-excision", {4, 3, 2}},
    {"z-plasty", {4, 3, 2}},
    {"multiple-z-plasty-with-excision", {7, 6, 2}},
    {"rhomboid-flap", {5, 4, 2}},
    {"v-y-advancement", {7, 6, 4}},
  };
  ASSERT_EQ(library.procedures().size(), expected.size());
  for (const auto& t : library.procedures())
  {
    SCOPED_TRACE(t.id());
    ASSERT_TRUE(expected.count(t.id()));
    const Expected& e = expected.at(t.id());
    EXPECT_EQ(t.pathPoints(), e.points);
    EXPECT_EQ(t.holeVertices(), 2 * (e.points - 1));
    ASSERT_EQ(int(t.sutures().size()), e.pairs);
    // Every border edge sewn exactly once (all these procedures close the hole).
    std::multiset<int> starts;
    int corners = 0;
    const int loopSize = t.holeVertices();
    for (const auto& s : t.sutures())
    {
      for (const auto& edge : {s.a, s.b})
      {
        const bool forward = (edge[0] + 1) % loopSize == edge[1];
        EXPECT_TRUE(forward || (edge[1] + 1) % loopSize == edge[0]);
        starts.insert(forward ? edge[0] : edge[1]);
      }
      // Corner rule: a shared vertex is matched with itself.
      const bool shares = s.a[0] == s.b[0] || s.a[0] == s.b[1] || s.a[1] == s.b[0] || s.a[1] == s.b[1];
      if (shares)
      {
        ++corners;
        EXPECT_TRUE(s.a[0] == s.b[0] || s.a[1] == s.b[1]);
      }
    }
    EXPECT_EQ(corners, e.corners);
    for (int v = 0; v < loopSize; ++v)
      EXPECT_EQ(starts.count(v), 1u) << "border edge starting at " << v;
  }
}

TEST(Sutures, ShippedZPlastyAndSimpleExcisionAreTheThesisPairs)
{
  const auto& library = test::shippedProcedures();
  ASSERT_NE(library.find("z-plasty"), nullptr);
  ASSERT_NE(library.find("simple-excision"), nullptr);
  EXPECT_EQ(library.find("z-plasty")->writtenSutures(), thesisZPlasty());
  EXPECT_EQ(library.find("simple-excision")->writtenSutures(), thesisSimpleExcision());
}

TEST(Sutures, SewnEdgesHaveEqualLengthsWhereTheFlapsAreRigid)
{
  // Z-plasty, ellipse, rhomboid and V-Y flaps move without stretching their
  // sewn edges; the excised Z stretches (its central sides are longer).
  const auto skin = test::cylinderSkin(80.0);
  for (const char* id : {"z-plasty", "elliptical-excision", "simple-excision", "rhomboid-flap", "v-y-advancement"})
  {
    SCOPED_TRACE(id);
    const auto* t = test::shippedProcedures().find(id);
    ASSERT_NE(t, nullptr);
    const IncisionPlan plan = t->place(skin, {0.3, 10.0});
    const fem::HoleLoop loop = plan.holeLoop(plan.chart(skin));
    for (const auto& s : plan.sutures())
    {
      const double la = (loop.points[s.a[1]] - loop.points[s.a[0]]).norm();
      const double lb = (loop.points[s.b[1]] - loop.points[s.b[0]]).norm();
      EXPECT_NEAR(la, lb, 1e-9 * std::max(la, 1.0));
    }
  }
}
