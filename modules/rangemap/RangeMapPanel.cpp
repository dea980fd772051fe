#include "modules/rangemap/RangeMapPanel.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>

#include <QCheckBox>
#include <QComboBox>
#include <QFileDialog>
#include <QFontDatabase>
#include <QFormLayout>
#include <QGroupBox>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QLineEdit>
#include <QListWidget>
#include <QPixmap>
#include <QPointer>
#include <QPushButton>
#include <QTableWidget>
#include <QTimer>
#include <QVBoxLayout>

#include "modules/rangemap/RangeMapLogic.h"
#include "modules/rangemap/RangeMapView.h"
#include "modules/segment/SegmentLogic.h"
#include "render/XyPlot.h"
#include "scene/LabelMapNode.h"
#include "scene/LandmarksNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/ScopedEdit.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"
#include "segmentation/LandmarkPlacement.h"
#include "segmentation/Landmarks.h"

namespace caps {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
constexpr double kHistogramBin = 1.0;   // mm
constexpr double kHistogramTop = 100.0; // mm: the histogram's widest range
constexpr double kThicknessTop = 30.0;  // mm: facial soft tissue is thinner almost everywhere
// The segmentation's skin: translucent so the bone shows through it.
constexpr double kSkinOpacity = 0.6;

// The volume the panel works on: the newest one.
VolumeNode* currentVolume(Scene& scene)
{
  const auto volumes = scene.nodesOfType(NodeType::Volume);
  return volumes.empty() ? nullptr : static_cast<VolumeNode*>(volumes.back());
}

/// The segmentation's skin surface (the newest "Skin").
SurfaceNode* skinSurface(Scene& scene)
{
  SurfaceNode* found = nullptr;
  for (Node* node : scene.nodesOfType(NodeType::Surface))
    if (node->name() == "Skin")
      found = static_cast<SurfaceNode*>(node);
  return found;
}

QString statistics(const RangeMapOutput& output)
{
  auto line = [](const char* what, const seg::ThicknessStatistics& s) {
    return QString("%1  min %2  median %3  mean %4  p95 %5 mm\n")
      .arg(what)
      .arg(s.min, 0, 'f', 1)
      .arg(s.median, 0, 'f', 1)
      .arg(s.mean, 0, 'f', 1)
      .arg(s.p95, 0, 'f', 1);
  };
  return QString::fromStdString(RangeMapLogic::describeAxis(output.axis)) + line("Radial:", output.radialStatistics) +
         line("Normal:", output.normalStatistics);
}

QString millimetres(double v)
{
  return std::isfinite(v) ? QString::number(v, 'f', 1) : QString("-");
}

enum MapKind
{
  kThicknessRadial,
  kThicknessNormal,
  kSkinRadius,
  kBoneRadius
};

} // namespace

RangeMapPanel::RangeMapPanel(RangeMapLogic& logic, ModuleHost& host, QWidget* parent)
  : QWidget(parent), logic_(logic), host_(host)
{
  auto* layout = new QVBoxLayout(this);
  addBuildControls(layout);
  addThicknessReview(layout);
  addLandmarks(layout);
  layout->addStretch(1);
  connectControls();
  observeTheScene();
  updateFromScene();
  reloadMaps();
}

/// Smoothing, the Build button and the maps' status.
void RangeMapPanel::addBuildControls(QVBoxLayout* layout)
{
  smooth_ = new QCheckBox(tr("Smooth the maps (3 x 3 box, thesis eq. 4.2)"), this);
  smooth_->setObjectName("rangemap.smooth");
  layout->addWidget(smooth_);
  run_ = new QPushButton(tr("Build range and thickness maps"), this);
  run_->setObjectName("rangemap.run");
  layout->addWidget(run_);
  status_ = new QLabel(this);
  status_->setObjectName("rangemap.status");
  status_->setWordWrap(true);
  status_->setFont(QFontDatabase::systemFont(QFontDatabase::FixedFont));
  layout->addWidget(status_);
}

