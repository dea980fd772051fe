// The Incision module plugin: metadata and factories only.

#include "modules/core/Module.h"
#include "modules/incision/IncisionLogic.h"
#include "modules/incision/IncisionPanel.h"
#include "modules/incision/PlanCommands.h"

namespace caps {
namespace {

class IncisionModule : public Module
{
public:
  std::string name() const override { return "incision"; }
  std::string title() const override { return "Incision"; }
  std::string help() const override
  {
    return "Plans the operation on the skin: a procedure (elliptical excision, Z-plasty, Z-plasty with "
           "excision, rhomboid flap, V-Y advancement) placed on the skin, its hole and sutures, and the "
           "lengths, angles and excised area measured on the 3D skin. Procedures are the files of "
           "data/procedures/.";
  }
  std::vector<ModuleCommand> commands() const override { return planCommands(); }
  std::unique_ptr<ModuleLogic> createLogic(Scene& scene) const override
  {
    return std::make_unique<IncisionLogic>(scene);
  }
  QWidget* createPanel(ModuleLogic& logic, ModuleHost& host, QWidget* parent) const override
  {
    return new IncisionPanel(static_cast<IncisionLogic&>(logic), host, parent);
  }
};

} // namespace
} // namespace caps

CAPS_DECLARE_MODULE(caps::IncisionModule)
