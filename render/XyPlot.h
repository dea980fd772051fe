#pragma once
/// @file XyPlot.h
/// @brief x–y curves drawn to a PNG for the printed results of a parameter
/// study (thesis §3.3.1: "standard x-y graphs ... of the analysis results
/// with respect to ... a parameter of the operation"). Rendered with
/// QPainter on a QImage: no widget, no display needed.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

class QImage;

namespace caps::render {

/// One curve: points joined in the order given, a marker at each.
struct PlotSeries
{
  std::string label;            ///< legend and y axis title, with the unit: "closure force (N)"
  std::vector<double> x;        ///< abscissae (the same unit for every series)
  std::vector<double> y;        ///< ordinates, as many as x
  std::uint32_t rgb = 0x1f77b4; ///< line colour 0xRRGGBB
};

/// A plot of one or two series over a common x axis. The first series is
/// read on the left y axis, the second on its own right y axis (both axes
/// are drawn in their curve's colour).
struct XyPlot
{
  std::string title;
  std::string xLabel;             ///< with the unit: "undermining width (mm)"
  std::vector<PlotSeries> series; ///< 1 or 2
  /// Each y axis reaches 0 when its data keep one sign (from 0 up for
  /// positive data, down to 0 for negative), so a change of a few per cent
  /// is not drawn as a large one; false: the axis spans the data only.
  bool yFromZero = true;
  int width = 1000; ///< pixels
  int height = 600;
};

/// Where the data went on the image: the data area's pixel box and each
/// axis's range, so a caller (or a test) can map data to pixels.
struct XyPlotGeometry
{
  double left = 0.0, top = 0.0, right = 0.0, bottom = 0.0; ///< data area (pixels, y down)
  std::array<double, 2> xRange{};                          ///< x at left and right
  std::vector<std::array<double, 2>> yRange;               ///< per series: y at bottom and top

  /// Pixel (column, row) of data point (x, y) of series @a series.
  std::array<double, 2> pixel(std::size_t series, double x, double y) const;
};

/// @brief Draws @a plot and writes it to @a file as a PNG (@a plot.width ×
/// @a plot.height, white background): title, axes with "nice" tick values
/// (1, 2 or 5 × 10^k steps) covering each series' data, axis titles, light
/// grid, a legend, the curves with markers. The y ranges have a little
/// headroom and reach 0 when @a plot.yFromZero says so.
///
/// Text needs a QGuiApplication. When the process has none (the command
/// line, tests), one is made for the drawing on Qt's "offscreen" platform
/// and removed after it, so no display is needed.
///
/// @throws std::invalid_argument for no series or more than two, a series
/// with no point or x and y of different sizes, a non-finite value, a size
/// under 200 × 150 pixels; std::runtime_error when a non-GUI Qt
/// application is running (text cannot be drawn) or the file cannot be written.
XyPlotGeometry writeXyPlotPng(const XyPlot& plot, const std::filesystem::path& file);

/// drawXyPlot()'s picture in memory (RGB32), for a widget to show; where
/// the data went goes to @a geometry when given. The same requirements and
/// exceptions as writeXyPlotPng (but no file).
QImage drawXyPlot(const XyPlot& plot, XyPlotGeometry* geometry = nullptr);

/// The tick values for data in [lo, hi]: equally spaced by 1, 2 or 5 × 10^k,
/// about @a targetCount of them, the first ≤ lo and the last ≥ hi (the
/// axis's range). A zero-width range is widened around its value first.
std::vector<double> niceTicks(double lo, double hi, int targetCount = 5);

} // namespace caps::render
