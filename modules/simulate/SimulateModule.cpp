// The Simulate module plugin: metadata and factories only.

#include "modules/core/Module.h"
#include "modules/simulate/SimulateCommands.h"
#include "modules/simulate/SimulateLogic.h"
#include "modules/simulate/SimulatePanel.h"

namespace caps {
namespace {

class SimulateModule : public Module
{
public:
  std::string name() const override { return "simulate"; }
  std::string title() const override { return "Simulate"; }
  std::string help() const override
  {
    return "Linear static finite element analysis with 20-node elements: solves a model and "
           "reports displacements and stresses. On the command line: caps fem MODEL.inp.";
  }
  std::unique_ptr<ModuleLogic> createLogic(Scene& scene) const override
  {
    return std::make_unique<SimulateLogic>(scene);
  }
  QWidget* createPanel(ModuleLogic& logic, ModuleHost& host, QWidget* parent) const override
  {
    return new SimulatePanel(static_cast<SimulateLogic&>(logic), host, parent);
  }
  std::vector<ModuleCommand> commands() const override { return simulateCommands(); }
};

} // namespace
} // namespace caps

CAPS_DECLARE_MODULE(caps::SimulateModule)
