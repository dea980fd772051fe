// A plan is refused where its cut runs through the CT slices that metal's
// streaks spoil: a head (a cylinder of skin, r = 80 mm) with a filling 60 mm
// in front of the axis at z = 40 mm; cuts above, below and across those slices.

#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>
#include <vtkImageData.h>
#include <vtkNew.h>

#include "AnalyticSkins.h"
#include "planning/CutOnSoundSkin.h"

namespace caps::test {
namespace {

constexpr double kFront = -pi / 2;

/// The CT: air, soft tissue within 80 mm of the axis, and a 4 mm cube of
/// metal (3071 HU) centred at (0, -60, 40) mm; 2 mm voxels, z from -100 to 100.
void makeCt(vtkImageData* ct)
{
  ct->SetDimensions(101, 101, 101);
  ct->SetSpacing(2.0, 2.0, 2.0);
  ct->SetOrigin(-100.0, -100.0, -100.0);
  ct->AllocateScalars(VTK_SHORT, 1);
  auto* v = static_cast<short*>(ct->GetScalarPointer());
  for (int k = 0; k < 101; ++k)
    for (int j = 0; j < 101; ++j)
      for (int i = 0; i < 101; ++i)
      {
        const double x = -100.0 + 2.0 * i, y = -100.0 + 2.0 * j, z = -100.0 + 2.0 * k;
        const bool metal = std::abs(x) <= 2.0 && std::abs(y + 60.0) <= 2.0 && std::abs(z - 40.0) <= 2.0;
        v[i + 101 * (j + 101 * k)] = metal ? 3071 : (std::hypot(x, y) < 80.0 ? 40 : -1000);
      }
}

/// A straight cut on the skin from (θ0, z0) to (θ1, z1), in five points.
planning::IncisionPlan straightCut(const seg::RangeMap& skin, double theta0, double z0, double theta1, double z1)
{
  std::vector<Eigen::Vector2d> path;
  for (int k = 0; k <= 4; ++k)
  {
    const double t = k / 4.0;
    path.push_back(
      planning::normalizedFromSkinPoint(skin.frame(), {theta0 + t * (theta1 - theta0), z0 + t * (z1 - z0)}));
  }
  return planning::IncisionPlan(path, {0.5 * (theta0 + theta1), 0.5 * (z0 + z1)});
}

TEST(CutOnSoundSkin, ACutThroughTheSlicesMetalSpoilsIsRefusedWithWhereAndWhatToDo)
{
  const seg::RangeMap skin = cylinderSkin(80.0);
  vtkNew<vtkImageData> ct;
  makeCt(ct);
  const std::vector<seg::MetalPiece> metal = seg::findMetal(ct);
  ASSERT_EQ(metal.size(), 1u);
  // The metal's slices (z 38 to 42) and 5 mm either side: z 33 to 47.
  const std::string across = planning::cutInMetalStreaks(
    straightCut(skin, kFront - 15 * degree, 40.0, kFront + 15 * degree, 40.0), skin, metal, ct);
  std::printf("[ refused  ] %s\n", across.c_str());
  EXPECT_NE(across.find("metal"), std::string::npos) << across;
  EXPECT_NE(across.find(", 40) mm; θ -105°, 40 mm along the head axis"), std::string::npos) << across;
  EXPECT_NE(across.find("Place the plan away"), std::string::npos) << across;

  // A vertical cut from z = 0 to z = 60 crosses them; it is refused at the
  // first of its millimetre steps in them, from below: at the lowest spoiled
  // slice (k from firstSpoiled - 0.5, at z = -100 + 2 k).
  const std::string upwards =
    planning::cutInMetalStreaks(straightCut(skin, kFront, 0.0, kFront, 60.0), skin, metal, ct);
  const std::size_t at = upwards.find("°, ");
  ASSERT_NE(at, std::string::npos) << upwards;
  const double zRefused = std::stod(upwards.substr(at + 4));
  EXPECT_NEAR(zRefused, -100.0 + 2.0 * (metal[0].firstSpoiled - 0.5), 1.0) << upwards;
  EXPECT_LT(zRefused, 38.0);

  // Below and above the spoiled slices: accepted, however close the cut
  // runs to them in θ.
  for (const double z : {0.0, 25.0, 55.0, 80.0})
    EXPECT_EQ(
      planning::cutInMetalStreaks(straightCut(skin, kFront - 15 * degree, z, kFront + 15 * degree, z), skin, metal, ct),
      "")
      << "z " << z;
  // No metal, or no CT: nothing to refuse.
  const planning::IncisionPlan plan = straightCut(skin, kFront - 15 * degree, 40.0, kFront + 15 * degree, 40.0);
  EXPECT_EQ(planning::cutInMetalStreaks(plan, skin, {}, ct), "");
  EXPECT_EQ(planning::cutInMetalStreaks(plan, skin, metal, nullptr), "");
}

// Skin pressed against the head holder (here: the test says the skin behind
// y = 70 mm is, LPS posterior): a cut reaching there is refused at its first
// millimetre step beyond it, with where; a cut on the face is accepted.
TEST(CutOnSoundSkin, ACutOverSkinAgainstTheHeadHolderIsRefused)
{
  const seg::RangeMap skin = cylinderSkin(80.0);
  const auto onTheHolder = [](const Eigen::Vector3d& p) { return p.y() > 70.0; };
  const double back = pi / 2;
  const std::string refused =
    planning::cutAgainstAnObject(straightCut(skin, back - 60 * degree, 10.0, back, 10.0), skin, onTheHolder);
  std::printf("[ refused  ] %s\n", refused.c_str());
  EXPECT_NE(refused.find("head holder"), std::string::npos) << refused;
  // y = 80 sin θ passes 70 at θ = asin(7/8) = 61.0°: the first step beyond.
  const std::size_t at = refused.find("θ ");
  ASSERT_NE(at, std::string::npos) << refused;
  EXPECT_NEAR(std::stod(refused.substr(at + 3)), std::asin(7.0 / 8.0) / degree, 1.0) << refused;
  EXPECT_EQ(planning::cutAgainstAnObject(straightCut(skin, kFront - 15 * degree, 10.0, kFront + 15 * degree, 10.0),
                                         skin, onTheHolder),
            "");
  EXPECT_EQ(planning::cutAgainstAnObject(straightCut(skin, back - 60 * degree, 10.0, back, 10.0), skin, {}), "");
}

} // namespace
} // namespace caps::test
