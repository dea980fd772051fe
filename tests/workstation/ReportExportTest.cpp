// File > Export plan report as PDF driven as a user drives it (issue 7 item
// 2): the save dialog answered, the report written while a progress dialog
// names each step, the status bar saying where; and Cancel in that progress
// dialog stops the report and writes nothing; the same with the
// convergence study, cancelled inside one of its solves; and the thickness
// report from the same menu.

#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include <QAction>
#include <QApplication>
#include <QFileDialog>
#include <QLineEdit>
#include <QProgressDialog>
#include <QStatusBar>
#include <QTimer>

#include "TestPaths.h"
#include "Workstation.h"
#include "app/RunProcess.h"
#include "report/DemoScene.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

QAction* actionNamed(QWidget& window, const QString& text)
{
  for (QAction* action : window.findChildren<QAction*>())
    if (action->text() == text)
      return action;
  return nullptr;
}

/// Polls every 50 ms (while the action's nested event loops run) until
/// @a step returns true.
void whenReady(const std::function<bool()>& step)
{
  auto* timer = new QTimer;
  timer->setInterval(50);
  QObject::connect(timer, &QTimer::timeout, [timer, step] {
    if (step())
    {
      timer->stop();
      timer->deleteLater();
    }
  });
  timer->start();
}

/// Answers the save dialog with @a file as soon as it shows (again on the
/// next tick while it is still there: the dialog reads its folder in the
/// background and may not take the first answer).
void answerSaveDialog(const fs::path& file)
{
  auto answered = std::make_shared<bool>(false);
  whenReady([file, answered] {
    auto* dialog = qobject_cast<QFileDialog*>(QApplication::activeModalWidget());
    if (!dialog)
      return *answered;
    // The name typed where a user types it (selectFile() alone may lose to
    // the dialog's own default name while it reads the folder).
    dialog->selectFile(QString::fromStdString(file.string()));
    if (auto* name = dialog->findChild<QLineEdit*>("fileNameEdit"))
      name->setText(QString::fromStdString(file.string()));
    QMetaObject::invokeMethod(dialog, "accept", Qt::QueuedConnection);
    *answered = true;
    return false;
  });
}

TEST(ReportExport, ThePdfIsWrittenWithProgressAndCancelWritesNothing)
{
  test::Workstation workstation;
  workstation.window().openPath(test::reportDemoFolder() / "sample.caps");
  ASSERT_TRUE(workstation.waitUntilIdle(120)) << workstation.errors();
  QAction* exportPdf = actionNamed(workstation.window(), "Export plan report as &PDF...");
  ASSERT_NE(exportPdf, nullptr);
  const fs::path folder = test::scratchFolder();

  // Cancelled at its first step: nothing written, the status bar says so, no error.
  const fs::path cancelled = folder / "cancelled.pdf";
  const std::size_t errorsBefore = workstation.window().reportedErrors().size();
  answerSaveDialog(cancelled);
  whenReady([] {
    for (QWidget* w : QApplication::topLevelWidgets())
      if (auto* progress = w->findChild<QProgressDialog*>("report.progress"))
      {
        progress->cancel();
        return true;
      }
    return false;
  });
  exportPdf->trigger();
  EXPECT_FALSE(fs::exists(cancelled));
  EXPECT_FALSE(fs::exists(cancelled.string() + ".writing"));
  EXPECT_EQ(workstation.window().reportedErrors().size(), errorsBefore) << workstation.errors();
  EXPECT_NE(workstation.window().statusBar()->currentMessage().indexOf("cancelled"), -1)
    << workstation.window().statusBar()->currentMessage().toStdString();

  // Written: the progress dialog showed the steps; the status bar names the file.
  const fs::path written = folder / "written" / "plan-report.pdf";
  fs::create_directories(written.parent_path());
  answerSaveDialog(written);
  auto stepSeen = std::make_shared<QString>();
  whenReady([stepSeen] {
    QProgressDialog* progress = nullptr;
    for (QWidget* w : QApplication::topLevelWidgets())
      if (auto* p = w->findChild<QProgressDialog*>("report.progress"))
        progress = p;
    if (!progress || progress->labelText().startsWith("Writing"))
      return false;
    *stepSeen = progress->labelText();
    return true;
  });
  exportPdf->trigger();
  ASSERT_TRUE(fs::exists(written)) << workstation.errors();
  EXPECT_FALSE(stepSeen->isEmpty()) << "no step was shown while the report was made";
  const auto info = test::runProcess("pdfinfo " + test::quoted(written.string()));
  EXPECT_NE(info.output.find("CAPS surgical plan report"), std::string::npos) << info.output;
  const std::string status = workstation.window().statusBar()->currentMessage().toStdString();
  EXPECT_NE(status.find(written.string()), std::string::npos) << status;
}

