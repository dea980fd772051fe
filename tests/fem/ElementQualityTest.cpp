// Element shape quality (elementQuality, checkMeshQuality) against the
// Verdict library's hexahedron metrics as VTK's vtkMeshQuality computes them
// (a second implementation), and against closed forms for prisms.

#include "fem/ElementQuality.h"

#include "fem/ElementShape.h"

#include "FemTestMeshes.h"

#include <vtkHexahedron.h>
#include <vtkMeshQuality.h>
#include <vtkNew.h>
#include <vtkPoints.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <random>

namespace caps::fem {
namespace {

using Map = std::function<Eigen::Vector3d(const Eigen::Vector3d&)>;

/// One element of @a kind whose every node sits at @a map of its natural
/// coordinates: straight-sided when @a map is the (tri)linear map of the
/// corners, so the corner metrics of Verdict apply to it.
Mesh oneElement(ElementKind kind, const Map& map)
{
  const ElementShape shape = kind == ElementKind::Wedge15 ? ElementShape::wedge15() : ElementShape(Hex20Shape());
  Mesh mesh;
  Element el;
  el.kind = kind;
  el.nodes.fill(-1);
  std::vector<Eigen::Vector3d> nodes;
  for (int slot = 0; slot < kHex20NodeCount; ++slot)
    if (shape.hasNode(slot))
    {
      el.nodes[std::size_t(slot)] = int(nodes.size());
      nodes.push_back(map(shape.naturalCoordinates(slot)));
    }
  mesh.nodes.resize(3, Eigen::Index(nodes.size()));
  for (std::size_t n = 0; n < nodes.size(); ++n)
    mesh.nodes.col(Eigen::Index(n)) = nodes[n];
  mesh.elements.push_back(el);
  return mesh;
}

/// The trilinear map of a brick with corners @a corner (VTK's order: the
/// bottom face counter-clockwise from (-1,-1,-1), then the top face).
Map trilinear(const std::array<Eigen::Vector3d, 8>& corner)
{
  return [corner](const Eigen::Vector3d& p) {
    static const int sign[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                   {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    for (int i = 0; i < 8; ++i)
      x +=
        corner[std::size_t(i)] * (1 + sign[i][0] * p.x()) * (1 + sign[i][1] * p.y()) * (1 + sign[i][2] * p.z()) / 8.0;
    return x;
  };
}

double verdictScaledJacobian(const std::array<Eigen::Vector3d, 8>& corner)
{
  vtkNew<vtkHexahedron> hex;
  for (int i = 0; i < 8; ++i)
  {
    hex->GetPointIds()->SetId(i, i);
    hex->GetPoints()->SetPoint(i, corner[std::size_t(i)].data());
  }
  return vtkMeshQuality::HexScaledJacobian(hex);
}

/// Longest over shortest of the brick's 12 edges, listed by hand. (Not
/// vtkMeshQuality::HexEdgeRatio: VTK 9.1's leaves out the edge from corner
/// 7 to corner 4 and returns 2.29 for a brick whose edges run from 1.44 to
/// 3.51 mm.)
double edgeRatioOf(const std::array<Eigen::Vector3d, 8>& corner)
{
  static const int edge[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                  {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  double shortest = 1e300, longest = 0.0;
  for (const auto& e : edge)
  {
    const double length = (corner[std::size_t(e[0])] - corner[std::size_t(e[1])]).norm();
    shortest = std::min(shortest, length);
    longest = std::max(longest, length);
  }
  return longest / shortest;
}

std::array<Eigen::Vector3d, 8> box(double a, double b, double c)
{
  std::array<Eigen::Vector3d, 8> corner;
  for (int i = 0; i < 8; ++i)
    corner[std::size_t(i)] = Eigen::Vector3d((i == 1 || i == 2 || i == 5 || i == 6) ? a : 0.0,
                                             (i == 2 || i == 3 || i == 6 || i == 7) ? b : 0.0, i >= 4 ? c : 0.0);
  return corner;
}

TEST(ElementQuality, DistortedBricksScoreAsVerdictScoresThem)
{
  std::mt19937 random(7);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  for (int trial = 0; trial < 50; ++trial)
  {
    SCOPED_TRACE(trial);
    std::array<Eigen::Vector3d, 8> corner = box(2.0, 3.0, 1.5);
    for (Eigen::Vector3d& c : corner)
      c += Eigen::Vector3d(jitter(random), jitter(random), 0.5 * jitter(random));
    const Mesh mesh = oneElement(ElementKind::Hex20, trilinear(corner));
    // Verdict takes the corners and the centre: the nodes and the one-point
    // rule here (the mid-side nodes of a straight-sided brick are never its
    // worst points at this distortion).
    const ElementQuality ours = elementQuality(mesh, 0, 1);
    EXPECT_NEAR(ours.scaledJacobian, verdictScaledJacobian(corner), 1e-12);
    EXPECT_NEAR(ours.edgeRatio, edgeRatioOf(corner), 1e-12);
    EXPECT_LE(elementQuality(mesh, 0, 3).scaledJacobian, ours.scaledJacobian + 1e-15);
  }
}

TEST(ElementQuality, CubesLongBricksAndInvertedBricks)
{
  const ElementQuality cube = elementQuality(oneElement(ElementKind::Hex20, trilinear(box(2.0, 2.0, 2.0))), 0);
  EXPECT_NEAR(cube.scaledJacobian, 1.0, 1e-14);
  EXPECT_NEAR(cube.edgeRatio, 1.0, 1e-14);
  const ElementQuality slab = elementQuality(oneElement(ElementKind::Hex20, trilinear(box(20.0, 2.0, 2.0))), 0);
  EXPECT_NEAR(slab.scaledJacobian, 1.0, 1e-14);
  EXPECT_NEAR(slab.edgeRatio, 10.0, 1e-12);
  // A brick sheared by 60 degrees: the angle between its edges at every
  // point is 30 degrees, so the scaled Jacobian is sin 30.
  std::array<Eigen::Vector3d, 8> sheared = box(2.0, 2.0, 2.0);
  for (int i = 4; i < 8; ++i)
    sheared[std::size_t(i)].x() += 2.0 * std::sqrt(3.0);
  EXPECT_NEAR(elementQuality(oneElement(ElementKind::Hex20, trilinear(sheared)), 0).scaledJacobian, 0.5, 1e-12);
  // One corner pushed through the opposite face: negative.
  std::array<Eigen::Vector3d, 8> inverted = box(2.0, 2.0, 2.0);
  inverted[6] = Eigen::Vector3d(0.5, 0.5, -0.5);
  EXPECT_LT(elementQuality(oneElement(ElementKind::Hex20, trilinear(inverted)), 0).scaledJacobian, 0.0);
}

/// A prism on triangle (a, b, c) of height h.
Map prism(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c, double h)
{
  return [=](const Eigen::Vector3d& p) {
    const Eigen::Vector2d xy = (1.0 - p.x() - p.y()) * a + p.x() * b + p.y() * c;
    return Eigen::Vector3d(xy.x(), xy.y(), 0.5 * h * (p.z() + 1.0));
  };
}

// A right prism's scaled Jacobian is 2/sqrt(3) times the sine of its
// triangle's smallest angle: 1 equilateral, 0.816 right isosceles.
TEST(ElementQuality, PrismsScoreBySineOfTheirSmallestAngle)
{
  const double s3 = std::sqrt(3.0);
  const ElementQuality equilateral =
    elementQuality(oneElement(ElementKind::Wedge15, prism({0, 0}, {2, 0}, {1, s3}, 2.0)), 0);
  EXPECT_NEAR(equilateral.scaledJacobian, 1.0, 1e-12);
  EXPECT_NEAR(equilateral.edgeRatio, 1.0, 1e-12);
  const ElementQuality right = elementQuality(oneElement(ElementKind::Wedge15, prism({0, 0}, {2, 0}, {0, 2}, 1.0)), 0);
  EXPECT_NEAR(right.scaledJacobian, 2.0 / s3 * std::sin(M_PI / 4.0), 1e-12);
  EXPECT_NEAR(right.edgeRatio, std::sqrt(8.0) / 1.0, 1e-12);
  // A sliver: angles 10, 10, 160 degrees.
  const double t = std::tan(10.0 * M_PI / 180.0);
  const ElementQuality sliver = elementQuality(oneElement(ElementKind::Wedge15, prism({0, 0}, {2, 0}, {1, t}, 1.0)), 0);
  EXPECT_NEAR(sliver.scaledJacobian, 2.0 / s3 * std::sin(10.0 * M_PI / 180.0), 1e-12);
}

TEST(ElementQuality, AMeshNamesItsWorstElementsAndCountsThoseOutsideTheLimits)
{
  Mesh mesh = oneElement(ElementKind::Hex20, trilinear(box(2.0, 2.0, 2.0)));
  std::array<Eigen::Vector3d, 8> thin = box(30.0, 2.0, 2.0);
  for (Eigen::Vector3d& c : thin)
    c.x() += 10.0;
  test::appendMesh(mesh, oneElement(ElementKind::Hex20, trilinear(thin)));
  std::array<Eigen::Vector3d, 8> sheared = box(2.0, 2.0, 2.0);
  for (int i = 4; i < 8; ++i)
    sheared[std::size_t(i)].x() += 20.0; // edges at 84 degrees from upright: sin 5.7 = 0.0995
  for (Eigen::Vector3d& c : sheared)
    c.y() += 10.0;
  test::appendMesh(mesh, oneElement(ElementKind::Hex20, trilinear(sheared)));
  const MeshQualityCheck check = checkMeshQuality(mesh);
  EXPECT_EQ(check.elements, 3);
  EXPECT_EQ(check.worstJacobianElement, 2);
  EXPECT_NEAR(check.minScaledJacobian, 2.0 / std::sqrt(404.0), 1e-12);
  EXPECT_NEAR(check.worstJacobianAt.y(), 11.0, 1.0);
  EXPECT_EQ(check.worstEdgeRatioElement, 1);
  EXPECT_NEAR(check.maxEdgeRatio, 15.0, 1e-12);
  EXPECT_NEAR(check.worstEdgeRatioAt.x(), 25.0, 1e-12);
  EXPECT_EQ(check.poorJacobian, 1);
  EXPECT_EQ(check.poorEdgeRatio, 2) << "the long brick and the sheared one (its slanted edges are 20.1 mm)";
  EXPECT_EQ(check.poorElements, 2) << "the sheared one is outside both limits and counts once";
  EXPECT_FALSE(check.withinLimits());
  EXPECT_THROW(elementQuality(mesh, 3), std::out_of_range);
}

} // namespace
} // namespace caps::fem