void RangeMapPanel::addThicknessReview(QVBoxLayout* layout)
{
  // Thickness review (thesis §4.2: the soft tissue between the two maps).
  auto* review = new QGroupBox(tr("Thickness review"), this);
  auto* reviewLayout = new QVBoxLayout(review);
  auto* row = new QHBoxLayout;
  map_kind_ = new QComboBox(review);
  map_kind_->setObjectName("rangemap.mapKind");
  map_kind_->addItem(tr("Thickness, radial"), kThicknessRadial);
  map_kind_->addItem(tr("Thickness, along the skin normal"), kThicknessNormal);
  map_kind_->addItem(tr("Skin, distance from the axis"), kSkinRadius);
  map_kind_->addItem(tr("Bone, distance from the axis"), kBoneRadius);
  row->addWidget(map_kind_, 1);
  paint_ = new QCheckBox(tr("On the 3D skin"), review);
  paint_->setObjectName("rangemap.paintThickness");
  paint_->setToolTip(tr("Paints the thickness the map shows (radial or along the normal) on the skin surface with "
                        "the same colours"));
  row->addWidget(paint_);
  reviewLayout->addLayout(row);
  map_view_ = new RangeMapView(review);
  map_view_->setObjectName("rangemap.map");
  map_view_->setToolTip(tr("Hover to read the maps; click to show the point on the face and in the slices"));
  reviewLayout->addWidget(map_view_);
  probe_ = new QLabel(tr("Hover over the map to read it."), review);
  probe_->setObjectName("rangemap.probe");
  probe_->setWordWrap(true);
  reviewLayout->addWidget(probe_);
  histogram_ = new ThicknessHistogram(review);
  histogram_->setObjectName("rangemap.histogram");
  reviewLayout->addWidget(histogram_);
  profile_button_ = new QPushButton(tr("Thickness along a line..."), review);
  profile_button_->setObjectName("rangemap.profile");
  profile_button_->setToolTip(tr("Click the line's two ends on the 3D skin: the thickness along it is plotted"));
  reviewLayout->addWidget(profile_button_);
  profile_plot_ = new QLabel(review);
  profile_plot_->setObjectName("rangemap.profilePlot");
  profile_plot_->setAlignment(Qt::AlignCenter);
  profile_plot_->hide();
  reviewLayout->addWidget(profile_plot_);
  profile_summary_ = new QLabel(review);
  profile_summary_->setObjectName("rangemap.profileSummary");
  profile_summary_->setWordWrap(true);
  profile_summary_->hide();
  reviewLayout->addWidget(profile_summary_);
  layout->addWidget(review);
}

/// The landmark table and its buttons.
void RangeMapPanel::addLandmarks(QVBoxLayout* layout)
{
  auto* marks = new QGroupBox(tr("Landmarks"), this);
  auto* marksLayout = new QVBoxLayout(marks);
  auto* nameRow = new QHBoxLayout;
  landmark_name_ = new QLineEdit(marks);
  landmark_name_->setObjectName("rangemap.landmarkName");
  landmark_name_->setPlaceholderText(tr("name, e.g. nasion"));
  nameRow->addWidget(landmark_name_, 1);
  add_landmark_ = new QPushButton(tr("Add on the face"), marks);
  add_landmark_->setObjectName("rangemap.addLandmark");
  add_landmark_->setToolTip(tr("Then click the point on the skin in the 3D view"));
  nameRow->addWidget(add_landmark_);
  marksLayout->addLayout(nameRow);
  place_landmarks_ = new QPushButton(tr("Place standard landmarks"), marks);
  place_landmarks_->setObjectName("rangemap.placeLandmarks");
  place_landmarks_->setToolTip(tr("Places the standard facial landmarks from the maps, where their anatomy is in "
                                  "the scan (check each: they are a first guess)"));
  marksLayout->addWidget(place_landmarks_);
  landmarks_ = new QTableWidget(0, 7, marks);
  landmarks_->setObjectName("rangemap.landmarks");
  landmarks_->setHorizontalHeaderLabels({tr("Name"), tr("θ (°)"), tr("z (mm)"), tr("Radial (mm)"), tr("Normal (mm)"),
                                         tr("Depth in the CT (mm)"), tr("Measured")});
  landmarks_->horizontalHeader()->setSectionResizeMode(QHeaderView::ResizeToContents);
  landmarks_->horizontalHeader()->setStretchLastSection(true);
  landmarks_->verticalHeader()->hide();
  landmarks_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  landmarks_->setSelectionBehavior(QAbstractItemView::SelectRows);
  landmarks_->setMinimumHeight(110);
  marksLayout->addWidget(landmarks_);
  auto* buttons = new QHBoxLayout;
  locate_ = new QPushButton(tr("Find on the map"), marks);
  locate_->setObjectName("rangemap.locate");
  locate_->setToolTip(tr("Click a point on the 3D skin to see it on the map"));
  remove_landmark_ = new QPushButton(tr("Remove"), marks);
  remove_landmark_->setObjectName("rangemap.removeLandmark");
  export_landmarks_ = new QPushButton(tr("Export CSV..."), marks);
  export_landmarks_->setObjectName("rangemap.exportLandmarks");
  buttons->addWidget(locate_);
  buttons->addWidget(remove_landmark_);
  buttons->addWidget(export_landmarks_);
  marksLayout->addLayout(buttons);
  // The distances the ruler measured on the slices, kept with the landmarks.
  distances_label_ = new QLabel(tr("Distances measured on the slices (click one to see it):"), marks);
  marksLayout->addWidget(distances_label_);
  distances_ = new QListWidget(marks);
  distances_->setObjectName("rangemap.distances");
  distances_->setMaximumHeight(90);
  marksLayout->addWidget(distances_);
  remove_distance_ = new QPushButton(tr("Remove distance"), marks);
  remove_distance_->setObjectName("rangemap.removeDistance");
  marksLayout->addWidget(remove_distance_);
  layout->addWidget(marks);
}

