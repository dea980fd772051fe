#include "modules/incision/StudyPlot.h"

#include "modules/core/GuiForPainting.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include <QColor>
#include <QCoreApplication>
#include <QFont>
#include <QFontMetricsF>
#include <QGuiApplication>
#include <QImage>
#include <QPainter>
#include <QPainterPath>
#include <QPen>

namespace caps::incision {
namespace {

QColor colour(std::uint32_t rgb)
{
  return QColor(int((rgb >> 16) & 0xff), int((rgb >> 8) & 0xff), int(rgb & 0xff));
}

/// A tick value with as many decimals as its step needs.
QString tickLabel(double value, double step)
{
  const int decimals = std::clamp(int(std::ceil(-std::log10(step) - 1e-9)), 0, 6);
  if (std::abs(value) < 0.5 * step * 1e-6)
    value = 0.0; // no "-0"
  return QString::number(value, 'f', decimals);
}

void validate(const XyPlot& plot)
{
  if (plot.series.empty() || plot.series.size() > 2)
    throw std::invalid_argument("a plot shows one or two curves, not " + std::to_string(plot.series.size()));
  if (plot.width < 200 || plot.height < 150)
    throw std::invalid_argument("a plot must be at least 200 x 150 pixels (got " + std::to_string(plot.width) + " x " +
                                std::to_string(plot.height) + ")");
  for (const PlotSeries& s : plot.series)
  {
    if (s.x.empty() || s.x.size() != s.y.size())
      throw std::invalid_argument("the curve \"" + s.label + "\" has " + std::to_string(s.x.size()) + " x and " +
                                  std::to_string(s.y.size()) + " y values: it needs at least one point, as many x as y");
    for (std::size_t i = 0; i < s.x.size(); ++i)
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]))
        throw std::invalid_argument("the curve \"" + s.label + "\" has a value that is not a number at point " +
                                    std::to_string(i));
  }
}

} // namespace

std::array<double, 2> XyPlotGeometry::pixel(std::size_t series, double x, double y) const
{
  const auto& yr = yRange.at(series);
  return {left + (x - xRange[0]) / (xRange[1] - xRange[0]) * (right - left),
          bottom - (y - yr[0]) / (yr[1] - yr[0]) * (bottom - top)};
}

std::vector<double> niceTicks(double lo, double hi, int targetCount)
{
  if (!std::isfinite(lo) || !std::isfinite(hi) || hi < lo)
    throw std::invalid_argument("tick values need a finite range lo <= hi");
  if (hi - lo <= 1e-12 * std::max(1.0, std::abs(lo)))
  {
    const double half = lo == 0.0 ? 1.0 : 0.1 * std::abs(lo);
    lo -= half;
    hi += half;
  }
  const double rough = (hi - lo) / double(std::max(targetCount - 1, 1));
  const double magnitude = std::pow(10.0, std::floor(std::log10(rough)));
  const double normalized = rough / magnitude;
  const double step = (normalized < 1.5 ? 1.0 : normalized < 3.0 ? 2.0 : normalized < 7.0 ? 5.0 : 10.0) * magnitude;
  const double first = std::floor(lo / step + 1e-9) * step;
  const double last = std::ceil(hi / step - 1e-9) * step;
  std::vector<double> ticks;
  for (int k = 0; first + k * step <= last + 0.5 * step; ++k)
    ticks.push_back(first + k * step);
  return ticks;
}

