// The continuum mesher (thesis §4.5.2) against independent answers: the
// thesis's node and element counts with N_e from Euler's formula, the
// analytic geometry of coaxial cylinders (skin r = 80 mm, bone below it at a
// given depth), the shell volume, the suture pairs of §4.4.5 with the corner
// rule, and a real closure of a lens-shaped excision whose sutured nodes must
// meet and whose displacement must be mirror-symmetric.

#include "fem/ContinuumMesher.h"
#include "fem/ElasticityIntegrator.h"
#include "fem/ElementGeometry.h"
#include "fem/HyperelasticMaterial.h"
#include "fem/NonlinearStaticAnalysis.h"
#include "fem/Quadrature.h"
#include "fem/StaticAnalysis.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <numbers>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

namespace caps::fem {
namespace {

constexpr double kSkinRadius = 80.0;
constexpr double kFaceTheta = -std::numbers::pi / 2.0; // the chart is centred on the front of the face

double thetaOf(const ChartPoint& c)
{
  return kFaceTheta + c.x() / kSkinRadius;
}

/// Skin on the cylinder r = 80 mm around the z axis; chart u = r0 (θ − θc), v = z.
TissueGeometry cylinderGeometry(std::function<double(const ChartPoint&)> depth)
{
  TissueGeometry g;
  g.skinPoint = [](const ChartPoint& c) {
    const double th = thetaOf(c);
    return Eigen::Vector3d(kSkinRadius * std::cos(th), kSkinRadius * std::sin(th), c.y());
  };
  g.tissueDepth = std::move(depth);
  g.inwardDirection = [](const ChartPoint& c) {
    const double th = thetaOf(c);
    return Eigen::Vector3d(-2.0 * std::cos(th), -2.0 * std::sin(th), 0.0); // not unit on purpose
  };
  return g;
}

double radiusOf(const Eigen::Vector3d& x)
{
  return std::hypot(x.x(), x.y());
}

/// A slit from (-10, 0) to (10, 0) (hole loop 0, 1, 2, 1' = 3) in the
/// rectangle [-20, 20] x [-10, 10], in 6 quadrilaterals and 4 triangles.
SurfaceMesh slitMesh()
{
  SurfaceMesh m;
  m.vertices = {{-10, 0},   {0, 0},     {10, 0},  {0, 0},                // hole loop (3 is the lower twin of 1)
                {-20, 0},   {20, 0},                                     // 4, 5: rim ends of the cut line
                {-20, 10},  {-10, 10},  {0, 10},  {10, 10},  {20, 10},   // 6..10
                {-20, -10}, {-10, -10}, {0, -10}, {10, -10}, {20, -10}}; // 11..15
  m.holeVertexCount = 4;
  m.polygons = {{4, 0, 7},      {4, 7, 6},      {0, 1, 8, 7},   {1, 2, 9, 8}, {2, 5, 10, 9},
                {11, 12, 0, 4}, {12, 13, 3, 0}, {13, 14, 2, 3}, {14, 15, 5},  {14, 5, 2}};
  m.outerBorder = {4, 11, 12, 13, 14, 15, 5, 10, 9, 8, 7, 6};
  return m;
}

std::vector<SutureEdgePair> slitSutures()
{
  return {{{0, 1}, {0, 3}}, {{1, 2}, {3, 2}}};
}

/// Mirror v -> -v of the lens mesh's vertices.
int lensMirror(int v)
{
  switch (v)
  {
  case 1:
    return 5;
  case 5:
    return 1;
  case 2:
    return 4;
  case 4:
    return 2;
  default:
    break;
  }
  if (v >= 8 && v <= 13)
    return v + 6;
  if (v >= 14 && v <= 19)
    return v - 6;
  return v; // 0, 3 (the lens's corners) and 6, 7 (the rim on v = 0)
}

/// A lens-shaped (elliptical) excision (Fig. 4.12): path (-15,0) (-5,0)
/// (5,0) (15,0), the inner twins offset by ±3 mm; loop 0..5 clockwise. The
/// mesh covers [-25, 25] x [-15, 15] and is mirror-symmetric in v.
SurfaceMesh lensMesh()
{
  SurfaceMesh m;
  m.vertices = {{-15, 0}, {-5, 3}, {5, 3}, {15, 0}, {5, -3}, {-5, -3}, // hole loop
                {-25, 0}, {25, 0}};                                    // 6, 7
  for (double u : {-25, -15, -5, 5, 15, 25})
    m.vertices.push_back({u, 15}); // 8..13
  for (double u : {-25, -15, -5, 5, 15, 25})
    m.vertices.push_back({u, -15}); // 14..19
  m.holeVertexCount = 6;
  const std::vector<std::vector<int>> upper = {{6, 0, 9},      {6, 9, 8},  {0, 1, 10, 9}, {1, 2, 11, 10},
                                               {2, 3, 12, 11}, {3, 7, 13}, {3, 13, 12}};
  m.polygons = upper;
  for (const auto& p : upper)
  { // mirrored polygons, reversed to stay counter-clockwise
    std::vector<int> q;
    for (auto it = p.rbegin(); it != p.rend(); ++it)
      q.push_back(lensMirror(*it));
    m.polygons.push_back(q);
  }
  return m;
}

std::vector<SutureEdgePair> lensSutures()
{ // §4.4.5, Fig. 4.12
  return {{{0, 1}, {0, 5}}, {{1, 2}, {5, 4}}, {{2, 3}, {4, 3}}};
}

/// N_e of a mesh of an annulus (one hole), from Euler: V - E + F = 0.
int annulusEdgeCount(const SurfaceMesh& m)
{
  return int(m.vertices.size() + m.polygons.size());
}

int thesisNodeCount(int nv, int ne, int nl)
{
  return nl * (2 * nv + ne) + nv + ne;
}

double constantDepth(const ChartPoint&)
{
  return 20.0;
}

/// Evaluates every element at every integration point (ElementGeometry
/// throws ElementError on a non-positive or collapsed Jacobian) and its
/// stiffness; returns the smallest det J and the total volume.
std::pair<double, double> checkJacobians(const Mesh& mesh)
{
  double minDet = std::numeric_limits<double>::infinity(), volume = 0.0;
  const LinearElasticMaterial material{1.0, 0.3, 0.0};
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const auto& el = mesh.elements[e];
    const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
    const ElementCoordinates x = mesh.elementCoordinates(e);
    const IntegrationRule& rule = integrationRule(el.kind, 3);
    PointGeometry g;
    for (std::size_t q = 0; q < rule.size(); ++q)
    {
      evaluateGeometry(shape, x, rule.points[q], int(e), g);
      minDet = std::min(minDet, g.detJ);
      volume += rule.weights[q] * g.detJ;
    }
    ElementMatrix ke;
    assembleElementStiffness(shape, x, material, rule, int(e), ke);
  }
  return {minDet, volume};
}

void expectThrowsWith(const std::function<void()>& f, const std::string& fragment)
{
  try
  {
    f();
    ADD_FAILURE() << "expected std::invalid_argument containing \"" << fragment << "\"";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(ContinuumMesherTest, CountsFollowTheThesisFormula)
{
  for (const SurfaceMesh& surface : {slitMesh(), lensMesh()})
  {
    const int nv = int(surface.vertices.size()), np = int(surface.polygons.size());
    const int ne = annulusEdgeCount(surface);
    int triangles = 0;
    for (const auto& p : surface.polygons)
      triangles += p.size() == 3 ? 1 : 0;
    for (int layers : {1, 2, 3, 5})
    {
      ContinuumMeshOptions options;
      options.layerCount = layers;
      const ContinuumMesh cm = meshContinuum(surface, {}, cylinderGeometry(constantDepth), options);
      EXPECT_EQ(int(cm.edges.size()), ne);
      EXPECT_EQ(cm.mesh.nodeCount(), thesisNodeCount(nv, ne, layers)) << layers << " layers";
      ASSERT_EQ(int(cm.mesh.elements.size()), layers * np);
      int wedges = 0;
      std::vector<int> uses(std::size_t(cm.mesh.nodeCount()), 0);
      for (std::size_t e = 0; e < cm.mesh.elements.size(); ++e)
      {
        const Element& el = cm.mesh.elements[e];
        const int slots = el.kind == ElementKind::Wedge15 ? 15 : 20;
        wedges += el.kind == ElementKind::Wedge15 ? 1 : 0;
        EXPECT_EQ(int(surface.polygons[std::size_t(cm.elementPolygon[e])].size()),
                  el.kind == ElementKind::Wedge15 ? 3 : 4);
        EXPECT_EQ(el.region, cm.elementLayer[e]);
        for (int k = 0; k < 20; ++k)
        {
          if (k < slots)
          {
            ASSERT_GE(el.nodes[std::size_t(k)], 0);
            ++uses[std::size_t(el.nodes[std::size_t(k)])];
          }
          else
          {
            EXPECT_EQ(el.nodes[std::size_t(k)], -1);
          }
        }
      }
      EXPECT_EQ(wedges, layers * triangles);
      EXPECT_EQ(std::count(uses.begin(), uses.end(), 0), 0) << "every node belongs to an element";
      validateMesh(cm.mesh, {{0, {1, 0.3, 0}}, {1, {1, 0.3, 0}}, {2, {1, 0.3, 0}}, {3, {1, 0.3, 0}}, {4, {1, 0.3, 0}}});
    }
  }
}

TEST(ContinuumMesherTest, JacobiansArePositiveAndVolumeMatchesTheCylindricalShell)
{
  // Constant depth 20 mm: the tissue is the shell 60 <= r <= 80 over the
  // chart region, volume = area / r0 * (80^2 - 60^2) / 2 (the slit has no area).
  for (int layers : {1, 3})
  {
    ContinuumMeshOptions options;
    options.layerCount = layers;
    const ContinuumMesh cm = meshContinuum(slitMesh(), slitSutures(), cylinderGeometry(constantDepth), options);
    const auto [minDet, volume] = checkJacobians(cm.mesh);
    EXPECT_GT(minDet, 0.0);
    const double exact = 40.0 * 20.0 / kSkinRadius * (80.0 * 80.0 - 60.0 * 60.0) / 2.0;
    EXPECT_NEAR(volume / exact, 1.0, 1e-5) << volume << " vs " << exact;
    std::cout << layers << " layer(s): volume " << volume << " mm^3 vs shell " << exact << " (relative error "
              << volume / exact - 1.0 << "), min det J " << minDet << "\n";
  }
  // The lens with a varying depth and unequal layers.
  ContinuumMeshOptions options;
  options.layerCount = 3;
  options.layerFractions = {0.2, 0.3, 0.5};
  const ContinuumMesh cm = meshContinuum(lensMesh(), lensSutures(), cylinderGeometry([](const ChartPoint& c) {
                                           return 15.0 + 5.0 * std::cos(c.x() / 15.0) + 0.02 * c.y() * c.y();
                                         }),
                                         options);
  EXPECT_GT(checkJacobians(cm.mesh).first, 0.0);
}

TEST(ContinuumMesherTest, NodesFollowSkinAndDepth)
{
  auto depth = [](const ChartPoint& c) { return 15.0 + 5.0 * std::cos(c.x() / 15.0) + 0.02 * c.y() * c.y(); };
  const SurfaceMesh surface = lensMesh();
  ContinuumMeshOptions options;
  options.layerCount = 3;
  options.layerFractions = {0.2, 0.3, 0.5};
  options.layerRegions = {7, 8, 9};
  const ContinuumMesh cm = meshContinuum(surface, lensSutures(), cylinderGeometry(depth), options);
  const std::vector<double> levels = {0.0, 0.2, 0.5, 1.0};
  auto expectAt = [&](int node, const ChartPoint& c, double fraction) {
    const Eigen::Vector3d x = cm.mesh.nodes.col(node);
    EXPECT_NEAR(radiusOf(x), kSkinRadius - fraction * depth(c), 1e-9) << "node " << node;
    EXPECT_NEAR(x.z(), c.y(), 1e-9);
    EXPECT_NEAR(std::atan2(x.y(), x.x()), thetaOf(c), 1e-12);
  };
  for (std::size_t v = 0; v < surface.vertices.size(); ++v)
  {
    const auto& column = cm.vertexColumns[v];
    ASSERT_EQ(column.size(), 7u);
    for (int k = 0; k <= 3; ++k)
      expectAt(column[std::size_t(2 * k)], surface.vertices[v], levels[std::size_t(k)]);
    for (int k = 0; k < 3; ++k)
      expectAt(column[std::size_t(2 * k + 1)], surface.vertices[v],
               0.5 * (levels[std::size_t(k)] + levels[std::size_t(k) + 1]));
    EXPECT_DOUBLE_EQ(cm.vertexDepths[v], depth(surface.vertices[v]));
  }
  // Mid-edge columns stand on the chart midpoint: the top node on the skin
  // cylinder, the bottom node at the depth of the midpoint.
  for (std::size_t e = 0; e < cm.edges.size(); ++e)
  {
    const ChartPoint mid =
      0.5 * (surface.vertices[std::size_t(cm.edges[e][0])] + surface.vertices[std::size_t(cm.edges[e][1])]);
    for (int k = 0; k <= 3; ++k)
      expectAt(cm.edgeColumns[e][std::size_t(k)], mid, levels[std::size_t(k)]);
  }
  // Top mid-edge slots of the skin layer's elements lie on the skin.
  for (std::size_t e = 0; e < cm.mesh.elements.size(); ++e)
  {
    const Element& el = cm.mesh.elements[e];
    EXPECT_EQ(el.region, 7 + cm.elementLayer[e]);
    if (cm.elementLayer[e] != 0)
      continue;
    const int first = el.kind == ElementKind::Hex20 ? 8 : 6, count = el.kind == ElementKind::Hex20 ? 4 : 3;
    for (int k = first; k < first + count; ++k)
      EXPECT_NEAR(radiusOf(cm.mesh.nodes.col(el.nodes[std::size_t(k)])), kSkinRadius, 1e-9);
  }
}

TEST(ContinuumMesherTest, DepthIsClampedAndDefaultedWhereThereIsNoBone)
{
  // Raw depth 2 + |u|/2, no bone beyond u = 18 mm; clamped to [6, 12], 9 mm without bone.
  auto raw = [](const ChartPoint& c) {
    return c.x() > 18.0 ? std::numeric_limits<double>::quiet_NaN() : 2.0 + 0.5 * std::abs(c.x());
  };
  auto expected = [](const ChartPoint& c) {
    if (c.x() > 18.0)
      return 9.0;
    return std::min(12.0, std::max(6.0, 2.0 + 0.5 * std::abs(c.x())));
  };
  ContinuumMeshOptions options;
  options.layerCount = 2;
  options.minDepth = 6.0;
  options.maxDepth = 12.0;
  options.noBoneDepth = 9.0;
  const SurfaceMesh surface = lensMesh();
  const ContinuumMesh cm = meshContinuum(surface, lensSutures(), cylinderGeometry(raw), options);
  int clampedLow = 0, clampedHigh = 0, noBone = 0;
  for (std::size_t v = 0; v < surface.vertices.size(); ++v)
  {
    const ChartPoint& c = surface.vertices[v];
    EXPECT_DOUBLE_EQ(cm.vertexDepths[v], expected(c));
    EXPECT_NEAR(radiusOf(cm.mesh.nodes.col(cm.vertexColumns[v].back())), kSkinRadius - expected(c), 1e-9);
    clampedLow += expected(c) == 6.0 ? 1 : 0;
    clampedHigh += expected(c) == 12.0 && c.x() <= 18.0 ? 1 : 0;
    noBone += c.x() > 18.0 ? 1 : 0;
  }
  EXPECT_GT(clampedLow, 0);
  EXPECT_GT(clampedHigh, 0);
  EXPECT_GT(noBone, 0);
  EXPECT_GT(checkJacobians(cm.mesh).first, 0.0);

  options.noBoneDepth.reset();
  expectThrowsWith([&] { meshContinuum(surface, lensSutures(), cylinderGeometry(raw), options); },
                   "no bone under vertex");
  EXPECT_DOUBLE_EQ(effectiveTissueDepth(3.0, options), 6.0);
  EXPECT_DOUBLE_EQ(effectiveTissueDepth(30.0, options), 12.0);
  EXPECT_DOUBLE_EQ(effectiveTissueDepth(7.5, options), 7.5);
}

TEST(ContinuumMesherTest, SuturesFollowTheCornerRule)
{
  for (int layers : {1, 2, 4})
  {
    ContinuumMeshOptions options;
    options.layerCount = layers;
    // Slit: only the inner point 1 and its twin 3 meet (0 and 2 are corners),
    // plus the two edges: (2 N_l + 1) + 2 (N_l + 1) pairs.
    const ContinuumMesh slit = meshContinuum(slitMesh(), slitSutures(), cylinderGeometry(constantDepth), options);
    EXPECT_EQ(int(slit.sutures.size()), 4 * layers + 3);
    // Lens (Fig. 4.12): vertices 1 -> 5, 2 -> 4 (each named by two edge
    // pairs, sutured once), 0 and 3 are corners; three edge pairs.
    const ContinuumMesh lens = meshContinuum(lensMesh(), lensSutures(), cylinderGeometry(constantDepth), options);
    ASSERT_EQ(int(lens.sutures.size()), 2 * (2 * layers + 1) + 3 * (layers + 1));
    std::set<std::pair<int, int>> pairs;
    for (const Suture& s : lens.sutures)
      pairs.insert({s.node, s.target});
    EXPECT_EQ(pairs.size(), lens.sutures.size());
    for (int i = 0; i <= 2 * layers; ++i)
    {
      EXPECT_TRUE(pairs.count({lens.vertexColumns[1][std::size_t(i)], lens.vertexColumns[5][std::size_t(i)]}));
      EXPECT_TRUE(pairs.count({lens.vertexColumns[2][std::size_t(i)], lens.vertexColumns[4][std::size_t(i)]}));
    }
    using EdgePair = std::pair<std::pair<int, int>, std::pair<int, int>>;
    for (const auto& [a, b] : std::vector<EdgePair>{{{0, 1}, {0, 5}}, {{1, 2}, {5, 4}}, {{2, 3}, {4, 3}}})
    {
      const int ea = lens.edgeIndex(a.first, a.second), eb = lens.edgeIndex(b.first, b.second);
      ASSERT_GE(ea, 0);
      ASSERT_GE(eb, 0);
      for (int k = 0; k <= layers; ++k)
        EXPECT_TRUE(pairs.count(
          {lens.edgeColumns[std::size_t(ea)][std::size_t(k)], lens.edgeColumns[std::size_t(eb)][std::size_t(k)]}));
    }
    // The corner columns carry no suture.
    for (int corner : {0, 3})
      for (int node : lens.vertexColumns[std::size_t(corner)])
        for (const Suture& s : lens.sutures)
          EXPECT_TRUE(s.node != node && s.target != node);
  }
}

TEST(ContinuumMesherTest, ThreePointsClosingTogetherAreSuturedOnceEach)
{
  // A Z-plasty-like set where vertex 1 is named onto 5 and onto 4 (by
  // different pairs): all three columns close onto one node, no node is
  // sutured to two targets and there is no loop.
  ContinuumMeshOptions options;
  options.layerCount = 2;
  const std::vector<SutureEdgePair> pairs = {{{0, 1}, {0, 5}}, {{1, 2}, {4, 3}}};
  const ContinuumMesh cm = meshContinuum(lensMesh(), pairs, cylinderGeometry(constantDepth), options);
  std::set<int> slaves;
  for (const Suture& s : cm.sutures)
    EXPECT_TRUE(slaves.insert(s.node).second) << "node " << s.node << " sutured twice";
  for (const Suture& s : cm.sutures)
    EXPECT_FALSE(slaves.count(s.target)) << "chain through " << s.target;
  // Groups: {1,5,4} per level (2 sutures), {2,3} per level (1), edges (0,1)-(0,5) and (1,2)-(4,3) (1 each).
  EXPECT_EQ(int(cm.sutures.size()), 5 * 3 + 2 * 3);
  EXPECT_NO_THROW(resolveConstraints(cm.mesh, cm.constraints()));
}

TEST(ContinuumMesherTest, FixedNodesAreTheBoneLessTheSutured)
{
  const SurfaceMesh surface = lensMesh();
  const int nv = int(surface.vertices.size()), ne = annulusEdgeCount(surface);
  for (int layers : {1, 3})
  {
    ContinuumMeshOptions options;
    options.layerCount = layers;
    const ContinuumMesh cm = meshContinuum(surface, lensSutures(), cylinderGeometry(constantDepth), options);
    ASSERT_EQ(int(cm.boneNodes.size()), nv + ne);
    for (int node : cm.boneNodes)
      EXPECT_NEAR(radiusOf(cm.mesh.nodes.col(node)), 60.0, 1e-9);
    // Sutured bone nodes: vertices 1, 2, 4, 5 and the six sutured hole edges.
    EXPECT_EQ(int(cm.fixedNodes.size()), nv + ne - 10);
    std::set<int> sutured;
    for (const Suture& s : cm.sutures)
    {
      sutured.insert(s.node);
      sutured.insert(s.target);
    }
    std::vector<int> expected;
    for (int node : cm.boneNodes)
      if (!sutured.count(node))
        expected.push_back(node);
    EXPECT_EQ(cm.fixedNodes, expected);
    EXPECT_TRUE(std::is_sorted(cm.fixedNodes.begin(), cm.fixedNodes.end()));
    const Constraints c = cm.constraints();
    EXPECT_EQ(c.prescribed.size(), 3 * cm.fixedNodes.size());
    EXPECT_EQ(c.sutures.size(), cm.sutures.size());

    // Clamped rim: the 14 outer vertices and 14 outer edges, whole columns.
    options.rim = RimCondition::Clamped;
    const ContinuumMesh clamped = meshContinuum(surface, lensSutures(), cylinderGeometry(constantDepth), options);
    EXPECT_EQ(int(clamped.rimNodes.size()), 14 * (2 * layers + 1) + 14 * (layers + 1));
    for (int node : clamped.rimNodes)
      EXPECT_TRUE(std::binary_search(clamped.fixedNodes.begin(), clamped.fixedNodes.end(), node));
    // Bone-and-rim union: the 28 rim bone nodes are counted once.
    EXPECT_EQ(clamped.fixedNodes.size(), cm.fixedNodes.size() + clamped.rimNodes.size() - 28);
  }
}

TEST(ContinuumMesherTest, UnderminingReleasesTheBoneNodesOfTheBand)
{
  // The slit (-10, 0)-(10, 0): at 10 mm lie the ends of the cut line (4, 5)
  // and the rows v = ±10 over it (7, 8, 9 and 12, 13, 14); the corners
  // (6, 10, 11, 15) are √200 mm away.
  const SurfaceMesh surface = slitMesh();
  auto flagged = [](const std::vector<char>& band) {
    std::vector<int> v;
    for (std::size_t i = 0; i < band.size(); ++i)
      if (band[i])
        v.push_back(int(i));
    return v;
  };
  EXPECT_EQ(flagged(underminingBand(surface, slitSutures(), 0.0)), std::vector<int>{});
  EXPECT_EQ(flagged(underminingBand(surface, slitSutures(), 9.9)), (std::vector<int>{0, 1, 2, 3}));
  const std::vector<char> band = underminingBand(surface, slitSutures(), 10.0);
  EXPECT_EQ(flagged(band), (std::vector<int>{0, 1, 2, 3, 4, 5, 7, 8, 9, 12, 13, 14}));
  expectThrowsWith([&] { underminingBand(surface, slitSutures(), -1.0); }, "undermining width");

  for (int layers : {1, 2})
  {
    ContinuumMeshOptions options;
    options.layerCount = layers;
    const ContinuumMesh held = meshContinuum(surface, slitSutures(), cylinderGeometry(constantDepth), options);
    options.underminedVertices = band;
    const ContinuumMesh freed = meshContinuum(surface, slitSutures(), cylinderGeometry(constantDepth), options);
    EXPECT_TRUE(held.underminedNodes.empty());
    EXPECT_EQ(freed.mesh.nodes, held.mesh.nodes);
    EXPECT_EQ(freed.boneNodes, held.boneNodes);
    ASSERT_EQ(freed.sutures.size(), held.sutures.size());
    // 12 vertices and the 18 of the 26 edges that touch none of the corners.
    ASSERT_EQ(freed.underminedNodes.size(), 30u);
    for (int v : flagged(band))
      EXPECT_TRUE(std::binary_search(freed.underminedNodes.begin(), freed.underminedNodes.end(),
                                     freed.vertexColumns[std::size_t(v)].back()));
    // 42 bone nodes: the 6 sutured (vertices 1, 3 and the 4 slit edges) are
    // in the band; the 12 of the corners and their 8 edges stay fixed.
    EXPECT_EQ(held.fixedNodes.size(), 36u);
    ASSERT_EQ(freed.fixedNodes.size(), 12u);
    for (int node : freed.fixedNodes)
    {
      EXPECT_TRUE(std::binary_search(held.fixedNodes.begin(), held.fixedNodes.end(), node));
      EXPECT_FALSE(std::binary_search(freed.underminedNodes.begin(), freed.underminedNodes.end(), node));
    }
    EXPECT_EQ(freed.constraints().prescribed.size(), 3 * freed.fixedNodes.size());

    // A clamped rim holds the tissue beyond the mesh, undermined or not.
    options.rim = RimCondition::Clamped;
    const ContinuumMesh clamped = meshContinuum(surface, slitSutures(), cylinderGeometry(constantDepth), options);
    for (int node : clamped.rimNodes)
      EXPECT_TRUE(std::binary_search(clamped.fixedNodes.begin(), clamped.fixedNodes.end(), node));
  }
  ContinuumMeshOptions wrong;
  wrong.underminedVertices = {1, 1};
  expectThrowsWith([&] { meshContinuum(surface, slitSutures(), cylinderGeometry(constantDepth), wrong); },
                   "undermining flags");
}

TEST(ContinuumMesherTest, LensClosureMeetsAndIsMirrorSymmetric)
{
  // Skin 2 mm, fat 5 mm, the rest muscle; depth varies in u and v^2 so the
  // cylinder's mirror z -> -z is the only symmetry.
  auto depth = [](const ChartPoint& c) { return 16.0 + 2.0 * std::sin(c.x() / 20.0) + 0.01 * c.y() * c.y(); };
  ContinuumMeshOptions options;
  options.layerCount = 3;
  options.layerFractions = {0.15, 0.35, 0.5};
  options.layerRegions = {0, 1, 2};
  const ContinuumMesh cm = meshContinuum(lensMesh(), lensSutures(), cylinderGeometry(depth), options);
  const MaterialTable materials = {{0, {0.5, 0.45, 1e-9}}, {1, {0.02, 0.45, 1e-9}}, {2, {0.1, 0.45, 1e-9}}};
  LinearStaticAnalysis analysis(cm.mesh, materials, cm.constraints());
  ASSERT_EQ(analysis.prepare(), SolverStatus::Success) << analysis.message();
  const Eigen::VectorXd u = analysis.solve(LoadCase{});
  const Eigen::Index n = cm.mesh.nodeCount();
  auto deformed = [&](int node) { return Eigen::Vector3d(cm.mesh.nodes.col(node) + u.segment<3>(3 * node)); };

  double gap = 0.0;
  for (const Suture& s : cm.sutures)
    gap = std::max(gap, (deformed(s.node) - deformed(s.target)).norm());
  EXPECT_LT(gap, 1e-9);
  for (int node : cm.fixedNodes)
    EXPECT_EQ(u.segment<3>(3 * node).norm(), 0.0);
  // The wound closed: the inner points' 3 mm offsets are taken up.
  const double uMax = u.cwiseAbs().maxCoeff();
  EXPECT_GT(uMax, 1.0);
  EXPECT_NEAR(deformed(cm.vertexColumns[1][0]).z(), 0.0, 1e-9);

  // Mirror symmetry: node j at (x, y, -z) of node i has (ux, uy, -uz).
  int matched = 0;
  double asymmetry = 0.0;
  for (Eigen::Index i = 0; i < n; ++i)
  {
    const Eigen::Vector3d xi = cm.mesh.nodes.col(i);
    const Eigen::Vector3d mirror(xi.x(), xi.y(), -xi.z());
    Eigen::Index j = -1;
    for (Eigen::Index k = 0; k < n; ++k)
      if ((cm.mesh.nodes.col(k) - mirror).norm() < 1e-9)
      {
        ASSERT_EQ(j, -1) << "coincident nodes";
        j = k;
      }
    ASSERT_GE(j, 0) << "node " << i << " has no mirror";
    const Eigen::Vector3d ui = u.segment<3>(3 * i), uj = u.segment<3>(3 * j);
    const double d = (Eigen::Vector3d(uj.x(), uj.y(), -uj.z()) - ui).norm();
    EXPECT_LT(d, 1e-9 * uMax) << "node " << i;
    asymmetry = std::max(asymmetry, d / uMax);
    ++matched;
  }
  EXPECT_EQ(matched, n);
  std::cout << "lens closure: " << n << " nodes, " << cm.mesh.elements.size() << " elements, " << cm.sutures.size()
            << " sutures, max |u| = " << uMax << " mm, largest suture gap " << gap << " mm, largest relative asymmetry "
            << asymmetry << "\n";
}

/// A flat slab whose skin is the plane through the origin spanned by e1
/// (chart u) and e2 (chart v), tilted about two axes so its normal n = e1 x
/// e2 is no coordinate axis; the bone 12 mm below, along -n.
struct TiltedSlab
{
  Eigen::Vector3d e1, e2, n;
};

TiltedSlab tiltedSlab()
{
  const Eigen::Matrix3d r =
    (Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitY()))
      .toRotationMatrix();
  return {r.col(0), r.col(1), r.col(2)};
}

TissueGeometry slabGeometry(const TiltedSlab& slab)
{
  TissueGeometry g;
  g.skinPoint = [slab](const ChartPoint& c) { return Eigen::Vector3d(c.x() * slab.e1 + c.y() * slab.e2); };
  g.tissueDepth = [](const ChartPoint&) { return 12.0; };
  g.inwardDirection = [slab](const ChartPoint&) { return Eigen::Vector3d(-slab.n); };
  return g;
}

TEST(ContinuumMesherTest, UnderminedTissueSlidesOnTheDeepPlane)
{
  // The lens excision closed on a tilted slab undermined 8 mm around the
  // wound: the freed deep face moves along the plane and not off it, in the
  // linear solve and in large deformation (the plane's normal is known in
  // closed form here, not taken from the mesher). Left free instead, the
  // same nodes leave the plane.
  const TiltedSlab slab = tiltedSlab();
  const SurfaceMesh surface = lensMesh();
  ContinuumMeshOptions options;
  options.layerCount = 2;
  options.layerFractions = {0.3, 0.7};
  options.layerRegions = {0, 1};
  options.underminedVertices = underminingBand(surface, lensSutures(), 8.0);
  const ContinuumMesh sliding = meshContinuum(surface, lensSutures(), slabGeometry(slab), options);
  ASSERT_FALSE(sliding.slidingNodes.empty());
  EXPECT_LE(sliding.slidingNodes.size(), sliding.underminedNodes.size());
  for (const SlidingNode& s : sliding.slidingNodes)
  {
    EXPECT_NEAR(std::abs(s.normal.dot(slab.n)), 1.0, 1e-12) << "node " << s.node;
    EXPECT_FALSE(std::binary_search(sliding.fixedNodes.begin(), sliding.fixedNodes.end(), s.node));
  }
  EXPECT_EQ(sliding.constraints().equations.size(), sliding.slidingNodes.size());

  const MaterialTable linear = {{0, {0.15, 0.45, 1e-9}}, {1, {0.02, 0.45, 1e-9}}};
  auto normalAndTangential = [&](const ContinuumMesh& cm, const Eigen::VectorXd& u) {
    double normal = 0.0, tangential = 0.0;
    for (const SlidingNode& s : sliding.slidingNodes) // the same nodes in both meshes
    {
      const Eigen::Vector3d d = u.segment<3>(3 * Eigen::Index(s.node));
      normal = std::max(normal, std::abs(d.dot(slab.n)));
      tangential = std::max(tangential, (d - d.dot(slab.n) * slab.n).norm());
    }
    EXPECT_EQ(cm.mesh.nodes, sliding.mesh.nodes);
    return std::pair{normal, tangential};
  };

  LinearStaticAnalysis small(sliding.mesh, linear, sliding.constraints());
  ASSERT_EQ(small.prepare(), SolverStatus::Success) << small.message();
  const Eigen::VectorXd u = small.solve(LoadCase{});
  const double uMax = u.cwiseAbs().maxCoeff();
  const auto [normal, tangential] = normalAndTangential(sliding, u);
  EXPECT_GT(uMax, 1.0);
  EXPECT_LT(normal, 1e-10 * uMax);
  EXPECT_GT(tangential, 0.05 * uMax);

  HyperelasticTable neoHookean;
  for (const auto& [region, m] : linear)
    neoHookean[region] = HyperelasticMaterial::fromLinear(HyperelasticLaw::NeoHookean, m);
  NonlinearStaticAnalysis large(sliding.mesh, neoHookean, sliding.constraints());
  IncrementControl control;
  control.initial = 0.25;
  const NonlinearResult r = large.solve(LoadCase{}, control);
  ASSERT_EQ(r.status, NonlinearStatus::Converged) << r.message;
  const auto [normalLarge, tangentialLarge] = normalAndTangential(sliding, r.displacements);
  EXPECT_LT(normalLarge, 1e-10 * uMax);
  EXPECT_GT(tangentialLarge, 0.05 * uMax);

  options.underminedBase = UnderminedBase::Free;
  const ContinuumMesh free = meshContinuum(surface, lensSutures(), slabGeometry(slab), options);
  EXPECT_TRUE(free.slidingNodes.empty());
  EXPECT_EQ(free.underminedNodes, sliding.underminedNodes);
  LinearStaticAnalysis loose(free.mesh, linear, free.constraints());
  ASSERT_EQ(loose.prepare(), SolverStatus::Success) << loose.message();
  const auto [normalFree, tangentialFree] = normalAndTangential(free, loose.solve(LoadCase{}));
  EXPECT_GT(normalFree, 1e-3 * uMax);
  std::cout << "sliding: " << sliding.slidingNodes.size() << " of " << sliding.underminedNodes.size()
            << " undermined nodes slide; max |u| " << uMax << " mm; on the deep plane |u.n| " << normal << " (linear), "
            << normalLarge << " (large deformation), tangential " << tangential << " mm; left free |u.n| " << normalFree
            << " mm, tangential " << tangentialFree << " mm\n";
}

/// Flat skin z = 0 over the chart, the bone `depth` mm under it: every
/// element is straight-sided, so volumes are exact.
TissueGeometry flatGeometry(double depth)
{
  TissueGeometry g;
  g.skinPoint = [](const ChartPoint& c) { return Eigen::Vector3d(c.x(), c.y(), 0.0); };
  g.tissueDepth = [depth](const ChartPoint&) { return depth; };
  g.inwardDirection = [](const ChartPoint&) { return Eigen::Vector3d(0.0, 0.0, -1.0); };
  return g;
}

double shoelaceArea(const std::vector<ChartPoint>& points, int count)
{
  double sum = 0.0;
  for (int i = 0; i < count; ++i)
  {
    const ChartPoint& a = points[std::size_t(i)];
    const ChartPoint& b = points[std::size_t((i + 1) % count)];
    sum += a.x() * b.y() - a.y() * b.x();
  }
  return std::abs(0.5 * sum);
}

TEST(ContinuumMesherTest, APartialCutSharesTheTwinsBelowIt)
{
  // The slit cut through the top layer of three: twin 3 of vertex 1 shares
  // its column from the cut's root (index 2) down, and so do the edges
  // (0, 1) / (0, 3) and (1, 2) / (3, 2) from level 1 down.
  const SurfaceMesh m = slitMesh();
  ContinuumMeshOptions options;
  options.layerCount = 3;
  options.cutLayers = 1;
  const ContinuumMesh cm = meshContinuum(m, slitSutures(), cylinderGeometry(constantDepth), options);
  ContinuumMeshOptions fullOptions;
  fullOptions.layerCount = 3;
  const ContinuumMesh full = meshContinuum(m, slitSutures(), cylinderGeometry(constantDepth), fullOptions);
  const int merged = 5 + 3 + 3; // vertex column indices 2..6, two edges' levels 1..3
  EXPECT_EQ(cm.mesh.nodeCount(), full.mesh.nodeCount() - merged);
  EXPECT_EQ(cm.mesh.elements.size(), full.mesh.elements.size()); // a slit has no floor
  for (int i = 0; i <= 6; ++i)
  {
    if (i < 2)
      EXPECT_NE(cm.vertexColumns[1][std::size_t(i)], cm.vertexColumns[3][std::size_t(i)]) << i;
    else
      EXPECT_EQ(cm.vertexColumns[1][std::size_t(i)], cm.vertexColumns[3][std::size_t(i)]) << i;
  }
  const int e01 = cm.edgeIndex(0, 1), e03 = cm.edgeIndex(0, 3);
  ASSERT_GE(e01, 0);
  ASSERT_GE(e03, 0);
  EXPECT_NE(cm.edgeColumns[std::size_t(e01)][0], cm.edgeColumns[std::size_t(e03)][0]);
  for (int level = 1; level <= 3; ++level)
    EXPECT_EQ(cm.edgeColumns[std::size_t(e01)][std::size_t(level)],
              cm.edgeColumns[std::size_t(e03)][std::size_t(level)]);
  // Sutures only in the layer cut: vertex 3 onto 1 at column indices 0, 1
  // and the two edges' skin level; nothing at the root or below.
  EXPECT_EQ(cm.sutures.size(), 4u);
  std::set<int> below;
  for (int v : {1, 3})
    for (int i = 2; i <= 6; ++i)
      below.insert(cm.vertexColumns[std::size_t(v)][std::size_t(i)]);
  for (const Suture& s : cm.sutures)
    EXPECT_EQ(below.count(s.node) + below.count(s.target), 0u);
  // Every node in some element; the bone nodes listed once each.
  std::vector<int> uses(std::size_t(cm.mesh.nodeCount()), 0);
  for (const auto& el : cm.mesh.elements)
    for (int node : el.nodes)
      if (node >= 0)
        ++uses[std::size_t(node)];
  EXPECT_EQ(std::count(uses.begin(), uses.end(), 0), 0);
  EXPECT_EQ(std::set<int>(cm.boneNodes.begin(), cm.boneNodes.end()).size(), cm.boneNodes.size());
  EXPECT_EQ(int(cm.boneNodes.size()), int(m.vertices.size()) - 1 + int(cm.edges.size()) - 2);
  checkJacobians(cm.mesh);
}

TEST(ContinuumMesherTest, APartialExcisionKeepsTheFloorAndTheVolumesAreExact)
{
  // The lens excision on flat skin, 12 mm deep, cut through the skin layer
  // (15 % of the depth) of three: the tissue kept is the region less the
  // lens over the top layer; the excised tissue is the lens over that layer.
  const SurfaceMesh m = lensMesh();
  const double depth = 12.0;
  ContinuumMeshOptions options;
  options.layerCount = 3;
  options.layerFractions = {0.15, 0.35, 0.5};
  options.cutLayers = 1;
  const ContinuumMesh cm = meshContinuum(m, lensSutures(), flatGeometry(depth), options);
  const double lens = shoelaceArea(m.vertices, m.holeVertexCount);
  const double region = 50.0 * 30.0;
  const std::size_t floorTriangles = std::size_t(m.holeVertexCount - 2);
  EXPECT_EQ(cm.mesh.elements.size(), 3 * m.polygons.size() + 2 * floorTriangles);
  const auto [minDet, volume] = checkJacobians(cm.mesh);
  EXPECT_GT(minDet, 0.0);
  const double kept = (region - lens) * depth + lens * depth * 0.85;
  EXPECT_NEAR(volume, kept, 1e-10 * kept);
  EXPECT_NEAR(meshVolume(cm.mesh), kept, 1e-10 * kept);

  const ContinuumMesh excised = meshExcisedTissue(m, flatGeometry(depth), options);
  EXPECT_EQ(excised.mesh.elements.size(), floorTriangles);
  EXPECT_NEAR(meshVolume(excised.mesh), lens * depth * 0.15, 1e-12 * lens * depth);
  // Full thickness: the whole lens down to the bone, in all three layers.
  options.cutLayers = 0;
  const ContinuumMesh whole = meshExcisedTissue(m, flatGeometry(depth), options);
  EXPECT_EQ(whole.mesh.elements.size(), 3 * floorTriangles);
  EXPECT_NEAR(meshVolume(whole.mesh), lens * depth, 1e-12 * lens * depth);
  // A slit removes nothing.
  EXPECT_TRUE(meshExcisedTissue(slitMesh(), flatGeometry(depth), options).mesh.elements.empty());
}

TEST(ContinuumMesherTest, TheExcisedBoxHasItsAnalyticVolume)
{
  // A 16 x 8 mm box excision on flat skin over a bone 9 mm down, its sides
  // refined every 2 mm, inside a 40 x 20 mm region of quadrilaterals whose
  // inner corners are the box's points: the excised volume is 16 * 8 * 9 mm³.
  SurfaceMesh m;
  std::vector<ChartPoint>& v = m.vertices;
  for (int i = 0; i < 8; ++i)
    v.push_back({-8.0 + 2 * i, -4.0}); // clockwise seen from the skin: along the bottom
  for (int i = 0; i < 4; ++i)
    v.push_back({8.0, -4.0 + 2 * i});
  for (int i = 0; i < 8; ++i)
    v.push_back({8.0 - 2 * i, 4.0});
  for (int i = 0; i < 4; ++i)
    v.push_back({-8.0, 4.0 - 2 * i});
  std::reverse(v.begin(), v.end()); // the hole loop runs clockwise
  m.holeVertexCount = int(v.size());
  // A ring of quads from each loop vertex to its point scaled out 2.5 times.
  const int n = m.holeVertexCount;
  for (int i = 0; i < n; ++i)
    v.push_back(2.5 * v[std::size_t(i)]);
  for (int i = 0; i < n; ++i)
  {
    const int j = (i + 1) % n;
    m.polygons.push_back({i, j, n + j, n + i});
  }
  ContinuumMeshOptions options;
  options.layerCount = 2;
  const ContinuumMesh excised = meshExcisedTissue(m, flatGeometry(9.0), options);
  EXPECT_NEAR(meshVolume(excised.mesh), 16.0 * 8.0 * 9.0, 1e-10);
  // And the mesh around it with the box's floor kept under a half-depth cut.
  options.cutLayers = 1;
  const ContinuumMesh cm = meshContinuum(m, {}, flatGeometry(9.0), options);
  const double ring = (2.5 * 2.5 - 1.0) * 16.0 * 8.0;
  EXPECT_NEAR(meshVolume(cm.mesh), ring * 9.0 + 16.0 * 8.0 * 4.5, 1e-9);
}

TEST(ContinuumMesherTest, APartialCutClosesHarderThanAFullOne)
{
  // The lens closed with its cut through one layer of three and through all
  // three: the sutured nodes meet either way, no rigid-body freedom is left,
  // and the tissue left under a partial cut holds the cut layer's base in
  // place, so the skin's sutures pull harder (sum of |K U| at the sutured
  // nodes on the skin).
  auto depth = [](const ChartPoint&) { return 12.0; };
  const MaterialTable materials = {{0, {0.15, 0.45, 1e-9}}, {1, {0.01, 0.45, 1e-9}}, {2, {0.05, 0.45, 1e-9}}};
  double pull[2] = {0.0, 0.0};
  for (int cutLayers : {0, 1})
  {
    ContinuumMeshOptions options;
    options.layerCount = 3;
    options.cutLayers = cutLayers;
    const ContinuumMesh cm = meshContinuum(lensMesh(), lensSutures(), cylinderGeometry(depth), options);
    LinearStaticAnalysis analysis(cm.mesh, materials, cm.constraints());
    ASSERT_EQ(analysis.prepare(), SolverStatus::Success) << analysis.message();
    const Eigen::VectorXd u = analysis.solve(LoadCase{});
    const Eigen::VectorXd f = analysis.internalForces(u);
    double gap = 0.0;
    for (const Suture& s : cm.sutures)
    {
      gap = std::max(gap, (cm.mesh.nodes.col(s.node) + u.segment<3>(3 * s.node) - cm.mesh.nodes.col(s.target) -
                           u.segment<3>(3 * s.target))
                            .norm());
      bool onSkin = false;
      for (const auto* columns : {&cm.vertexColumns, &cm.edgeColumns})
        for (const auto& column : *columns)
          onSkin = onSkin || column.front() == s.node;
      if (onSkin)
        pull[cutLayers] += f.segment<3>(3 * s.node).norm();
    }
    EXPECT_LT(gap, 1e-9);
  }
  EXPECT_GT(pull[1], 1.2 * pull[0]);
  std::cout << "lens closure force on the skin's sutures, cut through 3 of 3 layers: " << pull[0]
            << " N, through 1 of 3: " << pull[1] << " N\n";
}

TEST(ContinuumMesherTest, BadInputIsRejectedWithAClearMessage)
{
  const TissueGeometry geometry = cylinderGeometry(constantDepth);
  {
    SurfaceMesh m = slitMesh();
    m.vertices.push_back({-30, 0});
    m.polygons[1] = {4, 7, 6, 16, 11}; // not a valid cover, but the size is rejected first
    expectThrowsWith([&] { meshContinuum(m, {}, geometry); }, "surface polygon 1 has 5 vertices");
  }
  {
    // (0, 9) is shared by two polygons; (6, 8) is on the border, but the rim's.
    expectThrowsWith([&] { meshContinuum(lensMesh(), {{{0, 9}, {0, 15}}}, geometry); }, "not a border edge");
    expectThrowsWith([&] { meshContinuum(lensMesh(), {{{0, 1}, {6, 8}}}, geometry); }, "edge (6, 8)");
    expectThrowsWith([&] { meshContinuum(lensMesh(), {{{0, 1}, {1, 0}}}, geometry); }, "onto itself");
  }
  {
    ContinuumMeshOptions options;
    options.layerCount = 0;
    expectThrowsWith([&] { meshContinuum(slitMesh(), slitSutures(), geometry, options); }, "at least one layer");
    options.layerCount = 2;
    options.layerFractions = {0.3, 0.3};
    expectThrowsWith([&] { meshContinuum(slitMesh(), slitSutures(), geometry, options); }, "sum to");
  }
  {
    // Bone above the skin at u < -12 mm: the depth is negative there.
    const TissueGeometry inverted = cylinderGeometry([](const ChartPoint& c) { return c.x() < -12.0 ? -1.0 : 20.0; });
    expectThrowsWith([&] { meshContinuum(slitMesh(), slitSutures(), inverted); }, "bone must lie below the skin");
    const TissueGeometry flat = cylinderGeometry([](const ChartPoint&) { return 0.0; });
    expectThrowsWith([&] { meshContinuum(slitMesh(), slitSutures(), flat); }, "tissue depth at vertex 0");
    ContinuumMeshOptions options;
    options.noBoneDepth = -5.0;
    expectThrowsWith([&] { meshContinuum(slitMesh(), slitSutures(), geometry, options); }, "no bone must be positive");
  }
  {
    SurfaceMesh m = slitMesh();
    std::reverse(m.polygons[3].begin(), m.polygons[3].end());
    expectThrowsWith([&] { meshContinuum(m, {}, geometry); }, "not counter-clockwise");
  }
}

} // namespace
} // namespace caps::fem
