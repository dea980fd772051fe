// Automatic landmark placement on a stylised synthetic head whose landmarks
// are features at known places (LandmarkPhantoms.h).

#include <cmath>
#include <cstdio>
#include <stdexcept>
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

// The z of the smallest skin radius on the front in [lo, hi], densely.
double analyticProfileMinimum(double lo, double hi)
{
  double best = lo;
  for (double z = lo; z <= hi; z += 0.01)
    if (StylisedHead::skin(-kPi / 2, z) < StylisedHead::skin(-kPi / 2, best))
      best = z;
  return best;
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
  EXPECT_EQ(all.size(), 24u);
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
    // The concavity above the glabella: the dip at 56 pulled up a little by
    // the glabella's flank.
    {"supraglabella", StylisedHead::zSupraglabella, 1.5},
    // The last row of nasal bone, at or above its end (0.90 mm rows).
    {"rhinion", StylisedHead::zRhinion + 0.45, 0.5},
    {"mid_nasal", 0.5 * (StylisedHead::zNasion + StylisedHead::zRhinion), 1.5},
    // Between the lower lip (-40) and the chin (-62).
    {"sublabiale", analyticProfileMinimum(-58.0, -44.0), 1.0},
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
    // 32 mm from the midsagittal plane (under the pupil), on its side.
    const double lateral = StylisedHead::skin(cheek->theta, cheek->z) * std::abs(std::cos(cheek->theta));
    EXPECT_GE(lateral, 32.0);
    EXPECT_LT(lateral, 32.5);
    EXPECT_GT(side * (cheek->theta + kPi / 2), 0.0);
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

// The orbits' rims on the pupil's column, against the analytic bone: walking
// out of the orbit, where the bone first comes within 1 mm of the highest
// bone in the next 15 mm. A skull without orbits has no rims: not found, with why.
TEST_F(StylisedHeadPlacement, OrbitalRimsAreWhereTheOrbitsWallsEnd)
{
  const LandmarkPlacement placed = placeLandmarks(*skin_, *bone_);
  for (int side : {1, -1})
  {
    const std::string suffix = side > 0 ? "_left" : "_right";
    const Landmark* supra = placed.find("supraorbital" + suffix);
    const Landmark* infra = placed.find("infraorbital" + suffix);
    ASSERT_NE(supra, nullptr);
    ASSERT_NE(infra, nullptr);
    EXPECT_NEAR(supra->theta, infra->theta, 1e-12) << "one column, the pupil's";
    EXPECT_EQ(supra->theta > -kPi / 2, side > 0);
    for (const auto& [rim, direction] : {std::pair{supra, +1}, std::pair{infra, -1}})
    {
      const auto r = [theta = rim->theta](double z) { return StylisedHead::bone(theta, z); };
      double expected = StylisedHead::zOrbit;
      for (;; expected += direction * 0.001)
      {
        double highest = r(expected);
        for (double d = 0.0; d <= 15.0; d += 0.05)
          highest = std::max(highest, r(expected + direction * d));
        if (r(expected) >= highest - 1.0)
          break;
      }
      std::printf("[ landmark ] %-19s z %6.2f; analytic %6.2f\n", rim->name.c_str(), rim->z, expected);
      EXPECT_NEAR(rim->z, expected, 1.0) << rim->name; // within about a row (0.90 mm)
    }
  }
  const auto noOrbits = [](double theta, double z) {
    const double c = std::cos(theta), s = std::sin(theta);
    return z < -68.0 ? std::nan("") : 1.0 / std::sqrt(c * c / (60.0 * 60.0) + s * s / (70.0 * 70.0));
  };
  const LandmarkPlacement without = placeLandmarks(*skin_, fillMap(StylisedHead::frame(), noOrbits));
  for (const char* name : {"supraorbital_left", "supraorbital_right", "infraorbital_left", "infraorbital_right"})
  {
    EXPECT_EQ(without.find(name), nullptr) << name;
    for (const LandmarkStatus& status : without.status)
      if (status.name == name)
      {
        EXPECT_EQ(status.state, LandmarkState::NotFound) << name;
        EXPECT_NE(status.reason.find("orbit"), std::string::npos) << status.reason;
      }
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
  // The rhinion is the nasal bones' end: read on the bone map only.
  for (const char* name : {"rhinion", "mid_nasal"})
  {
    EXPECT_EQ(skinOnly.find(name), nullptr) << name;
    bool said = false;
    for (const auto& w : skinOnly.warnings)
      said =
        said || (w.rfind(std::string(name) + " not found", 0) == 0 && w.find("bone range map") != std::string::npos);
    EXPECT_TRUE(said) << name;
  }
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
    mentioned = mentioned || w.rfind("pogonion not found", 0) == 0;
  EXPECT_TRUE(mentioned);
}

/// The stylised head scanned over z in [zMin, zMax] only (a CT that does not
/// hold the whole face).
LandmarkPlacement placeOnScanOf(double zMin, double zMax)
{
  const CylindricalFrame frame(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), zMin, zMax, 512,
                               static_cast<int>(std::lround(zMax - zMin)) + 1);
  return placeLandmarks(fillMap(frame, StylisedHead::skin), fillMap(frame, StylisedHead::bone));
}

const LandmarkStatus& statusOf(const LandmarkPlacement& placed, const std::string& name)
{
  for (const auto& s : placed.status)
    if (s.name == name)
      return s;
  throw std::runtime_error("no status for " + name);
}

TEST(LandmarkPlacement, EveryStandardLandmarkHasAStatusAndAConfidence)
{
  const LandmarkPlacement placed = placeOnScanOf(-120.0, 110.0);
  ASSERT_EQ(placed.status.size(), standardLandmarks().size());
  for (std::size_t k = 0; k < placed.status.size(); ++k)
  {
    EXPECT_EQ(placed.status[k].name, standardLandmarks()[k].name);
    EXPECT_EQ(placed.status[k].state, LandmarkState::Placed)
      << placed.status[k].name << ": " << placed.status[k].reason;
    EXPECT_TRUE(std::string(placed.status[k].confidence) == "reliable" ||
                std::string(placed.status[k].confidence) == "fair" ||
                std::string(placed.status[k].confidence) == "approximate");
  }
  EXPECT_EQ(std::string(statusOf(placed, "pronasale").confidence), "reliable");
  EXPECT_EQ(std::string(statusOf(placed, "gonion_left").confidence), "approximate");
  EXPECT_TRUE(placed.warnings.empty());
}

TEST(LandmarkPlacement, AScanCutAboveTheNosePlacesNoFaceLandmark)
{
  // A cranium-only scan: from just above the nose (its tip at z = 0, the
  // nasion at 30, the glabella at 42) to the vertex. The brow is the most
  // prominent point left, and it is no nose.
  for (const double zMin : {10.0, 25.0, 35.0})
  {
    const LandmarkPlacement placed = placeOnScanOf(zMin, 110.0);
    EXPECT_TRUE(placed.landmarks.empty()) << "scan from z = " << zMin << ": " << placed.landmarks.size()
                                          << " placed, the first " << placed.landmarks.front().name;
    EXPECT_EQ(placed.features.pronasale, -1);
    EXPECT_FALSE(placed.features.noseMissing.empty());
    for (const char* name : {"pronasale", "subnasale", "labrale_superius", "labrale_inferius", "pogonion", "menton",
                             "mid_cheek_left", "zygion_right", "gonion_left"})
    {
      const LandmarkStatus& s = statusOf(placed, name);
      EXPECT_EQ(s.state, LandmarkState::NotInScan) << name;
      EXPECT_NE(s.reason.find("nose"), std::string::npos) << name << ": " << s.reason;
    }
    std::printf("scan from z = %.0f mm: %s\n", zMin, placed.features.noseMissing.c_str());
  }
}

TEST(LandmarkPlacement, AScanThatEndsAtTheNoseTipPlacesNoFaceLandmark)
{
  // The skin is found only from z = 2 mm up (a scan whose lowest slices cut
  // through the nose just above its tip; the map's rows below are empty):
  // the most prominent point is the edge of the scan, not the tip.
  const CylindricalFrame frame = StylisedHead::frame();
  const RangeMap skin =
    fillMap(frame, [](double theta, double z) { return z < 2.0 ? std::nan("") : StylisedHead::skin(theta, z); });
  const LandmarkPlacement placed = placeLandmarks(skin);
  EXPECT_TRUE(placed.landmarks.empty());
  EXPECT_NE(placed.features.noseMissing.find("edge of the scan"), std::string::npos) << placed.features.noseMissing;
}

TEST(LandmarkPlacement, ANoseOnAHeadTurnedALittleIsStillANose)
{
  // The stylised head turned 10° to its left on the table: the nose stands
  // 10° from the midline, so one side 20° from the midline is beside the
  // nose and the other is cheek.
  const CylindricalFrame frame = StylisedHead::frame();
  const double turn = 10 * kDeg;
  const LandmarkPlacement placed =
    placeLandmarks(fillMap(frame, [turn](double theta, double z) { return StylisedHead::skin(theta - turn, z); }));
  EXPECT_TRUE(placed.features.noseMissing.empty()) << placed.features.noseMissing;
  ASSERT_NE(placed.find("pronasale"), nullptr);
  EXPECT_NEAR(placed.find("pronasale")->z, 0.0, 1.0);
}

TEST(LandmarkPlacement, ALandmarkBeyondTheScanIsListedAsNotInTheScan)
{
  // The scan ends 70 mm above the nose tip: the forehead landmark (75 mm
  // above it) is not in the scan; the face below it all is.
  const LandmarkPlacement placed = placeOnScanOf(-120.0, 70.0);
  const LandmarkStatus& forehead = statusOf(placed, "forehead");
  EXPECT_EQ(forehead.state, LandmarkState::NotInScan);
  EXPECT_NE(forehead.reason.find("beyond the scan"), std::string::npos) << forehead.reason;
  EXPECT_EQ(statusOf(placed, "glabella").state, LandmarkState::Placed);
  EXPECT_EQ(statusOf(placed, "pogonion").state, LandmarkState::Placed);
  EXPECT_EQ(placed.landmarks.size(), standardLandmarks().size() - 1);
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
