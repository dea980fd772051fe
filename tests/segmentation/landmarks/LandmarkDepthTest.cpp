// Landmark depths measured in a synthetic CT: a skin sphere over a bone
// sphere, each boundary a 2 mm partial-volume ramp whose middle is the
// surface, on an anisotropic grid whose extent does not start at 0. The two
// measures have closed forms: the ray from the skin point along the inward
// normal meets the bone sphere where |p - t n - c_b| = R_b; the nearest bone
// is |p - c_b| - R_b away.

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include <vtkImageData.h>
#include <vtkNew.h>

#include "LandmarkPhantoms.h"
#include "segmentation/LandmarkDepth.h"
#include "segmentation/MetalArtefacts.h"

namespace caps::seg::test {
namespace {

constexpr double kAir = -1000, kTissue = 40, kBone = 1000;
constexpr double kThreshold = 0.5 * (kTissue + kBone); // the ramp's middle: the surface
constexpr double kSkinThreshold = 0.5 * (kAir + kTissue);

struct SpheresCt
{
  Eigen::Vector3d skinCentre{0, 0, 0};
  double skinRadius = 45;
  Eigen::Vector3d boneCentre{0, 0, 0};
  double boneRadius = 35;
  /// A bright bead that is not bone (not in the mask): metal, contrast.
  Eigen::Vector3d beadCentre{1e9, 0, 0};
  double beadRadius = 0;
  /// A thin bony wall (a sinus's) of this outer radius about the bone's
  /// centre, air inside it down to the bone sphere; 0: none. Its HU, spread
  /// by the 2 mm point spread, stays under the threshold; the segmentation
  /// has it in the mask, 1.6 mm thick.
  double wallRadius = 0;
  static constexpr double kWallThickness = 0.6;
  /// A head holder: tissue-like plastic filling y ≥ holderY (behind the
  /// head, LPS); none by default.
  double holderY = 1e9;

  vtkNew<vtkImageData> ct, mask;

  /// A CT's point spread: each boundary a 2 mm ramp.
  static double ramp(double insideBy) { return std::clamp(0.5 * insideBy + 0.5, 0.0, 1.0); }

  double huAt(const Eigen::Vector3d& x) const
  {
    double hu = kAir + (kTissue - kAir) * ramp(skinRadius - (x - skinCentre).norm());
    const double r = (x - boneCentre).norm();
    if (wallRadius > 0)
    {
      // The wall: a 0.6 mm slab seen through a 2 mm box (its peak 30 % of
      // the bone's contrast), then air, then the bone sphere.
      const double inner = wallRadius - kWallThickness;
      hu += (kBone - kTissue) * std::max(0.0, std::min(r + 1.0, wallRadius) - std::max(r - 1.0, inner)) / 2.0;
      hu += (kAir - kTissue) * ramp(inner - 1.0 - r);
      hu += (kBone - kAir) * ramp(boneRadius - r);
    }
    else
      hu += (kBone - kTissue) * ramp(boneRadius - r);
    hu = std::max(hu, kAir + (kTissue - kAir) * ramp(x.y() - holderY));
    if ((x - beadCentre).norm() < beadRadius)
      hu = 3000;
    return hu;
  }

  void build()
  {
    for (vtkImageData* image : {ct.GetPointer(), mask.GetPointer()})
    {
      image->SetExtent(10, 109, -5, 94, 3, 75);
      image->SetSpacing(1.0, 1.0, 1.4);
      image->SetOrigin(-60.0, -45.0, -54.2); // voxel (10, -5, 3) at (-50, -50, -50)
    }
    ct->AllocateScalars(VTK_SHORT, 1);
    mask->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
    const int* e = ct->GetExtent();
    for (int k = e[4]; k <= e[5]; ++k)
      for (int j = e[2]; j <= e[3]; ++j)
        for (int i = e[0]; i <= e[1]; ++i)
        {
          double world[3];
          ct->TransformIndexToPhysicalPoint(i, j, k, world);
          const Eigen::Vector3d x(world[0], world[1], world[2]);
          const double hu = huAt(x);
          *static_cast<short*>(ct->GetScalarPointer(i, j, k)) = static_cast<short>(std::lround(hu));
          const double r = (x - boneCentre).norm();
          const bool wall = wallRadius > 0 && std::abs(r - (wallRadius - 0.5 * kWallThickness)) <= 0.8;
          const bool bone = wall || (r <= boneRadius && hu >= kThreshold);
          *static_cast<unsigned char*>(mask->GetScalarPointer(i, j, k)) = bone ? 1 : 0;
        }
  }

