// The Report module plugin: the plan report (issue 7), `caps report`.

#include "modules/core/Module.h"
#include "modules/report/ReportCommands.h"

namespace caps {
namespace {

class ReportLogic : public ModuleLogic
{
public:
  using ModuleLogic::ModuleLogic;
};

class ReportModule : public Module
{
public:
  std::string name() const override { return "report"; }
  std::string title() const override { return "Report"; }
  std::string help() const override
  {
    return "Documents the plan (thesis §2.1, §3.3.3): a printed or PDF report with the procedure, the "
           "incision on the patient's face, measurements, the predicted result and its stresses, the tissue "
           "thickness, the storyboard of snapshots and the model's assumptions.";
  }
  std::vector<ModuleCommand> commands() const override { return reportCommands(); }
  std::unique_ptr<ModuleLogic> createLogic(Scene& scene) const override { return std::make_unique<ReportLogic>(scene); }
};

} // namespace
} // namespace caps

CAPS_DECLARE_MODULE(caps::ReportModule)
