// caps: the CAPS workstation (no arguments) and its headless command line.

#include <iostream>
#include <string>
#include <vector>

#include <QApplication>
#include <QSurfaceFormat>
#include <QVTKOpenGLNativeWidget.h>

#include "app/CommandLine.h"
#include "app/MainWindow.h"
#include "app/ModuleManager.h"
#include "app/Paths.h"
#include "app/Session.h"
#include "fem/BlasKernels.h"

int main(int argc, char** argv)
{
  caps::fem::useBestBlasKernels(argv); // may re-execute: first, before any thread
  const std::vector<std::string> args(argv + 1, argv + argc);
  caps::ModuleManager modules;
  for (const auto& folder : caps::ModuleManager::searchPath(caps::executablePath()))
    modules.loadFolder(folder);

  if (auto code = caps::runCommandLine(args, modules, std::cout, std::cerr))
    return *code;

  // The workstation: caps [PATH] [--screenshot PNG]
  std::string path, screenshot;
  for (size_t i = 0; i < args.size(); ++i)
  {
    if (args[i] == "--screenshot" && i + 1 < args.size())
      screenshot = args[++i];
    else if (!args[i].empty() && args[i][0] != '-' && path.empty())
      path = args[i];
    else
    {
      std::cerr << "caps: unexpected argument '" << args[i] << "'. Run caps --help.\n";
      return 2;
    }
  }

  QSurfaceFormat::setDefaultFormat(QVTKOpenGLNativeWidget::defaultFormat());
  QApplication application(argc, argv);
  QApplication::setApplicationName("CAPS");
  QApplication::setOrganizationName("CAPS");
  QApplication::setApplicationVersion(CAPS_VERSION);
  int code = 0;
  {
    caps::Session session(modules);
    caps::MainWindow window(session);
    window.show();
    // Unattended mode first, so messages of the opening go to stderr.
    if (!screenshot.empty())
      window.screenshotWhenIdle(screenshot);
    if (!path.empty())
      window.openPath(path);
    code = QApplication::exec();
  }
  return code;
}
