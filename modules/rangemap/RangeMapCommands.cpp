#include "modules/rangemap/RangeMapCommands.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <optional>

#include "modules/rangemap/RangeMapLogic.h"
#include "modules/rangemap/RangeMapPreview.h"
#include "modules/volumes/CommandLine.h"
#include "scene/NrrdIO.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"
#include "segmentation/LandmarkPlacement.h"
#include "segmentation/Landmarks.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

const char* kRangeMapUsage = "usage: caps rangemap CT --out DIR [--size NTHETAxNZ] [--smooth] [--series N|UID]\n"
                             "                      [--axis PX,PY,PZ,DX,DY,DZ] [--landmarks FILE.csv]\n"
                             "\n"
                             "Unwraps the skin and the bone of a head CT into cylindrical range maps r(theta, z)\n"
                             "around an axis fitted to the head (segmenting the CT first, with the default\n"
                             "thresholds), and the soft-tissue thickness, and writes into DIR:\n"
                             "  skin-range.nrrd, bone-range.nrrd   r of the skin and the bone (mm; NaN: none)\n"
                             "  thickness.nrrd                     r_skin - r_bone, along the ray from the axis\n"
                             "  thickness-normal.nrrd              thickness along the inward skin normal\n"
                             "  skin-range.png, thickness.png,     previews: the face in the middle, z up,\n"
                             "  thickness-normal.png               a colour bar in mm\n"
                             "  landmarks.csv                      facial landmarks placed from the maps, with\n"
                             "                                     the thickness under each (check and correct)\n"
                             "The NRRD files are 2D float images, theta fastest (rows of the map: theta from\n"
                             "-180 deg, -90 deg at the face; columns: z from the bottom of the scan up).\n"
                             "Prints the axis and the thickness statistics (mm).\n"
                             "\n"
                             "  --size NTHETAxNZ   samples around the head and along the axis (default 512x256)\n"
                             "  --smooth           3x3 box smoothing of the skin and bone maps (thesis eq. 4.2)\n"
                             "  --series N|UID     in a folder with several series, the one to use\n"
                             "  --axis PX,PY,PZ,DX,DY,DZ\n"
                             "                     set the head axis yourself: through the point P along the\n"
                             "                     direction D (LPS mm, as the workstation shows them) instead\n"
                             "                     of fitting it to the head\n"
                             "  --landmarks FILE   your landmarks instead of the automatic ones: a CSV like\n"
                             "                     landmarks.csv; a row's x,y,z (LPS mm) places it when given,\n"
                             "                     else its theta_deg,z_mm\n"
                             "\n"
                             "Exit status: 0 when written, 1 when the CT cannot be read or processed or the\n"
                             "files cannot be written, 2 on wrong usage.\n";

struct RangeMapArgs : cli::CtCommandArgs
{
  RangeMapLogic::Parameters parameters;
  fs::path landmarks; ///< the user's landmarks; empty: placed automatically
};

std::optional<std::string> parse(const std::vector<std::string>& argv, RangeMapArgs& parsed)
{
  return cli::parseCtCommand(argv, parsed,
                             [&parsed](const std::string& a, const std::vector<std::string>& args,
                                       std::size_t& i) -> std::optional<std::string> {
                               if (a == "--size")
                               {
                                 int nTheta = 0, nZ = 0;
                                 char tail = 0;
                                 if (i + 1 >= args.size() ||
                                     std::sscanf(args[++i].c_str(), "%dx%d%c", &nTheta, &nZ, &tail) != 2 ||
                                     nTheta < 8 || nZ < 4 || nTheta > 8192 || nZ > 8192)
                                   return "--size needs NTHETAxNZ, e.g. 512x256 (at least 8x4, at most 8192x8192)";
                                 parsed.parameters.nTheta = nTheta;
                                 parsed.parameters.nZ = nZ;
                               }
                               else if (a == "--smooth")
                                 parsed.parameters.smooth = true;
                               else if (a == "--axis")
                               {
                                 RangeMapLogic::Parameters::Axis axis;
                                 if (i + 1 >= args.size() || !parseAxis(args[++i], axis.point, axis.direction))
                                   return "--axis needs a point and a non-zero direction, PX,PY,PZ,DX,DY,DZ in LPS mm "
                                          "(e.g. 0,-200,750,0,0,1)";
                                 parsed.parameters.axis = axis;
                               }
                               else if (a == "--landmarks")
                               {
                                 if (i + 1 >= args.size())
                                   return "--landmarks needs a CSV file (as landmarks.csv)";
                                 parsed.landmarks = args[++i];
                               }
                               else
                                 return "unknown option " + a;
                               return std::nullopt;
                             });
}

