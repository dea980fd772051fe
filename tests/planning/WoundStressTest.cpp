// The largest skin stress near the wound on the cylinder
// phantom (skin r = 80 mm over bone r = 70 mm), checked against a second
// recovery of the stress and against the symmetry of an ellipse closure.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "AnalyticSkins.h"
#include "fem/ElementShape.h"
#include "fem/NodalStress.h"
#include "fem/StressRecovery.h"
#include "planning/PlanSimulation.h"
#include "planning/WoundStress.h"

namespace caps::planning {
namespace {

/// A 24 mm 3:1 ellipse along the axis direction u, centred at θ = 0, z = 0:
/// mirror symmetric about both chart axes. Solved once.
const PlanPrediction& ellipse()
{
  static const PlanPrediction p = [] {
    const auto& phantom = test::cylinderPhantom();
    const IncisionPlan plan =
      test::shippedProcedure("elliptical-excision")
        .place(phantom.skin, {0.0, 0.0}, {{"length", 24.0}, {"ratio", 3.0}, {"axis_angle", 0.0}});
    return simulatePlan(phantom.skin, phantom.bone, plan, test::phantomSimulationOptions());
  }();
  return p;
}

/// Chart distance to the hole border, by its own route: the nearest point
/// of each border edge from the edge's parametric line, clamped by hand.
double borderDistance(const fem::HoleLoop& hole, const fem::ChartPoint& p)
{
  double best = std::numeric_limits<double>::infinity();
  const std::size_t n = hole.points.size();
  for (std::size_t i = 0; i < n; ++i)
  {
    const Eigen::Vector2d a = hole.points[i], b = hole.points[(i + 1) % n];
    const double toA = (p - a).norm(), toB = (p - b).norm();
    double d = std::min(toA, toB);
    const Eigen::Vector2d e = b - a;
    if (e.norm() > 0.0)
    {
      const double along = (p - a).dot(e) / e.norm();
      if (along > 0.0 && along < e.norm())
        d = std::min(d, std::abs(e.x() * (p - a).y() - e.y() * (p - a).x()) / e.norm());
    }
    best = std::min(best, d);
  }
  return best;
}

/// The nodal stress at @a node by a second route: in each element around it,
/// σ at the Barlow points (2 × 2 × 2 of the brick, the 3 × 3 C3D15 points of
/// the wedge) from fem::recoverStress() at those body coordinates, fitted by
/// least squares with the brick's trilinear or the wedge's linear × linear
/// polynomial, evaluated at the node's natural coordinates; then the mean
/// over the elements.
fem::Vector6d secondRouteNodalStress(const PlanPrediction& p, int node)
{
  const fem::Mesh& mesh = p.continuum.mesh;
  const double g = 1.0 / std::sqrt(3.0), h = std::sqrt(0.6);
  fem::Vector6d sum = fem::Vector6d::Zero();
  int elements = 0;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const fem::Element& el = mesh.elements[e];
    std::vector<int> slots;
    for (int k = 0; k < int(el.nodes.size()); ++k)
      if (el.nodes[std::size_t(k)] == node)
        slots.push_back(k);
    if (slots.empty())
      continue;
    const bool brick = el.kind == fem::ElementKind::Hex20;
    std::vector<Eigen::Vector3d> points;
    if (brick)
    {
      for (double r : {-g, g})
        for (double s : {-g, g})
          for (double t : {-g, g})
            points.emplace_back(r, s, t);
    }
    else
    {
      for (double t : {-h, 0.0, h})
        for (const auto& rs :
             {Eigen::Vector2d(1.0 / 6, 1.0 / 6), Eigen::Vector2d(2.0 / 3, 1.0 / 6), Eigen::Vector2d(1.0 / 6, 2.0 / 3)})
          points.emplace_back(rs.x(), rs.y(), t);
    }
    auto basis = [brick](const Eigen::Vector3d& x) {
      Eigen::RowVectorXd b(brick ? 8 : 6);
      if (brick)
        b << 1, x[0], x[1], x[2], x[0] * x[1], x[1] * x[2], x[0] * x[2], x[0] * x[1] * x[2];
      else
        b << 1, x[0], x[1], x[2], x[0] * x[2], x[1] * x[2];
      return b;
    };
    Eigen::MatrixXd v(Eigen::Index(points.size()), brick ? 8 : 6), sigma(Eigen::Index(points.size()), 6);
    for (std::size_t k = 0; k < points.size(); ++k)
    {
      v.row(Eigen::Index(k)) = basis(points[k]);
      sigma.row(Eigen::Index(k)) =
        fem::recoverStress(mesh, p.materials, p.displacements, int(e), points[k]).stress.transpose();
    }
    const Eigen::MatrixXd coefficients = v.colPivHouseholderQr().solve(sigma);
    const fem::ElementShape shape = fem::ElementShape::fromConnectivity(el.kind, el.nodes);
    fem::Vector6d atNode = fem::Vector6d::Zero();
    for (int slot : slots)
      atNode += (basis(shape.naturalCoordinates(slot)) * coefficients).transpose();
    sum += atNode / double(slots.size());
    ++elements;
  }
  return sum / double(elements);
}

TEST(WoundStress, PeakAgreesWithASecondStressRecovery)
{
  const PlanPrediction& p = ellipse();
  const WoundStress w = woundSkinStress(p, 10.0);
  ASSERT_GE(w.vertex, 0);
  std::printf("[wound stress] ellipse 24 mm 3:1, 10 mm band: %d vertices; peak von Mises %.4g kPa at vertex %d "
              "(chart %.3f, %.3f mm, %.3g mm from the border), max principal %.4g kPa, mean von Mises %.4g kPa\n",
              w.vertexCount, 1e3 * w.peakVonMises, w.vertex, w.chart.x(), w.chart.y(), w.distance,
              1e3 * w.peakMaxPrincipal, 1e3 * w.meanVonMises);
  EXPECT_EQ(w.node, p.skin.nodes[std::size_t(w.vertex)]);
  EXPECT_EQ(w.chart, p.skin.chart[std::size_t(w.vertex)]);
  EXPECT_LT((w.original - p.continuum.mesh.nodes.col(w.node)).norm(), 1e-12);
  EXPECT_LT((w.displaced - p.displacedNode(w.node)).norm(), 1e-12);
  EXPECT_NEAR(w.distance, borderDistance(p.hole, w.chart), 1e-9);
  EXPECT_LE(w.distance, 10.0);

  const fem::Vector6d sigma = secondRouteNodalStress(p, w.node);
  const double vonMises =
    std::sqrt(0.5 * ((sigma[0] - sigma[1]) * (sigma[0] - sigma[1]) + (sigma[1] - sigma[2]) * (sigma[1] - sigma[2]) +
                     (sigma[2] - sigma[0]) * (sigma[2] - sigma[0])) +
              3.0 * (sigma[3] * sigma[3] + sigma[4] * sigma[4] + sigma[5] * sigma[5]));
  std::printf("[wound stress] second route at node %d: von Mises %.6g kPa (reported %.6g kPa)\n", w.node,
              1e3 * vonMises, 1e3 * w.peakVonMises);
  EXPECT_GT(w.peakVonMises, 0.0);
  EXPECT_NEAR(vonMises, w.peakVonMises, 1e-9 * w.peakVonMises);

  // The largest principal stress at its vertex, the second route's tensor's eigenvalue.
  ASSERT_GE(w.maxPrincipalVertex, 0);
  const fem::Vector6d s2 = secondRouteNodalStress(p, p.skin.nodes[std::size_t(w.maxPrincipalVertex)]);
  Eigen::Matrix3d t;
  t << s2[0], s2[3], s2[5], s2[3], s2[1], s2[4], s2[5], s2[4], s2[2];
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(t).eigenvalues().maxCoeff();
  EXPECT_NEAR(largest, w.peakMaxPrincipal, 1e-9 * std::abs(w.peakMaxPrincipal));
  // Tension pulls the wound shut: the largest principal stress is positive.
  EXPECT_GT(w.peakMaxPrincipal, 0.0);
}

TEST(WoundStress, NoVertexOfTheBandExceedsThePeak)
{
  const PlanPrediction& p = ellipse();
  const fem::NodalStressField field = fem::recoverNodalStresses(p.continuum.mesh, p.materials, p.displacements);
  for (const double radius : {3.0, 10.0})
  {
    const WoundStress w = woundSkinStress(p, radius);
    int inside = 0;
    double largest = 0.0, smallest = std::numeric_limits<double>::infinity();
    for (std::size_t v = 0; v < p.skin.nodes.size(); ++v)
    {
      if (borderDistance(p.hole, p.skin.chart[v]) > radius)
        continue;
      ++inside;
      const double vm = fem::vonMisesStress(field.stress.col(p.skin.nodes[v]));
      EXPECT_LE(vm, w.peakVonMises * (1.0 + 1e-12)) << "vertex " << v << " radius " << radius;
      EXPECT_LE(fem::principalStresses(field.stress.col(p.skin.nodes[v]))[0], w.peakMaxPrincipal * (1.0 + 1e-12));
      largest = std::max(largest, vm);
      smallest = std::min(smallest, vm);
    }
    EXPECT_EQ(inside, w.vertexCount) << radius;
    EXPECT_DOUBLE_EQ(largest, w.peakVonMises) << radius;
    // The band's mean lies between its extremes, strictly (the stress is not uniform).
    EXPECT_GT(w.meanVonMises, smallest) << radius;
    EXPECT_LT(w.meanVonMises, largest) << radius;
  }
}

TEST(WoundStress, PeakLiesAtTheWoundAndGrowsWithTheRadius)
{
  const PlanPrediction& p = ellipse();
  // Over the whole meshed skin the peak is still at the wound: the closure
  // stretches the skin next to the sutures most.
  const WoundStress all = woundSkinStress(p, 1e6);
  EXPECT_EQ(all.vertexCount, int(p.skin.nodes.size()));
  std::printf("[wound stress] whole skin: peak von Mises %.4g kPa %.3g mm from the border, mean %.4g kPa\n",
              1e3 * all.peakVonMises, all.distance, 1e3 * all.meanVonMises);
  EXPECT_LE(all.distance, 2.0 * test::phantomSimulationOptions().elementSize);
  EXPECT_GT(all.peakVonMises, 2.0 * all.meanVonMises);

  double previousPeak = 0.0, previousPrincipal = -std::numeric_limits<double>::infinity();
  int previousCount = 0;
  for (const double radius : {0.5, 1.0, 2.0, 4.0, 6.0, 10.0, 15.0, 20.0, 30.0, 1e6})
  {
    const WoundStress w = woundSkinStress(p, radius);
    std::printf("[wound stress] radius %5.1f mm: %4d vertices, peak %.4g kPa, max principal %.4g kPa, mean %.4g kPa\n",
                std::min(radius, 999.0), w.vertexCount, 1e3 * w.peakVonMises, 1e3 * w.peakMaxPrincipal,
                1e3 * w.meanVonMises);
    EXPECT_GE(w.peakVonMises, previousPeak) << radius;
    EXPECT_GE(w.peakMaxPrincipal, previousPrincipal) << radius;
    EXPECT_GE(w.vertexCount, previousCount) << radius;
    EXPECT_LE(w.distance, radius);
    previousPeak = w.peakVonMises;
    previousPrincipal = w.peakMaxPrincipal;
    previousCount = w.vertexCount;
  }
  EXPECT_EQ(previousPeak, all.peakVonMises);
}

TEST(WoundStress, SymmetricPlanHasAMirrorSymmetricPeak)
{
  const PlanPrediction& p = ellipse();
  const WoundStress w = woundSkinStress(p, 10.0);
  const fem::NodalStressField field = fem::recoverNodalStresses(p.continuum.mesh, p.materials, p.displacements);
  // The ellipse is symmetric about u = 0 (θ → −θ) and v = 0 (z → −z): the
  // mirror images of the peak's vertex carry the same von Mises stress.
  for (const Eigen::Vector2d& flip : {Eigen::Vector2d(-1, 1), Eigen::Vector2d(1, -1), Eigen::Vector2d(-1, -1)})
  {
    const fem::ChartPoint mirror = w.chart.cwiseProduct(flip);
    int found = -1;
    for (std::size_t v = 0; v < p.skin.chart.size(); ++v)
      if ((p.skin.chart[v] - mirror).norm() < 1e-6)
      {
        // Twins of an excision's border share no position; of the vertices
        // at this point take the one with the peak's value, if any.
        const double vm = fem::vonMisesStress(field.stress.col(p.skin.nodes[v]));
        if (found < 0 ||
            std::abs(vm - w.peakVonMises) <
              std::abs(fem::vonMisesStress(field.stress.col(p.skin.nodes[std::size_t(found)])) - w.peakVonMises))
          found = int(v);
      }
    ASSERT_GE(found, 0) << "no vertex at the mirror image (" << mirror.transpose() << ") of the peak";
    const double vm = fem::vonMisesStress(field.stress.col(p.skin.nodes[std::size_t(found)]));
    EXPECT_NEAR(vm, w.peakVonMises, 1e-6 * w.peakVonMises) << "mirror " << flip.transpose();
    // Mirrored in world too: y → −y for θ → −θ, z → −z.
    const Eigen::Vector3d worldFlip(1.0, flip.x(), flip.y());
    EXPECT_LT((p.skin.original[std::size_t(found)] - w.original.cwiseProduct(worldFlip)).norm(), 1e-6);
  }
}

TEST(WoundStress, RejectsABadRadiusAndAnEmptyPrediction)
{
  const PlanPrediction& p = ellipse();
  for (const double radius : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()})
    EXPECT_THROW(woundSkinStress(p, radius), std::invalid_argument) << radius;
  EXPECT_THROW(woundSkinStress(PlanPrediction{}, 10.0), std::invalid_argument);
}

} // namespace
} // namespace caps::planning
