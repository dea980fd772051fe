#include "modules/report/ReportCommands.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>

#include "modules/report/PlanAnimation.h"
#include "modules/report/PlanReport.h"
#include "modules/report/Storyboard.h"
#include "modules/report/ThicknessReport.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "modules/volumes/CommandLine.h"
#include "scene/Scene.h"
#include "scene/SceneBundle.h"
#include "scene/SnapshotNode.h"

#ifndef CAPS_VERSION
#define CAPS_VERSION "unknown"
#endif

namespace fs = std::filesystem;

namespace caps {
namespace {

/// Loads the scene bundle a command works on.
/// @throws std::invalid_argument when there is none at @a path.
void loadScene(const fs::path& path, Scene& scene)
{
  if (!fs::is_directory(path))
    throw std::invalid_argument("there is no scene at " + path.string() +
                                ": give the NAME.caps folder that the workstation or caps demo saved");
  loadSceneBundle(scene, path);
}

const char* kReportUsage = "usage: caps report SCENE.caps --pdf OUT.pdf [--deidentify] [--paper a4|letter]\n"
                           "                   [--surgeon NAME] [--date YYYY-MM-DD] [--plan NAME ...]\n"
                           "                   [--study convergence]\n"
                           "\n"
                           "Writes the plan report of a saved scene as a PDF (thesis §2.1, §3.3.3): the\n"
                           "patient and study, and for each plan the procedure and its parameters, the\n"
                           "incision on the face (front, oblique, profile), the measurements on the skin,\n"
                           "the predicted result before and after with the stress map, the closure force,\n"
                           "the tissue thickness under the incision, the storyboard of snapshots and the\n"
                           "model's assumptions. Each plan is predicted again from its recorded operations,\n"
                           "so the numbers are those caps plan printed.\n"
                           "\n"
                           "  --pdf OUT.pdf      the report to write (replaced only once the new one is complete)\n"
                           "  --deidentify       leaves out the patient's name, ID, birth date and the folders the\n"
                           "                     data came from, in the text and in the PDF's metadata\n"
                           "  --paper a4|letter  paper size (default a4)\n"
                           "  --surgeon NAME     the surgeon's name in the header (default: a line to sign)\n"
                           "  --date YYYY-MM-DD  the planning date (default today)\n"
                           "  --plan NAME        only this plan (repeatable); default every plan of the scene\n"
                           "  --study convergence\n"
                           "                     adds an appendix: each plan solved again with the mesh refined,\n"
                           "                     2-4 tissue layers and the meshed region grown (rim free and\n"
                           "                     clamped), with how far each number moves (12 solves a plan:\n"
                           "                     minutes)\n"
                           "\n"
                           "Figures are rendered offscreen; without a display, CAPS starts its own X server\n"
                           "(Xvfb, Debian package xvfb).\n"
                           "Exit status: 0 when written, 1 when the scene cannot be reported (the message\n"
                           "says why), 2 on wrong usage.\n";

/// The options every PDF report takes, where a report's parser meets them.
struct PdfOptions
{
  fs::path* pdf;
  bool* deidentify;
  report::PaperSize* paper;
  std::string* date;
};

/// Reads args[i] (and its value) when it is one of the PDF options, moving
/// @a i past them. nullopt: not one of them; "": read; else what is wrong.
std::optional<std::string> parsePdfOption(const std::vector<std::string>& args, std::size_t& i, const PdfOptions& o)
{
  const std::string& a = args[i];
  const bool hasValue = i + 1 < args.size();
  if (a == "--pdf")
  {
    if (!hasValue)
      return std::string("--pdf needs the file to write");
    *o.pdf = args[++i];
  }
  else if (a == "--deidentify")
    *o.deidentify = true;
  else if (a == "--paper")
  {
    const std::string paper = hasValue ? args[++i] : "";
    if (paper == "a4" || paper == "A4")
      *o.paper = report::PaperSize::A4;
    else if (paper == "letter" || paper == "Letter")
      *o.paper = report::PaperSize::Letter;
    else
      return std::string("--paper needs a4 or letter");
  }
  else if (a == "--date")
  {
    const std::string date = hasValue ? args[++i] : "";
    if (date.size() != 10 || date[4] != '-' || date[7] != '-')
      return std::string("--date needs a date as YYYY-MM-DD");
    *o.date = date;
  }
  else
    return std::nullopt;
  return std::string();
}

struct ReportArgs
{
  fs::path scene;
  fs::path pdf;
  report::ReportOptions options;
  bool help = false;
};

std::optional<std::string> parse(const std::vector<std::string>& args, ReportArgs& parsed)
{
  for (std::size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    const bool hasValue = i + 1 < args.size();
    if (a == "--help" || a == "-h")
      parsed.help = true;
    else if (const auto pdf = parsePdfOption(
               args, i, {&parsed.pdf, &parsed.options.deidentify, &parsed.options.paper, &parsed.options.planningDate}))
    {
      if (!pdf->empty())
        return pdf;
    }
    else if (a == "--surgeon")
    {
      if (!hasValue)
        return "--surgeon needs a name";
      parsed.options.surgeon = args[++i];
    }
    else if (a == "--plan")
    {
      if (!hasValue)
        return "--plan needs the name of a plan of the scene";
      parsed.options.plans.push_back(args[++i]);
    }
    else if (a == "--study")
    {
      if (!hasValue || args[i + 1] != "convergence")
        return "--study needs convergence (the only study the report prints)";
      ++i;
      parsed.options.convergenceStudy = true;
    }
    else if (!a.empty() && a[0] == '-')
      return "unknown option " + a;
    else if (parsed.scene.empty())
      parsed.scene = a;
    else
      return "one scene at a time (got " + parsed.scene.string() + " and " + a + ")";
  }
  if (parsed.help)
    return std::nullopt;
  if (parsed.scene.empty())
    return "SCENE.caps missing";
  if (parsed.pdf.empty())
    return "--pdf OUT.pdf missing";
  return std::nullopt;
}

int runReport(ModuleLogic&, const std::vector<std::string>& argv, std::ostream& out, std::ostream& err)
{
  return cli::runCommand<ReportArgs>("report", kReportUsage, argv, out, err, parse, [&](ReportArgs& args) {
    Scene scene;
    loadScene(args.scene, scene);
    const TaskProgress progress = cli::consoleProgress(err);
    const report::ReportDocument doc = report::buildPlanReport(scene, args.options, progress);
    if (!args.pdf.parent_path().empty())
      fs::create_directories(args.pdf.parent_path());
    report::PdfMetadata metadata;
    metadata.title = "CAPS surgical plan report";
    metadata.creator = std::string("CAPS ") + CAPS_VERSION;
    const int pages = doc.writePdf(args.pdf, args.options.paper, metadata);
    out << "wrote " << args.pdf.string() << " (" << pages << " pages)\n";
    return 0;
  });
}

const char* kAnimateUsage =
  "usage: caps animate SCENE.caps --out DIR [--plan NAME] [--frames N] [--turntable-frames M]\n"
  "                    [--size WxH] [--fps F] [--no-turntable] [--no-video]\n"
  "\n"
  "Exports the animations of a plan of a saved scene (thesis §3.3.3): the skin\n"
  "morphing from the wound as cut, through the wound gaping under the skin's\n"
  "pre-tension when the prediction carried one, to the predicted result, seen\n"
  "from one camera framing them all, and a turntable once round the head with the incision\n"
  "drawn, starting from the front. Each is written as a PNG sequence\n"
  "(DIR/pre-post/frame-0000.png ..., DIR/turntable/frame-0000.png ...) and, when\n"
  "ffmpeg is installed (Debian package ffmpeg), as DIR/pre-post.mp4 and\n"
  "DIR/turntable.mp4 (H.264, yuv420p). Without ffmpeg the frames are still\n"
  "written and the command to make the videos later is printed.\n"
  "\n"
  "  --out DIR             the folder to write into (frames already there are replaced)\n"
  "  --plan NAME           the plan to animate (default the scene's first plan)\n"
  "  --frames N            frames of the pre -> post animation (default 30, at least 2)\n"
  "  --turntable-frames M  frames of the turn around the head (default 72, at least 2)\n"
  "  --size WxH            frame size in pixels (default 960x720; odd sizes are made even)\n"
  "  --fps F               frame rate of the videos (default 24)\n"
  "  --no-turntable        only the pre -> post animation\n"
  "  --no-video            only the PNG sequences\n"
  "\n"
  "The environment variable CAPS_FFMPEG names the ffmpeg to run (default: ffmpeg\n"
  "on PATH). Frames are rendered offscreen; without a display, CAPS starts its own\n"
  "X server (Xvfb, Debian package xvfb).\n"
  "Exit status: 0 when written, 1 when the scene cannot be animated (the message\n"
  "says why), 2 on wrong usage.\n";

struct AnimateArgs
{
  fs::path scene;
  fs::path out;
  std::string plan;
  render::AnimationOptions options;
  bool help = false;
};

/// A whole positive number, or nullopt.
std::optional<int> positiveInt(const std::string& text)
{
  try
  {
    std::size_t used = 0;
    const int value = std::stoi(text, &used);
    if (used == text.size() && value > 0)
      return value;
  }
  catch (const std::exception&)
  {}
  return std::nullopt;
}

std::optional<std::string> parseAnimate(const std::vector<std::string>& args, AnimateArgs& parsed)
{
  for (std::size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    const bool hasValue = i + 1 < args.size();
    if (a == "--help" || a == "-h")
      parsed.help = true;
    else if (a == "--out")
    {
      if (!hasValue)
        return "--out needs the folder to write into";
      parsed.out = args[++i];
    }
    else if (a == "--plan")
    {
      if (!hasValue)
        return "--plan needs the name of a plan of the scene";
      parsed.plan = args[++i];
    }
    else if (a == "--frames" || a == "--turntable-frames")
    {
      const auto n = positiveInt(hasValue ? args[++i] : "");
      if (!n || *n < 2 || *n > 10000)
        return a + " needs a number of frames from 2 to 10000";
      (a == "--frames" ? parsed.options.prePostFrames : parsed.options.turntableFrames) = *n;
    }
    else if (a == "--size")
    {
      const std::string size = hasValue ? args[++i] : "";
      const std::size_t x = size.find('x');
      const auto w = x == std::string::npos ? std::nullopt : positiveInt(size.substr(0, x));
      const auto h = x == std::string::npos ? std::nullopt : positiveInt(size.substr(x + 1));
      if (!w || !h || *w < 16 || *h < 16 || *w > 8192 || *h > 8192)
        return "--size needs WIDTHxHEIGHT in pixels, 16 to 8192 each (e.g. 960x720)";
      parsed.options.width = *w;
      parsed.options.height = *h;
    }
    else if (a == "--fps")
    {
      double fps = 0.0;
      try
      {
        fps = hasValue ? std::stod(args[++i]) : 0.0;
      }
      catch (const std::exception&)
      {}
      if (!(fps > 0.0 && fps <= 240.0))
        return "--fps needs a frame rate from 0 to 240";
      parsed.options.framesPerSecond = fps;
    }
    else if (a == "--no-turntable")
      parsed.options.turntable = false;
    else if (a == "--no-video")
      parsed.options.video = false;
    else if (!a.empty() && a[0] == '-')
      return "unknown option " + a;
    else if (parsed.scene.empty())
      parsed.scene = a;
    else
      return "one scene at a time (got " + parsed.scene.string() + " and " + a + ")";
  }
  if (parsed.help)
    return std::nullopt;
  if (parsed.scene.empty())
    return "SCENE.caps missing";
  if (parsed.out.empty())
    return "--out DIR missing";
  return std::nullopt;
}

void printSequence(std::ostream& out, const render::FrameSequence& sequence)
{
  out << "wrote " << sequence.folder.string() << "/frame-0000.png ... (" << sequence.frames << " frames, "
      << sequence.width << "x" << sequence.height << ")\n";
  if (!sequence.video.empty())
    out << "wrote " << sequence.video.string() << "\n";
}

int runAnimate(ModuleLogic&, const std::vector<std::string>& argv, std::ostream& out, std::ostream& err)
{
  return cli::runCommand<AnimateArgs>("animate", kAnimateUsage, argv, out, err, parseAnimate, [&](AnimateArgs& args) {
    Scene scene;
    loadScene(args.scene, scene);
    const TaskProgress progress = cli::consoleProgress(err);
    const render::AnimationResult result =
      report::writePlanAnimation(scene, args.plan, args.out, args.options, progress);
    out << "plan \"" << result.planName << "\"\n";
    printSequence(out, result.prePost);
    if (result.turntable)
      printSequence(out, *result.turntable);
    char timing[96];
    std::snprintf(timing, sizeof timing, "rendered %d frames in %.1f s (%.2f frames/s)\n", result.framesRendered,
                  result.renderSeconds, result.framesRendered / std::max(1e-9, result.renderSeconds));
    out << timing;
    if (!result.videoMessage.empty())
      out << result.videoMessage << "\n";
    return 0;
  });
}

const char* kSnapshotUsage = "usage: caps snapshot SCENE.caps --plan NAME --view VIEW [--caption TEXT] [--size WxH]\n"
                             "\n"
                             "Adds a snapshot of a plan to the scene's storyboard (thesis §3.3.3), as the\n"
                             "workstation's snapshot button does, and saves the scene; the report prints the\n"
                             "snapshots in order with their captions.\n"
                             "\n"
                             "  --plan NAME       the plan (as the scene names it, e.g. \"Z-plasty 1\")\n"
                             "  --view VIEW       front, oblique or profile (the face, the incision drawn), before or\n"
                             "                    after (close-up, the same camera), stress (von Mises, colour bar)\n"
                             "  --caption TEXT    the caption (default: the plan and the view)\n"
                             "  --size WxH        pixels (default 1200x900)\n"
                             "Exit status: 0 when added, 1 when the scene cannot give that view, 2 on wrong usage.\n";

int runSnapshot(ModuleLogic&, const std::vector<std::string>& args, std::ostream& out, std::ostream& err)
{
  fs::path scenePath;
  std::string plan, view, caption;
  int width = 1200, height = 900;
  std::optional<std::string> problem;
  for (std::size_t i = 0; i < args.size() && !problem; ++i)
  {
    const std::string& a = args[i];
    const bool hasValue = i + 1 < args.size();
    if (a == "--help" || a == "-h")
    {
      out << kSnapshotUsage;
      return 0;
    }
    if ((a == "--plan" || a == "--view" || a == "--caption" || a == "--size") && !hasValue)
      problem = a + " needs a value";
    else if (a == "--plan")
      plan = args[++i];
    else if (a == "--view")
      view = args[++i];
    else if (a == "--caption")
      caption = args[++i];
    else if (a == "--size")
    {
      const std::string size = args[++i];
      const auto x = size.find('x');
      try
      {
        width = std::stoi(size.substr(0, x));
        height = std::stoi(size.substr(x + 1));
      }
      catch (const std::exception&)
      {
        problem = "--size needs WxH in pixels, e.g. 1200x900";
      }
      if (x == std::string::npos || width < 64 || height < 64 || width > 8000 || height > 8000)
        problem = "--size needs WxH in pixels from 64 to 8000, e.g. 1200x900";
    }
    else if (!a.empty() && a[0] == '-')
      problem = "unknown option " + a;
    else if (scenePath.empty())
      scenePath = a;
    else
      problem = "one scene at a time";
  }
  if (!problem && scenePath.empty())
    problem = "SCENE.caps missing";
  if (!problem && (plan.empty() || view.empty()))
    problem = "--plan NAME and --view VIEW are needed";
  if (problem)
  {
    err << "caps snapshot: " << *problem << "\n" << kSnapshotUsage;
    return 2;
  }
  try
  {
    const report::PlanView planView = report::planViewFromName(view);
    Scene scene;
    loadScene(scenePath, scene);
    const SnapshotNode& snapshot = report::takePlanSnapshot(scene, plan, planView, caption, width, height);
    saveSceneBundle(scene, scenePath);
    out << "added " << snapshot.name() << " (\"" << snapshot.caption() << "\") to " << scenePath.string() << "\n";
    return 0;
  }
  catch (const std::exception& e)
  {
    err << "caps snapshot: " << e.what() << "\n";
    return 1;
  }
}

const char* kThicknessReportUsage =
  "usage: caps thickness-report CT|SCENE.caps --pdf OUT.pdf [--deidentify] [--paper a4|letter]\n"
  "                             [--reviewer NAME] [--date YYYY-MM-DD]\n"
  "\n"
  "Writes the soft-tissue thickness review as a PDF (thesis §2.1, §4.2, §4.3): the\n"
  "patient and study, the standard facial landmarks placed automatically with their\n"
  "confidence and the depth at each measured in the CT by its published convention\n"
  "(perpendicular to the skin, or to the nearest bone), the landmarks not placed and\n"
  "why, the thickness statistics of the face, the thickness maps unwrapped and\n"
  "painted on the face with the landmarks numbered, and the method.\n"
  "\n"
  "  CT                 a CT as caps info reads it (DICOM folder, NRRD, NIfTI, MetaImage):\n"
  "                     segmented and mapped with the default thresholds first\n"
  "  SCENE.caps         a saved scene with its CT, label map and range maps\n"
  "  --pdf OUT.pdf      the report to write (replaced only once the new one is complete)\n"
  "  --deidentify       leaves out the patient's name, ID, birth date and the folders the\n"
  "                     data came from, in the text and in the PDF's metadata\n"
  "  --paper a4|letter  paper size (default a4)\n"
  "  --reviewer NAME    who reviewed it, in the header (default: a line to sign)\n"
  "  --date YYYY-MM-DD  the review date (default today)\n"
  "\n"
  "Figures are rendered offscreen; without a display, CAPS starts its own X server\n"
  "(Xvfb, Debian package xvfb).\n"
  "Exit status: 0 when written, 1 when the CT or scene cannot be reviewed (the\n"
  "message says why), 2 on wrong usage.\n";

struct ThicknessReportArgs
{
  fs::path input;
  fs::path pdf;
  report::ThicknessReportOptions options;
  bool help = false;
};

std::optional<std::string> parseThicknessReport(const std::vector<std::string>& args, ThicknessReportArgs& parsed)
{
  for (std::size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    const bool hasValue = i + 1 < args.size();
    if (a == "--help" || a == "-h")
      parsed.help = true;
    else if (const auto pdf = parsePdfOption(
               args, i, {&parsed.pdf, &parsed.options.deidentify, &parsed.options.paper, &parsed.options.date}))
    {
      if (!pdf->empty())
        return pdf;
    }
    else if (a == "--reviewer")
    {
      if (!hasValue)
        return "--reviewer needs a name";
      parsed.options.reviewer = args[++i];
    }
    else if (!a.empty() && a[0] == '-')
      return "unknown option " + a;
    else if (parsed.input.empty())
      parsed.input = a;
    else
      return "one CT or scene at a time (got " + parsed.input.string() + " and " + a + ")";
  }
  if (parsed.help)
    return std::nullopt;
  if (parsed.input.empty())
    return "CT or SCENE.caps missing";
  if (parsed.pdf.empty())
    return "--pdf OUT.pdf missing";
  return std::nullopt;
}

/// A saved scene is a folder holding scene.json; anything else is a CT.
bool isSceneBundle(const fs::path& path)
{
  return fs::is_directory(path) && fs::exists(path / "scene.json");
}

int runThicknessReport(ModuleLogic& logic, const std::vector<std::string>& argv, std::ostream& out, std::ostream& err)
{
  return cli::runCommand<ThicknessReportArgs>(
    "thickness-report", kThicknessReportUsage, argv, out, err, parseThicknessReport, [&](ThicknessReportArgs& args) {
      const TaskProgress progress = cli::consoleProgress(err);
      Scene& scene = logic.scene();
      if (isSceneBundle(args.input))
        loadScene(args.input, scene);
      else
      {
        seg::CtReadOptions read;
        read.progress = progress;
        VolumeNode* volume = cli::loadCt(logic, args.input, read, err);
        RangeMapLogic(scene).run(*volume, RangeMapLogic::Parameters{}, progress);
      }
      const report::ReportDocument doc = report::buildThicknessReport(scene, args.options, progress);
      if (!args.pdf.parent_path().empty())
        fs::create_directories(args.pdf.parent_path());
      const report::PdfMetadata metadata{report::kThicknessReportTitle, std::string("CAPS ") + CAPS_VERSION};
      const int pages = doc.writePdf(args.pdf, args.options.paper, metadata);
      out << "wrote " << args.pdf.string() << " (" << pages << " pages)\n";
      return 0;
    });
}

} // namespace

std::vector<ModuleCommand> reportCommands()
{
  return {{"report", "write the plan report of a scene as a PDF", kReportUsage, runReport},
          {"snapshot", "add a view of a plan to the scene's storyboard", kSnapshotUsage, runSnapshot},
          {"animate", "export a plan's pre -> post animation and a turntable as PNG frames and MP4", kAnimateUsage,
           runAnimate},
          {"thickness-report", "write the soft-tissue thickness review of a CT or scene as a PDF",
           kThicknessReportUsage, runThicknessReport}};
}

} // namespace caps
