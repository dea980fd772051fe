// A small test plugin: a module with a command that counts the scene's nodes.

#include <ostream>

#include "modules/core/Module.h"
#include "scene/Scene.h"

namespace {

class ProbeModule : public caps::Module
{
public:
  std::string name() const override { return "probe"; }
  std::string title() const override { return "Probe"; }
  std::string help() const override { return "Test module."; }
  std::unique_ptr<caps::ModuleLogic> createLogic(caps::Scene& scene) const override
  {
    return std::make_unique<caps::ModuleLogic>(scene);
  }
  std::vector<caps::ModuleCommand> commands() const override
  {
    return {{"probe", "count nodes", "usage: caps probe",
             [](caps::ModuleLogic& logic, const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
               out << "nodes=" << logic.scene().size() << " args=" << args.size();
               return 7;
             }}};
  }
};

} // namespace

CAPS_DECLARE_MODULE(ProbeModule)