// File > Export plan report with convergence study: the same report with
// the study run for every plan; its progress names the study's solve, and
// Cancel there stops the solve that runs and writes nothing.
TEST(ReportExport, TheConvergenceStudyRunsFromTheMenuAndCancelsMidSolve)
{
  test::Workstation workstation;
  workstation.window().openPath(test::reportDemoFolder() / "sample.caps");
  ASSERT_TRUE(workstation.waitUntilIdle(120)) << workstation.errors();
  QAction* exportStudy = actionNamed(workstation.window(), "Export plan report with &convergence study as PDF...");
  ASSERT_NE(exportStudy, nullptr);
  const fs::path file = test::scratchFolder() / "study.pdf";
  const std::size_t errorsBefore = workstation.window().reportedErrors().size();
  answerSaveDialog(file);
  auto stoppedAt = std::make_shared<QString>();
  whenReady([stoppedAt] {
    for (QWidget* w : QApplication::topLevelWidgets())
      if (auto* progress = w->findChild<QProgressDialog*>("report.progress"))
        if (progress->labelText().startsWith("Convergence study") && progress->labelText().contains("): "))
        {
          *stoppedAt = progress->labelText();
          progress->cancel();
          return true;
        }
    return false;
  });
  exportStudy->trigger();
  EXPECT_TRUE(stoppedAt->contains("element size")) << stoppedAt->toStdString();
  EXPECT_FALSE(fs::exists(file));
  EXPECT_EQ(workstation.window().reportedErrors().size(), errorsBefore) << workstation.errors();
  EXPECT_NE(workstation.window().statusBar()->currentMessage().indexOf("cancelled"), -1)
    << workstation.window().statusBar()->currentMessage().toStdString();
}

// File > Export thickness report (issue 22 item 5): the review of the
// scene's CT written where the user says, the status bar naming it, the
// landmark table in it.
TEST(ReportExport, TheThicknessReportIsWrittenFromTheFileMenu)
{
  test::Workstation workstation;
  workstation.window().openPath(test::reportDemoFolder() / "sample.caps");
  ASSERT_TRUE(workstation.waitUntilIdle(120)) << workstation.errors();
  QAction* exportThickness = actionNamed(workstation.window(), "Export &thickness report as PDF...");
  ASSERT_NE(exportThickness, nullptr);
  const fs::path file = test::scratchFolder() / "thickness-report.pdf";
  const std::size_t errorsBefore = workstation.window().reportedErrors().size();
  answerSaveDialog(file);
  exportThickness->trigger();
  ASSERT_TRUE(fs::exists(file)) << workstation.errors();
  EXPECT_EQ(workstation.window().reportedErrors().size(), errorsBefore) << workstation.errors();
  const auto info = test::runProcess("pdfinfo " + test::quoted(file.string()));
  EXPECT_NE(info.output.find("CAPS soft-tissue thickness report"), std::string::npos) << info.output;
  const auto text = test::runProcess("pdftotext " + test::quoted(file.string()) + " -");
  EXPECT_NE(text.output.find("pogonion"), std::string::npos) << text.output;
  EXPECT_NE(text.output.find("perpendicular to the skin"), std::string::npos) << text.output;
  const std::string status = workstation.window().statusBar()->currentMessage().toStdString();
  EXPECT_NE(status.find(file.string()), std::string::npos) << status;
}

} // namespace
} // namespace caps
