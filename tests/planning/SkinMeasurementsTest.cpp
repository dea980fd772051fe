// Lengths, angles and areas on analytic skins (cylinder, sphere), and the
// Z-plasty gain table of Fig. 2.2.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "AnalyticSkins.h"
#include "planning/SkinMeasurements.h"

using namespace caps;
using namespace caps::planning;
using test::degree;
using test::pi;

TEST(SkinLength, CylinderLimbsHaveTheirLengthInEveryDirection)
{
  const double radius = 80.0, length = 25.0;
  const auto skin = test::cylinderSkin(radius);
  const SkinChart chart(skin, 1.0, 0.0);
  // Along the axis: a straight line on the skin.
  EXPECT_NEAR(skinLength(chart, {0, -12.5}, {0, 12.5}), length, 1e-9);
  // Around the head: an arc of radius R, L/R radians.
  EXPECT_NEAR(skinLength(chart, {-12.5, 0}, {12.5, 0}), length, 1e-6);
  // Any direction: the cylinder unrolls onto the chart (a helix of length L).
  EXPECT_NEAR(skinLength(chart, {0, 0}, {length * std::cos(0.7), length * std::sin(0.7)}), length, 1e-6);
  // The polyline converges from below (chords).
  EXPECT_LT(skinLength(chart, {-12.5, 0}, {12.5, 0}, 5.0), length);
}

TEST(SkinLength, SphereMeridianIsAGreatCircleArc)
{
  const double rho = 60.0, a = 30.0;
  const auto skin = test::sphereSkin(rho);
  const SkinChart chart(skin, 0.4, 0.0);
  // From z = -a to z = a along a meridian: 2 ρ asin(a/ρ) = 62.83 mm, not 60.
  EXPECT_NEAR(skinLength(chart, {0, -a}, {0, a}), 2.0 * rho * std::asin(a / rho), 2e-3);
  // Along the equator r0 = ρ: the chart is true to scale.
  EXPECT_NEAR(skinLength(chart, {-20, 0}, {20, 0}), 40.0, 1e-3);
}

TEST(SkinAngle, CylinderKeepsChartAngles)
{
  const auto skin = test::cylinderSkin(80.0);
  const SkinChart chart(skin, -pi / 2, 10.0);
  for (double angle : {30.0, 60.0, 90.0, 135.0})
  {
    const ChartPoint a(10.0, 0.0), b(10.0 * std::cos(angle * degree), 10.0 * std::sin(angle * degree));
    EXPECT_NEAR(skinAngle(chart, {0, 0}, a, b) / degree, angle, 1e-4) << angle;
  }
}

TEST(SkinAngle, SphereEquatorIsConformalAtTheCentre)
{
  const auto skin = test::sphereSkin(60.0);
  const SkinChart chart(skin, 0.0, 0.0);
  EXPECT_NEAR(skinAngle(chart, {0, 0}, {10, 0}, {0, 10}) / degree, 90.0, 1e-3);
  EXPECT_NEAR(skinAngle(chart, {0, 0}, {10, 0}, {10, 10}) / degree, 45.0, 1e-2);
  // At z = 36 mm (r0 = 48 mm) the chart's u is still true to scale at its
  // centre, but the skin slopes in along the meridian: dr/dz = -z/r = -0.75,
  // so a 45° chart ray has the 3D tangent ê_θ + â − 0.75 ê_r, at
  // acos(1/√2.5625) = 51.3° from the u ray; the v ray stays at 90°.
  const SkinChart high(skin, 0.0, 36.0);
  EXPECT_NEAR(skinAngle(high, {0, 0}, {10, 0}, {0, 10}) / degree, 90.0, 1e-3);
  const double expected = std::acos(1.0 / std::sqrt(1.0 + 1.0 + 0.75 * 0.75)) / degree;
  EXPECT_NEAR(skinAngle(high, {0, 0}, {10, 0}, {10, 10}) / degree, expected, 0.05); // rows 0.05 mm apart
}

