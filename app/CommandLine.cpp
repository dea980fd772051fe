#include "app/CommandLine.h"

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "app/ModuleManager.h"
#include "app/Paths.h"
#include "app/Session.h"
#include "scene/SceneBundle.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

const char* kDemoUsage = "usage: caps demo [--out DIR]\n"
                         "\n"
                         "Runs the CAPS pipeline on the embedded sample head CT and writes its results\n"
                         "into DIR (default out/demo): info.txt (what was read), axial.png, coronal.png,\n"
                         "sagittal.png (middle slices, soft-tissue window); the skin and bone\n"
                         "label map (labels.nrrd, as `caps segment`; its surfaces are in the scene); the\n"
                         "range and thickness maps (skin-range, bone-range, thickness, thickness-normal\n"
                         ".nrrd, and the thickness review pictures skin-range.png, thickness.png,\n"
                         "thickness-normal.png, as `caps rangemap`); a Z-plasty on the left cheek and an\n"
                         "elliptical excision on the forehead, predicted (z-plasty/ and elliptical-excision/,\n"
                         "as `caps plan`); sample.caps (the scene, which `caps` opens and ParaView or\n"
                         "3D Slicer can read file by file); and plan-report.pdf, the printed plan of both\n"
                         "(as `caps report`).\n";

// Seconds since @a start, for the demo's step times.
double secondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Runs a module command on the session's logic.
int runModuleCommand(Session& session, const std::string& name, const std::vector<std::string>& args, std::ostream& out,
                     std::ostream& err)
{
  auto [module, command] = session.modules().findCommand(name);
  if (!command)
  {
    err << "caps: the command '" << name << "' is not available: its module did not load (see caps --list-modules).\n";
    return 1;
  }
  return command->run(session.logic(*module), args, out, err);
}

} // namespace

std::string usage(const ModuleManager& modules)
{
  std::ostringstream out;
  out << "CAPS - Computer-Aided Plastic Surgery workstation\n"
         "\n"
         "usage: caps                       open the workstation\n"
         "       caps PATH [--screenshot PNG]\n"
         "                                  open the workstation on a DICOM folder, an image\n"
         "                                  file or a scene bundle (NAME.caps); with\n"
         "                                  --screenshot, save the window once loaded and quit\n"
         "       caps COMMAND [ARGS...]     run a command without a window\n"
         "       caps COMMAND --help        help on a command\n"
         "       caps --list-modules        list the modules found, and why any failed\n"
         "       caps --version\n"
         "\n"
         "Commands:\n"
         "  demo      run the pipeline on the embedded sample CT (writes out/demo/)\n";
  for (const auto& loaded : modules.modules())
    for (const auto& command : loaded.module->commands())
    {
      std::string name = command.name;
      name.resize(std::max<size_t>(name.size(), 9), ' ');
      out << "  " << name << " " << command.summary << "  [" << loaded.module->name() << "]\n";
    }
  return out.str();
}

