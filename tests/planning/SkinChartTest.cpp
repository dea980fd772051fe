// The local mm chart of the skin: (θn, zn) ↔ (u, v) ↔ (θ, z), across the seam.

#include <gtest/gtest.h>

#include "AnalyticSkins.h"
#include "planning/SkinChart.h"

using namespace caps;
using namespace caps::planning;

TEST(SkinChart, ScaleIsTheSkinRadiusAtTheCentre)
{
  const auto skin = test::cylinderSkin(85.0);
  const SkinChart chart(skin, 0.5, 12.0);
  EXPECT_DOUBLE_EQ(chart.radius(), 85.0);
  const ChartPoint p = chart.toChart({0.5 + 0.1, 12.0 + 7.0});
  EXPECT_NEAR(p.x(), 8.5, 1e-12); // r0 · Δθ
  EXPECT_NEAR(p.y(), 7.0, 1e-12); // Δz
  // On the sphere the scale follows the radius where the chart sits.
  const auto sphere = test::sphereSkin(60.0);
  EXPECT_NEAR(SkinChart(sphere, 0.0, 36.0).radius(), 48.0, 1e-4);
}

TEST(SkinChart, RoundTripsAwayFromTheSeam)
{
  const auto skin = test::cylinderSkin(80.0);
  const SkinChart chart(skin, -test::pi / 2, -20.0); // front of the face
  for (double theta : {-2.0, -1.6, -1.0, 0.3})
    for (double z : {-90.0, -20.0, 45.0})
    {
      const SkinPoint back = chart.fromChart(chart.toChart({theta, z}));
      EXPECT_NEAR(back.theta, theta, 1e-12);
      EXPECT_NEAR(back.z, z, 1e-12);
    }
  for (const Eigen::Vector2d& n : {Eigen::Vector2d(-0.5, 0.0), Eigen::Vector2d(-0.4, 0.7), Eigen::Vector2d(0.2, -1.0)})
    EXPECT_NEAR((chart.toNormalized(chart.fromNormalized(n)) - n).norm(), 0.0, 1e-12);
  // Normalised coordinates are the frame's (§4.2.2): θn = θ/π, zn over [zMin, zMax].
  const Eigen::Vector2d n = chart.toNormalized(chart.toChart({-test::pi / 2, 50.0}));
  EXPECT_NEAR(n.x(), -0.5, 1e-12);
  EXPECT_NEAR(n.y(), 0.5, 1e-12);
}

TEST(SkinChart, SeamDoesNotSplitTheChart)
{
  const double radius = 80.0;
  const auto skin = test::cylinderSkin(radius);
  const SkinChart chart(skin, test::pi - 0.01, 0.0); // just before the seam at the back of the head
  // A point just past the seam (θ = -π + 0.01) is 0.02 rad further on, not 2π back.
  const ChartPoint p = chart.toChart({-test::pi + 0.01, 3.0});
  EXPECT_NEAR(p.x(), radius * 0.02, 1e-9);
  // Chart points on both sides come back wrapped into [-π, π) ...
  for (double u : {-5.0, -0.8, 0.0, 0.8, 1.6, 5.0})
  {
    const ChartPoint c(u, 2.0);
    const SkinPoint s = chart.fromChart(c);
    EXPECT_GE(s.theta, -test::pi);
    EXPECT_LT(s.theta, test::pi);
    EXPECT_NEAR((chart.toChart(s) - c).norm(), 0.0, 1e-9) << u;
    // ... and through normalised coordinates too.
    const Eigen::Vector2d n = chart.toNormalized(c);
    EXPECT_GE(n.x(), -1.0);
    EXPECT_LT(n.x(), 1.0);
    EXPECT_NEAR((chart.fromNormalized(n) - c).norm(), 0.0, 1e-9) << u;
  }
  // Lifting is continuous across the seam: 1 mm of chart is 1 mm on the cylinder.
  const Eigen::Vector3d a = chart.lift({0.3, 0.0}), b = chart.lift({1.3, 0.0});
  EXPECT_NEAR((b - a).norm(), 2.0 * radius * std::sin(0.5 / radius), 1e-9);
}

TEST(SkinChart, NoSkinAtTheCentreIsAClearError)
{
  const auto skin = test::cylinderSkin(80.0, -30.0, 30.0);
  try
  {
    SkinChart chart(skin, 0.0, 40.0);
    FAIL() << "a chart above the scan was accepted";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("no surface at θ = 0°, z = 40 mm"), std::string::npos) << e.what();
  }
  const SkinChart chart(skin, 0.0, 25.0);
  EXPECT_TRUE(std::isnan(chart.lift({0.0, 10.0}).x())); // above the scan: no skin
}
