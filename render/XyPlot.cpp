#include "render/XyPlot.h"

#include "render/GuiForPainting.h"

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

namespace caps::render {
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
                                  std::to_string(s.y.size()) +
                                  " y values: it needs at least one point, as many x as y");
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

namespace {

/// One plot drawn onto an image, step by step: draw() is the table of
/// contents. Sizes scale with the image height (600 px: 20 px title).
class XyPlotPainter
{
public:
  explicit XyPlotPainter(const XyPlot& plot)
    : plot_(plot), twoAxes_(plot.series.size() == 2), scale_(plot.height / 600.0), titleFont_(font(20, 10, true)),
      labelFont_(font(15, 9, false)), tickFont_(font(13, 8, false)), titleMetrics_(titleFont_),
      labelMetrics_(labelFont_), tickMetrics_(tickFont_), pad_(10.0 * scale_),
      image_(plot.width, plot.height, QImage::Format_RGB32)
  {
    chooseTicks();
    layOut();
  }

  const XyPlotGeometry& geometry() const { return g_; }

  QImage draw()
  {
    image_.fill(Qt::white);
    painter_.begin(&image_);
    painter_.setRenderHint(QPainter::Antialiasing, true);
    painter_.setRenderHint(QPainter::TextAntialiasing, true);
    drawGridAndFrame();
    drawXTicks();
    for (std::size_t s = 0; s < plot_.series.size(); ++s)
      drawYAxis(s);
    drawTitles();
    for (std::size_t s = 0; s < plot_.series.size(); ++s)
      drawCurve(s);
    drawLegend();
    painter_.end();
    return image_;
  }

private:
  QFont font(int pixelsAt600, int smallest, bool bold) const
  {
    QFont f("DejaVu Sans");
    f.setPixelSize(std::max(smallest, int(std::lround(pixelsAt600 * scale_))));
    f.setBold(bold);
    return f;
  }

  /// The axes: nice ticks over the data, a little headroom on y so no
  /// curve runs along the frame.
  void chooseTicks()
  {
    double xLo = plot_.series[0].x[0], xHi = xLo;
    for (const PlotSeries& s : plot_.series)
      for (double x : s.x)
      {
        xLo = std::min(xLo, x);
        xHi = std::max(xHi, x);
      }
    xTicks_ = niceTicks(xLo, xHi, 6);
    for (const PlotSeries& s : plot_.series)
    {
      const auto [low, high] = std::minmax_element(s.y.begin(), s.y.end());
      double lo = *low, hi = *high;
      if (plot_.yFromZero && lo > 0.0)
        lo = 0.0;
      if (plot_.yFromZero && hi < 0.0)
        hi = 0.0;
      const double margin = 0.04 * (hi - lo);
      yTicks_.push_back(niceTicks(lo == 0.0 ? lo : lo - margin, hi == 0.0 ? hi : hi + margin, 6));
    }
  }

  double widestTick(const std::vector<double>& ticks) const
  {
    double w = 0.0;
    for (double t : ticks)
      w = std::max(w, tickMetrics_.horizontalAdvance(tickLabel(t, ticks[1] - ticks[0])));
    return w;
  }

  /// The data area: room for the tick labels and axis titles on each side.
  void layOut()
  {
    const double pad = pad_;
    g_.left = pad + labelMetrics_.height() + pad + widestTick(yTicks_[0]) + pad;
    g_.right = plot_.width - (twoAxes_ ? pad + labelMetrics_.height() + pad + widestTick(yTicks_[1]) + pad : 3.0 * pad);
    g_.top = pad + titleMetrics_.height() + pad + labelMetrics_.height() + 1.5 * pad;
    g_.bottom = plot_.height - (pad + labelMetrics_.height() + pad + tickMetrics_.height() + pad);
    g_.xRange = {xTicks_.front(), xTicks_.back()};
    for (const auto& t : yTicks_)
      g_.yRange.push_back({t.front(), t.back()});
  }