TEST(SkinArea, SphereZoneIsArchimedes)
{
  // Archimedes' hat-box theorem: the zone of a sphere between two heights
  // has the area of the cylinder around it, ρ Δθ Δz.
  const double rho = 60.0;
  const auto skin = test::sphereSkin(rho);
  const SkinChart chart(skin, 0.0, 10.0);
  const double r0 = chart.radius(); // chart u = r0 Δθ
  const std::vector<ChartPoint> rectangle = {{-15, -20}, {15, -20}, {15, 20}, {-15, 20}};
  const double expected = rho * (30.0 / r0) * 40.0;
  EXPECT_NEAR(skinArea(chart, rectangle), expected, 1e-3 * expected);
  // Orientation does not matter.
  const std::vector<ChartPoint> clockwise(rectangle.rbegin(), rectangle.rend());
  EXPECT_NEAR(skinArea(chart, clockwise), expected, 1e-3 * expected);
}

TEST(SkinArea, NonConvexPolygonOnACylinder)
{
  const auto skin = test::cylinderSkin(80.0);
  const SkinChart chart(skin, 2.0, 0.0);
  // An L of three 10 mm squares, 300 mm²: not convex.
  const std::vector<ChartPoint> l = {{0, 0}, {20, 0}, {20, 10}, {10, 10}, {10, 20}, {0, 20}};
  EXPECT_NEAR(skinArea(chart, l), 300.0, 300.0 * 1e-5);
}

TEST(ExcisedArea, EllipseOnACylinderIsTheInscribedPolygon)
{
  const double radius = 80.0;
  const auto skin = test::cylinderSkin(radius);
  const auto* ellipse = test::shippedProcedures().find("elliptical-excision");
  ASSERT_NE(ellipse, nullptr);
  const double length = 30.0, ratio = 3.0;
  const IncisionPlan plan = ellipse->place(skin, {0.2, -10.0}, {{"length", length}, {"ratio", ratio}});
  const double a = 0.5 * length, b = 0.5 * length / ratio;
  const int border = 2 * (plan.pointCount() - 1);
  // Border points at equal steps of the ellipse parameter: (N/2) a b sin(2π/N).
  const double inscribed = 0.5 * border * a * b * std::sin(2.0 * pi / border);
  EXPECT_NEAR(excisedArea(plan, skin), inscribed, 1e-4 * inscribed);
  EXPECT_LT(excisedArea(plan, skin), pi * a * b); // the ellipse itself, π a b = 235.6 mm²
  EXPECT_GT(excisedArea(plan, skin), 0.95 * pi * a * b);
  // Turned 90°: the cylinder is developable, the area stays.
  const IncisionPlan turned =
    ellipse->place(skin, {0.2, -10.0}, {{"length", length}, {"ratio", ratio}, {"axis_angle", 90.0 * degree}});
  EXPECT_NEAR(excisedArea(turned, skin), inscribed, 1e-4 * inscribed);
}

TEST(ExcisedArea, RhombusAndSlits)
{
  const auto skin = test::cylinderSkin(80.0);
  const auto* rhomboid = test::shippedProcedures().find("rhomboid-flap");
  const IncisionPlan plan = rhomboid->place(skin, {0.0, 0.0}, {{"side_length", 15.0}});
  EXPECT_NEAR(excisedArea(plan, skin), 15.0 * 15.0 * std::sin(60.0 * degree), 1e-3); // the flap's cuts add nothing
  const IncisionPlan z = test::shippedProcedures().find("z-plasty")->place(skin, {0.0, 0.0});
  EXPECT_EQ(excisedArea(z, skin), 0.0);
  const IncisionPlan zx = test::shippedProcedures()
                            .find("multiple-z-plasty-with-excision")
                            ->place(skin, {0.0, 0.0}, {{"central_length", 24.0}, {"excision_width", 4.0}});
  EXPECT_NEAR(excisedArea(zx, skin), 0.5 * 24.0 * 4.0, 1e-3); // rhombus of diagonals 24 and 4
}

