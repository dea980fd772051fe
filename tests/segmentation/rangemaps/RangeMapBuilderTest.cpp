// buildRangeMaps on synthetic CTs: a skin ellipsoid around an off-centre bone
// ellipsoid, partial volume (4³ supersampling), Gaussian blur σ = 1 mm and
// 20 HU noise. Both maps must match the analytic outermost hits of the rays
// better than 0.3 voxel RMS, for float and int16 CTs, for an oblique
// direction matrix, and with a table beside the head that is not in the mask.

#include <cstring>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "RangeMapCompare.h"
#include "RangeMapPhantom.h"
#include "segmentation/RangeMapBuilder.h"

using namespace caps::seg;
using namespace caps::seg::test;

namespace {

const Ellipsoid skinShape(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(45, 54, 64));
const Ellipsoid boneShape(Eigen::Vector3d(0, 3, 2), Eigen::Vector3d(37, 43, 54));
const CylindricalFrame frame(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), -45, 45, 256, 91);
constexpr double sigmaMm = 1.0;
constexpr double noiseHu = 20.0;

RangeMapBuildOptions midThresholds()
{
  RangeMapBuildOptions options;
  options.skinThreshold = skinMidHu;
  options.boneThreshold = boneMidHu;
  return options;
}

double analyticSkin(double theta, double z)
{
  return skinShape.outermostHit(frame.axisPoint(z), frame.radialDirection(theta));
}
double analyticBone(double theta, double z)
{
  return boneShape.outermostHit(frame.axisPoint(z), frame.radialDirection(theta));
}

ImageGeometry anisotropicGrid()
{
  return centredGeometry(Eigen::Vector3i(110, 150, 112), Eigen::Vector3d(1.0, 1.0, 1.25), Eigen::Matrix3d::Identity(),
                         Eigen::Vector3d(0, 10, 0));
}

void expectSubVoxel(const SkinBoneRangeMaps& maps, double voxel, const char* label)
{
  const MapError skin = compare(maps.skin, analyticSkin);
  const MapError bone = compare(maps.bone, analyticBone);
  print((std::string(label) + " skin").c_str(), skin);
  print((std::string(label) + " bone").c_str(), bone);
  EXPECT_LT(skin.rms, 0.3 * voxel);
  EXPECT_LT(bone.rms, 0.3 * voxel);
  EXPECT_EQ(skin.missing + skin.extra + bone.missing + bone.extra, 0u);
  EXPECT_EQ(maps.skinFromMaskEdge + maps.boneFromMaskEdge, 0u);
}

bool sameBits(const RangeMap& a, const RangeMap& b)
{
  return a.values().size() == b.values().size() &&
         std::memcmp(a.values().data(), b.values().data(), a.values().size() * sizeof(float)) == 0;
}

} // namespace

TEST(RangeMapBuilder, EllipsoidPhantomFloatAndInt16)
{
  for (int type : {VTK_FLOAT, VTK_SHORT})
  {
    const Phantom p = makePhantom(anisotropicGrid(), skinShape, boneShape, {}, sigmaMm, noiseHu, type);
    const SkinBoneRangeMaps maps = buildRangeMaps(p.ct, p.body, p.bone, frame, midThresholds());
    expectSubVoxel(maps, 1.0,
                   type == VTK_FLOAT ? "ellipsoids, float, 1x1x1.25 mm:" : "ellipsoids, int16, 1x1x1.25 mm:");
  }
}

TEST(RangeMapBuilder, SameMapsForAnyThreadCount)
{
  const Phantom p = makePhantom(anisotropicGrid(), skinShape, boneShape, {}, sigmaMm, noiseHu, VTK_FLOAT);
  RangeMapBuildOptions one = midThresholds(), four = midThresholds();
  one.threads = 1;
  four.threads = 4;
  const auto a = buildRangeMaps(p.ct, p.body, p.bone, frame, one);
  const auto b = buildRangeMaps(p.ct, p.body, p.bone, frame, four);
  EXPECT_TRUE(sameBits(a.skin, b.skin));
  EXPECT_TRUE(sameBits(a.bone, b.bone));
}

