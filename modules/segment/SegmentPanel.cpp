#include "modules/segment/SegmentPanel.h"

#include <cmath>
#include <memory>

#include <QCheckBox>
#include <QDoubleSpinBox>
#include <QHeaderView>
#include <QSlider>
#include <QTableWidget>
#include <QTimer>
#include <QFormLayout>
#include <QLabel>
#include <QPushButton>
#include <QVBoxLayout>

#include "modules/segment/SegmentLogic.h"
#include "scene/Scene.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"

namespace caps {
namespace {

// The volume the panel works on: the newest one (a selector comes with the full panel).
VolumeNode* currentVolume(Scene& scene)
{
  const auto volumes = scene.nodesOfType(NodeType::Volume);
  return volumes.empty() ? nullptr : static_cast<VolumeNode*>(volumes.back());
}

QDoubleSpinBox* thresholdBox(double value, QWidget* parent)
{
  auto* box = new QDoubleSpinBox(parent);
  box->setRange(-1024.0, 3071.0);
  box->setDecimals(0);
  box->setSingleStep(10.0);
  box->setSuffix(" HU");
  box->setValue(value);
  return box;
}

} // namespace

SegmentPanel::SegmentPanel(SegmentLogic& logic, ModuleHost& host, QWidget* parent)
  : QWidget(parent), logic_(logic), host_(host)
{
  const SegmentLogic::Parameters defaults;
  auto* layout = new QVBoxLayout(this);
  auto* form = new QFormLayout;
  skin_ = thresholdBox(defaults.skinThresholdHu, this);
  bone_ = thresholdBox(defaults.boneThresholdHu, this);
  skin_->setObjectName("segment.skinThreshold");
  bone_->setObjectName("segment.boneThreshold");
  form->addRow(tr("Skin threshold (air / tissue):"), skin_);
  form->addRow(tr("Bone threshold (tissue / bone):"), bone_);
  layout->addLayout(form);
  preview_ = new QCheckBox(tr("Preview the thresholds on the slices"), this);
  preview_->setObjectName("segment.preview");
  preview_->setToolTip(tr("Soft tissue tinted red, bone yellow, as the thresholds would label them"));
  preview_->setChecked(true);
  layout->addWidget(preview_);
  run_ = new QPushButton(tr("Segment skin and bone"), this);
  run_->setObjectName("segment.run");
  layout->addWidget(run_);
  status_ = new QLabel(this);
  status_->setObjectName("segment.status");
  status_->setWordWrap(true);
  layout->addWidget(status_);
  layout->addWidget(new QLabel(tr("Surfaces in the 3D view:"), this));
  surfaces_ = new QTableWidget(0, 2, this);
  surfaces_->setObjectName("segment.surfaces");
  surfaces_->setHorizontalHeaderLabels({tr("Surface (tick to show)"), tr("Opacity")});
  surfaces_->horizontalHeader()->setSectionResizeMode(0, QHeaderView::Stretch);
  surfaces_->horizontalHeader()->setSectionResizeMode(1, QHeaderView::Fixed);
  surfaces_->horizontalHeader()->resizeSection(1, 130);
  surfaces_->verticalHeader()->hide();
  surfaces_->setSelectionMode(QAbstractItemView::NoSelection);
  surfaces_->setMinimumHeight(120);
  layout->addWidget(surfaces_);
  layout->addStretch(1);

  connect(skin_, qOverload<double>(&QDoubleSpinBox::valueChanged), this, [this](double) { updatePreview(); });
  connect(bone_, qOverload<double>(&QDoubleSpinBox::valueChanged), this, [this](double) { updatePreview(); });
  connect(preview_, &QCheckBox::toggled, this, [this](bool) { updatePreview(); });
  connect(surfaces_, &QTableWidget::itemChanged, this, [this](QTableWidgetItem* item) {
    if (item->column() != 0)
      return;
    auto* node = logic_.scene().nodeAs<SurfaceNode>(item->data(Qt::UserRole).toString().toStdString());
    const bool visible = item->checkState() == Qt::Checked;
    if (node && node->visible() != visible)
      node->setVisible(visible);
  });
  connect(run_, &QPushButton::clicked, this, &SegmentPanel::run);
  observer_ = logic_.scene().addObserver([this](SceneEvent, const Node& node) {
    if (node.type() == NodeType::Volume)
      updateFromScene();
    else if (node.type() == NodeType::Surface && !surfaces_pending_)
    {
      // Several surfaces change at once (a segmentation, a prediction): one update after them.
      surfaces_pending_ = true;
      QTimer::singleShot(0, this, [this]() {
        surfaces_pending_ = false;
        updateSurfaces();
      });
    }
  });
  updateFromScene();
  updateSurfaces();
}

void SegmentPanel::showEvent(QShowEvent* event)
{
  QWidget::showEvent(event);
  updatePreview();
}

void SegmentPanel::hideEvent(QHideEvent* event)
{
  QWidget::hideEvent(event);
  // The preview belongs to this panel: another module's work shows the segmentation.
  host_.previewThresholds(std::nullopt);
}

void SegmentPanel::updatePreview()
{
  if (!isVisible())
    return;
  if (preview_->isChecked())
    host_.previewThresholds(std::array<double, 2>{skin_->value(), bone_->value()});
  else
    host_.previewThresholds(std::nullopt);
}

void SegmentPanel::updateSurfaces()
{
  const QSignalBlocker block(surfaces_);
  const auto nodes = logic_.scene().nodesOfType(NodeType::Surface);
  surfaces_->setRowCount(static_cast<int>(nodes.size()));
  for (int row = 0; row < static_cast<int>(nodes.size()); ++row)
  {
    auto* node = static_cast<SurfaceNode*>(nodes[static_cast<size_t>(row)]);
    auto* item = new QTableWidgetItem(QString::fromStdString(node->name()));
    item->setFlags(Qt::ItemIsEnabled | Qt::ItemIsUserCheckable);
    item->setCheckState(node->visible() ? Qt::Checked : Qt::Unchecked);
    item->setData(Qt::UserRole, QString::fromStdString(node->id()));
    surfaces_->setItem(row, 0, item);
    auto* opacity = new QSlider(Qt::Horizontal, surfaces_);
    opacity->setObjectName(QString::fromStdString("segment.opacity." + node->name()));
    opacity->setRange(0, 100);
    opacity->setValue(static_cast<int>(std::lround(node->opacity() * 100)));
    const std::string id = node->id();
    connect(opacity, &QSlider::valueChanged, this, [this, id](int value) {
      auto* target = logic_.scene().nodeAs<SurfaceNode>(id);
      if (target && std::lround(target->opacity() * 100) != value)
        target->setOpacity(value / 100.0);
    });
    surfaces_->setCellWidget(row, 1, opacity);
  }
}

SegmentPanel::~SegmentPanel()
{
  logic_.scene().removeObserver(observer_);
}

void SegmentPanel::updateFromScene()
{
  VolumeNode* volume = currentVolume(logic_.scene());
  run_->setEnabled(volume != nullptr);
  status_->setText(volume ? tr("Volume: %1").arg(QString::fromStdString(volume->name()))
                          : tr("Load a CT in the Volumes module first."));
}

void SegmentPanel::run()
{
  VolumeNode* volume = currentVolume(logic_.scene());
  if (!volume)
    return;
  SegmentLogic::Parameters parameters;
  parameters.skinThresholdHu = skin_->value();
  parameters.boneThresholdHu = bone_->value();
  // The worker gets its own reference to the CT's voxels and the volume's id,
  // never the node: the scene is only touched in the finish function.
  vtkSmartPointer<vtkImageData> ct = volume->image();
  const std::string volumeId = volume->id();
  host_.runTask("Segmenting " + volume->name(), [this, ct, volumeId, parameters](const TaskProgress& progress) {
    auto output = std::make_shared<SegmentationOutput>(SegmentLogic::compute(ct, parameters, progress));
    return std::function<void()>([this, volumeId, output]() {
      auto* target = logic_.scene().nodeAs<VolumeNode>(volumeId);
      if (!target)
      {
        host_.showWarning("Segmentation", "The volume was closed while it was being segmented.");
        return;
      }
      const SegmentationResult result = logic_.addToScene(*target, std::move(*output));
      std::string notes;
      for (const auto& note : result.notes)
        notes += note + "\n";
      status_->setText(QString::fromStdString(notes));
      host_.showStatus("Segmented '" + target->name() + "'");
    });
  });
}

} // namespace caps
