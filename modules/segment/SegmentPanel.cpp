#include "modules/segment/SegmentPanel.h"

#include <memory>

#include <QDoubleSpinBox>
#include <QFormLayout>
#include <QLabel>
#include <QPushButton>
#include <QVBoxLayout>

#include "modules/segment/SegmentLogic.h"
#include "scene/Scene.h"
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
  form->addRow(tr("Skin threshold (air / tissue):"), skin_);
  form->addRow(tr("Bone threshold (tissue / bone):"), bone_);
  layout->addLayout(form);
  run_ = new QPushButton(tr("Segment skin and bone"), this);
  layout->addWidget(run_);
  status_ = new QLabel(this);
  status_->setWordWrap(true);
  layout->addWidget(status_);
  layout->addStretch(1);

  connect(run_, &QPushButton::clicked, this, &SegmentPanel::run);
  observer_ = logic_.scene().addObserver([this](SceneEvent, const Node& node) {
    if (node.type() == NodeType::Volume)
      updateFromScene();
  });
  updateFromScene();
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
  host_.runTask("Segmenting " + volume->name(), [this, ct, volumeId,
                                                 parameters](const TaskProgress& progress) {
    auto output = std::make_shared<SegmentationOutput>(
      SegmentLogic::compute(ct, parameters, progress));
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
