// The skin tension line guide against the published description of the
// relaxed skin tension lines of the face (Borges, Plast. Reconstr. Surg.
// 73:144, 1984, and the textbook figures after it): horizontal on the
// forehead, chin and neck, vertical at the glabella and on the upper lip,
// along the lower lid, radiating at the lateral canthus, across the nasal
// dorsum, down and out along the nasolabial fold on the cheek; mirror
// symmetric; and the traced lines following the field.

#include "planning/SkinTensionLines.h"

#include "planning/IncisionPlan.h"

#include "AnalyticSkins.h"

#include <gtest/gtest.h>

#include <cmath>

namespace caps {
namespace {

using planning::FaceLayout;
using planning::SkinTensionLines;
using test::cylinderSkin;

constexpr double kFront = -test::pi / 2.0;
constexpr double kRadius = 90.0;

std::vector<seg::Landmark> adultLandmarks()
{
  return {{"glabella", kFront, 62.0},          {"nasion", kFront, 50.0},
          {"pronasale", kFront, 20.0},         {"subnasale", kFront, -3.0},
          {"labrale_superius", kFront, -14.0}, {"labrale_inferius", kFront, -28.0},
          {"pogonion", kFront, -45.0},         {"menton", kFront, -57.0}};
}

class SkinTensionLinesTest : public ::testing::Test
{
protected:
  seg::RangeMap skin = cylinderSkin(kRadius, -150.0, 150.0);
  FaceLayout layout = FaceLayout::fromLandmarks(adultLandmarks(), skin);
  SkinTensionLines lines{skin, layout};

