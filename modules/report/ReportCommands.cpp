#include "modules/report/ReportCommands.h"

#include <filesystem>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>

#include "modules/report/PlanReport.h"
#include "modules/segment/SegmentCommands.h"
#include "scene/Scene.h"
#include "scene/SceneBundle.h"

#ifndef CAPS_VERSION
#define CAPS_VERSION "unknown"
#endif

namespace fs = std::filesystem;

namespace caps {
namespace {

const char* kReportUsage =
  "usage: caps report SCENE.caps --pdf OUT.pdf [--deidentify] [--paper a4|letter]\n"
  "                   [--surgeon NAME] [--date YYYY-MM-DD] [--plan NAME ...]\n"
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
  "\n"
  "Figures are rendered offscreen; without a display, CAPS starts its own X server\n"
  "(Xvfb, Debian package xvfb).\n"
  "Exit status: 0 when written, 1 when the scene cannot be reported (the message\n"
  "says why), 2 on wrong usage.\n";

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
    else if (a == "--pdf")
    {
      if (!hasValue)
        return "--pdf needs the file to write";
      parsed.pdf = args[++i];
    }
    else if (a == "--deidentify")
      parsed.options.deidentify = true;
    else if (a == "--paper")
    {
      const std::string paper = hasValue ? args[++i] : "";
      if (paper == "a4" || paper == "A4")
        parsed.options.paper = report::PaperSize::A4;
      else if (paper == "letter" || paper == "Letter")
        parsed.options.paper = report::PaperSize::Letter;
      else
        return "--paper needs a4 or letter";
    }
    else if (a == "--surgeon")
    {
      if (!hasValue)
        return "--surgeon needs a name";
      parsed.options.surgeon = args[++i];
    }
    else if (a == "--date")
    {
      const std::string date = hasValue ? args[++i] : "";
      if (date.size() != 10 || date[4] != '-' || date[7] != '-')
        return "--date needs a date as YYYY-MM-DD";
      parsed.options.planningDate = date;
    }
    else if (a == "--plan")
    {
      if (!hasValue)
        return "--plan needs the name of a plan of the scene";
      parsed.options.plans.push_back(args[++i]);
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
  ReportArgs args;
  if (auto problem = parse(argv, args))
  {
    err << "caps report: " << *problem << "\n" << kReportUsage;
    return 2;
  }
  if (args.help)
  {
    out << kReportUsage;
    return 0;
  }
  try
  {
    if (!fs::is_directory(args.scene))
      throw std::invalid_argument("there is no scene at " + args.scene.string() +
                                  ": give the NAME.caps folder that the workstation or caps demo saved");
    Scene scene;
    loadSceneBundle(scene, args.scene);
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
  }
  catch (const std::exception& e)
  {
    err << "caps report: " << e.what() << "\n";
    return 1;
  }
}

} // namespace

std::vector<ModuleCommand> reportCommands()
{
  return {{"report", "write the plan report of a scene as a PDF", kReportUsage, runReport}};
}

} // namespace caps