void printStatistics(std::ostream& out, const char* what, const seg::ThicknessStatistics& s, std::size_t samples)
{
  out << "  " << what << std::fixed << std::setprecision(1) << std::setw(7) << s.min << std::setw(8) << s.median
      << std::setw(8) << s.mean << std::setw(8) << s.p95 << "   (" << s.count << " of " << samples << " samples)\n";
  out.unsetf(std::ios::floatfield);
}

/// The user's landmarks from a CSV: placed by their world point when the row
/// has one (it stays right whatever the axis), else by (theta, z).
std::vector<seg::Landmark> readUserLandmarks(const fs::path& file, const seg::CylindricalFrame& frame)
{
  std::vector<seg::Landmark> landmarks;
  for (const auto& row : seg::readLandmarkCsv(file))
  {
    seg::Landmark landmark = row.landmark;
    if (row.position.allFinite())
    {
      const seg::CylindricalPoint c = frame.toCylindrical(row.position);
      landmark.theta = c.theta;
      landmark.z = c.z;
    }
    landmarks.push_back(landmark);
  }
  if (landmarks.empty())
    throw std::runtime_error(file.string() + " lists no landmarks: add one row per landmark "
                                             "(name,theta_deg,z_mm,x,y,z,...) as in landmarks.csv.");
  return landmarks;
}

// The standard facial landmarks placed automatically from the maps (or the
// user's, from --landmarks), with the thickness under each: a first table for
// the thickness review, to be corrected by the surgeon (the CSV can be edited
// and read back).
void writeLandmarkTable(const RangeMapLogic& logic, const VolumeNode& volume, const RangeMapOutput& maps,
                        const fs::path& userLandmarks, const fs::path& file, std::ostream& out, std::ostream& err)
{
  std::vector<seg::Landmark> landmarks;
  if (!userLandmarks.empty())
    landmarks = readUserLandmarks(userLandmarks, maps.skin.frame());
  else
  {
    seg::LandmarkPlacement placement;
    try
    {
      placement = seg::placeLandmarks(maps.skin, maps.bone);
    }
    catch (const std::exception& e)
    {
      err << "warning: no landmarks placed: " << e.what() << "\n";
      return;
    }
    for (const auto& warning : placement.warnings)
      err << "warning: " << warning << "\n";
    landmarks = std::move(placement.landmarks);
  }
  auto rows = seg::landmarkThickness(landmarks, maps.skin, maps.thickness, maps.thicknessNormal);
  logic.measureLandmarkDepths(volume, rows);
  if (userLandmarks.empty())
    out << "Thickness at the landmarks placed automatically (check them; mm):\n";
  else
    out << "Thickness at the landmarks of " << userLandmarks.string() << " (mm):\n";
  out << "                                      range maps      in the CT\n"
         "  landmark            theta    z     radial  normal  normal nearest   depth (convention)\n";
  for (const auto& row : rows)
  {
    std::string name = row.landmark.name;
    name.resize(std::max<std::size_t>(name.size(), 18), ' ');
    out << "  " << name << std::fixed << std::setprecision(0) << std::setw(6) << row.landmark.theta * 180.0 / M_PI
        << std::setprecision(1) << std::setw(7) << row.landmark.z << std::setw(8) << row.radial << std::setw(8)
        << row.normal << std::setw(8) << row.ctSkinNormal << std::setw(8) << row.ctNearestBone << std::setw(8)
        << row.depth << "   " << row.convention << (row.note.empty() ? "" : "; " + row.note) << "\n";
  }
  out.unsetf(std::ios::floatfield);
  seg::writeLandmarkCsv(file, rows);
  out << "wrote " << file.string() << "\n";
}