  /// Grid: the x ticks and the left axis's ticks; then the frame.
  void drawGridAndFrame()
  {
    painter_.setPen(QPen(kGrid, 1.0));
    for (double t : xTicks_)
    {
      const double x = g_.pixel(0, t, g_.yRange[0][0])[0];
      painter_.drawLine(QPointF(x, g_.top), QPointF(x, g_.bottom));
    }
    for (double t : yTicks_[0])
    {
      const double y = g_.pixel(0, g_.xRange[0], t)[1];
      painter_.drawLine(QPointF(g_.left, y), QPointF(g_.right, y));
    }
    painter_.setPen(QPen(kFrame, 1.2));
    painter_.setBrush(Qt::NoBrush);
    painter_.drawRect(QRectF(QPointF(g_.left, g_.top), QPointF(g_.right, g_.bottom)));
  }

  /// The x ticks and their values.
  void drawXTicks()
  {
    painter_.setFont(tickFont_);
    for (double t : xTicks_)
    {
      const double x = g_.pixel(0, t, g_.yRange[0][0])[0];
      painter_.setPen(QPen(kFrame, 1.2));
      painter_.drawLine(QPointF(x, g_.bottom), QPointF(x, g_.bottom + tickLength()));
      painter_.setPen(kInk);
      const QString text = tickLabel(t, xTicks_[1] - xTicks_[0]);
      const double w = tickMetrics_.horizontalAdvance(text);
      painter_.drawText(QPointF(x - w / 2.0, g_.bottom + tickLength() + pad_ / 2.0 + tickMetrics_.ascent()), text);
    }
  }

  /// The y axis of series @a s (left for the first, right for the second):
  /// in the curve's colour when there are two, its ticks, values and title.
  void drawYAxis(std::size_t s)
  {
    const QColor c = colour(plot_.series[s].rgb);
    const bool leftSide = s == 0;
    const double edge = leftSide ? g_.left : g_.right;
    if (twoAxes_)
    {
      painter_.setPen(QPen(c, 2.0));
      painter_.drawLine(QPointF(edge, g_.top), QPointF(edge, g_.bottom));
    }
    for (double t : yTicks_[s])
    {
      const double y = g_.pixel(s, g_.xRange[0], t)[1];
      painter_.setPen(QPen(twoAxes_ ? c : kFrame, 1.2));
      painter_.drawLine(QPointF(edge, y), QPointF(edge + (leftSide ? -tickLength() : tickLength()), y));
      painter_.setPen(kInk);
      const QString text = tickLabel(t, yTicks_[s][1] - yTicks_[s][0]);
      const double w = tickMetrics_.horizontalAdvance(text);
      const double x = leftSide ? edge - tickLength() - pad_ / 2.0 - w : edge + tickLength() + pad_ / 2.0;
      painter_.drawText(QPointF(x, y + (tickMetrics_.ascent() - tickMetrics_.descent()) / 2.0), text);
    }
    // The axis title, along the axis, in the curve's colour.
    painter_.save();
    painter_.setFont(labelFont_);
    painter_.setPen(twoAxes_ ? c.darker(115) : kInk);
    const QString title = QString::fromStdString(plot_.series[s].label);
    const double w = labelMetrics_.horizontalAdvance(title);
    const double centre = (g_.top + g_.bottom) / 2.0;
    if (leftSide)
    {
      painter_.translate(pad_ + labelMetrics_.ascent(), centre + w / 2.0);
      painter_.rotate(-90.0);
    }
    else
    {
      painter_.translate(plot_.width - pad_ - labelMetrics_.ascent(), centre - w / 2.0);
      painter_.rotate(90.0);
    }
    painter_.drawText(QPointF(0.0, 0.0), title);
    painter_.restore();
    painter_.setFont(tickFont_);
  }

  /// The x axis title and the plot title.
  void drawTitles()
  {
    painter_.setPen(kInk);
    painter_.setFont(labelFont_);
    {
      const QString text = QString::fromStdString(plot_.xLabel);
      const double w = labelMetrics_.horizontalAdvance(text);
      painter_.drawText(QPointF((g_.left + g_.right - w) / 2.0, plot_.height - pad_ - labelMetrics_.descent()), text);
    }
    painter_.setFont(titleFont_);
    const QString text = QString::fromStdString(plot_.title);
    const double w = titleMetrics_.horizontalAdvance(text);
    painter_.drawText(QPointF((plot_.width - w) / 2.0, pad_ + titleMetrics_.ascent()), text);
  }