  /// The closed forms from the skin point in direction u from the skin's centre.
  double alongNormal(const Eigen::Vector3d& u) const
  {
    const Eigen::Vector3d p = skinCentre + skinRadius * u, n = -u;
    // |p + t n - c|^2 = R^2: t^2 + 2 t n.(p - c) + |p - c|^2 - R^2 = 0, the smaller root.
    const Eigen::Vector3d w = p - boneCentre;
    const double b = n.dot(w), c = w.squaredNorm() - boneRadius * boneRadius;
    return -b - std::sqrt(b * b - c);
  }
  double nearest(const Eigen::Vector3d& u) const
  {
    return (skinCentre + skinRadius * u - boneCentre).norm() - boneRadius;
  }
};

std::vector<Eigen::Vector3d> directions()
{
  std::vector<Eigen::Vector3d> out;
  for (double polar : {-50.0, -20.0, 0.0, 25.0, 55.0})
    for (double azimuth = -170.0; azimuth < 180.0; azimuth += 40.0)
      out.emplace_back(std::cos(polar * kDeg) * std::cos(azimuth * kDeg),
                       std::cos(polar * kDeg) * std::sin(azimuth * kDeg), std::sin(polar * kDeg));
  return out;
}

TEST(LandmarkDepth, ConcentricSpheresGiveTheLayerThicknessBothWays)
{
  SpheresCt phantom;
  phantom.build();
  const BoneDepthProbe probe(phantom.ct, phantom.mask, kThreshold, kSkinThreshold);
  double worst = 0.0;
  for (const Eigen::Vector3d& u : directions())
  {
    const BoneDepth d = probe.measure(phantom.skinCentre + phantom.skinRadius * u);
    EXPECT_NEAR(d.alongSkinNormal, 10.0, 0.3);
    EXPECT_NEAR(d.toNearestBone, 10.0, 0.3);
    EXPECT_GT(d.inwardNormal.dot(-u), std::cos(1.0 * kDeg)); // the CT's normal is the sphere's
    worst = std::max({worst, std::abs(d.alongSkinNormal - 10.0), std::abs(d.toNearestBone - 10.0)});
  }
  std::printf("concentric spheres, 10 mm of tissue: worst error %.3f mm over %zu points\n", worst, directions().size());
}

TEST(LandmarkDepth, OffsetBoneSeparatesTheSkinNormalFromTheNearestBone)
{
  SpheresCt phantom;
  phantom.boneCentre = {0.0, 12.0, 0.0};
  phantom.boneRadius = 25.0;
  phantom.build();
  const BoneDepthProbe probe(phantom.ct, phantom.mask, kThreshold, kSkinThreshold);
  int differing = 0;
  double worstNormal = 0.0, worstDepth = 0.0;
  for (const Eigen::Vector3d& u : directions())
  {
    const BoneDepth d = probe.measure(phantom.skinCentre + phantom.skinRadius * u);
    const double along = phantom.alongNormal(u), nearest = phantom.nearest(u);
    worstNormal = std::max(worstNormal, std::acos(std::min(1.0, d.inwardNormal.dot(-u))) / kDeg);
    worstDepth = std::max({worstDepth, std::abs(d.alongSkinNormal - along), std::abs(d.toNearestBone - nearest)});
    EXPECT_NEAR(d.alongSkinNormal, along, 0.3) << u.transpose();
    EXPECT_NEAR(d.toNearestBone, nearest, 0.3) << u.transpose();
    EXPECT_LE(d.toNearestBone, d.alongSkinNormal + 1e-9);
    // The points found lie on the bone surface.
    EXPECT_NEAR((d.nearestBone - phantom.boneCentre).norm(), phantom.boneRadius, 0.3);
    EXPECT_NEAR((d.boneAlongNormal - phantom.boneCentre).norm(), phantom.boneRadius, 0.3);
    differing += along - nearest > 1.0;
  }
  EXPECT_GT(differing, 5); // the phantom does tell the two conventions apart
  EXPECT_LT(worstNormal, 1.0);
  std::printf("bone 12 mm off centre: worst skin normal %.2f deg, worst depth error %.3f mm; %d of %zu points "
              "differ by more than 1 mm between the conventions\n",
              worstNormal, worstDepth, differing, directions().size());
}

TEST(LandmarkDepth, BrightTissueOutsideTheBoneMaskIsNotBone)
{
  SpheresCt phantom;
  phantom.beadCentre = {0.0, -40.0, 0.0}; // 5 mm under the skin at the front (-y)
  phantom.beadRadius = 2.5;
  phantom.build();
  const BoneDepthProbe probe(phantom.ct, phantom.mask, kThreshold, kSkinThreshold);
  const BoneDepth d = probe.measure({0.0, -45.0, 0.0});
  EXPECT_NEAR(d.alongSkinNormal, 10.0, 0.3);
  EXPECT_NEAR(d.toNearestBone, 10.0, 0.3);
}

TEST(LandmarkDepth, AThinWallInTheMaskIsBoneThoughItsHuStaysUnderTheThreshold)
{
  // Skin at 45 mm, a 0.6 mm wall at 33 mm (its HU peak about 330 against a
  // 520 threshold), air, bone from 20 mm: the wall is the bone under the skin.
  SpheresCt phantom;
  phantom.wallRadius = 33.0;
  phantom.boneRadius = 20.0;
  phantom.build();
  double peak = -1e9;
  for (double r = 30.0; r <= 36.0; r += 0.05)
    peak = std::max(peak, phantom.huAt({0.0, -r, 0.0}));
  ASSERT_LT(peak, kThreshold); // the wall never reaches the threshold
  const BoneDepthProbe probe(phantom.ct, phantom.mask, kThreshold, kSkinThreshold);
  for (const Eigen::Vector3d& u : directions())
  {
    const BoneDepth d = probe.measure(phantom.skinCentre + phantom.skinRadius * u);
    // To the wall, to within a voxel of the mask's edge (not the bone 25 mm deep).
    EXPECT_NEAR(d.alongSkinNormal, 45.0 - 33.0, 1.5) << u.transpose();
    EXPECT_NEAR(d.toNearestBone, 45.0 - 33.0, 1.5) << u.transpose();
  }
}

TEST(MetalArtefacts, MetalIsFoundWithTheSlicesItsStreaksSpoil)
{
  // Two fillings (3071 HU beads of 2 and 1.5 mm radius) in the head, and a
  // speck of saturated enamel (one voxel) that is no metal.
  SpheresCt phantom;
  phantom.build();
  auto put = [&](const Eigen::Vector3d& centre, double radius) {
    int n = 0;
    const int* e = phantom.ct->GetExtent();
    for (int k = e[4]; k <= e[5]; ++k)
      for (int j = e[2]; j <= e[3]; ++j)
        for (int i = e[0]; i <= e[1]; ++i)
        {
          double world[3];
          phantom.ct->TransformIndexToPhysicalPoint(i, j, k, world);
          if ((Eigen::Vector3d(world[0], world[1], world[2]) - centre).norm() <= radius)
          {
            *static_cast<short*>(phantom.ct->GetScalarPointer(i, j, k)) = 3071;
            ++n;
          }
        }
    return n;
  };
  const int big = put({10.0, -30.0, -8.4}, 2.0);
  const int small = put({-12.0, -28.0, 14.0}, 1.5);
  *static_cast<short*>(phantom.ct->GetScalarPointer(60, 40, 40)) = 3071;
  ASSERT_GT(big, small);
  const std::vector<MetalPiece> pieces = findMetal(phantom.ct);
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_EQ(pieces[0].voxels, big); // largest first
  EXPECT_EQ(pieces[1].voxels, small);
  EXPECT_LT((pieces[0].centroid - Eigen::Vector3d(10.0, -30.0, -8.4)).norm(), 0.5);
  EXPECT_LT((pieces[1].centroid - Eigen::Vector3d(-12.0, -28.0, 14.0)).norm(), 0.5);
  EXPECT_EQ(pieces[0].peakHu, 3071.0);
  // Its slices, 5 mm (4 slices of 1.4 mm) either side, are spoiled: a skin
  // point 8 mm from it in its slice is, one 9 mm above it is not.
  EXPECT_EQ(pieces[0].lastSpoiled - pieces[0].lastSlice, 4);
  EXPECT_EQ(streaksAt(pieces, phantom.ct, {40.0, 8.0, -8.4}), &pieces[0]);
  EXPECT_EQ(streaksAt(pieces, phantom.ct, {10.0, -30.0, -8.4 + 2.0 + 5.0 + 2.0}), nullptr);
  EXPECT_NE(describe(pieces[0], phantom.ct).find("3071.0 HU"), std::string::npos) << describe(pieces[0], phantom.ct);
  // A CT without metal has none.
  SpheresCt clean;
  clean.build();
  EXPECT_TRUE(findMetal(clean.ct).empty());
}

TEST(LandmarkDepth, NoBoneWithinReachIsNaNAndBadImagesAreRefused)
{
  SpheresCt phantom;
  phantom.build();
  const BoneDepthProbe nearOnly(phantom.ct, phantom.mask, kThreshold, kSkinThreshold, 5.0);
  const BoneDepth d = nearOnly.measure({45.0, 0.0, 0.0});
  EXPECT_TRUE(std::isnan(d.alongSkinNormal));
  EXPECT_TRUE(std::isnan(d.toNearestBone));
  EXPECT_THROW(BoneDepthProbe(phantom.ct, phantom.ct, kThreshold), std::invalid_argument); // not a mask
  vtkNew<vtkImageData> other;
  other->SetDimensions(5, 5, 5);
  other->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  EXPECT_THROW(BoneDepthProbe(phantom.ct, other, kThreshold), std::invalid_argument);
}

// Skin pressed against the head holder: tissue-like HU just outside it. The
// skin beside it, or facing air, or 3 mm clear of the holder, is not.
TEST(LandmarkDepth, SkinAgainstTheHeadHolderIsFound)
{
  for (const double gap : {0.0, 3.0})
  {
    SpheresCt s;
    s.holderY = s.skinRadius + gap;
    s.build();
    const CtSampler ct(s.ct);
    const Eigen::Vector3d back = Eigen::Vector3d::UnitY(), front = -back, side = Eigen::Vector3d::UnitX();
    EXPECT_EQ(skinAgainstAnObject(ct, s.skinRadius * back, back, kSkinThreshold), gap == 0.0) << "gap " << gap;
    EXPECT_FALSE(skinAgainstAnObject(ct, s.skinRadius * front, front, kSkinThreshold)) << "gap " << gap;
    EXPECT_FALSE(skinAgainstAnObject(ct, s.skinRadius * side, side, kSkinThreshold)) << "gap " << gap;
  }
}

TEST(LandmarkDepth, EachLandmarkHasItsPublishedConvention)
{
  EXPECT_EQ(depthConventionOf("pronasale"), DepthConvention::NotADepth);
  EXPECT_EQ(depthConventionOf("menton"), DepthConvention::NearestBone);
  EXPECT_EQ(depthConventionOf("supraorbital_left"), DepthConvention::NearestBone); // the rim's edge
  EXPECT_EQ(depthConventionOf("infraorbital_right"), DepthConvention::NearestBone);
  EXPECT_EQ(depthConventionOf("glabella"), DepthConvention::SkinNormal);
  LandmarkDepth row;
  row.bone.alongSkinNormal = 7.0;
  row.bone.toNearestBone = 5.0;
  row.convention = DepthConvention::SkinNormal;
  EXPECT_EQ(row.depth(), 7.0);
  row.convention = DepthConvention::NearestBone;
  EXPECT_EQ(row.depth(), 5.0);
  row.convention = DepthConvention::NotADepth;
  EXPECT_TRUE(std::isnan(row.depth()));
  // No bone perpendicular to the skin (lips without teeth behind them): the
  // nearest bone, and the table says so.
  row.convention = DepthConvention::SkinNormal;
  row.bone.alongSkinNormal = RangeMap::quietNaN();
  EXPECT_EQ(row.measuredBy(), DepthConvention::NearestBone);
  EXPECT_EQ(row.depth(), 5.0);
  EXPECT_EQ(row.describeConvention(), "to the nearest bone (no bone perpendicular to the skin)");
}

} // namespace
} // namespace caps::seg::test
