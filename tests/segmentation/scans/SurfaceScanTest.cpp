// Surface scans (§3.2.1, §4.2.1): a coloured mesh unwrapped into range and colour
// maps, checked against analytic surfaces (sphere, cylinder) whose colours are a
// known linear function of position.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include <unistd.h>

#include <gtest/gtest.h>

#include <vtkPLYWriter.h>

#include "ScanPhantoms.h"
#include "segmentation/SurfaceScan.h"

using namespace caps::seg;
using caps::seg::test::linearColour;
using caps::seg::test::revolution;

namespace {

constexpr double R = 80.0;

CylindricalFrame tiltedFrame(int nTheta = 256, int nZ = 64)
{
  return CylindricalFrame(Eigen::Vector3d(10, -5, 3), Eigen::Vector3d(0.1, 0.0, 1.0), -60.0, 60.0, nTheta, nZ);
}

double sphereRadius(double z)
{
  return std::sqrt(std::max(0.0, R * R - z * z));
}

vtkSmartPointer<vtkPolyData> sphere(const CylindricalFrame& f)
{
  return revolution(f, 720, 351, -70.0, 70.0, sphereRadius, R);
}

std::filesystem::path tempPath(const std::string& name)
{
  return std::filesystem::temp_directory_path() / ("caps_scans_" + std::to_string(::getpid()) + "_" + name);
}

/// Max |r - analytic| and max colour channel error over the map.
void expectSphere(const SurfaceScan& scan, double rTol, double colourTol)
{
  const CylindricalFrame& f = scan.range.frame();
  double maxR = 0.0, maxC = 0.0;
  for (int j = 0; j < f.nZ(); ++j)
    for (int i = 0; i < f.nTheta(); ++i)
    {
      const float r = scan.range.at(i, j);
      ASSERT_TRUE(std::isfinite(r)) << i << " " << j;
      maxR = std::max(maxR, std::abs(r - sphereRadius(f.indexToZ(j))));
      const auto expected = linearColour(f, scan.range.surfacePoint(i, j), R);
      for (std::size_t c = 0; c < 3; ++c)
        maxC = std::max(maxC, std::abs(scan.colour.at(i, j)[c] - expected[c]));
    }
  EXPECT_LT(maxR, rTol);
  EXPECT_LE(maxC, colourTol);
  ::testing::Test::RecordProperty("max_r_error_mm", std::to_string(maxR));
  ::testing::Test::RecordProperty("max_colour_error", std::to_string(maxC));
}

} // namespace

TEST(SurfaceScan, RayCastSphereMatchesAnalyticRadiusAndColour)
{
  const CylindricalFrame f = tiltedFrame();
  const SurfaceScan scan = surfaceScanFromMesh(f, sphere(f));
  EXPECT_TRUE(scan.hasColours);
  EXPECT_EQ(scan.range.validCount(), static_cast<std::size_t>(f.nTheta()) * f.nZ()); // no holes
  // Facet chord error: R (1 - cos(π/720)) ≈ 7.6e-4 mm around, ≈ 9e-4 mm along meridians.
  // Colour: vertex colours rounded (±0.5), blend rounded (±0.5).
  expectSphere(scan, 3e-3, 1.0);
}

TEST(SurfaceScan, PlyFileWithVertexColoursReadsBackLikeTheMesh)
{
  const CylindricalFrame f = tiltedFrame();
  const auto path = tempPath("sphere.ply");
  auto writer = vtkSmartPointer<vtkPLYWriter>::New();
  writer->SetFileName(path.string().c_str());
  writer->SetInputData(sphere(f));
  writer->SetArrayName("RGB");
  writer->SetColorModeToDefault();
  writer->SetFileTypeToBinary();
  writer->Write();
  const SurfaceScan scan = readSurfaceScan(path.string(), f);
  std::filesystem::remove(path);
  EXPECT_TRUE(scan.hasColours);
  expectSphere(scan, 3e-3, 1.0);
}

TEST(SurfaceScan, ObjFileWithVertexColours)
{
  const CylindricalFrame f = tiltedFrame(128, 32);
  // A coarse cylinder r = 50 with 90 sides; colours as 0..1 floats on the v lines
  // (colour scale 70 mm so the linear colour is not clamped at z = ±65).
  auto mesh = revolution(
    f, 90, 13, -65.0, 65.0, [](double) { return 50.0; }, 70.0);
  const auto path = tempPath("cylinder.obj");
  {
    std::ofstream out(path);
    out.precision(17);
    auto* rgb = vtkUnsignedCharArray::SafeDownCast(mesh->GetPointData()->GetScalars());
    for (vtkIdType k = 0; k < mesh->GetNumberOfPoints(); ++k)
    {
      double p[3];
      mesh->GetPoint(k, p);
      out << "v " << p[0] << ' ' << p[1] << ' ' << p[2] << ' ' << rgb->GetValue(3 * k) / 255.0 << ' '
          << rgb->GetValue(3 * k + 1) / 255.0 << ' ' << rgb->GetValue(3 * k + 2) / 255.0 << '\n';
    }
    auto it = vtk::TakeSmartPointer(mesh->GetPolys()->NewIterator());
    for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell())
    {
      vtkIdType n = 0;
      const vtkIdType* ids = nullptr;
      it->GetCurrentCell(n, ids);
      out << "f " << ids[0] + 1 << ' ' << ids[1] + 1 << ' ' << ids[2] + 1 << '\n';
    }
  }
  const SurfaceScan scan = readSurfaceScan(path.string(), f);
  std::filesystem::remove(path);
  ASSERT_TRUE(scan.hasColours);
  EXPECT_EQ(scan.range.validCount(), static_cast<std::size_t>(f.nTheta()) * f.nZ());
  // A 90-gon: r along a facet is 50 cos(π/90) / cos(φ), φ the angle from the facet
  // middle; the map lies between the apothem and the circumradius.
  const double apothem = 50.0 * std::cos(std::numbers::pi / 90.0);
  double maxC = 0.0;
  for (int j = 0; j < f.nZ(); ++j)
    for (int i = 0; i < f.nTheta(); ++i)
    {
      EXPECT_GE(scan.range.at(i, j), apothem - 1e-4); // VTK points are float
      EXPECT_LE(scan.range.at(i, j), 50.0 + 1e-4);
      const auto expected = linearColour(f, scan.range.surfacePoint(i, j), 70.0);
      for (std::size_t c = 0; c < 3; ++c)
        maxC = std::max(maxC, std::abs(scan.colour.at(i, j)[c] - expected[c]));
    }
  EXPECT_LE(maxC, 1.0);
}

