#pragma once
/// @file GuiForPainting.h
/// @brief A QGuiApplication for drawing with QPainter (text needs one for its
/// font database) when the process has none: the command line and the tests
/// run without a window. Made on Qt's "offscreen" platform, which needs no
/// display, and removed with the object. Header-only: the modules that draw
/// (plots, reports) link Qt5::Gui themselves.

#include <cstdio>
#include <memory>
#include <stdexcept>

#include <QByteArray>
#include <QCoreApplication>
#include <QGuiApplication>
#include <QString>
#include <QtGlobal>

namespace caps::render {

class GuiForPainting
{
public:
  /// @throws std::runtime_error when a non-graphical Qt application
  /// (QCoreApplication) runs: text cannot be drawn in it.
  GuiForPainting()
  {
    QCoreApplication* existing = QCoreApplication::instance();
    if (existing)
    {
      if (!qobject_cast<QGuiApplication*>(existing))
        throw std::runtime_error("cannot draw text in a program that runs a non-graphical Qt application "
                                 "(QCoreApplication): text needs a QGuiApplication");
      return;
    }
    const bool hadPlatform = qEnvironmentVariableIsSet("QT_QPA_PLATFORM");
    const QByteArray platform = qgetenv("QT_QPA_PLATFORM");
    qputenv("QT_QPA_PLATFORM", "offscreen");
    static int argc = 1;
    static char name[] = "caps";
    static char* argv[] = {name, nullptr};
    // Without a session (XDG_RUNTIME_DIR unset, as in CI) Qt warns about its
    // runtime folder on start: not the user's concern, so not printed.
    previousHandler() = qInstallMessageHandler(dropStandardPathsWarnings);
    application_ = std::make_unique<QGuiApplication>(argc, argv);
    qInstallMessageHandler(previousHandler());
    if (hadPlatform)
      qputenv("QT_QPA_PLATFORM", platform);
    else
      qunsetenv("QT_QPA_PLATFORM");
  }
  GuiForPainting(const GuiForPainting&) = delete;
  GuiForPainting& operator=(const GuiForPainting&) = delete;

private:
  static QtMessageHandler& previousHandler()
  {
    static QtMessageHandler handler = nullptr;
    return handler;
  }
  static void dropStandardPathsWarnings(QtMsgType type, const QMessageLogContext& context, const QString& message)
  {
    if (message.startsWith(QLatin1String("QStandardPaths:")))
      return;
    if (previousHandler())
      previousHandler()(type, context, message);
    else
      std::fprintf(stderr, "%s\n", message.toLocal8Bit().constData());
  }

  std::unique_ptr<QGuiApplication> application_;
};

} // namespace caps::render