void RangeMapPanel::connectControls()
{
  connect(run_, &QPushButton::clicked, this, &RangeMapPanel::run);
  connect(map_kind_, qOverload<int>(&QComboBox::currentIndexChanged), this, [this](int) { chooseMap(); });
  connect(paint_, &QCheckBox::toggled, this, &RangeMapPanel::paintThickness);
  connect(profile_button_, &QPushButton::clicked, this, &RangeMapPanel::drawProfileLine);
  connect(map_view_, &RangeMapView::hovered, this, &RangeMapPanel::showProbe);
  connect(map_view_, &RangeMapView::clicked, this, &RangeMapPanel::locate);
  connect(add_landmark_, &QPushButton::clicked, this, &RangeMapPanel::addLandmark);
  connect(place_landmarks_, &QPushButton::clicked, this, &RangeMapPanel::placeStandardLandmarks);
  connect(remove_landmark_, &QPushButton::clicked, this, &RangeMapPanel::removeLandmark);
  connect(export_landmarks_, &QPushButton::clicked, this, &RangeMapPanel::exportLandmarks);
  connect(distances_, &QListWidget::itemClicked, this,
          [this](QListWidgetItem* item) { showDistance(distances_->row(item)); });
  connect(distances_, &QListWidget::currentRowChanged, this, [this](int row) {
    if (!filling_table_)
      showDistance(row);
  });
  connect(remove_distance_, &QPushButton::clicked, this, &RangeMapPanel::removeDistance);
  connect(landmarks_, &QTableWidget::cellClicked, this, [this](int r, int) { showLandmark(r); });
  connect(landmarks_, &QTableWidget::currentCellChanged, this, [this](int r, int, int previous, int) {
    if (!filling_table_ && r != previous)
      showLandmark(r); // the arrow keys go down the table too
  });
  connect(locate_, &QPushButton::clicked, this, [this]() {
    if (!review_)
    {
      host_.showError("Find on the map", "Build the range maps first.");
      return;
    }
    host_.pickInThreeDView("Click a point on the skin to find it on the map", [this](const SurfacePick& pick) {
      if (!review_)
        return;
      const auto chart = review_->chartOf(pick.position);
      map_view_->setMarker(chart);
      showProbe(chart[0], chart[1]);
    });
  });
}

void RangeMapPanel::observeTheScene()
{
  observer_ = logic_.scene().addObserver([this](SceneEvent, const Node& node) {
    if (node.type() == NodeType::Volume)
      updateFromScene();
    else if (node.type() == NodeType::RangeMap && !reload_pending_)
    {
      // Four maps arrive one after the other: read them once, afterwards.
      reload_pending_ = true;
      QTimer::singleShot(0, this, [this]() {
        reload_pending_ = false;
        reloadMaps();
      });
    }
    else if (node.type() == NodeType::Landmarks)
      updateLandmarks();
  });
}

RangeMapPanel::~RangeMapPanel()
{
  logic_.scene().removeObserver(observer_);
}

void RangeMapPanel::updateFromScene()
{
  VolumeNode* volume = currentVolume(logic_.scene());
  run_->setEnabled(volume != nullptr);
  if (!review_)
    status_->setText(volume ? tr("Volume: %1").arg(QString::fromStdString(volume->name()))
                            : tr("Load a CT in the Volumes module first."));
}

void RangeMapPanel::reloadMaps()
{
  review_ = ThicknessReview::fromScene(logic_.scene());
  depths_.clear(); // new maps may come with a new CT or label map
  if (const RangeMapNode* skin = RangeMapLogic::newestMaps(logic_.scene()).skin; review_ && skin)
    if (const auto* source = logic_.scene().nodeAs<VolumeNode>(skin->sourceVolumeId()); source && source->image())
      review_->setSpoiled(
        ThicknessReview::eitherOf(ThicknessReview::spoiledBy(logic_.metalOf(*source), source->image()),
                                  logic_.againstAnObject(*source, review_->skin().frame())));
  map_view_->setSpoiled(review_ ? review_->spoiledSamples() : std::vector<unsigned char>());
  const bool ready = review_.has_value();
  for (QWidget* w : std::initializer_list<QWidget*>{map_kind_, paint_, add_landmark_, place_landmarks_, locate_,
                                                    remove_landmark_, export_landmarks_, profile_button_})
    w->setEnabled(ready);
  if (!ready)
  {
    map_view_->clear();
    histogram_->setCounts({}, kHistogramBin);
    updateProfile();
    return;
  }
  updateThicknessScale();
  showMap();
  updateLandmarks();
  updateProfile();
  if (paint_->isChecked())
    paintThickness(true);
}

