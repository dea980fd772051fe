#pragma once
/// @file OffscreenDisplay.h
/// @brief An X display for offscreen VTK rendering: the one in DISPLAY, or a private Xvfb.

#include <string>

namespace caps::render {

/// @class OffscreenDisplay
/// @brief Makes sure this process can open an X display, starting a private Xvfb when it cannot.
///
/// The VTK of the workstation (Debian's 9.1) renders only through X
/// (vtkXOpenGLRenderWindow: no OSMesa, no EGL), even offscreen. Report
/// figures must render on a machine without a screen (the command line,
/// continuous integration), so ensure() checks DISPLAY and, when it is unset
/// or names a server that cannot be opened, starts
/// `Xvfb -displayfd FD -screen 0 2560x2048x24 -nolisten tcp` (Xvfb picks a free
/// display number and writes it to FD once it accepts connections), waits
/// for it and sets DISPLAY for this process. Xvfb is looked for on PATH and
/// in /usr/bin; the environment variable CAPS_XVFB names another executable.
///
/// The private server is stopped (SIGTERM, then SIGKILL, and always reaped)
/// by shutdown(), when the last OffscreenDisplay object is destroyed, or at
/// process exit. When ensure() is called from the main thread the server also
/// receives SIGTERM if this process dies without cleaning up.
///
/// The functions are serialised by a mutex, so one rendering thread (or
/// several taking turns) may call them while others run; ensure() is cheap
/// once the display is known to work and may be called before every render.
///
/// @warning setenv("DISPLAY") is not safe against a concurrent getenv in
/// another thread; call ensure() before starting threads that read DISPLAY.
/// @warning Close every X connection (render windows) before shutdown(): a
/// client of a killed server is terminated by Xlib at its next request.
///
/// @sa ReportFigures.h, which calls ensure() before every render.
class OffscreenDisplay
{
public:
  /// Calls ensure(); keeps a private server alive while any such object lives.
  /// @throws std::runtime_error as ensure().
  OffscreenDisplay();
  /// Stops the private server when this is the last object and ensure() started one.
  ~OffscreenDisplay();
  OffscreenDisplay(const OffscreenDisplay&) = delete;
  OffscreenDisplay& operator=(const OffscreenDisplay&) = delete;

  /// Makes sure DISPLAY names an X server this process can open.
  /// Does nothing when it already does (checked once per DISPLAY value).
  /// @throws std::runtime_error when Xvfb is needed and is not installed
  /// ("install the Debian package xvfb, or run under xvfb-run -a"), or when
  /// it does not start within 20 s (the message carries its error output).
  static void ensure();

  /// The DISPLAY value ensure() settled on ("" before the first call).
  static std::string display();

  /// True while a private Xvfb started by ensure() is running.
  static bool ownsServer();

  /// Process id of the private Xvfb, or -1.
  static int serverPid();

  /// Stops the private Xvfb now, if there is one, and restores the DISPLAY
  /// value found before it was started. A later ensure() starts a new one.
  static void shutdown();
};

} // namespace caps::render
