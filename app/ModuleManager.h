#pragma once
/// @file ModuleManager.h
/// @brief Finds and loads the module plugins at start; knows no module internals.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "modules/core/Module.h"

namespace caps {

class ModuleManager
{
public:
  struct Loaded
  {
    std::filesystem::path file;
    std::unique_ptr<Module> module;
  };
  struct Failed
  {
    std::filesystem::path file;
    std::string reason;
  };

  ModuleManager() = default;
  ~ModuleManager();
  ModuleManager(const ModuleManager&) = delete;
  ModuleManager& operator=(const ModuleManager&) = delete;

  /// The plugin folders: $CAPS_MODULE_PATH (':'-separated) first, then
  /// lib/caps/modules beside the folder of @a executable.
  static std::vector<std::filesystem::path> searchPath(const std::filesystem::path& executable);

  /// Loads every `*.so` in @a folder (sorted by name). A file that is not a
  /// CAPS module, was built for another module API, or repeats a loaded
  /// module's name goes to failures() with the reason, never stops the app.
  void loadFolder(const std::filesystem::path& folder);

  const std::vector<Loaded>& modules() const { return loaded_; }
  const std::vector<Failed>& failures() const { return failed_; }
  const std::vector<std::filesystem::path>& searchedFolders() const { return searched_; }

  const Module* find(const std::string& name) const;
  /// The command @a name and the module that owns it, or {nullptr, nullptr}.
  std::pair<const Module*, const ModuleCommand*> findCommand(const std::string& name) const;

  /// The `caps --list-modules` report.
  std::string report() const;

private:
  std::vector<Loaded> loaded_;
  std::vector<Failed> failed_;
  std::vector<std::filesystem::path> searched_;
  std::vector<void*> handles_;
  // Commands are copied out of the modules once so findCommand can hand out
  // stable pointers.
  std::vector<std::pair<const Module*, ModuleCommand>> commands_;
};

} // namespace caps
