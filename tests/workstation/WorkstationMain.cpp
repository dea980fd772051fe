// main() of the workstation tests: one QApplication (with VTK's OpenGL
// format) for all the tests of the process, then GoogleTest.

#include <QApplication>
#include <QSettings>
#include <QSurfaceFormat>
#include <QVTKOpenGLNativeWidget.h>
#include <gtest/gtest.h>

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  QSurfaceFormat::setDefaultFormat(QVTKOpenGLNativeWidget::defaultFormat());
  // The tests' own settings, not the user's (recent files, window layout).
  QApplication::setOrganizationName("CAPS-tests");
  QApplication application(argc, argv);
  QSettings().clear(); // each run starts from the default layout, with no recent files
  return RUN_ALL_TESTS();
}
