// Thickness: radial (r_skin - r_bone) and along the inward skin normal,
// against analytic answers: concentric spheres (normal thickness Rs - Rb
// everywhere) and a tilted coaxial cylinder; statistics on a known map.

#include <numbers>

#include <gtest/gtest.h>

#include "RangeMapCompare.h"
#include "RangeMapPhantom.h"
#include "segmentation/RangeMapBuilder.h"
#include "segmentation/Thickness.h"

using namespace caps::seg;
using namespace caps::seg::test;

namespace {

RangeMapBuildOptions midThresholds()
{
  RangeMapBuildOptions options;
  options.skinThreshold = skinMidHu;
  options.boneThreshold = boneMidHu;
  return options;
}

} // namespace

TEST(Thickness, ConcentricSpheres)
{
  // Skin sphere R = 50 mm around a bone sphere R = 40 mm, 1 mm voxels.
  const Ellipsoid skin(Eigen::Vector3d(1.3, -0.7, 0.4), Eigen::Vector3d(50, 50, 50));
  const Ellipsoid bone(Eigen::Vector3d(1.3, -0.7, 0.4), Eigen::Vector3d(40, 40, 40));
  const Phantom p = makePhantom(centredGeometry(Eigen::Vector3i(116, 116, 116), Eigen::Vector3d::Ones(),
                                                Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()),
                                skin, bone, {}, 1.0, 20.0, VTK_FLOAT);
  const CylindricalFrame frame(skin.centre, Eigen::Vector3d::UnitZ(), -30, 30, 256, 61);
  const auto maps = buildRangeMaps(p.ct, p.body, p.bone, frame, midThresholds());

  const RangeMap radial = radialThickness(maps.skin, maps.bone);
  const MapError radialError =
    compare(radial, [](double, double z) { return std::sqrt(50.0 * 50.0 - z * z) - std::sqrt(40.0 * 40.0 - z * z); });
  print("spheres: radial thickness", radialError);
  EXPECT_LT(radialError.rms, 0.3);
  EXPECT_EQ(radialError.missing, 0u);

  const RangeMap normal = normalThickness(maps.skin, maps.bone);
  const MapError normalError = compare(normal, [](double, double) { return 10.0; });
  print("spheres: normal thickness", normalError);
  EXPECT_LT(normalError.rms, 0.3);
  // Near zMin/zMax the normal leaves the bone map's z range: NaN there only.
  EXPECT_GT(normalError.compared, normal.values().size() * 8 / 10);

  // The smoothed skin (eq. 4.2) gives a steadier normal, same answer.
  const RangeMap smoothNormal = normalThickness(boxSmooth(maps.skin), boxSmooth(maps.bone));
  const MapError smoothError = compare(smoothNormal, [](double, double) { return 10.0; });
  print("spheres: normal thickness, smoothed maps", smoothError);
  EXPECT_LT(smoothError.rms, 0.3);

  const ThicknessStatistics s = thicknessStatistics(normal);
  EXPECT_NEAR(s.mean, 10.0, 0.1);
  EXPECT_NEAR(s.median, 10.0, 0.1);
}

TEST(Thickness, TiltedCoaxialCylinders)
{
  // Skin cylinder R = 50, bone R = 38 around a tilted axis, 0.8 x 0.8 x 1.5 mm voxels;
  // radial and normal thickness are both 12 mm on a frame along that axis.
  const Eigen::Vector3d point(2.0, -3.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(0.1, -0.2, 1.0).normalized();
  const Cylinder skin(point, axis, 50.0);
  const Cylinder bone(point, axis, 38.0);
  const Phantom p = makePhantom(
    centredGeometry(Eigen::Vector3i(176, 176, 92), Eigen::Vector3d(0.8, 0.8, 1.5), Eigen::Matrix3d::Identity(), point),
    skin, bone, {}, 1.0, 20.0, VTK_SHORT);
  const CylindricalFrame frame(point, axis, -40, 40, 360, 81);
  const auto maps = buildRangeMaps(p.ct, p.body, p.bone, frame, midThresholds());
  const MapError skinError = compare(maps.skin, [](double, double) { return 50.0; });
  const MapError boneError = compare(maps.bone, [](double, double) { return 38.0; });
  print("tilted cylinders: skin", skinError);
  print("tilted cylinders: bone", boneError);
  EXPECT_LT(skinError.rms, 0.3 * 0.8);
  EXPECT_LT(boneError.rms, 0.3 * 0.8);
  EXPECT_EQ(skinError.missing + boneError.missing, 0u);

  const MapError radialError = compare(radialThickness(maps.skin, maps.bone), [](double, double) { return 12.0; });
  const RangeMap normal = normalThickness(maps.skin, maps.bone);
  const MapError normalError = compare(normal, [](double, double) { return 12.0; });
  print("tilted cylinders: radial thickness", radialError);
  print("tilted cylinders: normal thickness", normalError);
  EXPECT_LT(radialError.rms, 0.3 * 0.8);
  EXPECT_LT(normalError.rms, 0.3 * 0.8);
  // Only on the first and last rows may the (one-sided, noisy) normal leave the z range.
  std::size_t missingInside = 0;
  for (int j = 1; j < normal.nZ() - 1; ++j)
    for (int i = 0; i < normal.nTheta(); ++i)
      missingInside += std::isnan(normal.at(i, j));
  EXPECT_EQ(missingInside, 0u);
}

TEST(Thickness, RadialOfAnalyticMapsAndStatistics)
{
  const CylindricalFrame frame(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 0, 10, 4, 3);
  RangeMap skin(frame), bone(frame);
  // 12 samples: thickness 1..10, two NaN (one in each map).
  for (int k = 0; k < 12; ++k)
  {
    skin.values()[k] = 50.0f + k;
    bone.values()[k] = 50.0f - 1.0f;
  }
  skin.values()[10] = RangeMap::quietNaN();
  bone.values()[11] = RangeMap::quietNaN();
  const RangeMap t = radialThickness(skin, bone);
  EXPECT_TRUE(std::isnan(t.values()[10]));
  EXPECT_TRUE(std::isnan(t.values()[11]));
  const ThicknessStatistics s = thicknessStatistics(t);
  EXPECT_EQ(s.count, 10u);
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 10.0);
  EXPECT_DOUBLE_EQ(s.mean, 5.5);
  EXPECT_DOUBLE_EQ(s.median, 5.5);
  EXPECT_NEAR(s.standardDeviation, std::sqrt(82.5 / 9.0), 1e-12);
  EXPECT_NEAR(s.p25, 3.25, 1e-12); // NumPy: np.percentile(range(1, 11), 25) = 3.25
  EXPECT_NEAR(s.p95, 9.55, 1e-12);
  EXPECT_NEAR(thicknessPercentile(t, 0), 1.0, 1e-12);
  EXPECT_EQ(thicknessStatistics(RangeMap(frame)).count, 0u);
  EXPECT_TRUE(std::isnan(thicknessPercentile(RangeMap(frame), 50)));
  // Different frames are refused.
  EXPECT_THROW(radialThickness(skin, RangeMap(frame.withGrid(8, 3))), std::invalid_argument);
}