TEST(RangeMapBuilder, ObliqueDirectionMatrixGivesTheSameMaps)
{
  // The same world-space phantom on an identity grid and on a grid rotated
  // 0.5 rad about (1, 2, 3) and mirrored (a left-handed index frame).
  const Eigen::Matrix3d oblique = Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix() *
                                  Eigen::Vector3d(1, -1, 1).asDiagonal();
  const Eigen::Vector3i dims(144, 144, 144);
  const Phantom a =
    makePhantom(centredGeometry(dims, Eigen::Vector3d::Ones(), Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()),
                skinShape, boneShape, {}, sigmaMm, noiseHu, VTK_FLOAT);
  const Phantom b =
    makePhantom(centredGeometry(dims, Eigen::Vector3d::Ones(), oblique, Eigen::Vector3d(0.3, -0.2, 0.1)), skinShape,
                boneShape, {}, sigmaMm, noiseHu, VTK_FLOAT, 8);
  const auto ma = buildRangeMaps(a.ct, a.body, a.bone, frame, midThresholds());
  const auto mb = buildRangeMaps(b.ct, b.body, b.bone, frame, midThresholds());
  expectSubVoxel(ma, 1.0, "ellipsoids, identity grid, 1 mm:");
  expectSubVoxel(mb, 1.0, "ellipsoids, oblique mirrored grid, 1 mm:");
  auto interpolate = [](const RangeMap& m) { return [&m](double t, double z) { return m.sample(t, z); }; };
  const MapError skin = compare(mb.skin, interpolate(ma.skin));
  const MapError bone = compare(mb.bone, interpolate(ma.bone));
  print("oblique vs identity grid, skin", skin);
  print("oblique vs identity grid, bone", bone);
  EXPECT_LT(skin.rms, 0.15);
  EXPECT_LT(bone.rms, 0.15);
  EXPECT_EQ(skin.missing + skin.extra + bone.missing + bone.extra, 0u);
}

TEST(RangeMapBuilder, TableOutsideTheBodyMaskIsNotSkin)
{
  // A table of soft-tissue density 15 mm behind the head, the whole width of the scan.
  const Box table(Eigen::Vector3d(-100, 69, -100), Eigen::Vector3d(100, 80, 100));
  const Phantom p = makePhantom(anisotropicGrid(), skinShape, boneShape, {&table}, sigmaMm, noiseHu, VTK_FLOAT);
  const auto maps = buildRangeMaps(p.ct, p.body, p.bone, frame, midThresholds());
  expectSubVoxel(maps, 1.0, "ellipsoids + table:");
  // The same CT with the table in the mask: the back of the head becomes the table.
  const Phantom wrong =
    makePhantom(anisotropicGrid(), skinShape, boneShape, {&table}, sigmaMm, noiseHu, VTK_FLOAT, 7, true);
  const auto bad = buildRangeMaps(wrong.ct, wrong.body, wrong.bone, frame, midThresholds());
  const int back = static_cast<int>(frame.thetaToIndex(std::numbers::pi / 2));
  EXPECT_NEAR(bad.skin.at(back, 45), 80.0, 1.0);
  EXPECT_NEAR(maps.skin.at(back, 45), analyticSkin(std::numbers::pi / 2, 0.0), 0.3);
}

TEST(RangeMapBuilder, RejectsMismatchedMasks)
{
  const Phantom p = makePhantom(centredGeometry(Eigen::Vector3i(20, 20, 20), Eigen::Vector3d::Ones(),
                                                Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()),
                                Ellipsoid(Eigen::Vector3d::Zero(), Eigen::Vector3d(6, 6, 6)),
                                Ellipsoid(Eigen::Vector3d::Zero(), Eigen::Vector3d(3, 3, 3)), {}, 1.0, 0.0, VTK_FLOAT);
  p.bone->SetOrigin(1, 0, 0);
  EXPECT_THROW(buildRangeMaps(p.ct, p.body, p.bone, frame), std::invalid_argument);
  EXPECT_THROW(buildRangeMaps(p.ct, p.body, nullptr, frame), std::invalid_argument);
}
