// The simulation pipeline on a cylinder phantom: skin r = 80 mm, bone
// r = 70 mm (10 mm of soft tissue), plans placed with the shipped procedures.

#include <cmath>
#include <cstdio>
#include <algorithm>
#include <map>
#include <set>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "AnalyticSkins.h"
#include "planning/PlanSimulation.h"

namespace caps::planning {
namespace {

using test::degree;

using Phantom = test::CylinderPhantom;
const Phantom& phantom()
{
  return test::cylinderPhantom();
}

SimulationOptions testOptions()
{
  return test::phantomSimulationOptions();
}

/// §4.5.2: N_l(2N_v + N_e) + N_v + N_e nodes, N_l N_p elements.
void expectThesisCounts(const PlanPrediction& p, int layers)
{
  const long nv = long(p.surface.mesh.vertices.size());
  const long ne = long(p.continuum.edges.size());
  const long np = long(p.surface.mesh.polygons.size());
  EXPECT_EQ(long(p.continuum.mesh.nodeCount()), layers * (2 * nv + ne) + nv + ne);
  EXPECT_EQ(long(p.continuum.mesh.elements.size()), layers * np);
  EXPECT_EQ(long(p.dofCount), 3 * long(p.continuum.mesh.nodeCount()));
}

void printSummary(const char* name, const PlanPrediction& p)
{
  std::printf("[%s] vertices %zu polygons %zu nodes %ld elements %zu DOF %ld (reduced %ld); gap %.3g mm -> %.3g mm; "
              "times mesh %.3f s assemble %.3f s factor %.3f s solve %.3f s\n",
              name, p.surface.mesh.vertices.size(), p.surface.mesh.polygons.size(), long(p.continuum.mesh.nodeCount()),
              p.continuum.mesh.elements.size(), long(p.dofCount), long(p.reducedDofCount), p.maxSutureGapBefore,
              p.maxSutureGap, p.times.mesh, p.times.assemble, p.times.factor, p.times.solve);
}

/// Outward radial displacement of skin vertex v (mm).
double radialDisplacement(const PlanPrediction& p, int v)
{
  const Eigen::Vector3d x = p.skin.original[v];
  const Eigen::Vector3d radial = Eigen::Vector3d(x.x(), x.y(), 0.0).normalized();
  return (p.skin.displaced[v] - x).dot(radial);
}

TEST(PlanSimulation, RefineHoleCutsSuturedEdgesIntoEqualPieces)
{
  // A Z: every segment tied to the others by the sutures, so all get the
  // pieces of the longest side.
  const IncisionPlan z =
    test::shippedProcedure("z-plasty").place(phantom().skin, {0.0, 0.0}, {{"central_length", 10.0}});
  const SkinChart chart = z.chart(phantom().skin);
  const RefinedHole r = refineHole(z.chartPath(chart), z.borderOffsets(), z.sutures(), 2.0);
  ASSERT_EQ(r.piecesPerSegment.size(), 3u);
  EXPECT_EQ(r.piecesPerSegment[0], r.piecesPerSegment[1]);
  EXPECT_EQ(r.piecesPerSegment[1], r.piecesPerSegment[2]);
  EXPECT_GE(r.piecesPerSegment[0], 5);
  for (std::size_t i = 0; i < r.hole.points.size(); ++i)
    EXPECT_LE((r.hole.points[(i + 1) % r.hole.points.size()] - r.hole.points[i]).norm(), 2.0 + 1e-9);
  // Each original suture pair became pieces-many sub-pairs.
  EXPECT_EQ(r.sutures.size(), z.sutures().size() * std::size_t(r.piecesPerSegment[0]));
  // Original loop vertices keep their places.
  const fem::HoleLoop original = z.holeLoop(chart);
  for (std::size_t v = 0; v < original.points.size(); ++v)
    EXPECT_LT((r.hole.points[r.refinedVertexOf[v]] - original.points[v]).norm(), 1e-12);
}

TEST(PlanSimulation, EllipticalExcisionClosesIntoASymmetricLine)
{
  const IncisionPlan plan =
    test::shippedProcedure("elliptical-excision")
      .place(phantom().skin, {0.0, 0.0}, {{"length", 24.0}, {"ratio", 3.0}, {"axis_angle", 0.0}});
  ASSERT_TRUE(plan.isExcision());
  const PlanPrediction p = simulatePlan(phantom().skin, phantom().bone, plan, testOptions());
  printSummary("ellipse 24 mm 3:1", p);
  expectThesisCounts(p, 3);
  EXPECT_GT(p.maxSutureGapBefore, 1.0);
  EXPECT_LT(p.maxSutureGap, 1e-9);

  // The two sides of the wound meet: each refined cut point and its twin coincide.
  const int m = int(p.hole.points.size()) / 2 + 1; // refined path points
  double twinGap = 0.0, offLine = 0.0;
  for (int k = 1; k + 1 < m; ++k)
  {
    const int twin = rightSideVertex(k, m);
    twinGap = std::max(twinGap, (p.skin.displaced[k] - p.skin.displaced[twin]).norm());
    offLine = std::max(offLine, std::abs(p.skin.displaced[k].z())); // the closed wound lies on z = 0 by symmetry
  }
  std::printf("[ellipse] twins' largest distance after closure %.3g mm, largest |z| of the closed wound %.3g mm\n",
              twinGap, offLine);
  EXPECT_LT(twinGap, 1e-9);
  EXPECT_LT(offLine, 1e-6);

  // Mirror symmetry about the plane θ = 0 (y → −y) and about z = 0, node by node.
  const auto& x = p.continuum.mesh.nodes;
  std::map<std::tuple<long, long, long>, int> index;
  auto key = [](double a, double b, double c) {
    return std::make_tuple(std::lround(a * 1e5), std::lround(b * 1e5), std::lround(c * 1e5));
  };
  for (int i = 0; i < int(x.cols()); ++i)
    index[key(x(0, i), x(1, i), x(2, i))] = i;
  const double scale = p.displacements.cwiseAbs().maxCoeff();
  for (int mirror = 0; mirror < 2; ++mirror)
  {
    const Eigen::Vector3d flip = mirror == 0 ? Eigen::Vector3d(1, -1, 1) : Eigen::Vector3d(1, 1, -1);
    int matched = 0;
    double worst = 0.0;
    for (int i = 0; i < int(x.cols()); ++i)
    {
      const Eigen::Vector3d y = x.col(i).cwiseProduct(flip);
      const auto it = index.find(key(y.x(), y.y(), y.z()));
      if (it == index.end())
        continue;
      ++matched;
      const Eigen::Vector3d ui = p.displacements.segment<3>(3 * i).cwiseProduct(flip);
      const Eigen::Vector3d uj = p.displacements.segment<3>(3 * it->second);
      worst = std::max(worst, (ui - uj).norm() / scale);
    }
    std::printf("[ellipse] mirror %s: %d of %ld nodes have a mirror node; largest relative asymmetry %.3g "
                "(max |u| %.3g mm)\n",
                mirror == 0 ? "θ → −θ" : "z → −z", matched, long(x.cols()), worst, scale);
    EXPECT_EQ(matched, int(x.cols())) << "the mesh is not mirror symmetric";
    EXPECT_LT(worst, 1e-6);
  }
}

TEST(PlanSimulation, ShortEllipsesMakeBiggerDogEars)
{
  // Same width (10 mm), 2:1 and 4:1 (thesis §2.1, Fig. 2.1).
  const double width = 10.0;
  double bulge[2] = {0, 0};
  for (int i = 0; i < 2; ++i)
  {
    const double ratio = i == 0 ? 2.0 : 4.0;
    const double length = ratio * width;
    const IncisionPlan plan =
      test::shippedProcedure("elliptical-excision")
        .place(phantom().skin, {0.0, 0.0}, {{"length", length}, {"ratio", ratio}, {"axis_angle", 0.0}});
    const PlanPrediction p = simulatePlan(phantom().skin, phantom().bone, plan, testOptions());
    printSummary(i == 0 ? "ellipse 2:1" : "ellipse 4:1", p);
    expectThesisCounts(p, 3);
    EXPECT_LT(p.maxSutureGap, 1e-9);
    // Skin points near the ends: within one width of either end of the major axis.
    for (std::size_t v = 0; v < p.skin.chart.size(); ++v)
    {
      const ChartPoint c = p.skin.chart[v];
      const double toEnd = std::min((c - ChartPoint(length / 2, 0)).norm(), (c - ChartPoint(-length / 2, 0)).norm());
      if (toEnd <= width)
        bulge[i] = std::max(bulge[i], radialDisplacement(p, int(v)));
    }
  }
  std::printf("[dog ears] width %.0f mm: largest outward bulge near the ends 2:1 %.4f mm, 4:1 %.4f mm\n", width,
              bulge[0], bulge[1]);
  EXPECT_GT(bulge[0], 0.0);
  EXPECT_GT(bulge[0], bulge[1]);
}

TEST(PlanSimulation, ZPlastyGainGrowsWithTheLimbAngle)
{
  double previous = -1.0;
  for (const double angle : {30.0, 45.0, 60.0, 75.0, 90.0})
  {
    const IncisionPlan plan =
      test::shippedProcedure("z-plasty")
        .place(phantom().skin, {0.0, 0.0},
               {{"central_length", 16.0}, {"limb_angle", angle * degree}, {"axis_angle", 90.0 * degree}});
    const PlanPrediction p = simulatePlan(phantom().skin, phantom().bone, plan, testOptions());
    char name[32];
    std::snprintf(name, sizeof name, "Z %.0f°", angle);
    printSummary(name, p);
    expectThesisCounts(p, 3);
    EXPECT_LT(p.maxSutureGap, 1e-9);
    ASSERT_TRUE(p.zPlasty.has_value());
    const ZPlastyPrediction& z = *p.zPlasty;
    std::printf("[Z %.0f°] predicted gain %.3f mm of %.3f mm = %.1f %%; Fig. 2.2 table %.0f %%, geometric %.1f %%\n",
                angle, z.predicted.gain, z.predicted.before, 100 * z.predicted.fraction, 100 * z.theoretical,
                100 * z.geometric);
    EXPECT_GT(z.predicted.gain, 0.0);
    EXPECT_GT(z.predicted.fraction, previous);
    previous = z.predicted.fraction;
  }
}

TEST(PlanSimulation, EveryShippedProcedureClosesIncludingAcrossTheSeam)
{
  // Every template at its defaults, on the face side and across θ = ±π.
  for (const ProcedureTemplate& t : test::shippedProcedures().procedures())
    for (const double theta : {-test::pi / 2, test::pi})
    {
      SCOPED_TRACE(t.id() + " at θ = " + std::to_string(theta));
      const IncisionPlan plan = t.place(phantom().skin, {theta, 5.0});
      const PlanPrediction p = simulatePlan(phantom().skin, phantom().bone, plan, testOptions());
      printSummary(t.id().c_str(), p);
      expectThesisCounts(p, 3);
      EXPECT_LT(p.maxSutureGap, 1e-9);
      EXPECT_EQ(p.zPlasty.has_value(), t.generator() == "z" || t.generator() == "multiple-z");
      if (p.zPlasty)
        std::printf("[%s] predicted gain %.1f %% of the central limb (geometric %.1f %%)\n", t.id().c_str(),
                    100 * p.zPlasty->predicted.fraction, 100 * p.zPlasty->geometric);
    }
}

TEST(PlanSimulation, LayersFollowTheBoneAndTheStatedFractions)
{
  const IncisionPlan plan =
    test::shippedProcedure("elliptical-excision").place(phantom().skin, {0.0, 0.0}, {{"length", 20.0}});
  SimulationOptions o = testOptions();
  o.layerFractions = {0.2, 0.4, 0.4}; // skin, fat, muscle
  const PlanPrediction p = simulatePlan(phantom().skin, phantom().bone, plan, o);
  expectThesisCounts(p, 3);
  ASSERT_EQ(p.continuum.levelFractions.size(), 4u);
  EXPECT_NEAR(p.continuum.levelFractions[1], 0.2, 1e-12);
  EXPECT_NEAR(p.continuum.levelFractions[2], 0.6, 1e-12);
  for (double d : p.continuum.vertexDepths)
    EXPECT_NEAR(d, 10.0, 1e-6); // skin r 80 − bone r 70
  // Bone nodes sit on the bone cylinder; the fixed ones (all but the wound's,
  // which the sutures sew together through the whole depth) do not move.
  for (int node : p.continuum.boneNodes)
  {
    const Eigen::Vector3d x = p.continuum.mesh.nodes.col(node);
    EXPECT_NEAR(std::hypot(x.x(), x.y()), 70.0, 1e-6);
  }
  EXPECT_GT(p.continuum.fixedNodes.size(), 0u);
  for (int node : p.continuum.fixedNodes)
    EXPECT_EQ(p.displacements.segment<3>(3 * node).norm(), 0.0);
  EXPECT_LT(p.maxSutureGap, 1e-9);
  EXPECT_EQ(p.materials.size(), 3u);
}

/// Distance (mm) in the chart from c to the segment a-b: the nearer end, or
/// the perpendicular when its foot falls between the ends.
double distanceToSegment(const ChartPoint& c, const ChartPoint& a, const ChartPoint& b)
{
  double d = std::min((c - a).norm(), (c - b).norm());
  const ChartPoint along = b - a;
  const double length = along.norm();
  if (length == 0.0)
    return d;
  const ChartPoint unit = along / length;
  const double foot = (c - a).dot(unit);
  if (foot > 0.0 && foot < length)
    d = std::min(d, std::abs(unit.x() * (c - a).y() - unit.y() * (c - a).x()));
  return d;
}

PlanPrediction ellipseClosure(double underminingWidth, double length, double regionRadius)
{
  const IncisionPlan plan =
    test::shippedProcedure("elliptical-excision")
      .place(phantom().skin, {0.0, 0.0}, {{"length", length}, {"ratio", 3.0}, {"axis_angle", 0.0}});
  SimulationOptions o = testOptions();
  o.regionRadius = regionRadius;
  o.underminingWidth = underminingWidth;
  return simulatePlan(phantom().skin, phantom().bone, plan, o);
}

TEST(PlanSimulation, UnderminingReleasesExactlyTheBoneNodesOfTheBand)
{
  const double width = 5.0;
  const PlanPrediction none = ellipseClosure(0.0, 24.0, 20.0);
  const PlanPrediction band = ellipseClosure(width, 24.0, 20.0);
  EXPECT_TRUE(none.continuum.underminedNodes.empty());
  EXPECT_EQ(std::count(none.underminedVertices.begin(), none.underminedVertices.end(), 1), 0);

  // The same mesh and the same sutures: only supports change.
  ASSERT_EQ(band.continuum.mesh.nodeCount(), none.continuum.mesh.nodeCount());
  ASSERT_EQ(band.continuum.mesh.elements.size(), none.continuum.mesh.elements.size());
  EXPECT_EQ(band.continuum.mesh.nodes, none.continuum.mesh.nodes);
  ASSERT_EQ(band.continuum.sutures.size(), none.continuum.sutures.size());
  for (std::size_t i = 0; i < band.continuum.sutures.size(); ++i)
  {
    EXPECT_EQ(band.continuum.sutures[i].node, none.continuum.sutures[i].node);
    EXPECT_EQ(band.continuum.sutures[i].target, none.continuum.sutures[i].target);
  }
  EXPECT_EQ(band.continuum.boneNodes, none.continuum.boneNodes);

  // The band counted from the surface mesh: vertices within the width of a
  // sutured border edge; their bone nodes, and those of edges between two of them.
  const auto& vertices = band.surface.mesh.vertices;
  std::set<std::pair<int, int>> suturedEdges;
  for (const auto& pair : band.sutures)
    for (const auto& e : {pair.a, pair.b})
      suturedEdges.insert({std::min(e[0], e[1]), std::max(e[0], e[1])});
  std::vector<bool> inside(vertices.size(), false);
  double closestToTheEdgeOfTheBand = 1e300;
  for (std::size_t v = 0; v < vertices.size(); ++v)
  {
    double d = 1e300;
    for (const auto& [a, b] : suturedEdges)
      d = std::min(d, distanceToSegment(vertices[v], vertices[a], vertices[b]));
    inside[v] = d <= width;
    closestToTheEdgeOfTheBand = std::min(closestToTheEdgeOfTheBand, std::abs(d - width));
  }
  std::vector<int> expected;
  int vertexCount = 0;
  for (std::size_t v = 0; v < vertices.size(); ++v)
    if (inside[v])
    {
      expected.push_back(band.continuum.vertexColumns[v].back());
      ++vertexCount;
    }
  for (std::size_t e = 0; e < band.continuum.edges.size(); ++e)
    if (inside[band.continuum.edges[e][0]] && inside[band.continuum.edges[e][1]])
      expected.push_back(band.continuum.edgeColumns[e].back());
  std::sort(expected.begin(), expected.end());
  std::printf("[undermining %.0f mm] %d of %zu surface vertices in the band (%zu hole vertices), %zu bone nodes "
              "released of %zu; nearest vertex to the band's edge %.3g mm from it\n",
              width, vertexCount, vertices.size(), band.hole.points.size(), expected.size(),
              band.continuum.boneNodes.size(), closestToTheEdgeOfTheBand);
  EXPECT_GT(vertexCount, int(band.hole.points.size())); // the band reaches beyond the wound
  EXPECT_LT(expected.size(), band.continuum.boneNodes.size());
  EXPECT_EQ(band.continuum.underminedNodes, expected);
  for (std::size_t v = 0; v < vertices.size(); ++v)
    EXPECT_EQ(band.underminedVertices[v] != 0, inside[v]) << "vertex " << v;

  // Every other fixed node is still fixed; the released ones are not.
  std::vector<int> stillFixed;
  std::set_difference(none.continuum.fixedNodes.begin(), none.continuum.fixedNodes.end(), expected.begin(),
                      expected.end(), std::back_inserter(stillFixed));
  EXPECT_EQ(band.continuum.fixedNodes, stillFixed);
  EXPECT_LT(band.continuum.fixedNodes.size(), none.continuum.fixedNodes.size());
  EXPECT_LT(band.maxSutureGap, 1e-9);

  // The freed skin slides over the bone: released bone nodes away from the
  // sutures move, fixed ones do not.
  std::set<int> sutured;
  for (const auto& s : band.continuum.sutures)
    sutured.insert({s.node, s.target});
  double slide = 0.0;
  for (int node : band.continuum.underminedNodes)
    if (!sutured.count(node))
      slide = std::max(slide, band.displacements.segment<3>(3 * node).norm());
  for (int node : band.continuum.fixedNodes)
    EXPECT_EQ(band.displacements.segment<3>(3 * node).norm(), 0.0);
  std::printf("[undermining %.0f mm] largest slide of a released bone node %.3g mm\n", width, slide);
  EXPECT_GT(slide, 1e-3);
}

TEST(PlanSimulation, SutureForcesBalanceTheBoneReactions)
{
  for (const double width : {0.0, 10.0})
  {
    SCOPED_TRACE("undermining " + std::to_string(width) + " mm");
    const PlanPrediction p = ellipseClosure(width, 24.0, 20.0);
    const ClosureForces& c = p.closure;
    ASSERT_EQ(c.sutures.size(), p.continuum.sutures.size());
    ASSERT_GT(c.magnitudeSum, 0.0);
    auto force = [&](int node) { return Eigen::Vector3d(p.nodalForces.segment<3>(3 * node)); };

    // Undermined bone nodes slide on the deep plane, which can push only
    // along its normal: the part of a force the plane cannot take.
    std::map<int, Eigen::Vector3d> planeNormal;
    for (const fem::SlidingNode& n : p.continuum.slidingNodes)
      planeNormal[n.node] = n.normal;
    EXPECT_EQ(planeNormal.empty(), width == 0.0);
    auto offThePlane = [&](int node, const Eigen::Vector3d& f) {
      const auto it = planeNormal.find(node);
      return it == planeNormal.end() ? f : Eigen::Vector3d(f - f.dot(it->second) * it->second);
    };

    // Each suture pulls its node and its target equally and oppositely: at
    // a target, its own K U cancels the sum over the nodes sewn onto it
    // (less the deep plane's push where the target slides).
    std::map<int, Eigen::Vector3d> onTargets;
    for (const SutureForce& s : c.sutures)
    {
      EXPECT_EQ((s.force - force(s.node)).norm(), 0.0);
      auto [it, added] = onTargets.emplace(s.target, Eigen::Vector3d::Zero());
      it->second += s.force;
    }
    double pairImbalance = 0.0;
    for (const auto& [target, sum] : onTargets)
      pairImbalance = std::max(pairImbalance, offThePlane(target, force(target) + sum).norm() / c.largest);

    // Global equilibrium without load: the sutures pull both ways alike, so
    // the bone's and the deep plane's reactions add up to zero; every other
    // node carries no force, and a sliding one only along the plane's normal.
    std::set<int> constrained(p.continuum.fixedNodes.begin(), p.continuum.fixedNodes.end());
    for (const SutureForce& s : c.sutures)
      constrained.insert({s.node, s.target});
    double freeForce = 0.0, supportMagnitude = 0.0;
    for (int node = 0; node < int(p.continuum.mesh.nodeCount()); ++node)
      if (!constrained.count(node))
        freeForce = std::max(freeForce, offThePlane(node, force(node)).norm());
    for (int node : p.continuum.fixedNodes)
      supportMagnitude += force(node).norm();
    const double globalImbalance = c.supportReaction.norm() / c.magnitudeSum;
    std::printf("[closure force, undermining %.0f mm] %zu sutures: sum of magnitudes %.6g N, largest %.4g N; "
                "bone: sum of magnitudes %.6g N; %zu nodes slide; relative imbalance per target %.2g, global %.2g; "
                "largest force at a free node %.2g N\n",
                width, c.sutures.size(), c.magnitudeSum, c.largest, supportMagnitude, planeNormal.size(), pairImbalance,
                globalImbalance, freeForce);
    EXPECT_LT(pairImbalance, 1e-8);
    EXPECT_LT(globalImbalance, 1e-8);
    EXPECT_LT(freeForce, 1e-8 * c.magnitudeSum);

    // Per plan pair: each pair's totals, and together they cover every suture.
    ASSERT_EQ(c.edges.size(), 8u); // the ellipse's 9 cut points zip into 8 pairs
    int counted = 0;
    double sumOfPairs = 0.0;
    for (const SuturedEdgeForce& e : c.edges)
    {
      std::printf("  pair (%d,%d)-(%d,%d): %d sutures, resultant %.4g N, sum of magnitudes %.4g N\n", e.edges.a[0],
                  e.edges.a[1], e.edges.b[0], e.edges.b[1], e.sutureCount, e.resultantMagnitude, e.magnitudeSum);
      EXPECT_GT(e.sutureCount, 0);
      EXPECT_LE(e.resultantMagnitude, e.magnitudeSum * (1 + 1e-12));
      counted += e.sutureCount;
      sumOfPairs += e.magnitudeSum;
    }
    EXPECT_GE(counted, int(c.sutures.size())); // shared cut points count twice
    EXPECT_GE(sumOfPairs, c.magnitudeSum * (1 - 1e-12));
  }
}

TEST(PlanSimulation, UnderminingReducesTheClosureForce)
{
  // A 30 × 10 mm ellipse in a 50 mm region, undermined ever wider.
  const double widths[] = {0.0, 5.0, 10.0, 20.0, 40.0};
  std::vector<double> force;
  for (const double width : widths)
  {
    const PlanPrediction p = ellipseClosure(width, 30.0, 50.0);
    EXPECT_LT(p.maxSutureGap, 1e-9);
    force.push_back(p.closure.magnitudeSum);
    std::printf("[undermining curve] width %4.0f mm: %zu bone nodes released, total closure force %.5g N "
                "(%.1f %% of none), largest suture %.4g N\n",
                width, p.continuum.underminedNodes.size(), p.closure.magnitudeSum, 100 * force.back() / force.front(),
                p.closure.largest);
  }
  std::printf("[undermining curve] published porcine data: undermining cut the closing force of a 9 × 9 cm defect "
              "by about 14 %%; here 20 mm cut it by %.1f %%, 40 mm by %.1f %%\n",
              100 * (1 - force[3] / force[0]), 100 * (1 - force[4] / force[0]));
  for (std::size_t i = 1; i < force.size(); ++i)
    EXPECT_LT(force[i], force[i - 1]) << "width " << widths[i];
  // It flattens: the last 20 mm gain less per mm than the first 10.
  EXPECT_LT((force[3] - force[4]) / 20.0, (force[0] - force[2]) / 10.0);
}

/// Tissue between radii rOuter and rInner under a chart polygon (chart u =
/// r0 (θ − θc), v = z): the area in (θ, z) is the chart area / r0.
double cylinderShellVolume(const std::vector<ChartPoint>& polygon, double r0, double rOuter, double rInner)
{
  double twiceArea = 0.0;
  for (std::size_t i = 0; i < polygon.size(); ++i)
  {
    const ChartPoint& a = polygon[i];
    const ChartPoint& b = polygon[(i + 1) % polygon.size()];
    twiceArea += a.x() * b.y() - a.y() * b.x();
  }
  return std::abs(0.5 * twiceArea) / r0 * (rOuter * rOuter - rInner * rInner) / 2.0;
}

TEST(PlanSimulation, ExcisedVolumeFromTheElementsIsTheAnalyticShell)
{
  // A 24 × 8 mm ellipse on the phantom (skin r = 80, bone r = 70): the
  // excised tissue is the prism of the refined hole from r = 80 to 70, and
  // with the cut through the skin layer only (one layer of three equal
  // ones), from r = 80 to 80 − 10 / 3. The elements are quadratic, the
  // cylinder is not, but along the rays they meet it to 4e-10 here.
  const IncisionPlan plan =
    test::shippedProcedure("elliptical-excision")
      .place(phantom().skin, {0.0, 0.0}, {{"length", 24.0}, {"ratio", 3.0}, {"axis_angle", 0.0}});
  const double r0 = plan.chart(phantom().skin).radius();
  for (const int cutLayers : {0, 1})
  {
    SimulationOptions o = testOptions();
    o.cutLayers = cutLayers;
    const PlanPrediction p = simulatePlan(phantom().skin, phantom().bone, plan, o);
    const double analytic = cylinderShellVolume(p.hole.points, r0, 80.0, cutLayers == 0 ? 70.0 : 80.0 - 10.0 / 3.0);
    std::printf("[excised volume] cut through %d of 3 layers: elements %.4f mm3, analytic %.4f mm3 (relative %.2g); "
                "range maps %.4f mm3\n",
                cutLayers == 0 ? 3 : cutLayers, p.excisedVolume, analytic, p.excisedVolume / analytic - 1.0,
                excisedVolume(plan, phantom().skin, phantom().bone));
    EXPECT_NEAR(p.excisedVolume, analytic, 1e-6 * analytic);
    EXPECT_EQ(p.excisedTissue.mesh.elements.size(), std::size_t(cutLayers == 0 ? 3 : 1) * (p.hole.points.size() - 2));
    EXPECT_LT(p.maxSutureGap, 1e-9);
    if (cutLayers == 0)
    { // the second method, over the plan's own hole polygon
      EXPECT_NEAR(p.excisedVolume, excisedVolume(plan, phantom().skin, phantom().bone), 2e-3 * analytic);
    }
  }
}

TEST(PlanSimulation, ACutOfPartialDepthTransposesLess)
{
  // A 60° Z-plasty cut through the skin layer only, not undermined: the
  // flaps stay bonded to the tissue below, so transposing them lengthens
  // the central axis less than the full-thickness cut does; only the cut
  // layer is sutured.
  const IncisionPlan plan =
    test::shippedProcedure("z-plasty")
      .place(phantom().skin, {0.0, 0.0},
             {{"central_length", 16.0}, {"limb_angle", 60.0 * degree}, {"axis_angle", 90.0 * degree}});
  SimulationOptions o = testOptions();
  o.underminingWidth = 0.0;
  const PlanPrediction full = simulatePlan(phantom().skin, phantom().bone, plan, o);
  o.cutLayers = 1;
  const PlanPrediction partial = simulatePlan(phantom().skin, phantom().bone, plan, o);
  ASSERT_TRUE(full.zPlasty && partial.zPlasty);
  std::printf("[Z 60°] gain %.1f %% cut through 3 of 3 layers, %.1f %% through 1; sutures %zu and %zu; "
              "closure force %.3g N and %.3g N\n",
              100 * full.zPlasty->predicted.fraction, 100 * partial.zPlasty->predicted.fraction,
              full.continuum.sutures.size(), partial.continuum.sutures.size(), full.closure.magnitudeSum,
              partial.closure.magnitudeSum);
  EXPECT_LT(partial.maxSutureGap, 1e-9);
  EXPECT_GT(partial.zPlasty->predicted.gain, 0.0);
  EXPECT_LT(partial.zPlasty->predicted.fraction, full.zPlasty->predicted.fraction);
  EXPECT_LT(partial.continuum.sutures.size(), full.continuum.sutures.size());
  EXPECT_LT(partial.continuum.mesh.nodeCount(), full.continuum.mesh.nodeCount()); // the twins below are one
  EXPECT_EQ(partial.excisedVolume, 0.0);                                          // a Z-plasty removes nothing

  // Raised in the plane at the cut's root over the procedure's own band, as
  // a surgeon raises skin flaps: the flaps slide on the tissue below, which
  // stays held by the bone, and transpose further.
  o.underminingWidth.reset();
  const PlanPrediction raised = simulatePlan(phantom().skin, phantom().bone, plan, o);
  ASSERT_TRUE(raised.zPlasty);
  EXPECT_LT(raised.maxSutureGap, 1e-9);
  EXPECT_GT(raised.zPlasty->predicted.fraction, partial.zPlasty->predicted.fraction);
  EXPECT_EQ(raised.continuum.fixedNodes, raised.continuum.boneNodes); // the bone holds all it held
  ASSERT_FALSE(raised.continuum.slidingNodes.empty());
  const double scale = raised.displacements.cwiseAbs().maxCoeff();
  double apart = 0.0, slide = 0.0;
  for (const fem::SlidingNode& n : raised.continuum.slidingNodes)
  {
    ASSERT_GE(n.beneath, 0) << "the raised tissue slides on the tissue below, not on the bone";
    EXPECT_EQ(raised.continuum.mesh.nodes.col(n.node), raised.continuum.mesh.nodes.col(n.beneath));
    const Eigen::Vector3d relative =
      raised.displacements.segment<3>(3 * n.node) - raised.displacements.segment<3>(3 * n.beneath);
    apart = std::max(apart, std::abs(relative.dot(n.normal)));
    slide = std::max(slide, (relative - relative.dot(n.normal) * n.normal).norm());
  }
  std::printf("[Z 60°, cut through 1 of 3, raised] gain %.1f %%; %zu nodes slide on the tissue below, largest slide "
              "%.3g mm, largest |(u - u_beneath).n| %.2g mm\n",
              100 * raised.zPlasty->predicted.fraction, raised.continuum.slidingNodes.size(), slide, apart);
  EXPECT_LT(apart, 1e-10 * scale);
  EXPECT_GT(slide, 0.1);

  o.cutLayers = 4;
  EXPECT_THROW(simulatePlan(phantom().skin, phantom().bone, plan, o), std::invalid_argument);
}

TEST(PlanSimulation, AMeshOutsideTheQualityLimitsSaysWhere)
{
  // 10 mm of tissue cut into a 0.1 mm skin layer on 2 mm elements: every
  // skin element is at least 20 times as wide as it is thick, and only
  // those (the fat and muscle layers are 4.95 mm thick).
  const IncisionPlan plan =
    test::shippedProcedure("elliptical-excision").place(phantom().skin, {0.0, 0.0}, {{"length", 20.0}});
  SimulationOptions o = testOptions();
  o.model = TissueModel::LinearElastic;
  o.layerFractions = {0.01, 0.495, 0.495};
  const PlanPrediction thin = simulatePlan(phantom().skin, phantom().bone, plan, o);
  const fem::MeshQualityCheck& q = thin.check.mesh;
  const long skinElements = long(std::count(thin.continuum.elementLayer.begin(), thin.continuum.elementLayer.end(), 0));
  EXPECT_EQ(q.poorEdgeRatio, skinElements);
  EXPECT_EQ(q.poorElements, skinElements);
  EXPECT_GE(q.maxEdgeRatio, 20.0);
  // The worst is a skin element: its centre 0.05 mm under the skin.
  EXPECT_EQ(thin.continuum.elementLayer[std::size_t(q.worstEdgeRatioElement)], 0);
  EXPECT_NEAR(std::hypot(q.worstEdgeRatioAt.x(), q.worstEdgeRatioAt.y()), 79.95, 0.05);
  // The caveat says how many, how bad, where, and how far from the wound
  // (the nearest sutured node).
  double nearest = 1e9;
  for (const fem::Suture& s : thin.continuum.sutures)
    nearest = std::min(nearest, (thin.continuum.mesh.nodes.col(s.node) - q.worstEdgeRatioAt).norm());
  const std::string& caveat = thin.check.caveat;
  std::printf("[quality] %s\n", caveat.c_str());
  for (const std::string& said :
       {std::to_string(skinElements) + " of " + std::to_string(q.elements) + " elements are shaped outside",
        std::string("in tissue layer 1 from the skin at "),
        std::to_string(std::lround(nearest)) + " mm from the wound"})
    EXPECT_NE(caveat.find(said), std::string::npos) << "not said: " << said;
  EXPECT_TRUE(thin.check.admissible()) << "a caveat, not a refusal";

  // The same plan on the stated layers keeps the limits and says nothing.
  o.layerFractions = {0.2, 0.4, 0.4};
  const PlanPrediction fair = simulatePlan(phantom().skin, phantom().bone, plan, o);
  EXPECT_TRUE(fair.check.mesh.withinLimits()) << fair.check.caveat;
  EXPECT_EQ(fair.check.caveat.find("shaped outside"), std::string::npos) << fair.check.caveat;
}

TEST(PlanSimulation, RefusesPlansOffTheSkinAndHolesUnderTheRegion)
{
  const Phantom& ph = phantom();
  // Centre beyond the scanned z range.
  IncisionPlan off({{0.0, 0.0}, {0.05, 0.0}}, SkinPoint{0.0, 150.0});
  EXPECT_THROW(simulatePlan(ph.skin, ph.bone, off, testOptions()), std::invalid_argument);

  // A hole in the skin map 12 mm from the wound, inside the meshed region
  // (a patch: rows empty all round are an edge of the scan, see below).
  seg::RangeMap holed = ph.skin;
  for (int j = 0; j < holed.nZ(); ++j)
  {
    const double z = holed.frame().indexToZ(j);
    if (z > 10.0 && z < 14.0)
      for (int i = 0; i < holed.nTheta(); ++i)
        if (std::abs(holed.frame().indexToTheta(i)) < 0.1)
          holed.at(i, j) = seg::RangeMap::quietNaN();
  }
  const IncisionPlan plan =
    test::shippedProcedure("elliptical-excision").place(ph.skin, {0.0, 0.0}, {{"length", 20.0}});
  {
    // Rows with no skin across the plan's width are where the scan ends: the
    // region stops at the last measured row.
    seg::RangeMap cut = ph.skin;
    for (int j = 0; j < cut.nZ(); ++j)
      if (cut.frame().indexToZ(j) > 10.0)
        for (int i = 0; i < cut.nTheta(); ++i)
          cut.at(i, j) = seg::RangeMap::quietNaN();
    const PlanPrediction p = simulatePlan(cut, ph.bone, plan, testOptions());
    EXPECT_TRUE(p.surface.reachedChartBound);
    EXPECT_LT(p.maxSutureGap, 1e-9);
    for (const auto& v : p.surface.mesh.vertices)
      EXPECT_LE(v.y(), 10.0);
  }
  try
  {
    simulatePlan(holed, ph.bone, plan, testOptions());
    ADD_FAILURE() << "a hole under the region was accepted";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("no surface"), std::string::npos) << e.what();
  }

  SimulationOptions bad = testOptions();
  bad.elementSize = 0.0;
  EXPECT_THROW(simulatePlan(ph.skin, ph.bone, plan, bad), std::invalid_argument);
  bad = testOptions();
  bad.layerCount = 0;
  EXPECT_THROW(simulatePlan(ph.skin, ph.bone, plan, bad), std::invalid_argument);
  bad = testOptions();
  bad.underminingWidth = -1.0;
  EXPECT_THROW(simulatePlan(ph.skin, ph.bone, plan, bad), std::invalid_argument);

  // No bone anywhere: the stated default depth.
  const seg::RangeMap noBone(ph.skin.frame());
  SimulationOptions o = testOptions();
  o.noBoneDepth = 8.0;
  const PlanPrediction p = simulatePlan(ph.skin, noBone, plan, o);
  for (double d : p.continuum.vertexDepths)
    EXPECT_DOUBLE_EQ(d, 8.0);
  EXPECT_LT(p.maxSutureGap, 1e-9);
}

} // namespace
} // namespace caps::planning
