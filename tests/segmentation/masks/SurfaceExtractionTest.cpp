// extractSurface(): closed surfaces of the phantom's masks, their volume and
// area against the ellipsoid's, and their position in LPS for rotated,
// mirrored and offset image geometries.

#include <cmath>

#include <gtest/gtest.h>

#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkMatrix3x3.h>
#include <vtkPointData.h>

#include "segmentation/HeadSegmentation.h"
#include "segmentation/SurfaceExtraction.h"
#include "tests/segmentation/masks/MaskTestUtil.h"
#include "tests/segmentation/masks/Phantom.h"

namespace caps::seg {
namespace {

/// Area of an ellipsoid by the midpoint rule on its (theta, phi)
/// parameterisation (converged to 1e-6 at this resolution).
double ellipsoidArea(const std::array<double, 3>& s)
{
  const int nt = 800, np = 1600;
  const double dt = M_PI / nt, dp = 2 * M_PI / np;
  double area = 0;
  for (int i = 0; i < nt; ++i)
  {
    const double t = (i + 0.5) * dt, st = std::sin(t), ct = std::cos(t);
    for (int j = 0; j < np; ++j)
    {
      const double p = (j + 0.5) * dp, sp = std::sin(p), cp = std::cos(p);
      area += st * std::sqrt(s[1] * s[1] * s[2] * s[2] * st * st * cp * cp +
                             s[0] * s[0] * s[2] * s[2] * st * st * sp * sp + s[0] * s[0] * s[1] * s[1] * ct * ct);
    }
  }
  return area * dt * dp;
}

/// Six times the signed enclosed volume, computed here from the triangles
/// (positive when they are oriented with outward normals).
double signedVolume6(vtkPolyData* surface)
{
  double sum = 0;
  vtkIdType n = 0;
  const vtkIdType* ids = nullptr;
  auto polys = surface->GetPolys();
  for (polys->InitTraversal(); polys->GetNextCell(n, ids);)
  {
    double a[3], b[3], c[3];
    surface->GetPoint(ids[0], a);
    surface->GetPoint(ids[1], b);
    surface->GetPoint(ids[2], c);
    sum += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return sum;
}

/// Largest |first-order distance| from the surface's points to the phantom
/// head's ellipsoid, and the fraction of point normals pointing outward.
std::pair<double, double> distanceAndOrientation(vtkPolyData* surface, const test::Phantom& ph, double expectedShift)
{
  double worst = 0;
  std::size_t outward = 0;
  vtkDataArray* normals = surface->GetPointData()->GetNormals();
  for (vtkIdType i = 0; i < surface->GetNumberOfPoints(); ++i)
  {
    double p[3], g[3], q = 0;
    surface->GetPoint(i, p);
    for (int a = 0; a < 3; ++a)
    {
      const double u = p[a] - ph.centre[a];
      q += u * u / (ph.head[a] * ph.head[a]);
      g[a] = u / (ph.head[a] * ph.head[a]);
    }
    const double root = std::sqrt(q);
    const double gradNorm = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) / root;
    worst = std::max(worst, std::abs((root - 1.0) / gradNorm - expectedShift));
    if (normals)
    {
      const double* n = normals->GetTuple3(i);
      outward += n[0] * g[0] + n[1] * g[1] + n[2] * g[2] > 0;
    }
  }
  return {worst, double(outward) / surface->GetNumberOfPoints()};
}

// Body surface of the phantom with the default smoothing: volume within 1% of
// the ellipsoid's (axes moved by the threshold shift), area within 2% (the
// smoothed staircase keeps a little extra area; measured in the output).
TEST(SurfaceExtraction, PhantomSkinMatchesTheEllipsoid)
{
  test::Phantom ph;
  auto ct = ph.image({150, 200, 135}, {0.8, 0.8, 1.0}, nullptr, {0, 10, 0});
  const auto masks = segmentHead(ct, SegmentationParameters{});
  auto skin = extractSurface(masks.body);
  const auto stats = test::surfaceStats(skin);
  const double shift = ph.thresholdShift(-400, ph.airHu, ph.tissueHu);
  const double volume = ph.ellipsoidVolume(ph.head, shift);
  const double area = ellipsoidArea({ph.head[0] + shift, ph.head[1] + shift, ph.head[2] + shift});
  std::printf("[ info     ] skin volume %.1f cm³ (ellipsoid %.1f, %+.2f%%), area %.1f cm² "
              "(ellipsoid %.1f, %+.2f%%)\n",
              stats.volume / 1e3, volume / 1e3, 100 * (stats.volume / volume - 1), stats.area / 100, area / 100,
              100 * (stats.area / area - 1));
  EXPECT_NEAR(stats.volume / volume, 1.0, 0.01);
  EXPECT_NEAR(stats.area / area, 1.0, 0.02);
  EXPECT_EQ(stats.regions, 1);
  EXPECT_EQ(stats.boundaryEdges, 0);
  EXPECT_EQ(stats.nonManifoldEdges, 0);
  EXPECT_GT(signedVolume6(skin), 0.0);

  // The skull is a closed shell: two closed surfaces, outer and inner.
  const auto bone = test::surfaceStats(extractSurface(masks.bone));
  EXPECT_EQ(bone.regions, 2);
  EXPECT_EQ(bone.boundaryEdges, 0);
  EXPECT_EQ(bone.nonManifoldEdges, 0);

  // Decimated for display: 90% fewer triangles, same volume within 1%, closed.
  SurfaceOptions display;
  display.targetReduction = 0.9;
  auto decimated = extractSurface(masks.body, display);
  const auto d = test::surfaceStats(decimated);
  EXPECT_LT(decimated->GetNumberOfCells(), 0.15 * skin->GetNumberOfCells());
  EXPECT_NEAR(d.volume / volume, 1.0, 0.01);
  EXPECT_EQ(d.regions, 1);
  EXPECT_EQ(d.boundaryEdges, 0);
}

// A rotated (and, second, mirrored: left-handed) direction matrix with
// anisotropic spacing: the surface lies on the ellipsoid in LPS (every point
// within 0.7 mm of the blurred-threshold surface: the iso-surface of a binary
// mask is off by up to about half a voxel diagonal before smoothing, and the
// largest spacing is 1.1 mm; a wrong mapping would be off by centimetres) and
// its normals point outward.
TEST(SurfaceExtraction, DirectionMatrixPutsTheSurfaceWhereTheHeadIs)
{
  test::Phantom ph;
  ph.table = false;
  ph.centre = {12.0, -30.0, 700.0}; // somewhere in a scanner's LPS frame
  const double shift = ph.thresholdShift(-400, ph.airHu, ph.tissueHu);
  auto rotated = test::rotation(35.0, {0.3, -0.5, 0.8});
  auto mirrored = vtkSmartPointer<vtkMatrix3x3>::New();
  mirrored->DeepCopy(rotated);
  for (int r = 0; r < 3; ++r)
    mirrored->SetElement(r, 0, -rotated->GetElement(r, 0));
  ASSERT_LT(mirrored->Determinant(), 0.0);
  for (vtkMatrix3x3* direction : {rotated.Get(), mirrored.Get()})
  {
    auto ct = ph.image({150, 150, 140}, {0.9, 1.0, 1.1}, direction, ph.centre);
    const auto masks = segmentHead(ct, SegmentationParameters{});
    auto skin = extractSurface(masks.body);
    const auto [worst, outward] = distanceAndOrientation(skin, ph, shift);
    std::printf("[ info     ] det %+.0f: farthest point %.3f mm from the ellipsoid, %.4f of the "
                "normals outward\n",
                direction->Determinant(), worst, outward);
    EXPECT_LT(worst, 0.7);
    EXPECT_GT(outward, 0.999);
    EXPECT_GT(signedVolume6(skin), 0.0);
    EXPECT_NEAR(test::surfaceStats(skin).volume / ph.ellipsoidVolume(ph.head, shift), 1.0, 0.01);
  }
}

// A box of voxels in an image whose extent does not start at 0: without
// smoothing, the surface's bounds are the box's voxel centres +- half a voxel
// (flying edges at 0.5 between 1 and 0). Its volume is a little less than the
// voxels' (the edges and corners are chamfered).
TEST(SurfaceExtraction, OffsetExtentAndBounds)
{
  auto mask = vtkSmartPointer<vtkImageData>::New();
  mask->SetExtent(5, 34, -3, 26, 10, 29);
  mask->SetOrigin(100.0, -50.0, 20.0);
  mask->SetSpacing(0.5, 0.7, 1.2);
  mask->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  auto* v = static_cast<unsigned char*>(mask->GetScalarPointer());
  std::fill_n(v, mask->GetNumberOfPoints(), static_cast<unsigned char>(0));
  // Voxels i in [10, 19], j in [0, 26] (touches the extent's end), k in [12, 15].
  for (int k = 12; k <= 15; ++k)
    for (int j = 0; j <= 26; ++j)
      for (int i = 10; i <= 19; ++i)
        *static_cast<unsigned char*>(mask->GetScalarPointer(i, j, k)) = 1;
  SurfaceOptions raw;
  raw.smoothingIterations = 0;
  auto surface = extractSurface(mask, raw);
  double b[6];
  surface->GetBounds(b);
  EXPECT_NEAR(b[0], 100.0 + 9.5 * 0.5, 1e-9);
  EXPECT_NEAR(b[1], 100.0 + 19.5 * 0.5, 1e-9);
  EXPECT_NEAR(b[2], -50.0 - 0.5 * 0.7, 1e-9);
  EXPECT_NEAR(b[3], -50.0 + 26.5 * 0.7, 1e-9); // closed beyond the image's last row
  EXPECT_NEAR(b[4], 20.0 + 11.5 * 1.2, 1e-9);
  EXPECT_NEAR(b[5], 20.0 + 15.5 * 1.2, 1e-9);
  const auto stats = test::surfaceStats(surface);
  EXPECT_LT(stats.volume, 10 * 27 * 4 * 0.5 * 0.7 * 1.2);
  EXPECT_GT(stats.volume, 0.95 * 10 * 27 * 4 * 0.5 * 0.7 * 1.2);
  EXPECT_EQ(stats.boundaryEdges, 0);
  EXPECT_EQ(stats.regions, 1);
}

TEST(SurfaceExtraction, EmptyMaskGivesEmptySurface)
{
  auto mask = vtkSmartPointer<vtkImageData>::New();
  mask->SetDimensions(8, 8, 8);
  mask->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  std::fill_n(static_cast<unsigned char*>(mask->GetScalarPointer()), 512, static_cast<unsigned char>(0));
  EXPECT_EQ(extractSurface(mask)->GetNumberOfPoints(), 0);
  EXPECT_THROW(extractSurface(nullptr), std::invalid_argument);
}

} // namespace
} // namespace caps::seg