int runRangeMap(ModuleLogic& moduleLogic, const std::vector<std::string>& argv, std::ostream& out, std::ostream& err)
{
  auto& logic = static_cast<RangeMapLogic&>(moduleLogic);
  return cli::runCommand<RangeMapArgs>("rangemap", kRangeMapUsage, argv, out, err, parse, [&](RangeMapArgs& args) {
    if (!args.landmarks.empty())
      seg::readLandmarkCsv(args.landmarks); // a bad file stops us before the long part
    cli::makeOutputFolder(args.out);
    const auto start = std::chrono::steady_clock::now();
    args.read.progress = cli::consoleProgress(err);
    VolumeNode* volume = cli::loadCt(logic, args.ct, args.read, err);
    RangeMapOutput maps;
    const RangeMapResult ids = logic.run(*volume, args.parameters, cli::consoleProgress(err), &maps);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    const seg::CylindricalFrame& frame = maps.skin.frame();
    out << "Range maps of '" << volume->name() << "' (" << frame.nTheta() << " x " << frame.nZ()
        << (args.parameters.smooth ? ", smoothed" : "") << ") in " << std::fixed << std::setprecision(1) << seconds
        << " s" << (ids.segmented ? ", after segmenting it with the default thresholds" : "") << "\n";
    out.unsetf(std::ios::floatfield);
    out << RangeMapLogic::describeAxis(maps.axis);
    const std::size_t samples = maps.skin.values().size();
    out << "Skin found at " << maps.skin.validCount() << " of " << samples << " samples, bone at "
        << maps.bone.validCount() << " (" << maps.skinFromMaskEdge << " and " << maps.boneFromMaskEdge
        << " from the mask edge)\n";
    out << "Soft-tissue thickness (mm):     min  median    mean     p95\n";
    printStatistics(out, "radial r_skin - r_bone", maps.radialStatistics, samples);
    printStatistics(out, "along the skin normal  ", maps.normalStatistics, samples);
    // Metal spoils the slices it lies in: say so before anything is read off them.
    const auto& metal = logic.metalOf(*volume);
    for (std::size_t k = 0; k < std::min<std::size_t>(metal.size(), 5); ++k)
      err << "warning: " << seg::describe(metal[k], volume->image())
          << "; the skin, bone and thickness there are not to be trusted\n";
    if (metal.size() > 5)
      err << "warning: " << metal.size() - 5 << " more pieces of metal\n";

    struct Output
    {
      const std::string& id;
      const char* nrrd;
      const char* png;
    };
    const Output files[] = {{ids.skinId, "skin-range.nrrd", "skin-range.png"},
                            {ids.boneId, "bone-range.nrrd", nullptr},
                            {ids.thicknessId, "thickness.nrrd", "thickness.png"},
                            {ids.thicknessNormalId, "thickness-normal.nrrd", "thickness-normal.png"}};
    for (const Output& file : files)
    {
      const auto* node = logic.scene().nodeAs<RangeMapNode>(file.id);
      NrrdIO::writeMatrix(node->values(), args.out / file.nrrd);
      out << "wrote " << (args.out / file.nrrd).string() << "\n";
      if (!file.png)
        continue;
      PreviewStyle style;
      if (node->role() == "skin")
        style = rangeStyle(node->values(), "Skin range r(theta, z): distance from the head axis");
      else
      {
        // One fixed scale for thickness, so pictures of two patients compare;
        // the face lies within it (thicker neck and scalp regions saturate).
        style.low = 0.0;
        style.high = 30.0;
        style.title = node->role() == "thickness" ? "Soft-tissue thickness, radial (r_skin - r_bone)"
                                                  : "Soft-tissue thickness along the inward skin normal";
      }
      writeRangeMapPreview(node->values(), node->zMin(), node->zMax(), style, args.out / file.png);
      out << "wrote " << (args.out / file.png).string() << "\n";
    }
    writeLandmarkTable(logic, *volume, maps, args.landmarks, args.out / "landmarks.csv", out, err);
    return 0;
  });
}

} // namespace

std::vector<ModuleCommand> rangeMapCommands()
{
  return {{"rangemap", "skin, bone and thickness range maps of a CT (NRRD) with PNG previews in mm", kRangeMapUsage,
           runRangeMap},
          scanCommand()};
}

} // namespace caps
