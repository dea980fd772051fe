// Thickness painted on a sphere's vertices against the analytic thickness of
// concentric spheres at each vertex.

#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>
#include <vtkFloatArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSphereSource.h>

#include "LandmarkPhantoms.h"
#include "segmentation/Thickness.h"
#include "segmentation/ThicknessPainting.h"

namespace caps::seg::test {
namespace {

vtkSmartPointer<vtkPolyData> skinSphere()
{
  vtkNew<vtkSphereSource> sphere;
  sphere->SetRadius(ConcentricSpheres::skinRadius);
  sphere->SetThetaResolution(96);
  sphere->SetPhiResolution(64);
  sphere->Update();
  return sphere->GetOutput();
}

TEST(ThicknessPainting, MatchesTheAnalyticThicknessAtEveryVertex)
{
  const CylindricalFrame frame = ConcentricSpheres::frame();
  const RangeMap skin = fillMap(frame, ConcentricSpheres::skin);
  const RangeMap bone = fillMap(frame, ConcentricSpheres::bone);
  const RangeMap radial = radialThickness(skin, bone);
  const RangeMap normal = normalThickness(skin, bone);

  vtkSmartPointer<vtkPolyData> surface = skinSphere();
  const long long finite = paintThickness(surface, radial);
  EXPECT_EQ(paintThickness(surface, normal, "normal_thickness_mm"), finite);
  auto* painted = vtkFloatArray::SafeDownCast(surface->GetPointData()->GetArray("thickness_mm"));
  auto* paintedNormal = vtkFloatArray::SafeDownCast(surface->GetPointData()->GetArray("normal_thickness_mm"));
  ASSERT_NE(painted, nullptr);
  ASSERT_NE(paintedNormal, nullptr);
  ASSERT_EQ(painted->GetNumberOfTuples(), surface->GetNumberOfPoints());
  EXPECT_STREQ(surface->GetPointData()->GetScalars()->GetName(), "normal_thickness_mm");

  double worstRadial = 0, worstNormal = 0;
  long long compared = 0, nanOutside = 0, outside = 0;
  for (vtkIdType k = 0; k < surface->GetNumberOfPoints(); ++k)
  {
    double p[3];
    surface->GetPoint(k, p);
    const double z = p[2];
    if (std::abs(z) > 85.0 + 1e-3 || std::hypot(p[0], p[1]) < 1e-6)
    {
      ++outside;
      nanOutside += std::isnan(painted->GetValue(k)) && std::isnan(paintedNormal->GetValue(k));
      continue;
    }
    if (std::abs(z) > 75.0) // the bone sphere's pole: steep, then no bone
      continue;
    ++compared;
    worstRadial = std::max(worstRadial, std::abs(painted->GetValue(k) - ConcentricSpheres::radial(z)));
    worstNormal = std::max(worstNormal, std::abs(paintedNormal->GetValue(k) - 10.0));
  }
  std::printf("[ painting ] %lld vertices, %lld finite, %lld compared (|z| <= 75 mm): worst radial "
              "error %.2e mm, normal %.2e mm; %lld of %lld outside the z range are NaN\n",
              static_cast<long long>(surface->GetNumberOfPoints()), finite, compared, worstRadial, worstNormal,
              nanOutside, outside);
  EXPECT_GT(compared, 3500);
  EXPECT_LT(worstRadial, 0.02);
  EXPECT_LT(worstNormal, 0.05);
  EXPECT_GT(outside, 0);
  EXPECT_EQ(nanOutside, outside);
}

TEST(ThicknessPainting, ReplacesTheArrayAndRefusesNothingToPaint)
{
  const RangeMap constant(ConcentricSpheres::frame(), 7.0f);
  vtkSmartPointer<vtkPolyData> surface = skinSphere();
  paintThickness(surface, constant);
  paintThickness(surface, constant);
  int count = 0;
  for (int a = 0; a < surface->GetPointData()->GetNumberOfArrays(); ++a)
    count += std::string(surface->GetPointData()->GetArrayName(a)) == "thickness_mm";
  EXPECT_EQ(count, 1);
  EXPECT_THROW(paintThickness(nullptr, constant), std::invalid_argument);
  EXPECT_THROW(paintThickness(surface, RangeMap()), std::invalid_argument);
}

} // namespace
} // namespace caps::seg::test
