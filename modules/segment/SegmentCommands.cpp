#include "modules/segment/SegmentCommands.h"

#include "modules/volumes/CommandLine.h"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>

#include <vtkCellArray.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSTLWriter.h>
#include <vtkSmartPointer.h>

#include "modules/segment/SegmentLogic.h"
#include "segmentation/SurfaceExtraction.h"
#include "modules/volumes/VolumesLogic.h"
#include "scene/LabelMapNode.h"
#include "scene/NrrdIO.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"

namespace fs = std::filesystem;

namespace caps {

namespace {

const char* kSegmentUsage = "usage: caps segment CT --out DIR [--skin-threshold HU] [--bone-threshold HU]\n"
                            "                    [--series N|UID] [--surfaces vtp,stl|vtp|stl|none]\n"
                            "\n"
                            "Segments the skin (the head as one solid, table and head holder removed,\n"
                            "internal air filled) and the bone of a head CT and writes into DIR:\n"
                            "  labels.nrrd           label map: 0 background, 1 soft tissue, 2 bone\n"
                            "  skin.vtp, skin.stl    skin surface (full resolution, smoothed; mm, patient LPS)\n"
                            "  bone.vtp, bone.stl    bone surface (same)\n"
                            "and prints the volumes (cm3), the surface areas (cm2) and what the\n"
                            "segmentation did.\n"
                            "\n"
                            "  CT                    a DICOM folder (or one of its files), or a NIfTI, NRRD\n"
                            "                        or MetaImage file\n"
                            "  --skin-threshold HU   air / soft-tissue threshold (default -400)\n"
                            "  --bone-threshold HU   soft-tissue / bone threshold (default 250)\n"
                            "  --series N|UID        in a folder with several series, the N-th (as listed by\n"
                            "                        caps info) or the one with this series instance UID\n"
                            "  --surfaces LIST       which surface files to write (default vtp,stl; none\n"
                            "                        skips the full-resolution surfaces)\n"
                            "\n"
                            "Exit status: 0 when written, 1 when the CT cannot be read or segmented or the\n"
                            "files cannot be written, 2 on wrong usage.\n";

struct SegmentArgs : cli::CtCommandArgs
{
  SegmentLogic::Parameters parameters;
  bool vtp = true; ///< surface files to write
  bool stl = true;
};

std::optional<std::string> parse(const std::vector<std::string>& argv, SegmentArgs& parsed)
{
  const auto option = [&parsed](const std::string& a, const std::vector<std::string>& args,
                                std::size_t& i) -> std::optional<std::string> {
    const bool hasValue = i + 1 < args.size();
    if (a == "--surfaces")
    {
      if (!hasValue)
        return "--surfaces needs vtp, stl, vtp,stl or none";
      const std::string list = args[++i];
      parsed.vtp = list.find("vtp") != std::string::npos;
      parsed.stl = list.find("stl") != std::string::npos;
      if (list != "none" && !parsed.vtp && !parsed.stl)
        return "--surfaces needs vtp, stl, vtp,stl or none (got '" + list + "')";
    }
    else if (a == "--skin-threshold" || a == "--bone-threshold")
    {
      double value = 0;
      if (!hasValue || !cli::parseNumber(args[++i], value))
        return a + " needs a number (HU)";
      (a == "--skin-threshold" ? parsed.parameters.skinThresholdHu : parsed.parameters.boneThresholdHu) = value;
    }
    else
      return "unknown option " + a;
    return std::nullopt;
  };
  if (auto problem = cli::parseCtCommand(argv, parsed, option))
    return problem;
  if (!parsed.help && parsed.parameters.boneThresholdHu <= parsed.parameters.skinThresholdHu)
    return "the bone threshold must be above the skin threshold";
  return std::nullopt;
}

int runSegment(ModuleLogic& moduleLogic, const std::vector<std::string>& argv, std::ostream& out, std::ostream& err)
{
  auto& logic = static_cast<SegmentLogic&>(moduleLogic);
  return cli::runCommand<SegmentArgs>("segment", kSegmentUsage, argv, out, err, parse, [&](SegmentArgs& args) {
    cli::makeOutputFolder(args.out);
    const auto start = std::chrono::steady_clock::now();
    const TaskProgress progress = cli::consoleProgress(err);
    args.read.progress = progress;
    VolumeNode* volume = cli::loadCt(logic, args.ct, args.read, err);
    const SegmentationResult ids = logic.segment(
      *volume, args.parameters, [&progress](double f, const std::string& step) { return progress(0.7 * f, step); });
    const auto* labels = logic.scene().nodeAs<LabelMapNode>(ids.labelMapId);
    vtkImageData* image = labels->image();
    // The files get the full-resolution surfaces; the scene keeps the display ones.
    const bool surfaceFiles = args.vtp || args.stl;
    vtkSmartPointer<vtkPolyData> skin, bone;
    if (surfaceFiles)
    {
      progress(0.7, "Full-resolution skin surface");
      skin = SegmentLogic::fullSurface(SegmentLogic::maskOf(image, kSoftTissueLabel));
      progress(0.8, "Full-resolution bone surface");
      bone = SegmentLogic::fullSurface(SegmentLogic::maskOf(image, kBoneLabel));
    }
    progress(0.95, "Writing files");
    std::vector<std::string> written = {"labels.nrrd"};
    NrrdIO::writeImage(image, args.out / "labels.nrrd");
    if (args.vtp)
    {
      seg::writeSurfaceVtp(skin, args.out / "skin.vtp");
      seg::writeSurfaceVtp(bone, args.out / "bone.vtp");
      written.insert(written.end(), {"skin.vtp", "bone.vtp"});
    }
    if (args.stl)
    {
      cli::writeStl(skin, args.out / "skin.stl");
      cli::writeStl(bone, args.out / "bone.stl");
      written.insert(written.end(), {"skin.stl", "bone.stl"});
    }
    progress(1.0, "Done");
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    const double body = SegmentLogic::volumeMm3(image, kSoftTissueLabel) / 1000.0;
    const double boneVolume = SegmentLogic::volumeMm3(image, kBoneLabel) / 1000.0;
    out << std::fixed << std::setprecision(1);
    out << "Segmented '" << volume->name() << "' (skin " << args.parameters.skinThresholdHu << " HU, bone "
        << args.parameters.boneThresholdHu << " HU) in " << seconds << " s\n";
    out << "  head (skin and all inside): " << std::setw(8) << body << " cm3\n";
    out << "  soft tissue:                " << std::setw(8) << body - boneVolume << " cm3\n";
    out << "  bone:                       " << std::setw(8) << boneVolume << " cm3\n";
    if (surfaceFiles)
    {
      out << "  skin surface:               " << std::setw(8) << SegmentLogic::surfaceAreaMm2(skin) / 100.0 << " cm2 ("
          << skin->GetNumberOfPolys() << " triangles)\n";
      out << "  bone surface:               " << std::setw(8) << SegmentLogic::surfaceAreaMm2(bone) / 100.0 << " cm2 ("
          << bone->GetNumberOfPolys() << " triangles)\n";
    }
    out.unsetf(std::ios::floatfield);
    out << "Segmentation notes:\n";
    for (const auto& note : ids.notes)
      out << "  - " << note << "\n";

    for (const auto& file : written)
      out << "wrote " << (args.out / file).string() << "\n";
    return 0;
  });
}

} // namespace

std::vector<ModuleCommand> segmentCommands()
{
  return {{"segment", "segment skin and bone of a CT: label map (NRRD), surfaces (VTP, STL), volumes", kSegmentUsage,
           runSegment}};
}

} // namespace caps
