#pragma once
/// @file RangeMapView.h
/// @brief An unwrapped (θ, z) range or thickness map on screen (thesis
/// §4.2, Fig. 4.4): the face in the middle, patient right on the left as
/// when facing the patient, z up; a colour bar in mm below; hovering and
/// clicking report the chart point under the mouse.

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <QImage>
#include <QWidget>

#include "segmentation/RangeMap.h"
#include "render/ColourMaps.h"

namespace caps {

class RangeMapView : public QWidget
{
  Q_OBJECT
public:
  explicit RangeMapView(QWidget* parent = nullptr);

  /// Shows @a map through @a colourMap over [low, high] (mm); the bar is titled @a title.
  void setMap(const seg::RangeMap& map, render::ColourMap colourMap, double low, double high, const QString& title);
  void clear();
  /// Samples of the maps (index i + nθ j, the maps' grid) that metal's
  /// streaks spoil: hatched in dark grey over their colour from the next
  /// setMap() on. Empty: none.
  void setSpoiled(std::vector<unsigned char> spoiled) { spoiled_ = std::move(spoiled); }
  bool hasMap() const { return !map_.empty(); }

  /// A crosshair at chart point (θ, z) (radians, mm); none with std::nullopt.
  void setMarker(std::optional<std::array<double, 2>> chartPoint);
  /// A line between two chart points (the thickness profile's); none with std::nullopt.
  void setProfileLine(std::optional<std::array<std::array<double, 2>, 2>> line);
  /// Dots with labels at chart points (the landmarks).
  void setLandmarks(std::vector<std::pair<QString, std::array<double, 2>>> landmarks);

  /// Widget point of chart point (θ, z); the chart point under widget point
  /// @a p, std::nullopt outside the map.
  QPointF widgetPointOf(double theta, double z) const;
  std::optional<std::array<double, 2>> chartPointAt(const QPointF& p) const;

  QSize sizeHint() const override { return {380, 260}; }
  bool hasHeightForWidth() const override { return true; }
  int heightForWidth(int width) const override;

signals:
  void hovered(double theta, double z);
  void left();
  void clicked(double theta, double z);

protected:
  void paintEvent(QPaintEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void leaveEvent(QEvent* event) override;

private:
  QRectF mapRect() const;

  seg::RangeMap map_;
  QImage image_;
  std::vector<unsigned char> spoiled_;
  render::ColourMap colour_map_ = render::ColourMap::Viridis;
  double low_ = 0.0, high_ = 1.0;
  QString title_;
  std::optional<std::array<double, 2>> marker_;
  std::optional<std::array<std::array<double, 2>, 2>> profile_line_;
  std::vector<std::pair<QString, std::array<double, 2>>> landmarks_;
};

/// A histogram of thickness (mm) as bars, with its axis.
class ThicknessHistogram : public QWidget
{
  Q_OBJECT
public:
  explicit ThicknessHistogram(QWidget* parent = nullptr);
  /// counts[k] is the bin [k·binWidth, (k+1)·binWidth); the last holds the
  /// rest. @a caption says what is counted, under the axis.
  void setCounts(std::vector<int> counts, double binWidth, QString caption = {});
  const QString& caption() const { return caption_; }
  QSize sizeHint() const override { return {380, 120}; }

protected:
  void paintEvent(QPaintEvent* event) override;

private:
  std::vector<int> counts_;
  double bin_width_ = 1.0;
  QString caption_;
};

} // namespace caps
