// The Results module plugin: metadata and factories only.

#include "modules/core/Module.h"
#include "modules/results/ResultsLogic.h"
#include "modules/results/ResultsPanel.h"

namespace caps {
namespace {

class ResultsModule : public Module
{
public:
  std::string name() const override { return "results"; }
  std::string title() const override { return "Results"; }
  std::string help() const override
  {
    return "Shows a predicted plan: before and after the operation with a deformation slider, "
           "coloured by stress, displacement or strain with a colour bar, the closure force and "
           "wound stress, a plot along the incision, and snapshots (Ctrl+T) for the report's "
           "storyboard.";
  }
  std::unique_ptr<ModuleLogic> createLogic(Scene& scene) const override
  {
    return std::make_unique<ResultsLogic>(scene);
  }
  QWidget* createPanel(ModuleLogic& logic, ModuleHost& host, QWidget* parent) const override
  {
    return new ResultsPanel(static_cast<ResultsLogic&>(logic), host, parent);
  }
};

} // namespace
} // namespace caps

CAPS_DECLARE_MODULE(caps::ResultsModule)
