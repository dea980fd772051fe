// The Report module plugin: the plan report, `caps report`.

#include <QApplication>
#include <QFileDialog>
#include <QPrintDialog>
#include <QPrinter>

#include <algorithm>
#include <cmath>

#include "modules/core/ModalProgress.h"
#include "modules/core/Module.h"
#include "modules/report/PlanReport.h"
#include "modules/report/ReportCommands.h"
#include "modules/report/ThicknessReport.h"
#include "segmentation/Progress.h"

#ifndef CAPS_VERSION
#define CAPS_VERSION "unknown"
#endif

namespace caps {
namespace {

class ReportLogic : public ModuleLogic
{
public:
  using ModuleLogic::ModuleLogic;
};

/// The report of the workstation's scene, built on the GUI thread (its
/// renders share the display with the views) under a modal progress dialog:
/// the user sees which plan is being predicted and rendered and may cancel
/// between steps (seg::Cancelled), and cannot change the scene meanwhile.
report::ReportDocument reportOfScene(ModuleLogic& logic, ModuleHost& host, const report::ReportOptions& options)
{
  const std::string what =
    options.convergenceStudy
      ? "Writing the plan report with its convergence study (each plan solved twelve more times)..."
      : "Writing the plan report...";
  host.showStatus(what);
  ModalProgress dialog(host.window(), QString::fromStdString(what), "Plan report", "report.progress");
  try
  {
    report::ReportDocument doc = report::buildPlanReport(logic.scene(), options, dialog.progress());
    dialog.finish();
    return doc;
  }
  catch (...)
  {
    host.showStatus("");
    throw;
  }
}

/// The kinds of PDF the File menu exports.
enum class PdfKind
{
  Plain,
  Deidentified,
  WithConvergenceStudy
};

void exportPdf(ModuleLogic& logic, ModuleHost& host, PdfKind kind)
{
  const char* name = kind == PdfKind::Deidentified           ? "plan-report-deidentified.pdf"
                     : kind == PdfKind::WithConvergenceStudy ? "plan-report-convergence.pdf"
                                                             : "plan-report.pdf";
  const QString file = QFileDialog::getSaveFileName(host.window(), "Export the plan report", name, "PDF (*.pdf)");
  if (file.isEmpty())
    return;
  report::ReportOptions options;
  options.deidentify = kind == PdfKind::Deidentified;
  options.convergenceStudy = kind == PdfKind::WithConvergenceStudy;
  report::ReportDocument doc("");
  try
  {
    doc = reportOfScene(logic, host, options);
  }
  catch (const seg::Cancelled&)
  {
    host.showStatus("The plan report was cancelled; nothing was written.");
    return;
  }
  report::PdfMetadata metadata{"CAPS surgical plan report", std::string("CAPS ") + CAPS_VERSION};
  const int pages = doc.writePdf(file.toStdString(), report::PaperSize::A4, metadata);
  host.showStatus("Wrote " + file.toStdString() + " (" + std::to_string(pages) + " pages)");
}

/// File > Export thickness report: the review of the scene's CT (its range
/// maps must be made), under a modal progress dialog as the plan report.
void exportThicknessReport(ModuleLogic& logic, ModuleHost& host)
{
  const QString file =
    QFileDialog::getSaveFileName(host.window(), "Export the thickness report", "thickness-report.pdf", "PDF (*.pdf)");
  if (file.isEmpty())
    return;
  const std::string what = "Writing the thickness report...";
  host.showStatus(what);
  report::ReportDocument doc("");
  {
    ModalProgress dialog(host.window(), QString::fromStdString(what), "Thickness report", "report.progress");
    try
    {
      doc = report::buildThicknessReport(logic.scene(), report::ThicknessReportOptions{}, dialog.progress());
      dialog.finish();
    }
    catch (const seg::Cancelled&)
    {
      host.showStatus("The thickness report was cancelled; nothing was written.");
      return;
    }
    catch (...)
    {
      host.showStatus("");
      throw;
    }
  }
  const report::PdfMetadata metadata{report::kThicknessReportTitle, std::string("CAPS ") + CAPS_VERSION};
  const int pages = doc.writePdf(file.toStdString(), report::PaperSize::A4, metadata);
  host.showStatus("Wrote " + file.toStdString() + " (" + std::to_string(pages) + " pages)");
}

void printReport(ModuleLogic& logic, ModuleHost& host)
{
  QPrinter printer(QPrinter::HighResolution);
  printer.setDocName("CAPS surgical plan report");
  QPrintDialog dialog(&printer, host.window());
  if (dialog.exec() != QDialog::Accepted)
    return;
  report::ReportDocument doc("");
  try
  {
    doc = reportOfScene(logic, host, report::ReportOptions{});
  }
  catch (const seg::Cancelled&)
  {
    host.showStatus("The plan report was cancelled; nothing was printed.");
    return;
  }
  const int pages = doc.render(printer);
  host.showStatus("Sent the plan report to the printer (" + std::to_string(pages) + " pages)");
}

class ReportModule : public Module
{
public:
  std::string name() const override { return "report"; }
  std::string title() const override { return "Report"; }
  std::string help() const override
  {
    return "Documents the plan (thesis §2.1, §3.3.3): a printed or PDF report with the procedure, the "
           "incision on the patient's face, measurements, the predicted result and its stresses, the tissue "
           "thickness, the storyboard of snapshots and the model's assumptions; and the soft-tissue thickness "
           "review: the landmarks with their depths, the thickness maps and how they were measured.";
  }
  std::vector<ModuleCommand> commands() const override { return reportCommands(); }
  std::vector<ModuleAction> actions() const override
  {
    return {{"File", "Export plan report as &PDF...", "Ctrl+E",
             [](ModuleLogic& logic, ModuleHost& host) { exportPdf(logic, host, PdfKind::Plain); }},
            {"File", "Export &de-identified plan report as PDF...", "",
             [](ModuleLogic& logic, ModuleHost& host) { exportPdf(logic, host, PdfKind::Deidentified); }},
            {"File", "Export plan report with &convergence study as PDF...", "",
             [](ModuleLogic& logic, ModuleHost& host) { exportPdf(logic, host, PdfKind::WithConvergenceStudy); }},
            {"File", "&Print plan report...", "Ctrl+P",
             [](ModuleLogic& logic, ModuleHost& host) { printReport(logic, host); }},
            {"File", "Export &thickness report as PDF...", "",
             [](ModuleLogic& logic, ModuleHost& host) { exportThicknessReport(logic, host); }}};
  }
  std::unique_ptr<ModuleLogic> createLogic(Scene& scene) const override { return std::make_unique<ReportLogic>(scene); }
};

} // namespace
} // namespace caps

CAPS_DECLARE_MODULE(caps::ReportModule)
