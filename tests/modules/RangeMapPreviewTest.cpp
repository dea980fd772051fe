// Range map previews drawn headless: the face in the middle, z up, viridis,
// NaN grey, a colour bar with text; written as PNG and read back.

#include <cmath>
#include <limits>
#include <numbers>

#include <gtest/gtest.h>
#include <vtkPNGReader.h>

#include "modules/rangemap/RangeMapPreview.h"
#include "TestPaths.h"

namespace {

std::array<int, 3> pixel(vtkImageData* image, int x, int y)
{
  const auto* p = static_cast<const unsigned char*>(image->GetScalarPointer(x, y, 0));
  return {p[0], p[1], p[2]};
}

std::array<int, 3> colourOf(double t)
{
  unsigned char c[3];
  caps::viridis(t, c);
  return {c[0], c[1], c[2]};
}

} // namespace

TEST(RangeMapPreview, FaceInTheMiddleZUpNanGrey)
{
  // 64 θ × 32 z: value 0 at the back (θ = π/2), 30 at the face (θ = -π/2),
  // NaN in the top row.
  const int nTheta = 64, nZ = 32;
  Eigen::MatrixXf values(nTheta, nZ);
  for (int i = 0; i < nTheta; ++i)
  {
    const double theta = -std::numbers::pi + 2 * std::numbers::pi * i / nTheta;
    for (int j = 0; j < nZ; ++j)
      values(i, j) = static_cast<float>(15.0 - 15.0 * std::sin(theta));
    values(i, nZ - 1) = std::numeric_limits<float>::quiet_NaN();
  }
  caps::PreviewStyle style;
  style.title = "Test map";
  style.low = 0;
  style.high = 30;
  style.pixelsPerSample = 4;
  const auto image = caps::renderRangeMapPreview(values, -50, 100, style);
  int dims[3];
  image->GetDimensions(dims);
  ASSERT_EQ(image->GetNumberOfScalarComponents(), 3);
  // The map is 256 × 128 pixels inside margins for the text and the colour bar.
  EXPECT_GT(dims[0], 256 + 100);
  EXPECT_GT(dims[1], 128 + 60);

  // Find the map: the left margin is 70 pixels, the bottom one 56 (see the
  // renderer); sample the middle of the map's middle and edge columns.
  const int left = 70, bottom = 56, mapW = 256, mapH = 128;
  EXPECT_EQ(pixel(image, left + mapW / 2, bottom + mapH / 2), colourOf(1.0)); // the face: 30 mm
  EXPECT_EQ(pixel(image, left + 1, bottom + mapH / 2), colourOf(0.0));        // the back: 0 mm
  EXPECT_EQ(pixel(image, left + mapW - 2, bottom + mapH / 2), colourOf(0.0));
  // Patient left (θ = 0, 15 mm) on the right of the face.
  EXPECT_EQ(pixel(image, left + 3 * mapW / 4, bottom + mapH / 2), colourOf(0.5));
  // The NaN row is the top row of the map (z up), grey.
  EXPECT_EQ(pixel(image, left + mapW / 2, bottom + mapH - 2), (std::array<int, 3>{150, 150, 150}));

  // There is text: dark pixels in the title band above the map.
  int dark = 0;
  for (int y = bottom + mapH + 2; y < dims[1]; ++y)
    for (int x = 0; x < dims[0]; ++x)
      dark += pixel(image, x, y)[0] < 100;
  EXPECT_GT(dark, 50) << "no title drawn";

  // Written as PNG and read back with the same size.
  const auto file = caps::test::scratchFolder() / "preview.png";
  caps::writeRangeMapPreview(values, -50, 100, style, file);
  auto reader = vtkSmartPointer<vtkPNGReader>::New();
  reader->SetFileName(file.c_str());
  reader->Update();
  int read[3];
  reader->GetOutput()->GetDimensions(read);
  EXPECT_EQ(read[0], dims[0]);
  EXPECT_EQ(read[1], dims[1]);

  EXPECT_THROW(caps::renderRangeMapPreview(Eigen::MatrixXf(0, 0), 0, 1, style), std::invalid_argument);
}
