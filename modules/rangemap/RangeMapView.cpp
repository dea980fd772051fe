#include "modules/rangemap/RangeMapView.h"

#include "modules/rangemap/LabelLayout.h"
#include "segmentation/CylindricalFrame.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <QMouseEvent>
#include <QPainter>

namespace caps {
namespace {

constexpr double kPi = std::numbers::pi;
// Margins around the map: z ticks on the left, directions above, the colour bar below.
constexpr double kLeft = 44, kRight = 8, kTop = 18, kBar = 58;

QColor qColour(const render::Rgb& c)
{
  return QColor::fromRgbF(c[0], c[1], c[2]);
}

/// A round step near range / count: 1, 2 or 5 times a power of ten.
double niceStep(double range, int count)
{
  const double raw = range / std::max(count, 1);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * power >= raw)
      return m * power;
  return 10.0 * power;
}

} // namespace

RangeMapView::RangeMapView(QWidget* parent) : QWidget(parent)
{
  setMouseTracking(true);
  setMinimumHeight(160);
  QSizePolicy policy(QSizePolicy::Preferred, QSizePolicy::Preferred);
  policy.setHeightForWidth(true);
  setSizePolicy(policy);
}

void RangeMapView::setMap(const seg::RangeMap& map, render::ColourMap colourMap, double low, double high,
                          const QString& title)
{
  map_ = map;
  colour_map_ = colourMap;
  low_ = low;
  high_ = high > low ? high : low + 1.0;
  title_ = title;
  // One pixel per sample; the face (θ = -π/2) in the middle column.
  const int nTheta = map_.nTheta(), nZ = map_.nZ();
  image_ = QImage(nTheta, nZ, QImage::Format_RGB32);
  for (int x = 0; x < nTheta; ++x)
  {
    const int i = ((x - nTheta / 4) % nTheta + nTheta) % nTheta;
    for (int j = 0; j < nZ; ++j)
    {
      const float v = map_.at(i, j);
      QColor c = std::isfinite(v) ? qColour(render::colourMapColour(colour_map_, (v - low_) / (high_ - low_)))
                                  : QColor(158, 158, 158);
      const std::size_t k = std::size_t(i) + std::size_t(nTheta) * std::size_t(j);
      if (k < spoiled_.size() && spoiled_[k] && (x + nZ - 1 - j) % 6 < 2) // diagonal hatching
        c = QColor(50, 50, 50);
      image_.setPixel(x, nZ - 1 - j, c.rgb());
    }
  }
  update();
}

void RangeMapView::clear()
{
  map_ = seg::RangeMap();
  image_ = QImage();
  marker_.reset();
  update();
}

void RangeMapView::setMarker(std::optional<std::array<double, 2>> chartPoint)
{
  marker_ = chartPoint;
  update();
}

void RangeMapView::setProfileLine(std::optional<std::array<std::array<double, 2>, 2>> line)
{
  profile_line_ = line;
  update();
}

void RangeMapView::setLandmarks(std::vector<std::pair<QString, std::array<double, 2>>> landmarks)
{
  landmarks_ = std::move(landmarks);
  update();
}

int RangeMapView::heightForWidth(int width) const
{
  const double mapWidth = std::max(10.0, width - kLeft - kRight);
  const double aspect = map_.empty() ? 0.5 : double(map_.nZ()) / map_.nTheta();
  return static_cast<int>(kTop + mapWidth * aspect + kBar);
}

QRectF RangeMapView::mapRect() const
{
  const double w = std::max(10.0, width() - kLeft - kRight);
  const double aspect = map_.empty() ? 0.5 : double(map_.nZ()) / map_.nTheta();
  const double h = std::max(10.0, std::min(w * aspect, height() - kTop - kBar));
  return {kLeft, kTop, w, h};
}

QPointF RangeMapView::widgetPointOf(double theta, double z) const
{
  const QRectF r = mapRect();
  // Column x of the picture shows θ = -3π/2 + 2π x / width.
  double t = seg::CylindricalFrame::wrapTheta(theta) + 1.5 * kPi; // in [π/2, 5π/2)
  if (t >= 2.0 * kPi)
    t -= 2.0 * kPi;
  const double x = r.left() + t / (2.0 * kPi) * r.width();
  const seg::CylindricalFrame& f = map_.frame();
  const double y = r.bottom() - (z - f.zMin()) / (f.zMax() - f.zMin()) * r.height();
  return {x, y};
}

