// Automatic landmark placement on a stylised synthetic head whose landmarks
// are features at known places (LandmarkPhantoms.h).

#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "LandmarkPhantoms.h"
#include "segmentation/LandmarkPlacement.h"

namespace caps::seg::test {
namespace {

struct Expected
{
  const char* name;
  double z;
  double tolerance; // mm
};

// The largest lateral extent r·|cos θ| of the analytic bone, by a dense search.
std::pair<double, double> analyticWidest(double zLow, double zHigh, double fromFront, double toFront, int side)
{
  double best = -1, bestTheta = 0, bestZ = 0;
  for (double a = fromFront; a <= toFront; a += 0.05 * kDeg)
    for (double z = zLow; z <= zHigh; z += 0.05)
    {
      const double theta = -kPi / 2 + side * a;
      const double w = StylisedHead::bone(theta, z) * std::abs(std::cos(theta));
      if (w > best)
        best = w, bestTheta = theta, bestZ = z;
    }
  return {bestTheta, bestZ};
}

class StylisedHeadPlacement : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    skin_ = new RangeMap(fillMap(StylisedHead::frame(), StylisedHead::skin));
    bone_ = new RangeMap(fillMap(StylisedHead::frame(), StylisedHead::bone));
  }
  static void TearDownTestSuite()
  {
    delete skin_;
    delete bone_;
  }
  static RangeMap* skin_;
  static RangeMap* bone_;
};
RangeMap* StylisedHeadPlacement::skin_ = nullptr;
RangeMap* StylisedHeadPlacement::bone_ = nullptr;

TEST(StandardLandmarks, HaveUniqueNamesAndDescriptions)
{
  const auto& all = standardLandmarks();
  EXPECT_EQ(all.size(), 16u);
  for (std::size_t a = 0; a < all.size(); ++a)
  {
    EXPECT_FALSE(std::string(all[a].description).empty());
    EXPECT_EQ(landmarkDescription(all[a].name), all[a].description);
    for (std::size_t b = a + 1; b < all.size(); ++b)
      EXPECT_NE(std::string(all[a].name), all[b].name);
  }
  EXPECT_EQ(landmarkDescription("no such landmark"), "");
}

TEST_F(StylisedHeadPlacement, MidlineLandmarksAreWithinToleranceOfTheirFeatures)
{
  const LandmarkPlacement placed = placeLandmarks(*skin_, *bone_);
  for (const auto& w : placed.warnings)
    ADD_FAILURE() << w;
  ASSERT_EQ(placed.landmarks.size(), standardLandmarks().size());
  // Row spacing is 0.90 mm: a feature's extremum is found to within about a
  // row, plus the shift its neighbours' slopes give it (≤ 0.4 mm here), plus
  // for the dips and lips the 5-row running median's shift on uneven slopes.
  const double zLs = StylisedHead::zLabraleSuperius, zSn = StylisedHead::zSubnasale;
  const Expected expected[] = {
    {"pronasale", 0.0, 1.0},
    {"nasion", StylisedHead::zNasion, 1.5},
    {"glabella", StylisedHead::zGlabella, 1.5},
    {"subnasale", zSn, 2.0},
    {"labrale_superius", zLs, 2.0},
    {"mid_philtrum", 0.5 * (zSn + zLs), 2.0},
    {"labrale_inferius", StylisedHead::zLabraleInferius, 1.5},
    {"pogonion", StylisedHead::zPogonion, 1.5},
    // The chin's underside is a logistic step 1 mm wide: the half-way rule
    // lands within ~1 mm of its centre.
    {"menton", StylisedHead::zMenton, 2.0},
    {"forehead", 75.0, 1.0},
  };
  for (const Expected& e : expected)
  {
    const Landmark* l = placed.find(e.name);
    ASSERT_NE(l, nullptr) << e.name;
    std::printf("[ landmark ] %-17s theta %7.2f deg  z %7.2f mm  (expected z %7.2f)\n", e.name, l->theta / kDeg, l->z,
                e.z);
    EXPECT_NEAR(l->z, e.z, e.tolerance) << e.name;
    EXPECT_NEAR(l->theta, -kPi / 2, 1e-9) << e.name;
  }
  for (int side : {1, -1})
  {
    const char* suffix = side > 0 ? "_left" : "_right";
    const Landmark* cheek = placed.find(std::string("mid_cheek") + suffix);
    ASSERT_NE(cheek, nullptr);
    EXPECT_NEAR(cheek->theta, -kPi / 2 + side * 50 * kDeg, 1e-9);
    EXPECT_NEAR(cheek->z, 0.0, 1.0);
  }
}

