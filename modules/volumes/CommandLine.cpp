#include "modules/volumes/CommandLine.h"

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <memory>

#include <vtkPolyData.h>
#include <vtkSTLWriter.h>
#include <vtkSmartPointer.h>

#include "modules/volumes/VolumesLogic.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"

namespace fs = std::filesystem;

namespace caps {
namespace cli {

std::optional<std::string> parseSeries(const std::string& value, seg::CtReadOptions& options)
{
  if (value.empty())
    return "--series needs a number or a series UID";
  if (value.find_first_not_of("0123456789") == std::string::npos)
  {
    const int n = std::atoi(value.c_str());
    if (n < 1)
      return "--series counts from 1";
    options.seriesIndex = n - 1;
  }
  else
    options.seriesUid = value;
  return std::nullopt;
}

std::optional<std::string> parseInputOutputCommand(const std::vector<std::string>& args, std::filesystem::path& input,
                                                   std::filesystem::path& out, bool& help, const CommandOption& option,
                                                   const char* inputName)
{
  for (std::size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h")
      help = true;
    else if (a == "--out")
    {
      if (i + 1 >= args.size())
        return "--out needs a folder";
      out = args[++i];
    }
    else if (!a.empty() && a[0] == '-')
    {
      if (auto problem = option(a, args, i))
        return problem;
    }
    else if (input.empty())
      input = a;
    else
      return std::string("one ") + inputName + " only (got '" + input.string() + "' and '" + a + "')";
  }
  if (help)
    return std::nullopt;
  if (input.empty())
    return std::string(inputName) + " missing";
  if (out.empty())
    return "--out DIR missing: where should the results go?";
  return std::nullopt;
}

std::optional<std::string> parseCtCommand(const std::vector<std::string>& args, CtCommandArgs& parsed,
                                          const CommandOption& option)
{
  return parseInputOutputCommand(
    args, parsed.ct, parsed.out, parsed.help,
    [&](const std::string& a, const std::vector<std::string>& all, std::size_t& i) -> std::optional<std::string> {
      if (a != "--series")
        return option(a, all, i);
      if (i + 1 >= all.size())
        return "--series needs a number or a series UID";
      return parseSeries(all[++i], parsed.read);
    },
    "CT");
}

void makeOutputFolder(const fs::path& folder)
{
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec || !fs::is_directory(folder))
    throw std::runtime_error("Cannot create the output folder " + folder.string() + ": " +
                             (ec ? ec.message() : "a file of that name exists"));
}

bool parseNumber(const std::string& text, double& value)
{
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return !text.empty() && end && *end == '\0' && std::isfinite(value);
}

TaskProgress consoleProgress(std::ostream& err)
{
  struct State
  {
    std::string step;
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  };
  auto state = std::make_shared<State>();
  return [&err, state](double fraction, const std::string& step) {
    if (step != state->step)
    {
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - state->start).count();
      err << "  [" << std::setw(3) << static_cast<int>(std::lround(100 * fraction)) << "%] " << std::fixed
          << std::setprecision(1) << std::setw(5) << t << " s  " << step << "\n";
      err.unsetf(std::ios::floatfield);
      state->step = step;
    }
    return true;
  };
}

VolumeNode* loadCt(ModuleLogic& logic, const fs::path& path, const seg::CtReadOptions& options, std::ostream& err)
{
  // The Volumes module's reading, on the same scene: a CT read before (by
  // `caps info` in the demo, say) is reused.
  VolumesLogic volumes(logic.scene());
  std::vector<std::string> warnings;
  VolumeNode* volume = volumes.load(path, options, warnings);
  for (const auto& w : warnings)
    err << "warning: " << w << "\n";
  return volume;
}

void writeStl(vtkPolyData* surface, const fs::path& file)
{
  auto writer = vtkSmartPointer<vtkSTLWriter>::New();
  writer->SetInputData(surface);
  writer->SetFileName(file.c_str());
  writer->SetFileTypeToBinary();
  writer->SetHeader("CAPS surface, mm, patient LPS");
  if (!writer->Write())
    throw std::runtime_error("Could not write " + file.string() + ": is the folder writable and the disk not full?");
}

} // namespace cli

} // namespace caps
