// segmentHead() on a synthetic head (tests/segmentation/masks/Phantom.h):
// mask volumes against the analytic volumes, the cavity filled, the bone
// island and the table removed, geometry, progress and cancel.

#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include <vtkMatrix3x3.h>

#include "segmentation/HeadSegmentation.h"
#include "tests/segmentation/masks/MaskTestUtil.h"
#include "tests/segmentation/masks/Phantom.h"

namespace caps::seg {
namespace {

// 0.8 x 0.8 x 1.0 mm voxels covering the head (100 x 120 x 110 mm), the table
// behind it (+y) and some air.
const std::array<int, 3> kDims{150, 200, 135};
const std::array<double, 3> kSpacing{0.8, 0.8, 1.0};
const std::array<double, 3> kGridCentre{0.0, 10.0, 0.0};

struct PhantomCase
{
  test::Phantom phantom;
  vtkSmartPointer<vtkImageData> ct;
  HeadMasks masks;
};

const PhantomCase& phantomCase()
{
  static const PhantomCase c = [] {
    PhantomCase p;
    p.ct = p.phantom.image(kDims, kSpacing, nullptr, kGridCentre);
    p.masks = segmentHead(p.ct, SegmentationParameters{});
    return p;
  }();
  return c;
}

bool setAt(vtkImageData* mask, const std::array<double, 3>& p)
{
  // Identity direction: index = (p - origin) / spacing, nearest voxel.
  int ijk[3];
  for (int a = 0; a < 3; ++a)
    ijk[a] = static_cast<int>(std::lround((p[a] - mask->GetOrigin()[a]) / mask->GetSpacing()[a]));
  return *static_cast<unsigned char*>(mask->GetScalarPointer(ijk)) != 0;
}

// Expected volumes: the threshold crossing of a blurred edge sits a known
// distance from the true edge (Phantom::thresholdShift: -0.12 mm for the skin
// at -400 HU between air and 40 HU, +0.28 mm for the bone at 250 HU between
// 40 and 700 HU with a 0.6 mm blur); ellipsoids with axes moved by that much.
// Tolerances: 1% for the body (the voxelised surface of a 690 cm³ ellipsoid
// at 0.8 mm; measured 0.00%), 3% for the 6 mm skull shell (two surfaces,
// each carrying the voxelisation error on a thin layer; measured -0.06%).
TEST(HeadSegmentationPhantom, MaskVolumesMatchTheAnalyticVolumes)
{
  const auto& c = phantomCase();
  const auto& ph = c.phantom;
  const double voxel = test::voxelVolume(c.ct);
  const double skinShift = ph.thresholdShift(-400, ph.airHu, ph.tissueHu);
  const double boneShift = ph.thresholdShift(250, ph.tissueHu, ph.boneHu);
  const double bodyExpected = ph.ellipsoidVolume(ph.head, skinShift);
  const double boneExpected = ph.ellipsoidVolume(ph.offsetAxes(ph.skullOffset), boneShift) -
                              ph.ellipsoidVolume(ph.offsetAxes(ph.skullOffset + ph.skullThickness), -boneShift);
  const double body = test::countSet(c.masks.body) * voxel;
  const double bone = test::countSet(c.masks.bone) * voxel;
  std::printf("[ info     ] body %.1f cm³ (expected %.1f, error %+.2f%%), bone %.1f cm³ "
              "(expected %.1f, error %+.2f%%)\n",
              body / 1e3, bodyExpected / 1e3, 100 * (body / bodyExpected - 1), bone / 1e3, boneExpected / 1e3,
              100 * (bone / boneExpected - 1));
  for (const auto& note : c.masks.notes)
    std::printf("[ note     ] %s\n", note.c_str());
  EXPECT_NEAR(body / bodyExpected, 1.0, 0.01);
  EXPECT_NEAR(bone / boneExpected, 1.0, 0.03);
  EXPECT_EQ(test::countComponents(c.masks.body), 1u);
}

TEST(HeadSegmentationPhantom, CavityIsFilledIslandAndTableRemoved)
{
  const auto& c = phantomCase();
  const auto& ph = c.phantom;
  const auto cavity = ph.at(ph.cavityCentre);
  const auto island = ph.at(ph.islandCentre);
  const double headBack = ph.centre[1] + ph.head[1];
  std::size_t cavityVoxels = 0, cavityFilled = 0, islandBone = 0, tableBody = 0, tableVoxels = 0;
  int dims[3];
  c.ct->GetDimensions(dims);
  const auto* hu = static_cast<const short*>(c.ct->GetScalarPointer());
  const auto* body = static_cast<const unsigned char*>(c.masks.body->GetScalarPointer());
  const auto* bone = static_cast<const unsigned char*>(c.masks.bone->GetScalarPointer());
  std::size_t n = 0;
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i, ++n)
      {
        const auto p = test::worldOf(c.ct, i, j, k);
        auto distance = [&](const std::array<double, 3>& q) {
          return std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]);
        };
        if (distance(cavity) < ph.cavityRadius - 1.0)
        {
          ++cavityVoxels;
          cavityFilled += body[n];
        }
        if (distance(island) < ph.islandRadius + 1.0)
          islandBone += bone[n];
        // Beyond the head's back by more than 1.5 mm: the post and the table
        // (the post may leave a sliver of up to reconstructionMarginMm).
        if (p[1] > headBack + 1.5)
        {
          tableVoxels += hu[n] > -400;
          tableBody += body[n];
        }
      }
  EXPECT_GT(cavityVoxels, 1000u);
  EXPECT_EQ(cavityFilled, cavityVoxels);
  EXPECT_EQ(islandBone, 0u);
  EXPECT_GT(tableVoxels * test::voxelVolume(c.ct), 50000.0); // the table is there: > 50 cm³
  EXPECT_EQ(tableBody, 0u);
  // The island is really there: without the island removal it is bone.
  SegmentationParameters keepIslands;
  keepIslands.minBoneIslandMm3 = 0;
  const auto masks = segmentHead(c.ct, keepIslands);
  EXPECT_TRUE(setAt(masks.bone, island));
  EXPECT_TRUE(setAt(masks.body, cavity));
  EXPECT_FALSE(setAt(masks.bone, cavity));
}