TEST_F(StylisedHeadPlacement, ZygionAndGonionAreTheWidestBonePoints)
{
  const LandmarkPlacement placed = placeLandmarks(*skin_, *bone_);
  const double menton = placed.features.mentonZ;
  const double subnasale = placed.find("subnasale")->z;
  const double nasion = placed.find("nasion")->z;
  for (int side : {1, -1})
  {
    const std::string suffix = side > 0 ? "_left" : "_right";
    const auto [zyTheta, zyZ] = analyticWidest(0.0, nasion, 25 * kDeg, 80 * kDeg, side);
    const auto [goTheta, goZ] = analyticWidest(menton, subnasale, 30 * kDeg, 95 * kDeg, side);
    const Landmark* zy = placed.find("zygion" + suffix);
    const Landmark* go = placed.find("gonion" + suffix);
    ASSERT_NE(zy, nullptr);
    ASSERT_NE(go, nullptr);
    std::printf("[ landmark ] zygion%-6s theta %7.2f z %6.2f; analytic %7.2f %6.2f\n", suffix.c_str(), zy->theta / kDeg,
                zy->z, zyTheta / kDeg, zyZ);
    std::printf("[ landmark ] gonion%-6s theta %7.2f z %6.2f; analytic %7.2f %6.2f\n", suffix.c_str(), go->theta / kDeg,
                go->z, goTheta / kDeg, goZ);
    // On the sample grid: within a column (0.70°) and a row (0.90 mm).
    EXPECT_NEAR(zy->theta, zyTheta, 1.0 * kDeg);
    EXPECT_NEAR(zy->z, zyZ, 1.0);
    EXPECT_NEAR(go->theta, goTheta, 1.0 * kDeg);
    EXPECT_NEAR(go->z, goZ, 1.0);
    // And near the bumps that make them (the cos θ of the width pulls them
    // a few degrees towards the side).
    EXPECT_NEAR(std::abs(zy->theta + kPi / 2), StylisedHead::zygionFromFront, 8 * kDeg);
    EXPECT_NEAR(zy->z, StylisedHead::zZygion, 1.5);
    EXPECT_NEAR(std::abs(go->theta + kPi / 2), StylisedHead::gonionFromFront, 8 * kDeg);
    EXPECT_NEAR(go->z, StylisedHead::zGonion, 1.5);
    // Patient left is θ > -90°.
    EXPECT_EQ(zy->theta > -kPi / 2, side > 0);
  }
}

TEST_F(StylisedHeadPlacement, WithoutABoneMapTheMidlineIsTheSame)
{
  const LandmarkPlacement withBone = placeLandmarks(*skin_, *bone_);
  const LandmarkPlacement skinOnly = placeLandmarks(*skin_);
  for (const char* name : {"pronasale", "nasion", "pogonion", "menton", "subnasale"})
    EXPECT_EQ(withBone.find(name)->z, skinOnly.find(name)->z) << name;
  // Zygion and gonion fall back on the skin (a circle of r = 80 beside the
  // face): still placed, on their side.
  ASSERT_NE(skinOnly.find("zygion_left"), nullptr);
  EXPECT_GT(skinOnly.find("zygion_left")->theta, -kPi / 2);
  EXPECT_LT(skinOnly.find("gonion_right")->theta, -kPi / 2);
}

TEST(LandmarkPlacement, AFaceWithoutAJawGivesWarningsNotGuesses)
{
  // A plain cylinder with a nose: no jaw underside, so no chin, menton, lips, gonion.
  const CylindricalFrame frame = StylisedHead::frame();
  const RangeMap skin = fillMap(frame, [](double theta, double z) {
    return 80.0 + 20.0 * gauss(angleFrom(theta, -kPi / 2), 0, 12 * kDeg) * gauss(z, 0, 6);
  });
  const LandmarkPlacement placed = placeLandmarks(skin);
  ASSERT_NE(placed.find("pronasale"), nullptr);
  EXPECT_NEAR(placed.find("pronasale")->z, 0.0, 1.0);
  EXPECT_EQ(placed.find("pogonion"), nullptr);
  EXPECT_EQ(placed.find("menton"), nullptr);
  EXPECT_EQ(placed.find("gonion_left"), nullptr);
  bool mentioned = false;
  for (const auto& w : placed.warnings)
    mentioned = mentioned || w.rfind("pogonion not placed", 0) == 0;
  EXPECT_TRUE(mentioned);
}

TEST(LandmarkPlacement, RefusesAnEmptyFaceAndABoneMapOnAnotherGrid)
{
  const CylindricalFrame frame = StylisedHead::frame();
  EXPECT_THROW(placeLandmarks(RangeMap(frame)), std::runtime_error);
  const RangeMap skin = fillMap(frame, StylisedHead::skin);
  EXPECT_THROW(placeLandmarks(skin, RangeMap(frame.withGrid(256, 128), 60.0f)), std::invalid_argument);
}

} // namespace
} // namespace caps::seg::test