TEST(MeasurePlan, ZPlastyOnACylinder)
{
  const auto skin = test::cylinderSkin(80.0);
  const auto* z = test::shippedProcedures().find("z-plasty");
  const IncisionPlan plan = z->place(skin, {-pi / 2, 0.0}, {{"central_length", 20.0}, {"limb_angle", 45.0 * degree}});
  const PlanMeasurements m = measurePlan(plan, skin);
  ASSERT_EQ(m.limbs.size(), 3u);
  for (const auto& limb : m.limbs)
  {
    EXPECT_NEAR(limb.chart, 20.0, 1e-9);
    EXPECT_NEAR(limb.skin, 20.0, 1e-6);
  }
  ASSERT_EQ(m.limbAngles.size(), 2u);
  for (const auto& angle : m.limbAngles)
  {
    EXPECT_NEAR(angle.chart / degree, 45.0, 1e-9);
    EXPECT_NEAR(angle.skin / degree, 45.0, 1e-3);
  }
  EXPECT_EQ(m.borderEdges.size(), 6u);
  // The skin wraps all the way around the tips of the limbs: 360°.
  ASSERT_EQ(m.borderAngles.size(), 6u);
  EXPECT_NEAR(m.borderAngles[0].skin / degree, 360.0, 1e-6);
  EXPECT_NEAR(m.borderAngles[3].skin / degree, 360.0, 1e-6);
  // At p1 the flap side (left, border point 1) has the acute 45°, its twin the rest.
  EXPECT_NEAR(m.borderAngles[1].skin / degree, 45.0, 1e-3);
  EXPECT_NEAR(m.borderAngles[5].skin / degree, 315.0, 1e-3);
  EXPECT_EQ(m.excisedArea, 0.0);
}

TEST(MeasurePlan, EllipseEndsArePointed)
{
  const auto skin = test::cylinderSkin(80.0);
  const IncisionPlan plan =
    test::shippedProcedures().find("elliptical-excision")->place(skin, {0.0, 0.0}, {{"length", 40.0}, {"ratio", 4.0}});
  const PlanMeasurements m = measurePlan(plan, skin);
  // The hole's angle at each end, 360° minus the skin's, set by the first
  // border chord: 2 atan(b sin(π/8) / (a (1 − cos(π/8)))).
  const double a = 20.0, b = 5.0, step = pi / 8;
  const double hole = 2.0 * std::atan(b * std::sin(step) / (a * (1.0 - std::cos(step))));
  EXPECT_NEAR(2.0 * pi - m.borderAngles[0].skin, hole, 1e-4);
  EXPECT_NEAR(2.0 * pi - m.borderAngles[8].skin, hole, 1e-4);
}

TEST(ZPlastyGain, TableOfFigure22)
{
  EXPECT_DOUBLE_EQ(zPlastyTheoreticalGain(30.0 * degree), 0.25);
  EXPECT_DOUBLE_EQ(zPlastyTheoreticalGain(45.0 * degree), 0.50);
  EXPECT_DOUBLE_EQ(zPlastyTheoreticalGain(60.0 * degree), 0.75);
  EXPECT_DOUBLE_EQ(zPlastyTheoreticalGain(75.0 * degree), 1.00);
  EXPECT_DOUBLE_EQ(zPlastyTheoreticalGain(90.0 * degree), 1.20);
  EXPECT_NEAR(zPlastyTheoreticalGain(52.5 * degree), 0.625, 1e-12);
  EXPECT_NEAR(zPlastyTheoreticalGain(85.0 * degree), 1.00 + 0.2 * 10.0 / 15.0, 1e-12);
  EXPECT_THROW(zPlastyTheoreticalGain(25.0 * degree), std::invalid_argument);
  EXPECT_THROW(zPlastyTheoreticalGain(95.0 * degree), std::invalid_argument);
}

TEST(ZPlastyGain, TableRoundsTheParallelogramGeometry)
{
  // Long diagonal minus short diagonal of the Z's parallelogram (Fig. 2.2
  // caption): √(5 − 4 cos α) − 1. The table rounds it to 5 percentage points.
  for (double angle : {30.0, 45.0, 60.0, 75.0, 90.0})
    EXPECT_NEAR(zPlastyGeometricGain(angle * degree), zPlastyTheoreticalGain(angle * degree), 0.05) << angle;
  EXPECT_NEAR(zPlastyGeometricGain(60.0 * degree), std::sqrt(3.0) - 1.0, 1e-12);
  // And it is the placed Z's own geometry: tips p0, p3 a long diagonal apart.
  const auto skin = test::cylinderSkin(80.0);
  const IncisionPlan plan = test::shippedProcedures().find("z-plasty")->place(skin, {0.0, 0.0});
  const auto path = plan.chartPath(plan.chart(skin));
  EXPECT_NEAR((path[3] - path[0]).norm() / 20.0 - 1.0, zPlastyGeometricGain(60.0 * degree), 1e-9);
}

