#include "modules/volumes/VolumesCommands.h"

#include <cstdlib>
#include <iostream>
#include <optional>

#include "modules/volumes/CommandLine.h"
#include "modules/volumes/VolumesLogic.h"
#include "scene/VolumeNode.h"
#include "segmentation/WindowLevel.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

const char* kInfoUsage = "usage: caps info PATH [--series N|UID] [--deidentify]\n"
                         "\n"
                         "Prints what CAPS reads from a CT: dimensions, spacing, origin, orientation,\n"
                         "HU range and the DICOM patient, study and series fields.\n"
                         "\n"
                         "  PATH          a DICOM folder (or one of its files), or a NIfTI (.nii, .nii.gz),\n"
                         "                NRRD (.nrrd, .nhdr) or MetaImage (.mha, .mhd) file\n"
                         "  --series N    in a folder with several series, load the N-th (as listed)\n"
                         "  --series UID  ... or the one with this series instance UID\n"
                         "                (a folder with several series and no --series lists them and stops)\n"
                         "  --deidentify  leave out the fields that identify the patient\n"
                         "\n"
                         "Exit status: 0 when read, 1 when the data cannot be read, 2 on wrong usage.\n";

const char* kSlicesUsage =
  "usage: caps slices PATH [--out DIR] [--preset NAME | --window W --level L] [--series N|UID]\n"
  "                   (a folder with several series gives its largest CT series)\n"
  "\n"
  "Writes the middle axial, coronal and sagittal slices of a CT as PNG pictures\n"
  "(radiological orientation, square pixels) into DIR (default: the current folder).\n"
  "Presets: 'Soft tissue' (default), 'Bone', 'Brain', 'Skin / air', 'Full range'.\n";

struct CommonArgs
{
  fs::path path;
  seg::CtReadOptions read;
  fs::path out = ".";
  double window = seg::kWindowPresets[0].window;
  double level = seg::kWindowPresets[0].level;
  bool help = false;
};

// Parses the arguments shared by the Volumes commands; returns an error text.
std::optional<std::string> parse(const std::vector<std::string>& args, bool withOutput, CommonArgs& parsed)
{
  for (size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    auto value = [&]() -> std::optional<std::string> {
      if (i + 1 >= args.size())
        return std::nullopt;
      return args[++i];
    };
    if (a == "--help" || a == "-h")
      parsed.help = true;
    else if (a == "--deidentify")
      parsed.read.deidentify = true;
    else if (a == "--series")
    {
      auto v = value();
      if (!v)
        return "--series needs a number or a series UID";
      if (auto problem = cli::parseSeries(*v, parsed.read))
        return problem;
    }
    else if (withOutput && a == "--out")
    {
      auto v = value();
      if (!v)
        return "--out needs a folder";
      parsed.out = *v;
    }
    else if (withOutput && (a == "--window" || a == "--level"))
    {
      auto v = value();
      char* end = nullptr;
      const double number = v ? std::strtod(v->c_str(), &end) : 0.0;
      if (!v || end == v->c_str() || *end)
        return a + " needs a number (HU)";
      (a == "--window" ? parsed.window : parsed.level) = number;
    }
    else if (withOutput && a == "--preset")
    {
      auto v = value();
      bool found = false;
      for (const auto& preset : seg::kWindowPresets)
        if (v && preset.name == *v)
        {
          parsed.window = preset.window;
          parsed.level = preset.level;
          found = true;
        }
      if (!found)
        return "unknown preset '" + v.value_or("") + "'";
    }
    else if (!a.empty() && a[0] == '-')
      return "unknown option " + a;
    else if (parsed.path.empty())
      parsed.path = a;
    else
      return "one PATH only (got '" + parsed.path.string() + "' and '" + a + "')";
  }
  if (!parsed.help && parsed.path.empty())
    return "PATH missing";
  return std::nullopt;
}

int runInfo(ModuleLogic& logic, const std::vector<std::string>& argv, std::ostream& out, std::ostream& err)
{
  const auto parseInfo = [](const std::vector<std::string>& a, CommonArgs& args) { return parse(a, false, args); };
  return cli::runCommand<CommonArgs>("info", kInfoUsage, argv, out, err, parseInfo, [&](CommonArgs& args) {
    // info describes one series: with several and none named, list them.
    args.read.requireSingleSeries = true;
    VolumeNode* volume = cli::loadCt(logic, args.path, args.read, err);
    out << VolumesLogic::describe(*volume);
    return 0;
  });
}

int runSlices(ModuleLogic& logic, const std::vector<std::string>& argv, std::ostream& out, std::ostream& err)
{
  const auto parseSlices = [](const std::vector<std::string>& a, CommonArgs& args) { return parse(a, true, args); };
  return cli::runCommand<CommonArgs>("slices", kSlicesUsage, argv, out, err, parseSlices, [&](CommonArgs& args) {
    VolumeNode* volume = cli::loadCt(logic, args.path, args.read, err);
    for (const auto& file : VolumesLogic::writeMiddleSlices(*volume, args.out, args.window, args.level))
      out << "wrote " << file.string() << "\n";
    return 0;
  });
}

} // namespace

std::vector<ModuleCommand> volumesCommands()
{
  return {
    {"info", "describe a CT: dimensions, spacing, orientation, HU range, DICOM fields", kInfoUsage, runInfo},
    {"slices", "write the middle axial, coronal and sagittal slices of a CT as PNG", kSlicesUsage, runSlices},
  };
}

} // namespace caps