void RangeMapPanel::chooseMap()
{
  const int kind = map_kind_->currentData().toInt();
  const ThicknessMeasure chosen = kind == kThicknessNormal   ? ThicknessMeasure::AlongNormal
                                  : kind == kThicknessRadial ? ThicknessMeasure::Radial
                                                             : measure_;
  const bool changed = chosen != measure_;
  measure_ = chosen;
  if (changed && review_)
    updateThicknessScale();
  showMap();
  if (changed && review_ && paint_->isChecked())
    paintThickness(true);
  if (changed)
    updateProfile();
}

void RangeMapPanel::drawProfileLine()
{
  if (!review_)
  {
    host_.showError("Thickness along a line", "Build the range maps first.");
    return;
  }
  QPointer<RangeMapPanel> self(this);
  host_.pickInThreeDView("Click where the line starts on the skin", [self](const SurfacePick& start) {
    if (!self)
      return;
    self->host_.pickInThreeDView("Click where the line ends on the skin", [self, start](const SurfacePick& end) {
      if (!self || !self->review_)
        return;
      self->profile_line_ = {self->review_->chartOf(start.position), self->review_->chartOf(end.position)};
      self->updateProfile();
    });
  });
}

void RangeMapPanel::updateProfile()
{
  const bool shown = review_ && profile_line_;
  map_view_->setProfileLine(shown ? profile_line_ : std::nullopt);
  profile_plot_->setVisible(shown);
  profile_summary_->setVisible(shown);
  if (!shown)
    return;
  ThicknessProfile profile;
  try
  {
    profile = review_->profile((*profile_line_)[0], (*profile_line_)[1], measure_);
  }
  catch (const std::exception& e) // neither end on the skin map (maps built again since)
  {
    profile_plot_->clear();
    profile_summary_->setText(QString::fromStdString(e.what()));
    return;
  }
  render::PlotSeries series{tr("thickness (mm)").toStdString(), {}, {}, 0x1f77b4};
  double holes = 0.0;
  for (std::size_t k = 0; k < profile.along.size(); ++k)
    if (std::isfinite(profile.thickness[k]))
    {
      series.x.push_back(profile.along[k]);
      series.y.push_back(profile.thickness[k]);
    }
    else if (k > 0)
      holes += profile.along[k] - profile.along[k - 1];
  const double length = profile.along.back();
  if (series.x.size() < 2)
  {
    profile_plot_->clear();
    profile_summary_->setText(tr("No thickness along this line: draw it on the face, where the maps have skin "
                                 "and bone."));
    return;
  }
  render::XyPlot plot;
  plot.title = tr("Soft-tissue thickness %1 along the line").arg(measureName(measure_)).toStdString();
  plot.xLabel = tr("along the skin (mm)").toStdString();
  plot.series = {series};
  plot.width = std::max(300, map_view_->width()); // drawn at the size shown: the text stays readable
  plot.height = std::max(200, plot.width * 11 / 20);
  profile_plot_->setPixmap(QPixmap::fromImage(render::drawXyPlot(plot)));
  const auto [low, high] = std::minmax_element(series.y.begin(), series.y.end());
  double mean = 0.0;
  for (double y : series.y)
    mean += y;
  mean /= static_cast<double>(series.y.size());
  QString text = tr("Line %1 mm along the skin: thickness %2 from %3 to %4 mm, mean %5 mm")
                   .arg(length, 0, 'f', 1)
                   .arg(measureName(measure_))
                   .arg(*low, 0, 'f', 1)
                   .arg(*high, 0, 'f', 1)
                   .arg(mean, 0, 'f', 1);
  if (holes > 0.0)
    text += tr("; no value over %1 mm (no skin or bone there on the maps)").arg(holes, 0, 'f', 1);
  profile_summary_->setText(text + ".");
}

void RangeMapPanel::updateThicknessScale()
{
  // The thickness colours run to the face's 98th percentile, in whole 5 mm,
  // so a few deep samples (the orbits, the nose) do not wash the face out.
  const std::vector<int> counts = review_->faceHistogram(kHistogramBin, 200, measure_);
  long total = 0;
  for (int c : counts)
    total += c;
  long seen = 0;
  double p98 = 25.0;
  for (std::size_t k = 0; k < counts.size(); ++k)
  {
    seen += counts[k];
    if (total > 0 && seen >= 0.98 * double(total))
    {
      p98 = (double(k) + 1.0) * kHistogramBin;
      break;
    }
  }
  // The colours stop at 30 mm (facial soft tissue is thinner almost
  // everywhere; deeper is the last colour). The histogram reaches the face's
  // 98th percentile, whatever it is: behind the nose and the eyes the bone
  // lies 30-60 mm deep, and one bar of "30 and more" would hide it.
  thickness_top_ = std::clamp(std::ceil(p98 / 5.0) * 5.0, 5.0, kThicknessTop);
  const double histogramTop = std::clamp(std::ceil(p98 / 5.0) * 5.0, 10.0, kHistogramTop);
  const double bin = histogramTop > 40.0 ? 2.0 * kHistogramBin : kHistogramBin;
  histogram_->setCounts(review_->faceHistogram(bin, int(std::lround(histogramTop / bin)) + 1, measure_), bin,
                        tr("soft-tissue thickness %1 over the face (mm); last bar: %2 mm and more")
                          .arg(measureName(measure_))
                          .arg(histogramTop, 0, 'f', 0));
}