  /// Series 0 marks its points with discs, series 1 with squares.
  void drawMarker(std::size_t s, const QPointF& p)
  {
    const double r = 4.5 * scale_;
    if (s == 0)
      painter_.drawEllipse(p, r, r);
    else
      painter_.drawRect(QRectF(p.x() - r, p.y() - r, 2.0 * r, 2.0 * r));
  }

  /// Series @a s: the curve, then its markers on top.
  void drawCurve(std::size_t s)
  {
    const PlotSeries& series = plot_.series[s];
    const QColor c = colour(series.rgb);
    QPainterPath path;
    for (std::size_t i = 0; i < series.x.size(); ++i)
    {
      const auto p = g_.pixel(s, series.x[i], series.y[i]);
      if (i == 0)
        path.moveTo(p[0], p[1]);
      else
        path.lineTo(p[0], p[1]);
    }
    painter_.setBrush(Qt::NoBrush);
    painter_.setPen(QPen(c, 2.5 * scale_, Qt::SolidLine, Qt::RoundCap, Qt::RoundJoin));
    painter_.drawPath(path);
    painter_.setPen(QPen(c, 1.5 * scale_));
    painter_.setBrush(c);
    for (std::size_t i = 0; i < series.x.size(); ++i)
    {
      const auto p = g_.pixel(s, series.x[i], series.y[i]);
      drawMarker(s, QPointF(p[0], p[1]));
    }
  }

  /// The legend, centred between the title and the data area.
  void drawLegend()
  {
    painter_.setFont(labelFont_);
    const double sample = 34.0 * scale_, gap = 8.0 * scale_, spacing = 28.0 * scale_;
    double total = 0.0;
    for (const PlotSeries& s : plot_.series)
      total += sample + gap + labelMetrics_.horizontalAdvance(QString::fromStdString(s.label));
    total += spacing * double(plot_.series.size() - 1);
    double x = (g_.left + g_.right - total) / 2.0;
    const double y = pad_ + titleMetrics_.height() + pad_ + labelMetrics_.height() / 2.0;
    for (std::size_t s = 0; s < plot_.series.size(); ++s)
    {
      const QColor c = colour(plot_.series[s].rgb);
      painter_.setPen(QPen(c, 2.5 * scale_, Qt::SolidLine, Qt::RoundCap));
      painter_.drawLine(QPointF(x, y), QPointF(x + sample, y));
      painter_.setPen(QPen(c, 1.5 * scale_));
      painter_.setBrush(c);
      drawMarker(s, QPointF(x + sample / 2.0, y));
      painter_.setPen(kInk);
      const QString text = QString::fromStdString(plot_.series[s].label);
      painter_.drawText(QPointF(x + sample + gap, y + (labelMetrics_.ascent() - labelMetrics_.descent()) / 2.0), text);
      x += sample + gap + labelMetrics_.horizontalAdvance(text) + spacing;
    }
  }

  double tickLength() const { return 6.0 * scale_; }

  inline static const QColor kInk{40, 40, 40}, kGrid{225, 225, 225}, kFrame{110, 110, 110};
  const XyPlot& plot_;
  const bool twoAxes_;
  const double scale_;
  const QFont titleFont_, labelFont_, tickFont_;
  const QFontMetricsF titleMetrics_, labelMetrics_, tickMetrics_;
  const double pad_;
  std::vector<double> xTicks_;
  std::vector<std::vector<double>> yTicks_;
  XyPlotGeometry g_;
  QImage image_;
  QPainter painter_;
};

} // namespace

QImage drawXyPlot(const XyPlot& plot, XyPlotGeometry* geometry)
{
  validate(plot);
  const GuiForPainting gui;
  XyPlotPainter painter(plot);
  QImage image = painter.draw();
  if (geometry)
    *geometry = painter.geometry();
  return image;
}

XyPlotGeometry writeXyPlotPng(const XyPlot& plot, const std::filesystem::path& file)
{
  XyPlotGeometry geometry;
  const QImage image = drawXyPlot(plot, &geometry);
  if (!image.save(QString::fromStdString(file.string()), "PNG"))
    throw std::runtime_error("cannot write " + file.string() + ": check the folder's permissions and space");
  return geometry;
}

} // namespace caps::render