  // θ of a point x mm of arc to the patient's left of the midline.
  static double theta(double x) { return kFront + x / kRadius; }
  // The line's angle above the horizontal, 0..90 degrees.
  double elevation(double x, double z) const
  {
    const Eigen::Vector2d d = lines.directionAt(theta(x), z);
    return std::atan2(std::abs(d.y()), std::abs(d.x())) / test::degree;
  }
};

TEST_F(SkinTensionLinesTest, LayoutFollowsTheLandmarks)
{
  EXPECT_DOUBLE_EQ(layout.frontTheta, kFront);
  EXPECT_NEAR(layout.scale, kRadius, 1e-4);
  EXPECT_DOUBLE_EQ(layout.zStomion, -21.0);
  EXPECT_NEAR(layout.eyeOffset, 32.0 * 53.0 / 53.0, 1e-12);
  EXPECT_NEAR(layout.eyeZ, 50.0 - 0.15 * 53.0, 1e-12);
}

TEST_F(SkinTensionLinesTest, MissingOrDisorderedLandmarksAreNamed)
{
  auto without = adultLandmarks();
  without.erase(without.begin() + 1); // nasion
  try
  {
    FaceLayout::fromLandmarks(without, skin);
    FAIL() << "no error without a nasion";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("nasion"), std::string::npos) << e.what();
  }
  auto swapped = adultLandmarks();
  std::swap(swapped[2].z, swapped[3].z); // pronasale below subnasale
  EXPECT_THROW(FaceLayout::fromLandmarks(swapped, skin), std::invalid_argument);
}

TEST_F(SkinTensionLinesTest, HorizontalOnForeheadChinAndNeck)
{
  EXPECT_LT(elevation(0.0, 90.0), 3.0);   // mid-forehead
  EXPECT_LT(elevation(0.0, -40.0), 10.0); // chin
  EXPECT_LT(elevation(0.0, -70.0), 3.0);  // neck
  EXPECT_LT(elevation(40.0, -72.0), 3.0);
  // The forehead's lines arch down towards the temples.
  EXPECT_GT(elevation(55.0, 95.0), 5.0);
  EXPECT_LT(elevation(55.0, 95.0), 30.0);
}

TEST_F(SkinTensionLinesTest, VerticalAtTheGlabellaAndOnTheUpperLip)
{
  EXPECT_GT(elevation(0.0, 57.0), 80.0); // between the brows
  EXPECT_GT(elevation(0.0, -9.0), 80.0); // philtrum
  // Lateral parts of the lips radiate from the mouth: oblique.
  EXPECT_GT(elevation(15.0, -10.0), 20.0);
  EXPECT_LT(elevation(15.0, -10.0), 70.0);
}

TEST_F(SkinTensionLinesTest, AlongTheLidsRadiatingAtTheCanthusAcrossTheNose)
{
  const double eye = layout.eyeOffset;
  EXPECT_LT(elevation(eye, layout.eyeZ - 10.0), 10.0);        // lower lid
  EXPECT_LT(elevation(eye + 25.0, layout.eyeZ), 10.0);        // lateral canthus, level
  EXPECT_GT(elevation(eye + 24.0, layout.eyeZ + 12.0), 15.0); // crow's feet fan upwards above it
  EXPECT_LT(elevation(0.0, 32.0), 10.0);                      // nasal dorsum
}

TEST_F(SkinTensionLinesTest, CheekLinesRunDownAndOutAlongTheNasolabialFold)
{
  // On the patient's left (x > 0) "down and out" is a line through the
  // second quadrant of the (u, v) chart: u and v of opposite signs.
  for (double side : {1.0, -1.0})
  {
    const Eigen::Vector2d d = lines.directionAt(theta(side * 30.0), -5.0);
    EXPECT_LT(side * d.x() * d.y(), 0.0) << "side " << side;
    const double e = elevation(side * 30.0, -5.0);
    EXPECT_GT(e, 45.0);
    EXPECT_LT(e, 80.0);
  }
  // In front of the ear they turn vertical.
  EXPECT_GT(elevation(85.0, 10.0), 80.0);
}

TEST_F(SkinTensionLinesTest, MirrorSymmetric)
{
  for (double x = 2.0; x < 90.0; x += 7.0)
    for (double z = -80.0; z < 120.0; z += 9.0)
    {
      const Eigen::Vector2d l = lines.directionAt(theta(x), z), r = lines.directionAt(theta(-x), z);
      EXPECT_NEAR(std::abs(l.x()), std::abs(r.x()), 1e-9) << x << ", " << z;
      EXPECT_NEAR(l.x() * l.y(), -r.x() * r.y(), 1e-9) << x << ", " << z;
    }
}

TEST_F(SkinTensionLinesTest, AngleToADirection)
{
  EXPECT_NEAR(lines.angleTo(theta(0.0), 90.0, {1.0, 0.0}), 0.0, 3.0);
  EXPECT_NEAR(lines.angleTo(theta(0.0), 90.0, {0.0, -2.0}), 90.0, 3.0);
  EXPECT_NEAR(lines.angleTo(theta(0.0), 90.0, {1.0, 1.0}), 45.0, 3.0);
  EXPECT_THROW(lines.angleTo(theta(0.0), 90.0, {0.0, 0.0}), std::invalid_argument);
}

TEST_F(SkinTensionLinesTest, TracedLinesFollowTheFieldAndKeepApart)
{
  const double spacing = 9.0;
  const auto traced = lines.traceLines(spacing);
  ASSERT_GT(traced.size(), 20U);
  double worst = 0.0;
  std::size_t segments = 0;
  for (const auto& line : traced)
  {
    ASSERT_GE(line.size(), 2U);
    for (std::size_t i = 0; i + 1 < line.size(); ++i)
    {
      const double th = 0.5 * (line[i].theta + line[i + 1].theta), z = 0.5 * (line[i].z + line[i + 1].z);
      const Eigen::Vector2d d(kRadius * (line[i + 1].theta - line[i].theta), line[i + 1].z - line[i].z);
      worst = std::max(worst, lines.angleTo(th, z, d));
      ++segments;
      EXPECT_TRUE(lines.covers(line[i].theta, line[i].z));
    }
  }
  EXPECT_GT(segments, 1000U);
  EXPECT_LT(worst, 5.0);
  // Points of different lines stay at least half a spacing apart (less a step).
  double closest = 1e9;
  for (std::size_t a = 0; a < traced.size(); ++a)
    for (std::size_t b = a + 1; b < traced.size(); ++b)
      for (std::size_t i = 0; i < traced[a].size(); i += 3)
        for (std::size_t j = 0; j < traced[b].size(); j += 3)
          closest = std::min(
            closest, std::hypot(kRadius * (traced[a][i].theta - traced[b][j].theta), traced[a][i].z - traced[b][j].z));
  EXPECT_GT(closest, 0.5 * spacing - 1.5);
  // Nothing outside the face: forehead to neck, ear to ear in front.
  EXPECT_FALSE(lines.covers(theta(0.0), 200.0));
  EXPECT_FALSE(lines.covers(theta(150.0), 0.0));
}

TEST_F(SkinTensionLinesTest, PlanAxisAgainstTheLines)
{
  // A horizontal cut on the forehead lies along the lines; a vertical one across them.
  const seg::CylindricalFrame& frame = skin.frame();
  auto normalized = [&frame](double x, double z) { return planning::normalizedFromSkinPoint(frame, {theta(x), z}); };
  planning::IncisionPlan along({normalized(-10.0, 90.0), normalized(0.0, 90.0), normalized(10.0, 90.0)},
                               {theta(0.0), 90.0});
  planning::IncisionPlan across({normalized(0.0, 80.0), normalized(0.0, 90.0), normalized(0.0, 100.0)},
                                {theta(0.0), 90.0});
  const auto a = planning::axisToTensionLines(along, lines);
  EXPECT_EQ(a.axis, "p0–p2");
  EXPECT_LT(a.degrees, 3.0);
  EXPECT_GT(planning::axisToTensionLines(across, lines).degrees, 87.0);
  // A Z-plasty is judged by its central limb p1–p2.
  planning::IncisionPlan z(
    {normalized(-10.0, 100.0), normalized(-5.0, 90.0), normalized(5.0, 90.0), normalized(10.0, 80.0)},
    {theta(0.0), 90.0});
  z.setGenerator("z");
  const auto c = planning::axisToTensionLines(z, lines);
  EXPECT_EQ(c.axis, "p1–p2");
  EXPECT_LT(c.degrees, 3.0);
}

} // namespace
} // namespace caps