TEST(ZPlastyGain, PredictedFromDisplacedFlapTips)
{
  const std::array<Eigen::Vector3d, 2> before = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(20, 0, 0)};
  const std::array<Eigen::Vector3d, 2> after = {Eigen::Vector3d(-2, 1, 3), Eigen::Vector3d(33, -1, 0)};
  const ZPlastyGain g = zPlastyPredictedGain(before, after, {2, 0, 0});
  EXPECT_DOUBLE_EQ(g.before, 20.0);
  EXPECT_DOUBLE_EQ(g.after, 35.0); // only the axial part counts
  EXPECT_DOUBLE_EQ(g.gain, 15.0);
  EXPECT_DOUBLE_EQ(g.fraction, 0.75);
  EXPECT_THROW(zPlastyPredictedGain(before, after, {0, 1, 0}), std::invalid_argument);
}

TEST(ZPlastyGain, FlapTipsAndCentralAxisOfPlacedZs)
{
  const auto skin = test::cylinderSkin(80.0);
  const IncisionPlan z = test::shippedProcedures().find("z-plasty")->place(skin, {0.0, 0.0});
  EXPECT_EQ(zPlastyFlapTips(z), (std::array<int, 2>{1, 2}));
  // Central limb around the head at θ = 0 (patient left): the axis is ±ŷ in the world.
  const Eigen::Vector3d axis = centralAxis(z, skin);
  EXPECT_NEAR(std::abs(axis.y()), 1.0, 1e-3);
  const IncisionPlan zx = test::shippedProcedures().find("multiple-z-plasty-with-excision")->place(skin, {0.0, 0.0});
  EXPECT_EQ(zPlastyFlapTips(zx), (std::array<int, 2>{2, 4}));
  const IncisionPlan e = test::shippedProcedures().find("elliptical-excision")->place(skin, {0.0, 0.0});
  EXPECT_THROW(zPlastyFlapTips(e), std::invalid_argument);
}

TEST(MeasurePlan, EveryProcedureWithItsDefaults)
{
  // Printed for the record; on the cylinder (developable) skin lengths equal
  // chart lengths, on the sphere (r0 at the centre, curving away) they differ.
  const auto cylinder = test::cylinderSkin(80.0);
  const auto sphere = test::sphereSkin(80.0);
  for (const auto& t : test::shippedProcedures().procedures())
  {
    SCOPED_TRACE(t.id());
    const IncisionPlan onCylinder = t.place(cylinder, {-pi / 2, 0.0});
    const IncisionPlan onSphere = t.place(sphere, {-pi / 2, 20.0});
    const PlanMeasurements c = measurePlan(onCylinder, cylinder), s = measurePlan(onSphere, sphere);
    std::printf("%s: limbs (chart / cylinder R80 / sphere R80 at z=20) mm:", t.id().c_str());
    for (size_t k = 0; k < c.limbs.size(); ++k)
    {
      std::printf(" %.3f/%.3f/%.3f", c.limbs[k].chart, c.limbs[k].skin, s.limbs[k].skin);
      EXPECT_NEAR(c.limbs[k].skin, c.limbs[k].chart, 1e-6);
    }
    std::printf("\n  angles (chart / cylinder / sphere) deg:");
    for (size_t k = 0; k < c.limbAngles.size(); ++k)
    {
      std::printf(" %.2f/%.2f/%.2f", c.limbAngles[k].chart / degree, c.limbAngles[k].skin / degree,
                  s.limbAngles[k].skin / degree);
      EXPECT_NEAR(c.limbAngles[k].skin, c.limbAngles[k].chart, 1e-5);
    }
    std::printf("\n  excised area (cylinder / sphere) mm²: %.3f / %.3f\n", c.excisedArea, s.excisedArea);
  }
}

