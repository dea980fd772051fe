#include "app/ModuleManager.h"

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <sstream>

namespace fs = std::filesystem;

namespace caps {

namespace {

/// Why the plugin behind @a handle was built from other sources than this
/// caps, or "" when it was built with it. Its shared libraries are this
/// build's; a plugin from another build may disagree with them about the
/// layout of every class they exchange (a heap corruption, not an error).
std::string buildStampMismatch(void* handle)
{
  using StampFn = const char* (*)();
  auto stamp = reinterpret_cast<StampFn>(dlsym(handle, "caps_module_build_stamp"));
  const std::string ours = buildStamp();
  const std::string rebuild = ": rebuild it with this caps (cmake --build on the build folder) or remove it from the "
                              "module folder";
  if (!stamp)
    return "carries no build stamp (built before caps " + ours + ")" + rebuild;
  const std::string theirs = stamp() ? stamp() : "";
  if (theirs != ours)
    return "was built from other sources (build " + theirs + ", this caps is " + ours + ")" + rebuild;
  return {};
}

} // namespace

ModuleManager::~ModuleManager()
{
  // Objects made by a plugin's code must go before its code is unloaded.
  commands_.clear();
  loaded_.clear();
  for (auto it = handles_.rbegin(); it != handles_.rend(); ++it)
    dlclose(*it);
}

std::vector<fs::path> ModuleManager::searchPath(const fs::path& executable)
{
  std::vector<fs::path> folders;
  if (const char* env = std::getenv("CAPS_MODULE_PATH"))
  {
    std::stringstream list(env);
    std::string item;
    while (std::getline(list, item, ':'))
      if (!item.empty())
        folders.emplace_back(item);
  }
  std::error_code ec;
  fs::path exe = fs::weakly_canonical(executable, ec);
  if (exe.empty())
    exe = executable;
  folders.push_back(exe.parent_path().parent_path() / "lib" / "caps" / "modules");
  return folders;
}

void ModuleManager::loadFolder(const fs::path& folder)
{
  searched_.push_back(folder);
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    return;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder, ec))
    if (entry.path().extension() == ".so")
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());

  for (const auto& file : files)
  {
    // Never unmapped (RTLD_NODELETE): a plugin's libraries may register
    // global objects elsewhere (VTK's rendering factories in VTK's core
    // registry) that are destroyed at exit, after the manager is gone.
    void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (!handle)
    {
      const char* why = dlerror();
      failed_.push_back({file, std::string("cannot be loaded: ") + (why ? why : "unknown error")});
      continue;
    }
    using VersionFn = int (*)();
    using CreateFn = Module* (*)();
    auto version = reinterpret_cast<VersionFn>(dlsym(handle, "caps_module_api_version"));
    auto create = reinterpret_cast<CreateFn>(dlsym(handle, "caps_create_module"));
    if (!version || !create)
    {
      failed_.push_back({file, "is not a CAPS module (no caps_module_api_version or "
                               "caps_create_module; declare it with CAPS_DECLARE_MODULE)"});
      dlclose(handle);
      continue;
    }
    if (version() != kModuleApiVersion)
    {
      failed_.push_back({file, "was built for module API " + std::to_string(version()) + ", this caps uses " +
                                 std::to_string(kModuleApiVersion) + ": rebuild the module"});
      dlclose(handle);
      continue;
    }
    if (const std::string why = buildStampMismatch(handle); !why.empty())
    {
      failed_.push_back({file, why});
      dlclose(handle);
      continue;
    }
    std::unique_ptr<Module> module;
    try
    {
      module.reset(create());
    }
    catch (const std::exception& e)
    {
      failed_.push_back({file, std::string("failed to start: ") + e.what()});
      dlclose(handle);
      continue;
    }
    if (!module)
    {
      failed_.push_back({file, "failed to start: caps_create_module returned nothing"});
      dlclose(handle);
      continue;
    }
    if (const Module* other = find(module->name()))
    {
      auto it = std::find_if(loaded_.begin(), loaded_.end(), [&](const Loaded& l) { return l.module.get() == other; });
      failed_.push_back({file, "repeats module '" + module->name() + "' already loaded from " + it->file.string()});
      module.reset();
      dlclose(handle);
      continue;
    }
    handles_.push_back(handle);
    for (auto& command : module->commands())
    {
      if (findCommand(command.name).first)
        failed_.push_back({file, "command '" + command.name + "' of module '" + module->name() +
                                   "' is already provided by another module; ignored"});
      else
        commands_.emplace_back(module.get(), std::move(command));
    }
    loaded_.push_back({file, std::move(module)});
  }
}

const Module* ModuleManager::find(const std::string& name) const
{
  for (const auto& l : loaded_)
    if (l.module->name() == name)
      return l.module.get();
  return nullptr;
}

std::pair<const Module*, const ModuleCommand*> ModuleManager::findCommand(const std::string& name) const
{
  for (const auto& [module, command] : commands_)
    if (command.name == name)
      return {module, &command};
  return {nullptr, nullptr};
}

std::string ModuleManager::report() const
{
  std::ostringstream out;
  out << "Module folders searched:\n";
  for (const auto& folder : searched_)
    out << "  " << folder.string() << "\n";
  out << "Loaded modules (" << loaded_.size() << "):\n";
  for (const auto& l : loaded_)
  {
    out << "  " << l.module->name() << "  \"" << l.module->title() << "\"  from " << l.file.string() << "\n";
    std::string commands;
    for (const auto& [module, command] : commands_)
      if (module == l.module.get())
        commands += (commands.empty() ? "" : ", ") + command.name;
    if (!commands.empty())
      out << "      commands: " << commands << "\n";
  }
  if (!failed_.empty())
  {
    out << "Not loaded (" << failed_.size() << "):\n";
    for (const auto& f : failed_)
      out << "  " << f.file.string() << " " << f.reason << "\n";
  }
  return out.str();
}

} // namespace caps
