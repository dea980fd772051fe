// x-y curves to PNG (the undermining study's plot): a known plot drawn and
// read back, its pixels checked where the data map to.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <stdexcept>

#include <QColor>
#include <QImage>
#include <gtest/gtest.h>

#include "render/XyPlot.h"

namespace caps::render {
namespace {

namespace fs = std::filesystem;

fs::path artifact(const std::string& name)
{
  const fs::path folder = fs::path(CAPS_TEST_ARTIFACTS_DIR) / "incision";
  fs::create_directories(folder);
  return folder / name;
}

/// Distance in RGB between a pixel and 0xRRGGBB.
int colourDistance(QRgb pixel, std::uint32_t rgb)
{
  return std::abs(qRed(pixel) - int((rgb >> 16) & 0xff)) + std::abs(qGreen(pixel) - int((rgb >> 8) & 0xff)) +
         std::abs(qBlue(pixel) - int(rgb & 0xff));
}

/// True if a pixel within @a reach of (x, y) has the colour (to a small tolerance).
bool colourNear(const QImage& image, double x, double y, std::uint32_t rgb, int reach = 2)
{
  for (int dy = -reach; dy <= reach; ++dy)
    for (int dx = -reach; dx <= reach; ++dx)
    {
      const int px = int(std::lround(x)) + dx, py = int(std::lround(y)) + dy;
      if (px >= 0 && py >= 0 && px < image.width() && py < image.height() &&
          colourDistance(image.pixel(px, py), rgb) <= 24)
        return true;
    }
  return false;
}

constexpr std::uint32_t kBlue = 0x1f4e9c;
constexpr std::uint32_t kRed = 0xc0392b;

XyPlot knownPlot()
{
  XyPlot plot;
  plot.title = "A known plot";
  plot.xLabel = "width (mm)";
  plot.series.push_back({"force (N)", {0, 5, 10, 20, 40}, {2.0, 1.8, 1.7, 1.65, 1.62}, kBlue});
  plot.series.push_back({"stress (kPa)", {0, 5, 10, 20, 40}, {22.2, 23.0, 24.0, 26.5, 29.8}, kRed});
  plot.width = 800;
  plot.height = 500;
  plot.yFromZero = false; // the axes span the data: the curves fill the area
  return plot;
}

TEST(XyPlot, NiceTicksCoverTheDataWithRoundSteps)
{
  const std::vector<double> x = niceTicks(0.0, 40.0, 6);
  ASSERT_GE(x.size(), 3u);
  EXPECT_DOUBLE_EQ(x.front(), 0.0);
  EXPECT_DOUBLE_EQ(x.back(), 40.0);
  EXPECT_DOUBLE_EQ(x[1] - x[0], 10.0);
  const std::vector<double> y = niceTicks(1.62, 2.0, 6);
  EXPECT_LE(y.front(), 1.62);
  EXPECT_GE(y.back(), 2.0);
  const double step = y[1] - y[0];
  const double mantissa = step / std::pow(10.0, std::floor(std::log10(step)));
  EXPECT_TRUE(std::abs(mantissa - 1.0) < 1e-9 || std::abs(mantissa - 2.0) < 1e-9 || std::abs(mantissa - 5.0) < 1e-9)
    << step;
  for (std::size_t i = 1; i < y.size(); ++i)
    EXPECT_NEAR(y[i] - y[i - 1], step, 1e-12);
  // A constant is widened around its value.
  const std::vector<double> c = niceTicks(3.0, 3.0);
  EXPECT_LT(c.front(), 3.0);
  EXPECT_GT(c.back(), 3.0);
}

TEST(XyPlot, CurvesAreDrawnWhereTheDataMapTo)
{
  const XyPlot plot = knownPlot();
  const fs::path file = artifact("study-plot-known.png");
  fs::remove(file);
  const XyPlotGeometry g = writeXyPlotPng(plot, file);
  QImage image;
  ASSERT_TRUE(image.load(QString::fromStdString(file.string()), "PNG")) << file;
  EXPECT_EQ(image.width(), 800);
  EXPECT_EQ(image.height(), 500);

  // The data area lies inside the image, with room for the axes' text.
  EXPECT_GT(g.left, 20.0);
  EXPECT_LT(g.right, 780.0);
  EXPECT_GT(g.top, 20.0);
  EXPECT_LT(g.bottom, 480.0);
  EXPECT_LE(g.xRange[0], 0.0);
  EXPECT_GE(g.xRange[1], 40.0);
  ASSERT_EQ(g.yRange.size(), 2u);
  for (std::size_t s = 0; s < 2; ++s)
  {
    const auto [lo, hi] = std::minmax_element(plot.series[s].y.begin(), plot.series[s].y.end());
    EXPECT_LE(g.yRange[s][0], *lo);
    EXPECT_GE(g.yRange[s][1], *hi);
  }

  // Each curve's colour at its data points and half way along its segments.
  for (std::size_t s = 0; s < 2; ++s)
  {
    const PlotSeries& series = plot.series[s];
    for (std::size_t i = 0; i < series.x.size(); ++i)
    {
      const auto p = g.pixel(s, series.x[i], series.y[i]);
      EXPECT_TRUE(colourNear(image, p[0], p[1], series.rgb)) << series.label << " point " << i;
      if (i + 1 < series.x.size())
      {
        const auto q = g.pixel(s, series.x[i + 1], series.y[i + 1]);
        EXPECT_TRUE(colourNear(image, (p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0, series.rgb))
          << series.label << " segment " << i;
      }
    }
  }
  // Just above the bottom of the data area at x = 10, where both curves are
  // well above (a quarter of the height): no curve colour there.
  const double emptyX = g.pixel(0, 10.0, 0.0)[0];
  const double emptyY = g.bottom - 8.0;
  ASSERT_GT(emptyY - g.pixel(0, 10.0, 1.7)[1], 40.0);
  ASSERT_GT(emptyY - g.pixel(1, 10.0, 24.0)[1], 40.0);
  EXPECT_FALSE(colourNear(image, emptyX, emptyY, kBlue, 2));
  EXPECT_FALSE(colourNear(image, emptyX, emptyY, kRed, 2));

  // Not blank: text and frame make dark pixels; many distinct colours (anti-aliasing).
  int dark = 0;
  std::set<QRgb> colours;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x)
    {
      const QRgb c = image.pixel(x, y);
      colours.insert(c);
      if (qGray(c) < 100)
        ++dark;
    }
  EXPECT_GT(dark, 500);
  EXPECT_GT(colours.size(), 50u);
  // The title is text above the data area: dark pixels in the top band.
  int titleInk = 0;
  for (int y = 0; y < int(g.top) - 30; ++y)
    for (int x = 0; x < image.width(); ++x)
      if (qGray(image.pixel(x, y)) < 100)
        ++titleInk;
  EXPECT_GT(titleInk, 50) << "no title drawn";
}

TEST(XyPlot, OneSeriesAndBadInput)
{
  XyPlot one = knownPlot();
  one.series.pop_back();
  const fs::path file = artifact("study-plot-one.png");
  const XyPlotGeometry g = writeXyPlotPng(one, file);
  EXPECT_EQ(g.yRange.size(), 1u);
  QImage image(QString::fromStdString(file.string()));
  ASSERT_FALSE(image.isNull());
  const auto p = g.pixel(0, 10.0, 1.7);
  EXPECT_TRUE(colourNear(image, p[0], p[1], kBlue));

  // From zero: positive data get an axis from 0, the curve drawn where that puts it.
  XyPlot fromZero = knownPlot();
  fromZero.yFromZero = true;
  const XyPlotGeometry z = writeXyPlotPng(fromZero, artifact("study-plot-from-zero.png"));
  EXPECT_EQ(z.yRange[0][0], 0.0);
  EXPECT_EQ(z.yRange[1][0], 0.0);
  EXPECT_GE(z.yRange[1][1], 29.8);
  EXPECT_LT(z.yRange[1][1], 40.0);
  QImage zeroImage(QString::fromStdString(artifact("study-plot-from-zero.png").string()));
  const auto q = z.pixel(1, 20.0, 26.5);
  EXPECT_TRUE(colourNear(zeroImage, q[0], q[1], kRed));

  XyPlot bad = knownPlot();
  bad.series[1].y.pop_back();
  EXPECT_THROW(writeXyPlotPng(bad, artifact("bad.png")), std::invalid_argument);
  bad = knownPlot();
  bad.series[0].y[2] = std::nan("");
  EXPECT_THROW(writeXyPlotPng(bad, artifact("bad.png")), std::invalid_argument);
  bad = knownPlot();
  bad.series.clear();
  EXPECT_THROW(writeXyPlotPng(bad, artifact("bad.png")), std::invalid_argument);
  bad = knownPlot();
  bad.width = 10;
  EXPECT_THROW(writeXyPlotPng(bad, artifact("bad.png")), std::invalid_argument);
  EXPECT_THROW(writeXyPlotPng(knownPlot(), fs::path("/nonexistent-folder/plot.png")), std::runtime_error);
}

} // namespace
} // namespace caps::render
