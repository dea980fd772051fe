// The interior nodes' optimisation (fem/InteriorNodeOptimization.h) on flat
// skin over a bone with a diagonal cliff, where radial columns make sheared
// elements: checked against what it must not change (the skin, the rim, the
// bone surface, each node's depth, the body's volume against the analytic
// integral of the depth, coincident nodes of an undermined plane) and
// against checkMeshQuality(), which it does not use to decide its moves.

#include "fem/ContinuumMesher.h"
#include "fem/ElementQuality.h"
#include "fem/InteriorNodeOptimization.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <vector>

namespace caps::fem {
namespace {

constexpr double kHalfWidth = 12.0; // mm
constexpr int kCells = 12;

/// Tissue depth under chart point c: 10 mm, with a cliff of 16 mm across
/// the diagonal u + v/2 = 0 about 4 mm wide (slope up to 2, 63 degrees).
double cliffDepth(const ChartPoint& c)
{
  return 10.0 + 8.0 * std::tanh((c.x() + 0.5 * c.y()) / 2.0);
}

/// Flat skin z = 0, the bone cliffDepth() straight below it.
TissueGeometry cliffGeometry()
{
  TissueGeometry g;
  g.skinPoint = [](const ChartPoint& c) { return Eigen::Vector3d(c.x(), c.y(), 0.0); };
  g.tissueDepth = cliffDepth;
  g.inwardDirection = [](const ChartPoint&) { return Eigen::Vector3d(0.0, 0.0, -1.0); };
  return g;
}

/// A square of kCells x kCells quadrilaterals over [-kHalfWidth, kHalfWidth]^2, no hole.
SurfaceMesh squareGrid()
{
  SurfaceMesh m;
  const double h = 2.0 * kHalfWidth / kCells;
  const auto id = [](int i, int j) { return j * (kCells + 1) + i; };
  for (int j = 0; j <= kCells; ++j)
    for (int i = 0; i <= kCells; ++i)
      m.vertices.emplace_back(-kHalfWidth + i * h, -kHalfWidth + j * h);
  for (int j = 0; j < kCells; ++j)
    for (int i = 0; i < kCells; ++i)
      m.polygons.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
  for (int i = 0; i < kCells; ++i)
    m.outerBorder.push_back(id(i, 0));
  for (int j = 0; j < kCells; ++j)
    m.outerBorder.push_back(id(kCells, j));
  for (int i = kCells; i > 0; --i)
    m.outerBorder.push_back(id(i, kCells));
  for (int j = kCells; j > 0; --j)
    m.outerBorder.push_back(id(0, j));
  return m;
}

ContinuumMeshOptions threeLayers(bool optimize)
{
  ContinuumMeshOptions options;
  options.layerCount = 3;
  options.layerFractions = {0.2, 0.4, 0.4};
  options.optimizeInteriorNodes = optimize;
  return options;
}

bool onTheRim(const ChartPoint& c)
{
  return std::abs(std::abs(c.x()) - kHalfWidth) < 1e-9 || std::abs(std::abs(c.y()) - kHalfWidth) < 1e-9;
}

TEST(InteriorNodeOptimization, UprightElementsOverABoneCliffInTheSameBody)
{
  const SurfaceMesh surface = squareGrid();
  const ContinuumMesh placed = meshContinuum(surface, {}, cliffGeometry(), threeLayers(false));
  const ContinuumMesh moved = meshContinuum(surface, {}, cliffGeometry(), threeLayers(true));
  ASSERT_EQ(placed.mesh.nodeCount(), moved.mesh.nodeCount());
  ASSERT_EQ(placed.mesh.elements.size(), moved.mesh.elements.size());

  // Better by the checks' own measure, and reported as it was.
  const MeshQualityCheck before = checkMeshQuality(placed.mesh);
  const MeshQualityCheck after = checkMeshQuality(moved.mesh);
  const InteriorNodeOptimization& report = moved.nodeOptimization;
  EXPECT_GT(before.poorJacobian, 0) << "the cliff should shear the radial columns";
  EXPECT_EQ(report.poorElementsBefore, before.poorJacobian);
  EXPECT_DOUBLE_EQ(report.minScaledJacobianBefore, before.minScaledJacobian);
  EXPECT_LT(after.poorJacobian, before.poorJacobian);
  EXPECT_GE(after.minScaledJacobian, before.minScaledJacobian);
  EXPECT_GT(report.movedNodes, 0);
  EXPECT_GT(report.movableDeepNodes, 0);

  // The skin and the rim's columns stay; the bone's nodes stay on the bone;
  // the inner nodes keep their depth (they move across the vertical columns).
  for (std::size_t v = 0; v < surface.vertices.size(); ++v)
  {
    const auto& column = moved.vertexColumns[v];
    for (std::size_t i = 0; i < column.size(); ++i)
    {
      const Eigen::Vector3d was = placed.mesh.nodes.col(column[i]), is = moved.mesh.nodes.col(column[i]);
      if (i == 0 || onTheRim(surface.vertices[v]))
      {
        EXPECT_EQ(was, is) << "vertex " << v << " level " << i;
      }
      else if (i + 1 == column.size())
      {
        EXPECT_NEAR(is.z(), -cliffDepth(ChartPoint(is.x(), is.y())), 1e-9) << "bone node of vertex " << v;
      }
      else if (i % 2 == 0)
      {
        EXPECT_NEAR(is.z(), was.z(), 1e-9) << "vertex " << v << " level " << i;
      }
    }
  }
  for (std::size_t e = 0; e < moved.edges.size(); ++e) // the bone's mid-edge nodes too
  {
    const Eigen::Vector3d is = moved.mesh.nodes.col(moved.edgeColumns[e].back());
    EXPECT_NEAR(is.z(), -cliffDepth(ChartPoint(is.x(), is.y())), 1e-9) << "bone mid-edge node of edge " << e;
  }

  // The same body: both volumes against the integral of the depth (midpoint
  // rule on a fine grid), the moved mesh no further from it than 0.01 %.
  double exact = 0.0;
  const int n = 1200;
  const double d = 2.0 * kHalfWidth / n;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      exact += cliffDepth(ChartPoint(-kHalfWidth + (i + 0.5) * d, -kHalfWidth + (j + 0.5) * d)) * d * d;
  const double placedVolume = meshVolume(placed.mesh), movedVolume = meshVolume(moved.mesh);
  EXPECT_NEAR(movedVolume, exact, 1e-4 * exact);
  std::cout << "cliff: elements below 0.2 " << before.poorJacobian << " -> " << after.poorJacobian
            << ", smallest scaled Jacobian " << before.minScaledJacobian << " -> " << after.minScaledJacobian << ", "
            << report.movedNodes << " of " << report.movableNodes << " nodes moved (largest " << report.largestMove
            << " mm); volume " << placedVolume << " -> " << movedVolume << " mm^3, exact " << exact << "\n";
}

TEST(InteriorNodeOptimization, AnUnderminedPlaneStaysOnePlace)
{
  // A cut through the top layer with everything undermined: the raised
  // tissue's nodes on the plane and the ones beneath them are two nodes at
  // one place, and must move together (the sliding constraint relates them).
  const SurfaceMesh surface = squareGrid();
  ContinuumMeshOptions options = threeLayers(true);
  options.cutLayers = 1;
  options.underminedVertices.assign(surface.vertices.size(), 1);
  const ContinuumMesh moved = meshContinuum(surface, {}, cliffGeometry(), options);
  ASSERT_FALSE(moved.slidingNodes.empty());
  int pairsThatMoved = 0;
  const ContinuumMesh placed = meshContinuum(surface, {}, cliffGeometry(), [&] {
    ContinuumMeshOptions o = options;
    o.optimizeInteriorNodes = false;
    return o;
  }());
  for (const SlidingNode& s : moved.slidingNodes)
  {
    ASSERT_GE(s.beneath, 0);
    EXPECT_EQ(moved.mesh.nodes.col(s.node), moved.mesh.nodes.col(s.beneath)) << "node " << s.node;
    pairsThatMoved += moved.mesh.nodes.col(s.node) != placed.mesh.nodes.col(s.node);
  }
  EXPECT_GT(pairsThatMoved, 0);
  EXPECT_LE(checkMeshQuality(moved.mesh).poorJacobian, checkMeshQuality(placed.mesh).poorJacobian);
}

TEST(InteriorNodeOptimization, RefusesFlagsThatDoNotFitTheColumns)
{
  ContinuumMesh mesh = meshContinuum(squareGrid(), {}, cliffGeometry(), threeLayers(false));
  EXPECT_THROW(optimizeInteriorNodes(mesh, std::vector<char>(3, 0)), std::invalid_argument);
  DeepSurface deep;
  deep.pointUnder = [](const ChartPoint& c) { return Eigen::Vector3d(c.x(), c.y(), -cliffDepth(c)); };
  EXPECT_THROW(optimizeInteriorNodes(mesh, std::vector<char>(mesh.vertexColumns.size(), 0), &deep),
               std::invalid_argument);
}

} // namespace
} // namespace caps::fem