TEST(SurfaceScan, VertexBucketingLeavesHolesOnACoarseMeshRayCastingDoesNot)
{
  const CylindricalFrame f = tiltedFrame(128, 32);
  auto coarse = revolution(
    f, 40, 9, -65.0, 65.0, [](double) { return 50.0; }, 50.0);
  const SurfaceScan vertices = surfaceScanFromMesh(f, coarse, SurfaceScanSampling::Vertices);
  const SurfaceScan rays = surfaceScanFromMesh(f, coarse, SurfaceScanSampling::RayCast);
  const std::size_t all = static_cast<std::size_t>(f.nTheta()) * f.nZ();
  EXPECT_LE(vertices.range.validCount(), 40u * 9u);
  EXPECT_EQ(rays.range.validCount(), all);
}

TEST(SurfaceScan, VertexBucketingOnBucketCentresIsExact)
{
  // One vertex at every sample (θ_i, z_j) on a cylinder r = 50: the §3.2.7 rule
  // gives r = 50 and each vertex's colour exactly.
  const CylindricalFrame f = tiltedFrame(64, 16);
  auto mesh = revolution(
    f, f.nTheta(), f.nZ(), f.zMin(), f.zMax(), [](double) { return 50.0; }, 50.0);
  const SurfaceScan scan = surfaceScanFromMesh(f, mesh, SurfaceScanSampling::Vertices);
  ASSERT_EQ(scan.range.validCount(), static_cast<std::size_t>(f.nTheta()) * f.nZ());
  for (int j = 0; j < f.nZ(); ++j)
    for (int i = 0; i < f.nTheta(); ++i)
    {
      EXPECT_NEAR(scan.range.at(i, j), 50.0, 1e-4);
      const auto expected = linearColour(f, f.toWorld(50.0, f.indexToTheta(i), f.indexToZ(j)), 50.0);
      for (std::size_t c = 0; c < 3; ++c)
        EXPECT_EQ(scan.colour.at(i, j)[c], std::round(expected[c]));
    }
}

TEST(SurfaceScan, OutermostCrossingWins)
{
  // Two concentric cylinders (r = 40 inside r = 60): the map is the outer one.
  const CylindricalFrame f = tiltedFrame(64, 16);
  auto outer = revolution(
    f, 180, 5, -65.0, 65.0, [](double) { return 60.0; }, 60.0);
  auto inner = revolution(
    f, 180, 5, -65.0, 65.0, [](double) { return 40.0; }, 60.0);
  auto both = vtkSmartPointer<vtkPolyData>::New();
  auto points = vtkSmartPointer<vtkPoints>::New();
  auto polys = vtkSmartPointer<vtkCellArray>::New();
  for (vtkPolyData* m : {inner.GetPointer(), outer.GetPointer()})
  {
    const vtkIdType base = points->GetNumberOfPoints();
    for (vtkIdType k = 0; k < m->GetNumberOfPoints(); ++k)
      points->InsertNextPoint(m->GetPoint(k));
    auto it = vtk::TakeSmartPointer(m->GetPolys()->NewIterator());
    for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell())
    {
      vtkIdType n = 0;
      const vtkIdType* ids = nullptr;
      it->GetCurrentCell(n, ids);
      const vtkIdType t[3] = {ids[0] + base, ids[1] + base, ids[2] + base};
      polys->InsertNextCell(3, t);
    }
  }
  both->SetPoints(points);
  both->SetPolys(polys);
  const SurfaceScan scan = surfaceScanFromMesh(f, both);
  EXPECT_FALSE(scan.hasColours);
  for (float r : scan.range.values())
  {
    EXPECT_GE(r, 60.0 * std::cos(std::numbers::pi / 180.0) - 1e-4);
    EXPECT_LE(r, 60.0 + 1e-4);
  }
}

TEST(SurfaceScan, UnreadableFilesThrowWithTheirName)
{
  const CylindricalFrame f = tiltedFrame(64, 16);
  EXPECT_THROW(readSurfaceScan("/nonexistent/head.ply", f), std::runtime_error);
  const auto path = tempPath("head.stl");
  std::ofstream(path) << "solid x\nendsolid x\n";
  try
  {
    readSurfaceScan(path.string(), f);
    ADD_FAILURE() << "no exception";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("head.stl"), std::string::npos);
  }
  std::filesystem::remove(path);
}
