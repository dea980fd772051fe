#include "modules/rangemap/RangeMapPanel.h"

#include <memory>

#include <QCheckBox>
#include <QFontDatabase>
#include <QLabel>
#include <QPushButton>
#include <QVBoxLayout>

#include "modules/rangemap/RangeMapLogic.h"
#include "modules/segment/SegmentLogic.h"
#include "scene/LabelMapNode.h"
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
  return QString::fromStdString(RangeMapLogic::describeAxis(output.axis)) +
         line("Radial:", output.radialStatistics) + line("Normal:", output.normalStatistics);
}

} // namespace

RangeMapPanel::RangeMapPanel(RangeMapLogic& logic, ModuleHost& host, QWidget* parent)
  : QWidget(parent), logic_(logic), host_(host)
{
  auto* layout = new QVBoxLayout(this);
  smooth_ = new QCheckBox(tr("Smooth the maps (3 x 3 box, thesis eq. 4.2)"), this);
  layout->addWidget(smooth_);
  run_ = new QPushButton(tr("Build range and thickness maps"), this);
  layout->addWidget(run_);
  status_ = new QLabel(this);
  status_->setWordWrap(true);
  status_->setFont(QFontDatabase::systemFont(QFontDatabase::FixedFont));
  layout->addWidget(status_);
  layout->addStretch(1);

  connect(run_, &QPushButton::clicked, this, &RangeMapPanel::run);
  observer_ = logic_.scene().addObserver([this](SceneEvent, const Node& node) {
    if (node.type() == NodeType::Volume)
      updateFromScene();
  });
  updateFromScene();
}

RangeMapPanel::~RangeMapPanel()
{
  logic_.scene().removeObserver(observer_);
}

void RangeMapPanel::updateFromScene()
{
  VolumeNode* volume = currentVolume(logic_.scene());
  run_->setEnabled(volume != nullptr);
  status_->setText(volume ? tr("Volume: %1").arg(QString::fromStdString(volume->name()))
                          : tr("Load a CT in the Volumes module first."));
}

void RangeMapPanel::run()
{
  VolumeNode* volume = currentVolume(logic_.scene());
  if (!volume)
    return;
  RangeMapLogic::Parameters parameters;
  parameters.smooth = smooth_->isChecked();
  // The worker gets the voxels, never the nodes; with no label map yet it
  // segments first (with the default thresholds) and adds the label map at the end.
  vtkSmartPointer<vtkImageData> ct = volume->image();
  LabelMapNode* existing = SegmentLogic(logic_.scene()).findLabelMap(*volume);
  vtkSmartPointer<vtkImageData> labels = existing ? existing->image() : nullptr;
  const std::string volumeId = volume->id();
  host_.runTask("Range maps of " + volume->name(), [this, ct, labels, volumeId,
                                                    parameters](const TaskProgress& progress) {
    auto segmentation = std::make_shared<SegmentationOutput>();
    vtkSmartPointer<vtkImageData> labelImage = labels;
    TaskProgress rest = progress;
    if (!labelImage)
    {
      SegmentLogic::Parameters p;
      p.skinThresholdHu = parameters.skinThresholdHu;
      p.boneThresholdHu = parameters.boneThresholdHu;
      *segmentation = SegmentLogic::compute(ct, p, [&progress](double f, const std::string& s) {
        return progress(0.5 * f, s);
      });
      labelImage = segmentation->labels;
      rest = [&progress](double f, const std::string& s) { return progress(0.5 + 0.5 * f, s); };
    }
    auto output =
      std::make_shared<RangeMapOutput>(RangeMapLogic::compute(ct, labelImage, parameters, rest));
    const bool segmented = !labels;
    return std::function<void()>([this, volumeId, segmentation, output, segmented]() {
      auto* target = logic_.scene().nodeAs<VolumeNode>(volumeId);
      if (!target)
      {
        host_.showWarning("Range maps", "The volume was closed while its maps were being built.");
        return;
      }
      if (segmented)
        SegmentLogic(logic_.scene()).addToScene(*target, std::move(*segmentation));
      logic_.addToScene(*target, *output);
      status_->setText(statistics(*output));
      host_.showStatus("Range maps of '" + target->name() + "' built");
    });
  });
}

} // namespace caps