void RangeMapPanel::showMap()
{
  if (!review_)
    return;
  const int kind = map_kind_->currentData().toInt();
  auto rangeOf = [](const seg::RangeMap& map) {
    std::vector<float> v;
    for (float x : map.values())
      if (std::isfinite(x))
        v.push_back(x);
    if (v.empty())
      return std::pair{0.0, 1.0};
    std::sort(v.begin(), v.end());
    const double lo = v[v.size() * 2 / 100], hi = v[v.size() * 98 / 100];
    return std::pair{std::floor(lo / 10.0) * 10.0, std::ceil(hi / 10.0) * 10.0};
  };
  switch (kind)
  {
  case kThicknessNormal:
    if (!review_->thicknessNormal().empty())
    {
      map_view_->setMap(review_->thicknessNormal(), render::ColourMap::Thickness, 0.0, thickness_top_,
                        tr("soft-tissue thickness along the skin normal (mm)"));
      break;
    }
    [[fallthrough]];
  case kThicknessRadial:
    map_view_->setMap(review_->thickness(), render::ColourMap::Thickness, 0.0, thickness_top_,
                      tr("soft-tissue thickness, radial (mm)"));
    break;
  case kSkinRadius:
  {
    const auto [lo, hi] = rangeOf(review_->skin());
    map_view_->setMap(review_->skin(), render::ColourMap::Viridis, lo, hi,
                      tr("skin: distance from the head axis (mm)"));
    break;
  }
  case kBoneRadius:
  {
    const auto [lo, hi] = rangeOf(review_->bone());
    map_view_->setMap(review_->bone(), render::ColourMap::Viridis, lo, hi,
                      tr("bone: distance from the head axis (mm)"));
    break;
  }
  }
}

void RangeMapPanel::showProbe(double theta, double z)
{
  if (!review_)
    return;
  const ThicknessProbe p = review_->probe(theta, z);
  probe_->setText(tr("θ %1°  z %2 mm   skin %3  bone %4 mm\nthickness: radial %5 mm, along the normal %6 mm")
                    .arg(p.theta / kDegree, 0, 'f', 1)
                    .arg(p.z, 0, 'f', 1)
                    .arg(millimetres(p.skinRadius))
                    .arg(millimetres(p.boneRadius))
                    .arg(millimetres(p.thickness))
                    .arg(millimetres(p.thicknessNormal)));
}

void RangeMapPanel::locate(double theta, double z)
{
  if (!review_)
    return;
  map_view_->setMarker(std::array<double, 2>{theta, z});
  showProbe(theta, z);
  const ThicknessProbe p = review_->probe(theta, z);
  if (std::isfinite(p.skinPoint[0]))
    host_.setCursorPosition(p.skinPoint);
  else
    host_.showStatus("No skin was found there on the map.");
}

void RangeMapPanel::paintThickness(bool on)
{
  SurfaceNode* skin = skinSurface(logic_.scene());
  if (!skin || !skin->polyData())
  {
    if (on)
      host_.showError("Thickness on the skin", "There is no skin surface: segment the CT in the Segment module.");
    return;
  }
  if (on && review_)
  {
    skin->setPolyData(review_->paintThickness(skin->polyData(), measure_));
    skin->setColourMap(render::colourMapName(render::ColourMap::Thickness));
    skin->setScalarRange({0.0, thickness_top_});
    skin->setColourBarTitle(std::string("Soft-tissue thickness, ") + measureName(measure_) + " (mm)");
    skin->setOpacity(1.0);
    skin->setColourArray("thickness_mm");
  }
  else if (!on)
  {
    skin->setOpacity(kSkinOpacity);
    skin->setColourArray("");
  }
}

LandmarksNode* RangeMapPanel::landmarksNode(bool create)
{
  const auto nodes = logic_.scene().nodesOfType(NodeType::Landmarks);
  if (!nodes.empty())
    return static_cast<LandmarksNode*>(nodes.back());
  if (!create)
    return nullptr;
  auto node = std::make_unique<LandmarksNode>();
  node->setName("Landmarks");
  return static_cast<LandmarksNode*>(logic_.scene().addNode(std::move(node)));
}