std::optional<std::array<double, 2>> RangeMapView::chartPointAt(const QPointF& p) const
{
  if (map_.empty())
    return std::nullopt;
  const QRectF r = mapRect();
  if (!r.contains(p))
    return std::nullopt;
  const double theta = seg::CylindricalFrame::wrapTheta(-1.5 * kPi + 2.0 * kPi * (p.x() - r.left()) / r.width());
  const seg::CylindricalFrame& f = map_.frame();
  const double z = f.zMin() + (r.bottom() - p.y()) / r.height() * (f.zMax() - f.zMin());
  return std::array<double, 2>{theta, z};
}

void RangeMapView::paintEvent(QPaintEvent*)
{
  QPainter painter(this);
  painter.fillRect(rect(), palette().window());
  if (map_.empty())
  {
    painter.drawText(rect(), Qt::AlignCenter | Qt::TextWordWrap, tr("No maps yet: build them above."));
    return;
  }
  const QRectF r = mapRect();
  painter.drawImage(r, image_);
  painter.setPen(palette().color(QPalette::WindowText));
  painter.drawRect(r);

  // Directions above the map, as facing the patient.
  const char* directions[5] = {"back", "right", "face", "left", "back"};
  QFontMetrics metrics(font());
  for (int q = 0; q <= 4; ++q)
  {
    const double x = r.left() + q * r.width() / 4.0;
    painter.drawLine(QPointF(x, r.top() - 3), QPointF(x, r.top()));
    const QString label = tr(directions[q]);
    const double w = metrics.horizontalAdvance(label);
    const double left = std::clamp(x - w / 2, 0.0, width() - w);
    painter.drawText(QPointF(left, r.top() - 5), label);
  }
  // z ticks on the left.
  const seg::CylindricalFrame& f = map_.frame();
  const double step = niceStep(f.zMax() - f.zMin(), 4);
  for (double z = std::ceil(f.zMin() / step) * step; z <= f.zMax() + 1e-9; z += step)
  {
    const double y = widgetPointOf(-kPi / 2, z).y();
    painter.drawLine(QPointF(r.left() - 4, y), QPointF(r.left(), y));
    const QString label = QString::number(z, 'f', 0);
    painter.drawText(QRectF(0, y - 8, r.left() - 6, 16), Qt::AlignRight | Qt::AlignVCenter, label);
  }
  painter.save();
  painter.translate(10, r.center().y());
  painter.rotate(-90);
  painter.drawText(QRectF(-40, -10, 80, 14), Qt::AlignCenter, tr("z (mm)"));
  painter.restore();

  // Landmarks and the marker.
  painter.setRenderHint(QPainter::Antialiasing);
  // The dots, then each name beside its dot where it covers no other name
  // or dot (LabelLayout.h); a name with no room is left to the table.
  std::vector<std::array<double, 2>> anchors, sizes;
  for (const auto& [name, point] : landmarks_)
  {
    const QPointF p = widgetPointOf(point[0], point[1]);
    painter.setPen(QPen(Qt::white, 1.5));
    painter.setBrush(QColor(220, 30, 30));
    painter.drawEllipse(p, 3.5, 3.5);
    anchors.push_back({p.x(), p.y()});
    sizes.push_back({double(metrics.horizontalAdvance(name)), double(metrics.height())});
  }
  const std::vector<std::optional<LabelBox>> labels =
    layOutLabels(anchors, sizes, {0.0, 0.0, double(width()), double(height())});
  painter.setPen(Qt::white);
  for (std::size_t k = 0; k < labels.size(); ++k)
    if (labels[k])
      painter.drawText(QRectF(labels[k]->x, labels[k]->y, labels[k]->width, labels[k]->height),
                       Qt::AlignLeft | Qt::AlignVCenter, landmarks_[k].first);
  if (profile_line_)
  { // the shorter way round in θ, as ThicknessReview::profile goes; broken at the seam
    const auto& [from, to] = *profile_line_;
    const double dTheta = std::remainder(to[0] - from[0], 2.0 * std::numbers::pi);
    painter.setPen(QPen(QColor(255, 255, 255), 2.0));
    QPointF last = widgetPointOf(from[0], from[1]);
    for (int k = 1; k <= 64; ++k)
    {
      const double t = k / 64.0;
      const QPointF p =
        widgetPointOf(seg::CylindricalFrame::wrapTheta(from[0] + t * dTheta), from[1] + t * (to[1] - from[1]));
      if (std::abs(p.x() - last.x()) < 0.5 * r.width())
        painter.drawLine(last, p);
      last = p;
    }
  }
  if (marker_)
  {
    const QPointF p = widgetPointOf((*marker_)[0], (*marker_)[1]);
    painter.setPen(QPen(QColor(255, 220, 0), 1.5));
    painter.drawLine(QPointF(p.x() - 8, p.y()), QPointF(p.x() + 8, p.y()));
    painter.drawLine(QPointF(p.x(), p.y() - 8), QPointF(p.x(), p.y() + 8));
  }
  painter.setRenderHint(QPainter::Antialiasing, false);

  // The colour bar below, with its title and unit.
  const QRectF bar(r.left(), r.bottom() + 8, r.width(), 10);
  for (int x = 0; x < int(bar.width()); ++x)
  {
    painter.setPen(qColour(render::colourMapColour(colour_map_, x / std::max(1.0, bar.width() - 1))));
    painter.drawLine(QPointF(bar.left() + x, bar.top()), QPointF(bar.left() + x, bar.bottom()));
  }
  painter.setPen(palette().color(QPalette::WindowText));
  painter.setBrush(Qt::NoBrush);
  painter.drawRect(bar);
  const double barStep = niceStep(high_ - low_, 5);
  for (double v = std::ceil(low_ / barStep) * barStep; v <= high_ + 1e-9; v += barStep)
  {
    const double x = bar.left() + (v - low_) / (high_ - low_) * bar.width();
    painter.drawLine(QPointF(x, bar.bottom()), QPointF(x, bar.bottom() + 3));
    const QString label = QString::number(v, 'g', 3);
    const double w = metrics.horizontalAdvance(label);
    painter.drawText(QPointF(std::clamp(x - w / 2, 0.0, width() - w), bar.bottom() + 15), label);
  }
  painter.drawText(QRectF(0, bar.bottom() + 16, width(), 16), Qt::AlignHCenter | Qt::AlignVCenter, title_);
}

