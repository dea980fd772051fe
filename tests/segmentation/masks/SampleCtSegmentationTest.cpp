// The embedded sample head-and-neck CT: the body is one solid without the
// table and the head holder, the skin and bone surfaces are closed, the bone
// volume is plausible. Read and segmented once per test binary.

#include <chrono>
#include <cstdio>
#include <iostream>

#include <gtest/gtest.h>

#include "segmentation/CtReader.h"
#include "segmentation/HeadSegmentation.h"
#include "segmentation/SurfaceExtraction.h"
#include "tests/TestPaths.h"
#include "tests/segmentation/masks/MaskTestUtil.h"

namespace caps::seg {
namespace {

class SampleCt : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    ct_ = new CtVolume(readCtVolume(test::sampleCt()));
    const auto start = std::chrono::steady_clock::now();
    // Print each step with the time it started (the log shows where time goes).
    std::string lastStep;
    auto progress = [&](double, const std::string& step) {
      if (step != lastStep)
      {
        const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("[ step     ] %6.2f s  %s\n", t, step.c_str());
        lastStep = step;
      }
      return true;
    };
    masks_ = new HeadMasks(segmentHead(ct_->image, SegmentationParameters{}, progress));
    seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("[ timing   ] sample CT segmentation (512x512x295): %.2f s\n", seconds_);
    for (const auto& note : masks_->notes)
      std::printf("[ note     ] %s\n", note.c_str());
  }
  static void TearDownTestSuite()
  {
    delete masks_;
    delete ct_;
    masks_ = nullptr;
    ct_ = nullptr;
  }
  static CtVolume* ct_;
  static HeadMasks* masks_;
  static double seconds_;
};
CtVolume* SampleCt::ct_ = nullptr;
HeadMasks* SampleCt::masks_ = nullptr;
double SampleCt::seconds_ = 0;

TEST_F(SampleCt, WritesPictures)
{
  vtkImageData* image = ct_->image;
  int dims[3];
  image->GetDimensions(dims);
  const auto folder = test::artifacts() / "segmentation-masks";
  std::filesystem::create_directories(folder);
  for (int k : {dims[2] / 8, dims[2] / 4, dims[2] / 2, 3 * dims[2] / 4, dims[2] - 10})
    test::writeSlicePicture(image, masks_->body, masks_->bone, 2, k,
                            folder / ("sample-axial-" + std::to_string(k) + ".png"));
  test::writeSlicePicture(image, masks_->body, masks_->bone, 0, dims[0] / 2, folder / "sample-sagittal.png");
  test::writeSlicePicture(image, masks_->body, masks_->bone, 1, dims[1] / 2, folder / "sample-coronal.png");
}

// The sample's geometry is identity-oriented (rows j run anterior to
// posterior). In the head's slices (k >= 150, above where the neck meets the
// holder; found from the data: the body's back-most row is 384 or less there),
// the curved head holder and its pillow lie behind the head, in rows >= 430,
// and the holder's side arms at columns < 60 and > 452. None of it may be
// body, and there must be something there, or the check says nothing.
TEST_F(SampleCt, BodyExcludesHeadHolderAndPillow)
{
  vtkImageData* image = ct_->image;
  int dims[3];
  image->GetDimensions(dims);
  ASSERT_EQ(dims[0], 512);
  ASSERT_EQ(dims[2], 295);
  std::size_t holderVoxels = 0, bodyInHolderRegion = 0;
  const auto* body = static_cast<const unsigned char*>(masks_->body->GetScalarPointer());
  for (int k = 150; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i)
      {
        if (j < 430 && i >= 60 && i <= 452)
          continue;
        const std::size_t n = (std::size_t(k) * dims[1] + j) * dims[0] + i;
        holderVoxels += image->GetScalarComponentAsDouble(i, j, k, 0) > -400;
        bodyInHolderRegion += body[n];
      }
  std::printf("[ info     ] holder region: %zu voxels above -400 HU, %zu of them body\n", holderVoxels,
              bodyInHolderRegion);
  EXPECT_GT(holderVoxels * test::voxelVolume(image), 10000.0); // > 10 cm³ of holder and pillow
  EXPECT_EQ(bodyInHolderRegion, 0u);
}

TEST_F(SampleCt, BodyIsOneSolidComponent)
{
  EXPECT_EQ(test::countComponents(masks_->body), 1u);
  // One solid: no enclosed air. The complement, padded with one layer of
  // background all round (so that the pockets of outside air cut off by the
  // image border join the rest), is one 6-connected region.
  int dims[3];
  masks_->body->GetDimensions(dims);
  auto complement = vtkSmartPointer<vtkImageData>::New();
  complement->SetDimensions(dims[0] + 2, dims[1] + 2, dims[2] + 2);
  complement->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  auto* c = static_cast<unsigned char*>(complement->GetScalarPointer());
  std::fill_n(c, complement->GetNumberOfPoints(), static_cast<unsigned char>(1));
  test::forEachVoxel(masks_->body, [&](int i, int j, int k, unsigned char v) {
    c[(std::size_t(k + 1) * (dims[1] + 2) + (j + 1)) * (dims[0] + 2) + (i + 1)] = v ? 0 : 1;
  });
  EXPECT_EQ(test::countComponents(complement, false), 1u);
}

