// Starts the real workstation on the X display this test runs under (ctest
// runs it inside `xvfb-run -a`), loads the sample CT, saves a screenshot to
// build/test-artifacts/ and checks that it quits cleanly and that the slice
// views show the CT (an empty workstation, as a control, does not pass the
// same check).

#include <cstdlib>
#include <set>

#include <QColor>
#include <QImage>
#include <gtest/gtest.h>

#include "RunProcess.h"
#include "TestPaths.h"
#include "report/DemoScene.h"

namespace fs = std::filesystem;
using caps::test::quoted;

namespace {

caps::test::ProcessResult runWorkstation(const std::string& args)
{
  if (!std::getenv("DISPLAY"))
    ADD_FAILURE() << "No X display: run this test under xvfb-run -a (ctest does).";
  return caps::test::runProcess(quoted(CAPS_EXECUTABLE) + " " + args);
}

struct RegionStats
{
  int greyLevels = 0;        // distinct grey values
  double darkFraction = 0;   // near-black pixels (air around the head)
  double brightFraction = 0; // tissue and bone in the soft-tissue window
};

// Statistics of a rectangle given in fractions of the image size.
RegionStats stats(const QImage& image, double x0, double y0, double x1, double y1)
{
  RegionStats s;
  std::set<int> levels;
  int dark = 0, bright = 0, total = 0;
  for (int y = static_cast<int>(y0 * image.height()); y < static_cast<int>(y1 * image.height()); ++y)
    for (int x = static_cast<int>(x0 * image.width()); x < static_cast<int>(x1 * image.width()); ++x)
    {
      const int g = qGray(image.pixel(x, y));
      levels.insert(g);
      dark += g < 20;
      bright += g > 90;
      ++total;
    }
  s.greyLevels = static_cast<int>(levels.size());
  s.darkFraction = static_cast<double>(dark) / total;
  s.brightFraction = static_cast<double>(bright) / total;
  return s;
}

} // namespace

// The axial view sits top right, the sagittal view bottom right: both show
// CT (many grey levels, air around the head, tissue in the soft-tissue window).
static void expectCtInSliceViews(const QImage& image)
{
  EXPECT_GE(image.width(), 1000);
  for (auto [name, y0, y1] : {std::tuple{"axial", 0.12, 0.5}, std::tuple{"sagittal", 0.55, 0.92}})
  {
    const RegionStats s = stats(image, 0.66, y0, 0.98, y1);
    EXPECT_GT(s.greyLevels, 100) << name;
    EXPECT_GT(s.darkFraction, 0.05) << name;
    EXPECT_GT(s.brightFraction, 0.15) << name;
  }
}

TEST(GuiSmoke, WorkstationShowsTheSampleInTheSliceViews)
{
  const fs::path shot = caps::test::artifacts() / "workstation-sample.png";
  fs::remove(shot);
  const auto r = runWorkstation(quoted(caps::test::sampleCt().string()) + " --screenshot " + quoted(shot.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  ASSERT_FALSE(r.crashed);
  QImage image(QString::fromStdString(shot.string()));
  ASSERT_FALSE(image.isNull()) << "no screenshot at " << shot;
  expectCtInSliceViews(image);
  EXPECT_NE(r.output.find("Loaded 'Neck"), std::string::npos) << r.output;
}

// A scene saved by `caps demo` opens again in the workstation with its CT.
// The demo's run is the ctest fixture's (its exit code checked there), or
// this process's own when run alone, rather than a third run of 40 s here.
TEST(GuiSmoke, SavedSceneReopens)
{
  const fs::path demo = caps::test::reportDemoFolder();
  ASSERT_TRUE(fs::exists(demo / "sample.caps")) << demo;
  const fs::path shot = caps::test::artifacts() / "workstation-scene.png";
  fs::remove(shot);
  const auto r = runWorkstation(quoted((demo / "sample.caps").string()) + " --screenshot " + quoted(shot.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  QImage image(QString::fromStdString(shot.string()));
  ASSERT_FALSE(image.isNull());
  expectCtInSliceViews(image);
  EXPECT_NE(r.output.find("Opened scene"), std::string::npos) << r.output;
}

TEST(GuiSmoke, EmptyWorkstationHasBlankSliceViews)
{
  const fs::path shot = caps::test::artifacts() / "workstation-empty.png";
  fs::remove(shot);
  const auto r = runWorkstation("--screenshot " + quoted(shot.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  QImage image(QString::fromStdString(shot.string()));
  ASSERT_FALSE(image.isNull());
  const RegionStats s = stats(image, 0.66, 0.12, 0.98, 0.5);
  EXPECT_LT(s.brightFraction, 0.05);
}

TEST(GuiSmoke, UnreadableInputIsReportedNotCrashed)
{
  const fs::path folder = caps::test::scratchFolder();
  const fs::path shot = folder / "shot.png";
  const auto r = runWorkstation(quoted(folder.string()) + " --screenshot " + quoted(shot.string()));
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_FALSE(r.crashed);
  EXPECT_NE(r.output.find("No readable DICOM slices"), std::string::npos) << r.output;
}