TEST(HeadSegmentationPhantom, MasksHaveTheCtGeometry)
{
  const auto& c = phantomCase();
  for (vtkImageData* mask : {c.masks.body.Get(), c.masks.bone.Get()})
  {
    EXPECT_EQ(mask->GetScalarType(), VTK_UNSIGNED_CHAR);
    EXPECT_EQ(mask->GetNumberOfScalarComponents(), 1);
    for (int a = 0; a < 6; ++a)
      EXPECT_EQ(mask->GetExtent()[a], c.ct->GetExtent()[a]);
    for (int a = 0; a < 3; ++a)
    {
      EXPECT_DOUBLE_EQ(mask->GetOrigin()[a], c.ct->GetOrigin()[a]);
      EXPECT_DOUBLE_EQ(mask->GetSpacing()[a], c.ct->GetSpacing()[a]);
    }
    std::size_t other = 0;
    test::forEachVoxel(mask, [&](int, int, int, unsigned char v) { other += v > 1; });
    EXPECT_EQ(other, 0u);
  }
}

// The same anatomy sampled on a rotated, anisotropic grid (float HU this
// time): the masks must agree with the ellipsoid in LPS voxel by voxel away
// from its surface, and the volume must not change.
TEST(HeadSegmentationPhantom, RotatedGridGivesTheSameAnatomy)
{
  test::Phantom ph;
  ph.table = false;
  auto direction = test::rotation(35.0, {0.3, -0.5, 0.8});
  auto shortCt = ph.image({150, 150, 140}, {0.9, 1.0, 1.1}, direction, {0, 0, 0});
  auto ct = vtkSmartPointer<vtkImageData>::New();
  ct->CopyStructure(shortCt);
  ct->SetDirectionMatrix(direction);
  ct->AllocateScalars(VTK_FLOAT, 1);
  for (vtkIdType n = 0; n < ct->GetNumberOfPoints(); ++n)
    static_cast<float*>(ct->GetScalarPointer())[n] = static_cast<const short*>(shortCt->GetScalarPointer())[n];
  const auto masks = segmentHead(ct, SegmentationParameters{});
  EXPECT_EQ(masks.body->GetDirectionMatrix()->GetElement(0, 1), direction->GetElement(0, 1));

  std::size_t wrong = 0, checked = 0;
  test::forEachVoxel(masks.body, [&](int i, int j, int k, unsigned char v) {
    const auto p = test::worldOf(ct, i, j, k);
    double q = 0;
    for (int a = 0; a < 3; ++a)
      q += std::pow((p[a] - ph.centre[a]) / ph.head[a], 2);
    const double radial = std::sqrt(q);
    if (std::abs(radial - 1.0) < 0.04) // within ~2 mm of the skin: skip
      return;
    ++checked;
    wrong += (radial < 1.0) != (v != 0);
  });
  EXPECT_GT(checked, 1000000u);
  EXPECT_EQ(wrong, 0u);
  const double expected = ph.ellipsoidVolume(ph.head, ph.thresholdShift(-400, ph.airHu, ph.tissueHu));
  EXPECT_NEAR(test::countSet(masks.body) * test::voxelVolume(ct) / expected, 1.0, 0.01);
}

TEST(HeadSegmentationPhantom, ReportsProgressAndHonoursCancel)
{
  test::Phantom ph;
  ph.table = false;
  auto ct = ph.image({110, 130, 120}, {1.0, 1.0, 1.0});
  std::vector<double> fractions;
  segmentHead(ct, SegmentationParameters{}, [&](double f, const std::string& step) {
    EXPECT_FALSE(step.empty());
    fractions.push_back(f);
    return true;
  });
  ASSERT_GE(fractions.size(), 8u);
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
  for (std::size_t i = 1; i < fractions.size(); ++i)
    EXPECT_GE(fractions[i], fractions[i - 1]);

  // Cancel at several points: each throws Cancelled, never anything else.
  for (double at : {0.0, 0.1, 0.3, 0.5, 0.7, 0.9})
  {
    EXPECT_THROW(segmentHead(ct, SegmentationParameters{}, [at](double f, const std::string&) { return f < at; }),
                 Cancelled)
      << "cancel at " << at;
  }
}

TEST(HeadSegmentation, RefusesEmptyOrAirOnlyImages)
{
  EXPECT_THROW(segmentHead(nullptr, SegmentationParameters{}), std::invalid_argument);
  auto air = vtkSmartPointer<vtkImageData>::New();
  air->SetDimensions(20, 20, 20);
  air->AllocateScalars(VTK_SHORT, 1);
  std::fill_n(static_cast<short*>(air->GetScalarPointer()), 8000, short{-1000});
  EXPECT_THROW(segmentHead(air, SegmentationParameters{}), std::invalid_argument);
}

} // namespace
} // namespace caps::seg