void RangeMapView::mouseMoveEvent(QMouseEvent* event)
{
  if (auto chart = chartPointAt(event->pos()))
    emit hovered((*chart)[0], (*chart)[1]);
  else
    emit left();
}

void RangeMapView::mousePressEvent(QMouseEvent* event)
{
  if (event->button() != Qt::LeftButton)
    return;
  if (auto chart = chartPointAt(event->pos()))
    emit clicked((*chart)[0], (*chart)[1]);
}

void RangeMapView::leaveEvent(QEvent*)
{
  emit left();
}

ThicknessHistogram::ThicknessHistogram(QWidget* parent) : QWidget(parent)
{
  setMinimumHeight(100);
}

void ThicknessHistogram::setCounts(std::vector<int> counts, double binWidth, QString caption)
{
  counts_ = std::move(counts);
  bin_width_ = binWidth;
  caption_ = std::move(caption);
  setAccessibleDescription(caption_); // what a screen reader says it counts
  update();
}

void ThicknessHistogram::paintEvent(QPaintEvent*)
{
  QPainter painter(this);
  painter.fillRect(rect(), palette().window());
  if (counts_.empty())
    return;
  const QRectF plot(44, 8, width() - 52, height() - 40);
  const int most = std::max(1, *std::max_element(counts_.begin(), counts_.end()));
  const double barWidth = plot.width() / double(counts_.size());
  for (std::size_t k = 0; k < counts_.size(); ++k)
  {
    const double h = plot.height() * counts_[k] / most;
    const double centre = (double(k) + 0.5) * bin_width_;
    const double top = counts_.size() * bin_width_;
    painter.fillRect(QRectF(plot.left() + k * barWidth, plot.bottom() - h, barWidth - 1, h),
                     qColour(render::colourMapColour(render::ColourMap::Thickness, centre / top)));
  }
  painter.setPen(palette().color(QPalette::WindowText));
  painter.drawLine(plot.bottomLeft(), plot.bottomRight());
  painter.drawLine(plot.bottomLeft(), plot.topLeft());
  const double range = counts_.size() * bin_width_;
  const double step = niceStep(range, 5);
  QFontMetrics metrics(font());
  for (double v = 0; v <= range + 1e-9; v += step)
  {
    const double x = plot.left() + v / range * plot.width();
    painter.drawLine(QPointF(x, plot.bottom()), QPointF(x, plot.bottom() + 3));
    const QString label = QString::number(v, 'g', 3);
    painter.drawText(QPointF(x - metrics.horizontalAdvance(label) / 2.0, plot.bottom() + 15), label);
  }
  painter.drawText(QRectF(0, plot.bottom() + 16, width(), 16), Qt::AlignCenter,
                   caption_.isEmpty() ? tr("soft-tissue thickness over the face (mm); last bar: and more") : caption_);
  painter.drawText(QRectF(0, plot.top() - 4, plot.left() - 4, 16), Qt::AlignRight, QString::number(most));
  painter.drawText(QRectF(0, plot.bottom() - 12, plot.left() - 4, 16), Qt::AlignRight, "0");
}

} // namespace caps