void RangeMapPanel::addLandmark()
{
  if (!review_)
  {
    host_.showError("Add a landmark", "Build the range maps first: a landmark's thickness is read off them.");
    return;
  }
  host_.pickInThreeDView("Click the landmark on the skin", [this](const SurfacePick& pick) {
    LandmarksNode* node = landmarksNode(true);
    QString name = landmark_name_->text().trimmed();
    if (name.isEmpty())
      name = tr("Landmark %1").arg(node->landmarks().size() + 1);
    node->add({name.toStdString(), pick.position});
    landmark_name_->clear();
    const auto chart = review_->chartOf(pick.position);
    map_view_->setMarker(chart);
    showProbe(chart[0], chart[1]);
  });
}

void RangeMapPanel::removeLandmark()
{
  LandmarksNode* node = landmarksNode(false);
  const int row = landmarks_->currentRow();
  if (!node || row < 0)
  {
    host_.showStatus("Choose a landmark in the table first.");
    return;
  }
  node->remove(static_cast<size_t>(row));
}

void RangeMapPanel::exportLandmarks()
{
  LandmarksNode* node = landmarksNode(false);
  if (!node || (node->landmarks().empty() && node->distances().empty()) || !review_)
  {
    host_.showError("Export landmarks", "There are no landmarks yet: add some with 'Add on the face' (or measure "
                                        "with View > Ruler on the slices).");
    return;
  }
  const QString file =
    QFileDialog::getSaveFileName(host_.window(), tr("Export the landmarks"), "landmarks.csv", tr("CSV (*.csv)"));
  if (file.isEmpty())
    return;
  std::vector<ThicknessReview::CtDepth> depths;
  for (const auto& landmark : node->landmarks())
  {
    const MeasuredDepth* d = depthOf(landmark);
    depths.push_back(d ? ThicknessReview::CtDepth{d->depth, d->convention, d->note} : ThicknessReview::CtDepth{});
  }
  // The ruler's distances beside it: landmarks.csv, landmarks-distances.csv.
  const std::filesystem::path landmarksFile = file.toStdString();
  const std::filesystem::path distancesFile =
    landmarksFile.parent_path() / (landmarksFile.stem().string() + "-distances.csv");
  std::vector<std::pair<std::filesystem::path, std::string>> outputs{
    {landmarksFile, review_->landmarksCsv(node->landmarks(), depths)}};
  if (!node->distances().empty())
    outputs.emplace_back(distancesFile, ThicknessReview::distancesCsv(node->distances()));
  for (const auto& [path, text] : outputs)
  {
    std::ofstream out(path, std::ios::binary);
    out << text;
    out.close();
    if (!out)
    {
      host_.showError("Export landmarks",
                      "Could not write " + path.string() + ": check the folder exists and you may write there.");
      return;
    }
  }
  host_.showStatus("Landmarks written to " + landmarksFile.string() +
                   (outputs.size() > 1 ? ", the ruler's distances to " + distancesFile.string() : std::string()));
}

void RangeMapPanel::updateLandmarks()
{
  LandmarksNode* node = landmarksNode(false);
  const auto& list = node ? node->landmarks() : std::vector<LandmarksNode::Landmark>{};
  filling_table_ = true;
  landmarks_->setRowCount(static_cast<int>(list.size()));
  std::vector<std::pair<QString, std::array<double, 2>>> onMap;
  for (std::size_t r = 0; r < list.size(); ++r)
  {
    const QString name = QString::fromStdString(list[r].name);
    QStringList cells{name, "-", "-", "-", "-", "-", "-"};
    if (review_)
    {
      const auto chart = review_->chartOf(list[r].position);
      const ThicknessProbe p = review_->probe(chart[0], chart[1]);
      const MeasuredDepth* d = depthOf(list[r]);
      cells = QStringList{name,
                          QString::number(p.theta / kDegree, 'f', 1),
                          QString::number(p.z, 'f', 1),
                          millimetres(p.thickness),
                          millimetres(p.thicknessNormal),
                          d ? millimetres(d->depth) : QString("-"),
                          d ? QString::fromStdString(d->convention) : QString("-")};
      onMap.emplace_back(name, chart);
    }
    for (int c = 0; c < cells.size(); ++c)
      landmarks_->setItem(static_cast<int>(r), c, new QTableWidgetItem(cells[c]));
    if (const MeasuredDepth* d = review_ ? depthOf(list[r]) : nullptr; d && !d->note.empty())
    { // metal streaks in its slices: say so where the depth is read
      auto* measured = landmarks_->item(static_cast<int>(r), 6);
      measured->setText(measured->text() + tr("; check: metal streaks"));
      measured->setToolTip(QString::fromStdString(d->note));
    }
  }
  map_view_->setLandmarks(std::move(onMap));
  distances_->clear();
  const auto& distances = node ? node->distances() : std::vector<LandmarksNode::Distance>{};
  for (const auto& d : distances)
    distances_->addItem(QString("%1: %2 mm").arg(QString::fromStdString(d.name)).arg(d.length(), 0, 'f', 1));
  for (QWidget* w : std::initializer_list<QWidget*>{distances_label_, distances_, remove_distance_})
    w->setVisible(!distances.empty());
  filling_table_ = false;
  updateHandles();
  if (!dragged_.empty())
  { // the landmark just dragged: its new depth, drawn
    for (std::size_t r = 0; r < list.size(); ++r)
      if (list[r].name == dragged_)
      {
        landmarks_->selectRow(static_cast<int>(r));
        showLandmark(static_cast<int>(r));
      }
    dragged_.clear();
  }
}