TEST(ExcisedVolume, BoxOnACylinderIsItsAnnularSector)
{
  // Skin r = 80 mm over bone r = 70 mm; a box 20 mm around the head (20/80
  // rad) by 10 mm along the axis: (80² − 70²) / 2 · 0.25 · 10 = 1875 mm³.
  const auto skin = test::cylinderSkin(80.0);
  const auto bone = test::cylinderSkin(70.0);
  const SkinChart chart(skin, 0.3, 5.0);
  const std::vector<ChartPoint> box = {{-10, -5}, {10, -5}, {10, 5}, {-10, 5}};
  const double sector = 0.5 * (80.0 * 80.0 - 70.0 * 70.0) * (20.0 / 80.0) * 10.0;
  EXPECT_NEAR(tissueVolume(chart, bone, box), sector, 1e-9 * sector);
  // Either orientation; an L (not star-shaped about its centroid) adds up.
  const std::vector<ChartPoint> reversed(box.rbegin(), box.rend());
  EXPECT_NEAR(tissueVolume(chart, bone, reversed), sector, 1e-9 * sector);
  const std::vector<ChartPoint> l = {{0, 0}, {20, 0}, {20, 10}, {10, 10}, {10, 20}, {0, 20}};
  const double perChartArea = (80.0 * 80.0 - 70.0 * 70.0) / (2.0 * 80.0);
  EXPECT_NEAR(tissueVolume(chart, bone, l), 300.0 * perChartArea, 1e-9 * 300.0 * perChartArea);

  // Bone sloping along the axis, r = 70 + 0.1 z: the depth shrinks upwards.
  seg::RangeMap cone = bone;
  for (int j = 0; j < cone.nZ(); ++j)
    for (int i = 0; i < cone.nTheta(); ++i)
      cone.at(i, j) = float(70.0 + 0.1 * cone.frame().indexToZ(j));
  auto cube = [](double z) { return std::pow(70.0 + 0.1 * z, 3) / 0.3; };
  const double sloped = 0.5 * (20.0 / 80.0) * (80.0 * 80.0 * 10.0 - (cube(10.0) - cube(0.0)));
  const double measured = tissueVolume(chart, cone, box);
  std::printf("[excised volume] box 20 x 10 mm: flat bone %.6g mm³ (analytic %.6g), sloping bone %.6g mm³ "
              "(analytic %.6g)\n",
              tissueVolume(chart, bone, box), sector, measured, sloped);
  EXPECT_NEAR(measured, sloped, 1e-6 * sloped);

  // Bone above the skin is refused; no bone: the stated default depth.
  EXPECT_THROW(tissueVolume(chart, test::cylinderSkin(90.0), box), std::invalid_argument);
  const seg::RangeMap noBone(skin.frame());
  const double defaulted = 0.5 * (80.0 * 80.0 - 72.0 * 72.0) * (20.0 / 80.0) * 10.0;
  EXPECT_NEAR(tissueVolume(chart, noBone, box, 8.0), defaulted, 1e-9 * defaulted);
  EXPECT_THROW(tissueVolume(chart, noBone, box, 0.0), std::invalid_argument);
}

TEST(ExcisedVolume, PlansRemoveTheirHoleDownToTheBone)
{
  const auto skin = test::cylinderSkin(80.0);
  const auto bone = test::cylinderSkin(70.0);
  const double perChartArea = (80.0 * 80.0 - 70.0 * 70.0) / (2.0 * 80.0);
  const IncisionPlan rhombus =
    test::shippedProcedures().find("rhomboid-flap")->place(skin, {0.0, 0.0}, {{"side_length", 15.0}});
  const double area = 15.0 * 15.0 * std::sin(60.0 * degree);
  EXPECT_NEAR(excisedVolume(rhombus, skin, bone), perChartArea * area, 1e-6 * perChartArea * area);
  const IncisionPlan z = test::shippedProcedures().find("z-plasty")->place(skin, {0.0, 0.0});
  EXPECT_EQ(excisedVolume(z, skin, bone), 0.0);
}
