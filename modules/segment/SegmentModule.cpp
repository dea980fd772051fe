// The Segment module plugin: metadata and factories only.

#include "modules/core/Module.h"
#include "modules/segment/SegmentCommands.h"
#include "modules/segment/SegmentLogic.h"
#include "modules/segment/SegmentPanel.h"

namespace caps {
namespace {

class SegmentModule : public Module
{
public:
  std::string name() const override { return "segment"; }
  std::string title() const override { return "Segment"; }
  std::string help() const override
  {
    return "Segment the skin and the bone of a head CT by thresholds (air/tissue -400 HU, "
           "tissue/bone 250 HU by default): a label map (soft tissue, bone) and the skin and "
           "bone surfaces, without the CT table and the head holder.";
  }
  std::unique_ptr<ModuleLogic> createLogic(Scene& scene) const override
  {
    return std::make_unique<SegmentLogic>(scene);
  }
  QWidget* createPanel(ModuleLogic& logic, ModuleHost& host, QWidget* parent) const override
  {
    return new SegmentPanel(static_cast<SegmentLogic&>(logic), host, parent);
  }
  std::vector<ModuleCommand> commands() const override { return segmentCommands(); }
};

} // namespace
} // namespace caps

CAPS_DECLARE_MODULE(caps::SegmentModule)
