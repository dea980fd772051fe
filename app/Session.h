#pragma once
/// @file Session.h
/// @brief One scene and the logic of every loaded module bound to it: what
/// the workstation and a headless command both work on.

#include <map>
#include <memory>

#include "app/ModuleManager.h"
#include "scene/Scene.h"

namespace caps {

class Session
{
public:
  explicit Session(const ModuleManager& modules) : modules_(modules) {}
  ~Session() { logics_.clear(); } // logic refers to the scene: it goes first

  Scene& scene() { return scene_; }
  const ModuleManager& modules() const { return modules_; }

  /// The module's logic, made on first use.
  ModuleLogic& logic(const Module& module)
  {
    auto& slot = logics_[&module];
    if (!slot)
      slot = module.createLogic(scene_);
    return *slot;
  }

private:
  const ModuleManager& modules_;
  Scene scene_;
  std::map<const Module*, std::unique_ptr<ModuleLogic>> logics_;
};

} // namespace caps