XyPlotGeometry writeXyPlotPng(const XyPlot& plot, const std::filesystem::path& file)
{
  validate(plot);
  const caps::GuiForPainting gui;
  const bool twoAxes = plot.series.size() == 2;

  // The axes: nice ticks over the data.
  double xLo = plot.series[0].x[0], xHi = xLo;
  for (const PlotSeries& s : plot.series)
    for (double x : s.x)
    {
      xLo = std::min(xLo, x);
      xHi = std::max(xHi, x);
    }
  const std::vector<double> xTicks = niceTicks(xLo, xHi, 6);
  std::vector<std::vector<double>> yTicks;
  for (const PlotSeries& s : plot.series)
  {
    // A little headroom, so no curve runs along the frame.
    const auto [low, high] = std::minmax_element(s.y.begin(), s.y.end());
    double lo = *low, hi = *high;
    if (plot.yFromZero && lo > 0.0)
      lo = 0.0;
    if (plot.yFromZero && hi < 0.0)
      hi = 0.0;
    const double margin = 0.04 * (hi - lo);
    yTicks.push_back(niceTicks(lo == 0.0 ? lo : lo - margin, hi == 0.0 ? hi : hi + margin, 6));
  }

  // Sizes scale with the image height (600 px: 20 px title).
  const double scale = plot.height / 600.0;
  QFont titleFont("DejaVu Sans");
  titleFont.setPixelSize(std::max(10, int(std::lround(20 * scale))));
  titleFont.setBold(true);
  QFont labelFont("DejaVu Sans");
  labelFont.setPixelSize(std::max(9, int(std::lround(15 * scale))));
  QFont tickFont("DejaVu Sans");
  tickFont.setPixelSize(std::max(8, int(std::lround(13 * scale))));
  const QFontMetricsF titleMetrics(titleFont), labelMetrics(labelFont), tickMetrics(tickFont);

  // Room for the tick labels and axis titles on each side.
  auto widestTick = [&](const std::vector<double>& ticks) {
    double w = 0.0;
    for (double t : ticks)
      w = std::max(w, tickMetrics.horizontalAdvance(tickLabel(t, ticks[1] - ticks[0])));
    return w;
  };
  const double pad = 10.0 * scale;
  XyPlotGeometry g;
  g.left = pad + labelMetrics.height() + pad + widestTick(yTicks[0]) + pad;
  g.right = plot.width - (twoAxes ? pad + labelMetrics.height() + pad + widestTick(yTicks[1]) + pad : 3.0 * pad);
  g.top = pad + titleMetrics.height() + pad + labelMetrics.height() + 1.5 * pad;
  g.bottom = plot.height - (pad + labelMetrics.height() + pad + tickMetrics.height() + pad);
  g.xRange = {xTicks.front(), xTicks.back()};
  for (const auto& t : yTicks)
    g.yRange.push_back({t.front(), t.back()});

  QImage image(plot.width, plot.height, QImage::Format_RGB32);
  image.fill(Qt::white);
  QPainter painter(&image);
  painter.setRenderHint(QPainter::Antialiasing, true);
  painter.setRenderHint(QPainter::TextAntialiasing, true);
  const QColor ink(40, 40, 40), grid(225, 225, 225), frame(110, 110, 110);
  const QRectF area(QPointF(g.left, g.top), QPointF(g.right, g.bottom));

  // Grid: the x ticks and the left axis's ticks.
  painter.setPen(QPen(grid, 1.0));
  for (double t : xTicks)
  {
    const double x = g.pixel(0, t, g.yRange[0][0])[0];
    painter.drawLine(QPointF(x, g.top), QPointF(x, g.bottom));
  }
  for (double t : yTicks[0])
  {
    const double y = g.pixel(0, g.xRange[0], t)[1];
    painter.drawLine(QPointF(g.left, y), QPointF(g.right, y));
  }
  painter.setPen(QPen(frame, 1.2));
  painter.setBrush(Qt::NoBrush);
  painter.drawRect(area);

  // Ticks and their values.
  const double tickLength = 6.0 * scale;
  painter.setFont(tickFont);
  for (double t : xTicks)
  {
    const double x = g.pixel(0, t, g.yRange[0][0])[0];
    painter.setPen(QPen(frame, 1.2));
    painter.drawLine(QPointF(x, g.bottom), QPointF(x, g.bottom + tickLength));
    painter.setPen(ink);
    const QString text = tickLabel(t, xTicks[1] - xTicks[0]);
    const double w = tickMetrics.horizontalAdvance(text);
    painter.drawText(QPointF(x - w / 2.0, g.bottom + tickLength + pad / 2.0 + tickMetrics.ascent()), text);
  }
  for (std::size_t s = 0; s < plot.series.size(); ++s)
  {
    const QColor c = colour(plot.series[s].rgb);
    const bool leftSide = s == 0;
    const double edge = leftSide ? g.left : g.right;
    if (twoAxes) // each axis in its curve's colour
    {
      painter.setPen(QPen(c, 2.0));
      painter.drawLine(QPointF(edge, g.top), QPointF(edge, g.bottom));
    }
    for (double t : yTicks[s])
    {
      const double y = g.pixel(s, g.xRange[0], t)[1];
      painter.setPen(QPen(twoAxes ? c : frame, 1.2));
      painter.drawLine(QPointF(edge, y), QPointF(edge + (leftSide ? -tickLength : tickLength), y));
      painter.setPen(ink);
      const QString text = tickLabel(t, yTicks[s][1] - yTicks[s][0]);
      const double w = tickMetrics.horizontalAdvance(text);
      const double x = leftSide ? edge - tickLength - pad / 2.0 - w : edge + tickLength + pad / 2.0;
      painter.drawText(QPointF(x, y + (tickMetrics.ascent() - tickMetrics.descent()) / 2.0), text);
    }
    // The axis title, along the axis, in the curve's colour.
    painter.save();
    painter.setFont(labelFont);
    painter.setPen(twoAxes ? c.darker(115) : ink);
    const QString title = QString::fromStdString(plot.series[s].label);
    const double w = labelMetrics.horizontalAdvance(title);
    const double centre = (g.top + g.bottom) / 2.0;
    if (leftSide)
    {
      painter.translate(pad + labelMetrics.ascent(), centre + w / 2.0);
      painter.rotate(-90.0);
    }
    else
    {
      painter.translate(plot.width - pad - labelMetrics.ascent(), centre - w / 2.0);
      painter.rotate(90.0);
    }
    painter.drawText(QPointF(0.0, 0.0), title);
    painter.restore();
    painter.setFont(tickFont);
  }

  // The x axis title and the plot title.
  painter.setPen(ink);
  painter.setFont(labelFont);
  {
    const QString text = QString::fromStdString(plot.xLabel);
    const double w = labelMetrics.horizontalAdvance(text);
    painter.drawText(QPointF((g.left + g.right - w) / 2.0, plot.height - pad - labelMetrics.descent()), text);
  }
  painter.setFont(titleFont);
  {
    const QString text = QString::fromStdString(plot.title);
    const double w = titleMetrics.horizontalAdvance(text);
    painter.drawText(QPointF((plot.width - w) / 2.0, pad + titleMetrics.ascent()), text);
  }

  // The curves, then their markers on top.
  const double markerRadius = 4.5 * scale;
  auto drawMarker = [&](std::size_t s, const QPointF& p) {
    if (s == 0)
      painter.drawEllipse(p, markerRadius, markerRadius);
    else
      painter.drawRect(QRectF(p.x() - markerRadius, p.y() - markerRadius, 2.0 * markerRadius, 2.0 * markerRadius));
  };
  for (std::size_t s = 0; s < plot.series.size(); ++s)
  {
    const PlotSeries& series = plot.series[s];
    const QColor c = colour(series.rgb);
    QPainterPath path;
    for (std::size_t i = 0; i < series.x.size(); ++i)
    {
      const auto p = g.pixel(s, series.x[i], series.y[i]);
      if (i == 0)
        path.moveTo(p[0], p[1]);
      else
        path.lineTo(p[0], p[1]);
    }
    painter.setBrush(Qt::NoBrush);
    painter.setPen(QPen(c, 2.5 * scale, Qt::SolidLine, Qt::RoundCap, Qt::RoundJoin));
    painter.drawPath(path);
    painter.setPen(QPen(c, 1.5 * scale));
    painter.setBrush(c);
    for (std::size_t i = 0; i < series.x.size(); ++i)
    {
      const auto p = g.pixel(s, series.x[i], series.y[i]);
      drawMarker(s, QPointF(p[0], p[1]));
    }
  }

  // The legend, centred between the title and the data area.
  painter.setFont(labelFont);
  const double sample = 34.0 * scale, gap = 8.0 * scale, spacing = 28.0 * scale;
  double total = 0.0;
  for (const PlotSeries& s : plot.series)
    total += sample + gap + labelMetrics.horizontalAdvance(QString::fromStdString(s.label));
  total += spacing * double(plot.series.size() - 1);
  double x = (g.left + g.right - total) / 2.0;
  const double y = pad + titleMetrics.height() + pad + labelMetrics.height() / 2.0;
  for (std::size_t s = 0; s < plot.series.size(); ++s)
  {
    const QColor c = colour(plot.series[s].rgb);
    painter.setPen(QPen(c, 2.5 * scale, Qt::SolidLine, Qt::RoundCap));
    painter.drawLine(QPointF(x, y), QPointF(x + sample, y));
    painter.setPen(QPen(c, 1.5 * scale));
    painter.setBrush(c);
    drawMarker(s, QPointF(x + sample / 2.0, y));
    painter.setPen(ink);
    const QString text = QString::fromStdString(plot.series[s].label);
    painter.drawText(QPointF(x + sample + gap, y + (labelMetrics.ascent() - labelMetrics.descent()) / 2.0), text);
    x += sample + gap + labelMetrics.horizontalAdvance(text) + spacing;
  }
  painter.end();

  if (!image.save(QString::fromStdString(file.string()), "PNG"))
    throw std::runtime_error("cannot write " + file.string() + ": check the folder's permissions and space");
  return g;
}

} // namespace caps::incision
