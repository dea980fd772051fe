// The Expression module plugin: metadata and factories only.

#include "modules/core/Module.h"
#include "modules/expression/ExpressionCommands.h"
#include "modules/expression/ExpressionLogic.h"
#include "modules/expression/ExpressionPanel.h"

namespace caps {
namespace {

class ExpressionModule : public Module
{
public:
  std::string name() const override { return "expression"; }
  std::string title() const override { return "Expressions"; }
  std::string help() const override
  {
    return "Facial expressions on the unoperated face (thesis 5.3): builds the whole face model from the range "
           "maps and the facial landmarks, solves it once per muscle, and then moves the skin in real time "
           "with a slider per expression (smile, frown, pucker, ...) and per muscle. Expressions are saved in "
           "the scene and play as an animation.";
  }
  std::unique_ptr<ModuleLogic> createLogic(Scene& scene) const override
  {
    return std::make_unique<ExpressionLogic>(scene);
  }
  QWidget* createPanel(ModuleLogic& logic, ModuleHost& host, QWidget* parent) const override
  {
    return new ExpressionPanel(static_cast<ExpressionLogic&>(logic), host, parent);
  }
  std::vector<ModuleCommand> commands() const override { return expressionCommands(); }
};

} // namespace
} // namespace caps

CAPS_DECLARE_MODULE(caps::ExpressionModule)
