// Range maps as 16-bit grey PNG and colour maps as RGB PNG (§4.2.1): round trips
// within the stated quantisation step, NaN kept as 0, frame kept in text chunks.

#include <cmath>
#include <filesystem>
#include <numbers>

#include <unistd.h>

#include <gtest/gtest.h>

#include <vtkImageData.h>
#include <vtkPNGReader.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>

#include "segmentation/RangeMapImage.h"

using namespace caps::seg;

namespace {

std::filesystem::path tempPath(const std::string& name)
{
  return std::filesystem::temp_directory_path() / ("caps_scans_" + std::to_string(::getpid()) + "_" + name);
}

/// An ellipsoid head (semi-axes 75, 95, 110 mm) on a 512 × 256 frame reaching past its
/// top and bottom, so the first and last rows are NaN; plus a hole in the face.
RangeMap ellipsoidMap()
{
  const CylindricalFrame f(Eigen::Vector3d(1.5, -2.25, 30.0), Eigen::Vector3d(0.05, -0.1, 1.0), -120.0, 120.0, 512,
                           256);
  RangeMap map(f);
  for (int j = 0; j < f.nZ(); ++j)
    for (int i = 0; i < f.nTheta(); ++i)
    {
      const double t = f.indexToTheta(i), z = f.indexToZ(j);
      const double q = 1.0 - z * z / (110.0 * 110.0);
      if (q > 0.0)
        map.at(i, j) =
          static_cast<float>(std::sqrt(q / (std::pow(std::cos(t) / 75.0, 2) + std::pow(std::sin(t) / 95.0, 2))));
    }
  for (int j = 120; j < 125; ++j)
    for (int i = 120; i < 130; ++i)
      map.at(i, j) = RangeMap::quietNaN();
  return map;
}

} // namespace

TEST(RangeMapImage, SixteenBitRoundTripWithinHalfAStep)
{
  const RangeMap map = ellipsoidMap();
  const auto path = tempPath("range.png");
  const RangeMapImageEncoding e = writeRangeMapPng(map, path.string());
  // r spans less than [0, 95] mm here: step < 95 / 65534 ≈ 1.45e-3 mm.
  EXPECT_GT(e.stepMm, 0.0);
  EXPECT_LT(e.stepMm, 1.5e-3);
  const RangeMap back = readRangeMapPng(path.string());
  EXPECT_EQ(back.frame(), map.frame()); // frame restored exactly from the text chunks
  double maxError = 0.0;
  for (std::size_t k = 0; k < map.values().size(); ++k)
  {
    ASSERT_EQ(std::isnan(map.values()[k]), std::isnan(back.values()[k])) << k;
    if (std::isfinite(map.values()[k]))
      maxError = std::max(maxError, std::abs(static_cast<double>(map.values()[k]) - back.values()[k]));
  }
  EXPECT_LE(maxError, 0.5 * e.stepMm + 1e-5); // + float rounding of r ≈ 95 mm
  RecordProperty("step_mm", std::to_string(e.stepMm));
  RecordProperty("max_error_mm", std::to_string(maxError));
  const RangeMapImageEncoding stored = readRangeMapImageEncoding(path.string());
  EXPECT_EQ(stored.offsetMm, e.offsetMm);
  EXPECT_EQ(stored.stepMm, e.stepMm);
  std::filesystem::remove(path);
}

TEST(RangeMapImage, PictureIsUprightSixteenBitGreyAndNaNIsZero)
{
  const RangeMap map = ellipsoidMap();
  const auto path = tempPath("upright.png");
  writeRangeMapPng(map, path.string());
  auto reader = vtkSmartPointer<vtkPNGReader>::New();
  reader->SetFileName(path.string().c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  int dims[3];
  image->GetDimensions(dims);
  EXPECT_EQ(dims[0], 512);
  EXPECT_EQ(dims[1], 256);
  EXPECT_EQ(image->GetScalarType(), VTK_UNSIGNED_SHORT);
  EXPECT_EQ(image->GetNumberOfScalarComponents(), 1);
  EXPECT_EQ(image->GetScalarComponentAsDouble(0, 0, 0, 0), 0.0);     // below the chin: NaN
  EXPECT_EQ(image->GetScalarComponentAsDouble(125, 122, 0, 0), 0.0); // the hole
  // Column 128 is θ = -π/2 (the face), row 128 z ≈ 0: r = 95 mm, the largest, so near white.
  EXPECT_GT(image->GetScalarComponentAsDouble(128, 128, 0, 0), 65000.0);
  std::filesystem::remove(path);
}

TEST(RangeMapImage, EditedImageWithoutTextChunksReadsWithAKnownFrame)
{
  const RangeMap map = ellipsoidMap();
  const auto path = tempPath("edited.png");
  const RangeMapImageEncoding e = writeRangeMapPng(map, path.string());
  // "Edit" it: paint one pixel to a known grey value and save without the text chunks.
  auto reader = vtkSmartPointer<vtkPNGReader>::New();
  reader->SetFileName(path.string().c_str());
  reader->Update();
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->DeepCopy(reader->GetOutput());
  image->SetScalarComponentFromDouble(200, 100, 0, 0, 30001.0);
  auto writer = vtkSmartPointer<vtkPNGWriter>::New();
  writer->SetFileName(path.string().c_str());
  writer->SetInputData(image);
  writer->Write();
  EXPECT_THROW(readRangeMapPng(path.string()), std::runtime_error);
  const RangeMap back = readRangeMapPng(path.string(), map.frame(), e);
  EXPECT_NEAR(back.at(200, 100), e.offsetMm + 30000.0 * e.stepMm, 1e-5);
  EXPECT_NEAR(back.at(201, 100), map.at(201, 100), e.stepMm);
  EXPECT_THROW(readRangeMapPng(path.string(), map.frame().withGrid(256, 128), e), std::runtime_error);
  std::filesystem::remove(path);
}

TEST(RangeMapImage, ColourMapRoundTripIsExact)
{
  const CylindricalFrame f(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), -50.0, 50.0, 96, 40);
  ColourMap map(f);
  for (int j = 0; j < f.nZ(); ++j)
    for (int i = 0; i < f.nTheta(); ++i)
      map.at(i, j) = {static_cast<std::uint8_t>(i * 2), static_cast<std::uint8_t>(j * 6),
                      static_cast<std::uint8_t>((i * 7 + j * 13) % 256)};
  const auto path = tempPath("colour.png");
  writeColourMapPng(map, path.string());
  const ColourMap back = readColourMapPng(path.string(), f);
  EXPECT_EQ(back.values(), map.values());
  EXPECT_THROW(readColourMapPng(path.string(), f.withGrid(64, 40)), std::runtime_error);
  EXPECT_THROW(readColourMapPng("/nonexistent/colour.png", f), std::runtime_error);
  std::filesystem::remove(path);
}
