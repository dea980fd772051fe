// The RangeMap module plugin: metadata and factories only.

#include "modules/core/Module.h"
#include "modules/rangemap/RangeMapCommands.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "modules/rangemap/RangeMapPanel.h"

namespace caps {
namespace {

class RangeMapModule : public Module
{
public:
  std::string name() const override { return "rangemap"; }
  std::string title() const override { return "Range maps"; }
  std::string help() const override
  {
    return "Unwrap the skin and the bone into cylindrical range maps r(theta, z) around an "
           "axis fitted to the head (thesis section 4.2), and map the soft-tissue thickness "
           "between them, radially and along the skin normal.";
  }
  std::unique_ptr<ModuleLogic> createLogic(Scene& scene) const override
  {
    return std::make_unique<RangeMapLogic>(scene);
  }
  QWidget* createPanel(ModuleLogic& logic, ModuleHost& host, QWidget* parent) const override
  {
    return new RangeMapPanel(static_cast<RangeMapLogic&>(logic), host, parent);
  }
  std::vector<ModuleCommand> commands() const override { return rangeMapCommands(); }
};

} // namespace
} // namespace caps

CAPS_DECLARE_MODULE(caps::RangeMapModule)