int runDemo(const std::vector<std::string>& args, ModuleManager& modules, std::ostream& out, std::ostream& err)
{
  fs::path folder = "out/demo";
  for (size_t i = 0; i < args.size(); ++i)
  {
    if (args[i] == "--help" || args[i] == "-h")
    {
      out << kDemoUsage;
      return 0;
    }
    if (args[i] == "--out" && i + 1 < args.size())
      folder = args[++i];
    else
    {
      err << "caps demo: unexpected argument '" << args[i] << "'\n" << kDemoUsage;
      return 2;
    }
  }
  const fs::path sample = sampleCtPath();
  std::error_code ec;
  if (!fs::is_directory(sample, ec))
  {
    err << "caps demo: the sample CT is missing at " << sample.string()
        << ". Set CAPS_DATA_DIR to the data folder of the CAPS sources.\n";
    return 1;
  }
  fs::create_directories(folder, ec);
  if (ec)
  {
    err << "caps demo: cannot create " << folder.string() << ": " << ec.message() << "\n";
    return 1;
  }

  Session session(modules);
  out << "CAPS demo on the sample CT " << sample.string() << "\n"
      << "Head and neck CT from the Weasis demo archive (N. Roduit), CC BY 4.0\n\n";

  auto start = std::chrono::steady_clock::now();
  auto stepDone = [&](const char* step) {
    out << std::fixed << std::setprecision(1) << "[" << step << ": " << secondsSince(start) << " s]\n\n";
    out.unsetf(std::ios::floatfield);
    start = std::chrono::steady_clock::now();
  };

  // 1. Read and describe the CT.
  std::ostringstream info;
  if (int code = runModuleCommand(session, "info", {sample.string()}, info, err))
    return code;
  std::ofstream(folder / "info.txt") << info.str();
  out << info.str();
  stepDone("read");

  // 2. The middle slices as pictures.
  if (int code = runModuleCommand(session, "slices", {sample.string(), "--out", folder.string()}, out, err))
    return code;
  stepDone("slices");

  // 3. Skin and bone (the CT read in step 1 is reused: same session).
  if (int code = runModuleCommand(session, "segment", {sample.string(), "--out", folder.string(), "--surfaces", "none"},
                                  out, err))
    return code;
  stepDone("segment");

  // 4. Range maps and the thickness review pictures (on step 3's label map).
  if (int code = runModuleCommand(session, "rangemap", {sample.string(), "--out", folder.string()}, out, err))
    return code;
  stepDone("rangemap");

  // 5. Two plans on the sample's face, predicted (as `caps plan`, on step 4's
  // range maps): a Z-plasty on the left cheek and an elliptical excision on
  // the forehead.
  const std::pair<const char*, std::vector<std::string>> plans[] = {{"z-plasty", {"--at", "-40,-47"}},
                                                                    {"elliptical-excision", {"--at", "-90,25"}}};
  for (const auto& [procedure, where] : plans)
  {
    std::vector<std::string> planArgs{sample.string(), "--procedure", procedure, "--out",
                                      (folder / procedure).string()};
    planArgs.insert(planArgs.end(), where.begin(), where.end());
    if (int code = runModuleCommand(session, "plan", planArgs, out, err))
      return code;
  }
  stepDone("plans");

  // 6. The scene, as the workstation would save it.
  const fs::path bundle = folder / "sample.caps";
  try
  {
    saveSceneBundle(session.scene(), bundle);
  }
  catch (const std::exception& e)
  {
    err << "caps demo: " << e.what() << "\n";
    return 1;
  }
  out << "wrote " << bundle.string() << "\n";
  stepDone("save scene");

  // 7. Two snapshots for the storyboard, as the workstation's snapshot
  // button takes them, then the plan report of the saved scene, as a
  // surgeon would print it.
  for (const char* view : {"before", "after"})
    if (int code =
          runModuleCommand(session, "snapshot", {bundle.string(), "--plan", "Z-plasty 1", "--view", view}, out, err))
      return code;
  if (int code = runModuleCommand(session, "report", {bundle.string(), "--pdf", (folder / "plan-report.pdf").string()},
                                  out, err))
    return code;
  stepDone("report");
  out << "Demo finished: results in " << folder.string() << "\n";
  return 0;
}

std::optional<int> runCommandLine(const std::vector<std::string>& args, ModuleManager& modules, std::ostream& out,
                                  std::ostream& err)
{
  if (args.empty())
    return std::nullopt;
  const std::string& first = args.front();
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  if (first == "--help" || first == "-h" || first == "help")
  {
    out << usage(modules);
    return 0;
  }
  if (first == "--version")
  {
    out << "caps " << CAPS_VERSION << "\n";
    return 0;
  }
  if (first == "--list-modules")
  {
    out << modules.report();
    return modules.modules().empty() ? 1 : 0;
  }
  if (first == "demo")
    return runDemo(rest, modules, out, err);
  if (modules.findCommand(first).second)
  {
    Session session(modules);
    return runModuleCommand(session, first, rest, out, err);
  }
  std::error_code ec;
  if (first[0] == '-' || fs::exists(first, ec))
    return std::nullopt; // workstation options or a path to open
  err << "caps: unknown command '" << first << "'. Run caps --help for the list";
  if (modules.modules().empty())
    err << " (no module loaded: see caps --list-modules)";
  err << ".\n";
  return 2;
}

} // namespace caps