TEST_F(SampleCt, MasksHaveTheCtGeometry)
{
  for (vtkImageData* mask : {masks_->body.Get(), masks_->bone.Get()})
  {
    ASSERT_NE(mask, nullptr);
    EXPECT_EQ(mask->GetScalarType(), VTK_UNSIGNED_CHAR);
    for (int a = 0; a < 6; ++a)
      EXPECT_EQ(mask->GetExtent()[a], ct_->image->GetExtent()[a]);
    for (int a = 0; a < 3; ++a)
    {
      EXPECT_DOUBLE_EQ(mask->GetOrigin()[a], ct_->image->GetOrigin()[a]);
      EXPECT_DOUBLE_EQ(mask->GetSpacing()[a], ct_->image->GetSpacing()[a]);
    }
    for (int e = 0; e < 9; ++e)
      EXPECT_DOUBLE_EQ(mask->GetDirectionMatrix()->GetData()[e], ct_->image->GetDirectionMatrix()->GetData()[e]);
  }
}

// Bone: the scan covers the skull below the vertex, the face, the cervical
// spine, the shoulder girdle and the upper ribs and sternum. An adult skull
// alone holds about 0.5-0.7 L of bone (dry skull mass ~0.6-0.9 kg at a
// density near 1.3-1.9 g/cm³), the cervical spine, clavicles, scapulae and
// upper ribs add a few hundred cm³; with the top of the skull missing and
// contrast-filled vessels added, 0.4-1.5 L is plausible, far from the body
// (~9 L) and far from empty.
TEST_F(SampleCt, BoneVolumeIsPlausible)
{
  const double boneMm3 = test::countSet(masks_->bone) * test::voxelVolume(ct_->image);
  const double bodyMm3 = test::countSet(masks_->body) * test::voxelVolume(ct_->image);
  std::printf("[ info     ] body %.3f L, bone %.3f L\n", bodyMm3 * 1e-6, boneMm3 * 1e-6);
  EXPECT_GT(boneMm3, 0.4e6);
  EXPECT_LT(boneMm3, 1.5e6);
  EXPECT_GT(bodyMm3, 4e6);
  EXPECT_LT(bodyMm3, 15e6);
}

// The skin and bone surfaces (smoothed, not decimated). Rule for
// "closed": no boundary edge and no non-manifold edge. Skin: the largest
// connected region holds at least 99% of the area (a solid without cavities
// has one). Bone cannot be one region in a head-and-neck scan: the mandible,
// each vertebra, the hyoid, clavicles, scapulae, ribs and sternum are
// separate bones (joints and discs lie below 250 HU), and contrast-filled
// vessels add pieces; the skull with the facial skeleton is the largest
// region and must hold at least 60% of the bone area.
TEST_F(SampleCt, SkinAndBoneSurfacesAreClosed)
{
  SurfaceOptions options; // smoothed, not decimated: the label maps' surfaces
  const auto start = std::chrono::steady_clock::now();
  auto skin = extractSurface(masks_->body, options);
  const double skinSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  auto bone = extractSurface(masks_->bone, options);
  const auto skinStats = test::surfaceStats(skin);
  const auto boneStats = test::surfaceStats(bone);
  std::printf("[ timing   ] skin surface (smoothed): %.2f s, %lld triangles\n", skinSeconds,
              static_cast<long long>(skin->GetNumberOfCells()));
  std::printf("[ info     ] skin: %d regions, largest %.4f of the area, %.0f cm², %.3f L\n", skinStats.regions,
              skinStats.largestRegionAreaFraction, skinStats.area / 100, skinStats.volume * 1e-6);
  std::printf("[ info     ] bone: %d regions, largest %.4f of the area, %.0f cm², %.3f L\n", boneStats.regions,
              boneStats.largestRegionAreaFraction, boneStats.area / 100, boneStats.volume * 1e-6);
  EXPECT_EQ(skinStats.boundaryEdges, 0);
  EXPECT_EQ(skinStats.nonManifoldEdges, 0);
  EXPECT_GE(skinStats.largestRegionAreaFraction, 0.99);
  std::printf("[ info     ] edges: skin %lld boundary %lld non-manifold, bone %lld boundary "
              "%lld non-manifold\n",
              static_cast<long long>(skinStats.boundaryEdges), static_cast<long long>(skinStats.nonManifoldEdges),
              static_cast<long long>(boneStats.boundaryEdges), static_cast<long long>(boneStats.nonManifoldEdges));
  EXPECT_EQ(boneStats.boundaryEdges, 0);
  EXPECT_EQ(boneStats.nonManifoldEdges, 0);
  EXPECT_GE(boneStats.largestRegionAreaFraction, 0.6);
  // The surface encloses the mask's volume (the smoothing keeps it).
  const double bodyMm3 = test::countSet(masks_->body) * test::voxelVolume(ct_->image);
  EXPECT_NEAR(skinStats.volume / bodyMm3, 1.0, 0.01);

  // Decimated 80% for display: still one region with the same volume.
  options.targetReduction = 0.8;
  const auto decimateStart = std::chrono::steady_clock::now();
  auto display = extractSurface(masks_->body, options);
  const double decimateSeconds =
    std::chrono::duration<double>(std::chrono::steady_clock::now() - decimateStart).count();
  const auto displayStats = test::surfaceStats(display);
  std::printf("[ timing   ] skin surface decimated 80%%: %.2f s, %lld triangles, %lld boundary "
              "%lld non-manifold edges\n",
              decimateSeconds, static_cast<long long>(display->GetNumberOfCells()),
              static_cast<long long>(displayStats.boundaryEdges),
              static_cast<long long>(displayStats.nonManifoldEdges));
  EXPECT_EQ(displayStats.boundaryEdges, 0);
  EXPECT_GE(displayStats.largestRegionAreaFraction, 0.99);
  EXPECT_NEAR(displayStats.volume / skinStats.volume, 1.0, 0.01);
}

} // namespace
} // namespace caps::seg