void RangeMapPanel::showLandmark(int row)
{
  LandmarksNode* node = landmarksNode(false);
  if (!node || !review_ || row < 0 || row >= static_cast<int>(node->landmarks().size()))
    return;
  const LandmarksNode::Landmark& landmark = node->landmarks()[static_cast<std::size_t>(row)];
  const auto chart = review_->chartOf(landmark.position);
  map_view_->setMarker(chart);
  showProbe(chart[0], chart[1]);
  host_.setCursorPosition(landmark.position);
  const MeasuredDepth* d = depthOf(landmark);
  if (!d || !std::isfinite(d->depth) || !std::isfinite(d->boneEnd[0]))
  {
    host_.showMeasuredSegment(std::nullopt);
    host_.showStatus(landmark.name + ": no depth measured in the CT" +
                     (d ? " (" + d->convention + ")" : std::string(" (segment the CT first)")));
    return;
  }
  char label[96];
  std::snprintf(label, sizeof label, "%s %.1f mm", landmark.name.c_str(), d->depth);
  host_.showMeasuredSegment(MeasuredSegment{d->skinEnd, d->boneEnd, label});
  host_.showStatus(std::string(label) + ", " + d->convention + ": drawn on the slices");
}

void RangeMapPanel::showDistance(int row)
{
  LandmarksNode* node = landmarksNode(false);
  if (!node || row < 0 || row >= static_cast<int>(node->distances().size()))
    return;
  const LandmarksNode::Distance& d = node->distances()[static_cast<std::size_t>(row)];
  char label[96];
  std::snprintf(label, sizeof label, "%s %.1f mm", d.name.c_str(), d.length());
  host_.setCursorPosition(d.from); // the slice it was measured on
  host_.showMeasuredSegment(MeasuredSegment{d.from, d.to, label});
  host_.showStatus(std::string(label) + ": drawn on the slices");
}

void RangeMapPanel::removeDistance()
{
  LandmarksNode* node = landmarksNode(false);
  const int row = distances_->currentRow();
  if (!node || row < 0 || row >= static_cast<int>(node->distances().size()))
  {
    host_.showStatus("Choose a distance in the list first.");
    return;
  }
  host_.showMeasuredSegment(std::nullopt);
  ScopedEdit edit(logic_.scene(), node->id(), "Remove " + node->distances()[static_cast<std::size_t>(row)].name);
  node->removeDistance(static_cast<std::size_t>(row));
}

void RangeMapPanel::updateHandles()
{
  if (!isVisible())
    return; // the handles belong to the panel shown (hideEvent took ours away)
  LandmarksNode* node = review_ ? landmarksNode(false) : nullptr;
  if (!node || node->landmarks().empty())
  {
    host_.setThreeDViewHandles({}, nullptr);
    return;
  }
  std::vector<std::array<double, 3>> points;
  for (const auto& landmark : node->landmarks())
    points.push_back(landmark.position);
  QPointer<RangeMapPanel> self(this);
  host_.setThreeDViewHandles(points, [self](int index, const SurfacePick& pick) {
    if (self)
      self->moveLandmark(static_cast<std::size_t>(index), pick);
  });
}

void RangeMapPanel::moveLandmark(std::size_t index, const SurfacePick& pick)
{
  LandmarksNode* node = landmarksNode(false);
  const SurfaceNode* skin = skinSurface(logic_.scene());
  if (!node || index >= node->landmarks().size())
    return;
  if (!skin || pick.surface != skin->id())
  {
    host_.showStatus("A landmark goes on the skin: let it go over the skin surface.");
    updateHandles(); // the handle goes back to the landmark
    return;
  }
  std::vector<LandmarksNode::Landmark> list = node->landmarks();
  dragged_ = list[index].name;
  list[index].position = pick.position;
  ScopedEdit edit(logic_.scene(), node->id(), "Move landmark " + dragged_);
  node->setLandmarks(std::move(list)); // the table follows, measured again
}

void RangeMapPanel::showEvent(QShowEvent* event)
{
  QWidget::showEvent(event);
  updateHandles();
}

void RangeMapPanel::hideEvent(QHideEvent* event)
{
  QWidget::hideEvent(event);
  host_.setThreeDViewHandles({}, nullptr);
  host_.showMeasuredSegment(std::nullopt);
}

