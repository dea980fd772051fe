// Checks the 8-to-20 node interpolation functions (thesis eq. 4.16), the
// Gauss rules and the Jacobian check against independent answers: partition
// of unity, the Kronecker property, finite differences, exact integrals.

#include "fem/ElementGeometry.h"
#include "fem/Hex20Shape.h"
#include "fem/Quadrature.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

namespace caps::fem {
namespace {

std::vector<std::uint32_t> sampleMasks()
{
  std::vector<std::uint32_t> masks = {0u, Hex20Shape::kAllMidside, 0x001u, 0x800u, 0x0F0u, 0xF0Fu};
  std::mt19937 rng(7);
  for (int i = 0; i < 20; ++i)
    masks.push_back(rng() & Hex20Shape::kAllMidside);
  return masks;
}

std::vector<Eigen::Vector3d> samplePoints()
{
  std::vector<Eigen::Vector3d> p;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 30; ++i)
    p.emplace_back(u(rng), u(rng), u(rng));
  p.emplace_back(1.0, 1.0, 1.0);
  p.emplace_back(0.0, 0.0, 0.0);
  return p;
}

TEST(Hex20Shape, PartitionOfUnityForAnySubsetOfMidsideNodes)
{
  for (std::uint32_t mask : sampleMasks())
  {
    const Hex20Shape shape(mask);
    for (const auto& p : samplePoints())
    {
      ShapeVector h;
      ShapeDerivatives dh;
      shape.evaluate(p, h, dh);
      EXPECT_NEAR(h.sum(), 1.0, 1e-14) << "mask " << mask;
      EXPECT_LT(dh.colwise().sum().norm(), 1e-13) << "mask " << mask;
    }
  }
}

TEST(Hex20Shape, KroneckerPropertyAtPresentNodes)
{
  for (std::uint32_t mask : sampleMasks())
  {
    const Hex20Shape shape(mask);
    for (int node = 0; node < kHex20NodeCount; ++node)
    {
      if (!shape.hasNode(node))
        continue;
      ShapeVector h;
      shape.values(batheNaturalCoordinates(node), h);
      for (int k = 0; k < kHex20NodeCount; ++k)
      {
        const double expected = (k == node) ? 1.0 : 0.0;
        EXPECT_NEAR(h[k], expected, 1e-15) << "mask " << mask << " node " << node << " h_" << k;
      }
    }
  }
}

TEST(Hex20Shape, AbsentNodesHaveZeroFunctions)
{
  const Hex20Shape shape(0x0F0u); // nodes 12..15 present only
  EXPECT_EQ(shape.nodeCount(), 12);
  ShapeVector h;
  shape.values(Eigen::Vector3d(0.3, -0.2, 0.1), h);
  for (int k = 8; k < 20; ++k)
    if (!shape.hasNode(k))
    {
      EXPECT_EQ(h[k], 0.0);
    }
}

TEST(Hex20Shape, DerivativesMatchFiniteDifferences)
{
  const double eps = 1e-6;
  for (std::uint32_t mask : sampleMasks())
  {
    const Hex20Shape shape(mask);
    for (const auto& p : samplePoints())
    {
      ShapeVector h;
      ShapeDerivatives dh;
      shape.evaluate(p, h, dh);
      for (int d = 0; d < 3; ++d)
      {
        ShapeVector hp, hm;
        Eigen::Vector3d pp = p, pm = p;
        pp[d] += eps;
        pm[d] -= eps;
        shape.values(pp, hp);
        shape.values(pm, hm);
        const ShapeVector fd = (hp - hm) / (2 * eps);
        EXPECT_LT((fd - dh.col(d)).cwiseAbs().maxCoeff(), 1e-9) << "mask " << mask << " dir " << d;
      }
    }
  }
}

TEST(Hex20Shape, EightNodeElementIsTrilinear)
{
  const Hex20Shape shape(0u);
  const Eigen::Vector3d p(0.2, -0.7, 0.4);
  ShapeVector h;
  shape.values(p, h);
  for (int k = 0; k < 8; ++k)
  {
    const Eigen::Vector3d n = batheNaturalCoordinates(k);
    EXPECT_NEAR(h[k], (1 + n[0] * p[0]) * (1 + n[1] * p[1]) * (1 + n[2] * p[2]) / 8, 1e-15);
  }
}

TEST(Hex20Shape, ConnectivityWithAbsentNodesGivesMask)
{
  std::array<int, 20> nodes;
  for (int k = 0; k < 20; ++k)
    nodes[k] = k;
  nodes[9] = -1;
  nodes[19] = -1;
  const Hex20Shape shape = Hex20Shape::fromConnectivity(nodes);
  EXPECT_FALSE(shape.hasNode(9));
  EXPECT_FALSE(shape.hasNode(19));
  EXPECT_TRUE(shape.hasNode(8));
  EXPECT_EQ(shape.nodeCount(), 18);
}

TEST(Quadrature, GaussRulesIntegratePolynomialsExactly)
{
  for (int n : {2, 3})
  {
    const IntegrationRule& rule = gaussRule(n);
    ASSERT_EQ(int(rule.size()), n * n * n);
    double volume = 0.0, poly = 0.0;
    const int deg = 2 * n - 1; // exact up to this degree in each variable
    for (std::size_t q = 0; q < rule.size(); ++q)
    {
      const auto& p = rule.points[q];
      volume += rule.weights[q];
      poly += rule.weights[q] * std::pow(p[0], deg - 1) * std::pow(p[1], 2) * (1 + p[2]);
    }
    EXPECT_NEAR(volume, 8.0, 1e-14);
    // int x^(deg-1) dx = 2/deg (deg-1 even), int y^2 = 2/3, int (1+z) = 2.
    EXPECT_NEAR(poly, 2.0 / deg * 2.0 / 3.0 * 2.0, 1e-14) << n;
  }
  EXPECT_NEAR(gaussRule(3).points[0][0], -0.774596669241483, 1e-15); // Table 4.6
  EXPECT_THROW(gaussRule(5), std::invalid_argument);
}

ElementCoordinates unitCube(double scale = 1.0)
{
  ElementCoordinates x;
  for (int k = 0; k < 20; ++k)
    x.row(k) = scale * batheNaturalCoordinates(k).transpose();
  return x;
}

TEST(ElementGeometry, CubeJacobianAndWorldDerivatives)
{
  const Hex20Shape shape;
  PointGeometry g;
  evaluateGeometry(shape, unitCube(2.0), Eigen::Vector3d(0.1, 0.2, 0.3), 0, g);
  EXPECT_NEAR(g.detJ, 8.0, 1e-13);
  EXPECT_TRUE(g.world.isApprox(Eigen::Vector3d(0.2, 0.4, 0.6), 1e-14));
  EXPECT_TRUE(g.dhWorld.isApprox(0.5 * g.dhNatural, 1e-14));
}

TEST(ElementGeometry, InvertedElementIsNamedWithItsPosition)
{
  ElementCoordinates x = unitCube();
  x.col(2) *= -1.0; // mirror: left-handed
  PointGeometry g;
  try
  {
    evaluateGeometry(Hex20Shape(), x, gaussRule(3).points[0], 42, g);
    FAIL() << "no error";
  }
  catch (const ElementError& e)
  {
    EXPECT_EQ(e.element(), 42);
    const std::string m = e.what();
    EXPECT_NE(m.find("element 42"), std::string::npos) << m;
    EXPECT_NE(m.find("inverted"), std::string::npos) << m;
    EXPECT_NE(m.find("world"), std::string::npos) << m;
  }
}

TEST(ElementGeometry, CollapsedElementIsRejected)
{
  ElementCoordinates x = unitCube();
  x.col(2).setZero(); // flat
  PointGeometry g;
  EXPECT_THROW(evaluateGeometry(Hex20Shape(), x, Eigen::Vector3d::Zero(), 5, g), ElementError);
}

TEST(ElementGeometry, DegenerateWedgeIsValidAtGaussPointsAndZeroOnCollapsedEdge)
{
  // Collapse the face s = +1 onto the edge r = 0 (nodes 0, 1, 8 / 4, 5, 12 / 16, 17).
  ElementCoordinates x = unitCube();
  const int groups[3][3] = {{0, 1, 8}, {4, 5, 12}, {16, 17, 17}};
  for (const auto& grp : groups)
  {
    const Eigen::RowVector3d mid = 0.5 * (x.row(grp[0]) + x.row(grp[1]));
    for (int k : grp)
      x.row(k) = Eigen::RowVector3d(0.0, mid[1], mid[2]);
  }
  // Mid-side nodes on the slanted faces move to the new edge midpoints.
  x.row(9) = 0.5 * (x.row(0) + x.row(2));
  x.row(11) = 0.5 * (x.row(0) + x.row(3));
  x.row(13) = 0.5 * (x.row(4) + x.row(6));
  x.row(15) = 0.5 * (x.row(4) + x.row(7));
  PointGeometry g;
  double volume = 0.0;
  for (int n : {2, 3})
  {
    volume = 0.0;
    const IntegrationRule& rule = gaussRule(n);
    for (std::size_t q = 0; q < rule.size(); ++q)
    {
      evaluateGeometry(Hex20Shape(), x, rule.points[q], 0, g);
      EXPECT_GT(g.detJ, 0.0);
      volume += rule.weights[q] * g.detJ;
    }
    EXPECT_NEAR(volume, 4.0, 1e-12); // triangle of area 2 times height 2
  }
  evaluateGeometry(Hex20Shape(), x, Eigen::Vector3d(0.3, 1.0, 0.2), 0, g, false);
  EXPECT_NEAR(g.detJ, 0.0, 1e-14);
  EXPECT_THROW(evaluateGeometry(Hex20Shape(), x, Eigen::Vector3d(0.3, 1.0, 0.2), 0, g), ElementError);
}

} // namespace
} // namespace caps::fem