const RangeMapPanel::MeasuredDepth* RangeMapPanel::depthOf(const LandmarksNode::Landmark& landmark)
{
  if (auto found = depths_.find(landmark.name); found != depths_.end() && found->second.position == landmark.position)
    return &found->second;
  const VolumeNode* volume = currentVolume(logic_.scene());
  if (!volume)
    return nullptr;
  seg::LandmarkThickness row;
  row.landmark.name = landmark.name;
  row.position = Eigen::Vector3d(landmark.position[0], landmark.position[1], landmark.position[2]);
  std::vector<seg::LandmarkThickness> rows{row};
  try
  {
    if (!logic_.measureLandmarkDepths(*volume, rows))
      return nullptr; // no label map yet: nothing says where the bone is
  }
  catch (const std::exception&)
  {
    return nullptr; // a CT the label map does not fit: the maps' columns still read
  }
  const seg::LandmarkThickness& measured = rows.front();
  const auto lps = [](const Eigen::Vector3d& p) { return std::array<double, 3>{p.x(), p.y(), p.z()}; };
  MeasuredDepth& d = depths_[landmark.name];
  d = {landmark.position,         measured.depth, measured.convention, measured.note, lps(measured.depthSkinEnd),
       lps(measured.depthBoneEnd)};
  return &d;
}

void RangeMapPanel::placeStandardLandmarks()
{
  if (!review_)
    return;
  seg::LandmarkPlacement placed;
  try
  {
    placed = seg::placeLandmarks(review_->skin(), review_->bone());
  }
  catch (const std::exception& e)
  {
    host_.showError("Place the standard landmarks", e.what());
    return;
  }
  LandmarksNode* node = landmarksNode(true);
  std::vector<LandmarksNode::Landmark> list;
  for (const auto& l : node->landmarks())
    if (seg::landmarkDescription(l.name).empty()) // the user's own stay
      list.push_back(l);
  for (const seg::Landmark& l : placed.landmarks)
  {
    const ThicknessProbe p = review_->probe(l.theta, l.z);
    if (std::isfinite(p.skinPoint[0]))
      list.push_back({l.name, p.skinPoint});
  }
  node->setLandmarks(std::move(list));
  std::string status = "Placed " + std::to_string(placed.landmarks.size()) + " of " +
                       std::to_string(placed.status.size()) + " standard landmarks (check each)";
  if (!placed.warnings.empty())
    status += "; " + placed.warnings.front() + (placed.warnings.size() > 1 ? " (and others, see the report)" : "");
  host_.showStatus(status);
}

void RangeMapPanel::run()
{
  VolumeNode* volume = currentVolume(logic_.scene());
  if (!volume)
    return;
  RangeMapLogic::Parameters parameters;
  parameters.smooth = smooth_->isChecked();
  // The worker gets the voxels, never the nodes; with no label map yet it
  // segments first (with the default thresholds) and adds the label map at
  // the end. An existing one's crossings are searched at its own thresholds.
  vtkSmartPointer<vtkImageData> ct = volume->image();
  LabelMapNode* existing = SegmentLogic(logic_.scene()).findLabelMap(*volume);
  if (existing)
    parameters = RangeMapLogic::forLabelMap(parameters, *existing);
  vtkSmartPointer<vtkImageData> labels = existing ? existing->image() : nullptr;
  const std::string volumeId = volume->id();
  host_.runTask(
    "Range maps of " + volume->name(), [this, ct, labels, volumeId, parameters](const TaskProgress& progress) {
      auto segmentation = std::make_shared<SegmentationOutput>();
      vtkSmartPointer<vtkImageData> labelImage = labels;
      TaskProgress rest = progress;
      if (!labelImage)
      {
        SegmentLogic::Parameters p;
        p.skinThresholdHu = parameters.skinThresholdHu;
        p.boneThresholdHu = parameters.boneThresholdHu;
        *segmentation =
          SegmentLogic::compute(ct, p, [&progress](double f, const std::string& s) { return progress(0.5 * f, s); });
        labelImage = segmentation->labels;
        rest = [&progress](double f, const std::string& s) { return progress(0.5 + 0.5 * f, s); };
      }
      auto output = std::make_shared<RangeMapOutput>(RangeMapLogic::compute(ct, labelImage, parameters, rest));
      const bool segmented = !labels;
      return std::function<void()>([this, volumeId, segmentation, output, segmented]() {
        auto* target = logic_.scene().nodeAs<VolumeNode>(volumeId);
        if (!target)
        {
          host_.showWarning("Range maps", "The volume was closed while its maps were being built.");
          return;
        }
        SegmentLogic segment(logic_.scene());
        if (segmented)
          segment.addToScene(*target, std::move(*segmentation));
        const LabelMapNode* madeFrom = segment.findLabelMap(*target);
        logic_.addToScene(*target, *output, madeFrom ? madeFrom->id() : NodeId{});
        status_->setText(statistics(*output));
        host_.showStatus("Range maps of '" + target->name() + "' built");
      });
    });
}

} // namespace caps
