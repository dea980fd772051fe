// `caps scan` run as a user would: a coloured PLY of a known surface of
// revolution in, range and colour pictures out that read back to the
// analytic radius; calibration by measured distances recovers the scale the
// "scanner" got wrong; bad input exits with a message.

#include <cmath>
#include <fstream>
#include <numbers>
#include <regex>

#include <gtest/gtest.h>
#include <vtkPLYWriter.h>

#include "app/RunProcess.h"
#include "segmentation/RangeMapImage.h"
#include "segmentation/scans/ScanPhantoms.h"
#include "TestPaths.h"

namespace fs = std::filesystem;
using caps::test::quoted;
using caps::test::runProcess;

namespace {

caps::test::ProcessResult runCaps(const std::string& args)
{
  return runProcess(quoted(CAPS_EXECUTABLE) + " " + args);
}

// An egg of revolution about the z axis through (5, -3, 0): r(z) =
// 80 sqrt(1 - (z/100)^2) for z in [-90, 90], a stand-in for a face scan.
double trueRadius(double z)
{
  return 80.0 * std::sqrt(1.0 - (z / 100.0) * (z / 100.0));
}
const Eigen::Vector3d kAxisPoint(5, -3, 0);

// The scan as a scanner with wrong scale factors would give it: r times sh, z times sv.
fs::path writeScan(const fs::path& folder, double sh, double sv)
{
  const caps::seg::CylindricalFrame f(kAxisPoint, Eigen::Vector3d::UnitZ(), -100, 100);
  auto mesh = caps::seg::test::revolution(
    f, 720, 361, -90.0 * sv, 90.0 * sv, [&](double z) { return sh * trueRadius(z / sv); }, 100.0);
  const fs::path file = folder / "face.ply";
  auto writer = vtkSmartPointer<vtkPLYWriter>::New();
  writer->SetFileName(file.c_str());
  writer->SetInputData(mesh);
  writer->SetArrayName("RGB");
  writer->SetFileTypeToBinary();
  writer->Write();
  return file;
}

} // namespace

TEST(ScanCommand, WritesRangeAndColourPicturesThatReadBack)
{
  const fs::path folder = caps::test::scratchFolder();
  const fs::path ply = writeScan(folder, 1.0, 1.0);
  const fs::path out = folder / "scan";
  const auto r =
    runCaps("scan " + quoted(ply.string()) + " --out " + quoted(out.string()) + " --size 360x90 --axis 5,-3,0,0,0,1");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("coloured"), std::string::npos) << r.output;
  for (const char* file : {"range.png", "colour.png", "range.nrrd", "range-preview.png"})
    EXPECT_TRUE(fs::exists(out / file)) << file;

  // The 16-bit picture carries its frame: r at each sample is the egg's radius
  // (a 720-sided polygon: chord error 80 (1 - cos(pi/720)) < 1e-3 mm; 16-bit steps).
  const caps::seg::RangeMap range = caps::seg::readRangeMapPng((out / "range.png").string());
  const auto& f = range.frame();
  EXPECT_EQ(f.nTheta(), 360);
  EXPECT_EQ(f.nZ(), 90);
  EXPECT_NEAR((f.origin() - kAxisPoint).norm(), 0.0, 1e-6);
  double worst = 0.0;
  for (int j = 0; j < f.nZ(); ++j)
    for (int i = 0; i < f.nTheta(); i += 7)
      worst = std::max(worst, std::abs(range.at(i, j) - trueRadius(f.indexToZ(j))));
  EXPECT_LT(worst, 0.02);
  const caps::seg::ColourMap colour = caps::seg::readColourMapPng((out / "colour.png").string(), f);
  // Colour is linear in the local coordinates (ScanPhantoms.h): at the front
  // (theta = -90 deg, column 90) on the equator, y = -80 mm: green 128 - 96.
  const auto& front = colour.at(90, 45);
  EXPECT_NEAR(front[1], 128.0 - 120.0 * trueRadius(f.indexToZ(45)) / 100.0, 2.0);
}

TEST(ScanCommand, CalibrationByMeasuredDistancesUndoesTheScannersScale)
{
  const double sh = 1.2, sv = 0.85; // what the scanner got wrong
  const fs::path folder = caps::test::scratchFolder();
  const fs::path ply = writeScan(folder, sh, sv);
  // Landmark pairs as located on the (wrong) scan, distances as measured on the
  // patient (the true egg): two across the face, two up and down it.
  struct Mark
  {
    double thetaDeg, z; // true z
  };
  auto truePoint = [](const Mark& m) {
    const double t = m.thetaDeg * std::numbers::pi / 180.0;
    return Eigen::Vector3d(trueRadius(m.z) * std::cos(t), trueRadius(m.z) * std::sin(t), m.z);
  };
  const std::pair<Mark, Mark> pairs[] = {
    {{-120, 10}, {-60, 10}}, {{-110, -30}, {-70, -30}}, {{-90, 40}, {-90, -20}}, {{-100, 20}, {-100, -50}}};
  const char* names[] = {"outer canthi", "mouth width", "nasion-subnasale", "upper face height"};
  const char* classes[] = {"horizontal", "horizontal", "vertical", "vertical"};
  const fs::path csv = folder / "distances.csv";
  {
    std::ofstream file(csv);
    file << "name,direction,from_theta_deg,from_z_mm,to_theta_deg,to_z_mm,measured_mm\n";
    file.precision(17);
    for (int k = 0; k < 4; ++k)
      file << names[k] << "," << classes[k] << "," << pairs[k].first.thetaDeg << "," << pairs[k].first.z * sv << ","
           << pairs[k].second.thetaDeg << "," << pairs[k].second.z * sv << ","
           << (truePoint(pairs[k].first) - truePoint(pairs[k].second)).norm() << "\n";
  }
  const fs::path out = folder / "scan";
  const auto r = runCaps("scan " + quoted(ply.string()) + " --out " + quoted(out.string()) +
                         " --size 720x180 --axis 5,-3,0,0,0,1 --calibrate " + quoted(csv.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("horizontal ([0-9.]+), vertical ([0-9.]+);"))) << r.output;
  EXPECT_NEAR(std::stod(m[1]), 1.0 / sh, 2e-3) << r.output;
  EXPECT_NEAR(std::stod(m[2]), 1.0 / sv, 2e-3) << r.output;
  EXPECT_NE(r.output.find("upper face height"), std::string::npos) << r.output;

  // The written maps are calibrated: the true egg again.
  const caps::seg::RangeMap range = caps::seg::readRangeMapPng((out / "range.png").string());
  for (double z : {-60.0, 0.0, 45.0})
    EXPECT_NEAR(range.sample(-std::numbers::pi / 2, z), trueRadius(z), 0.15) << z;
}

TEST(ScanCommand, BadInput)
{
  const fs::path folder = caps::test::scratchFolder();
  const fs::path text = folder / "notes.ply";
  std::ofstream(text) << "this is not a mesh\n";
  auto r = runCaps("scan " + quoted(text.string()) + " --out " + quoted((folder / "o").string()));
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_FALSE(r.crashed);
  EXPECT_NE(r.output.find("caps scan: "), std::string::npos) << r.output;

  r = runCaps("scan");
  EXPECT_EQ(r.exitCode, 2) << r.output;
  EXPECT_NE(r.output.find("MESH missing"), std::string::npos) << r.output;
  r = runCaps("scan a.ply");
  EXPECT_EQ(r.exitCode, 2) << r.output;
  r = runCaps("scan a.ply --out x --axis 1,2,3");
  EXPECT_EQ(r.exitCode, 2) << r.output;
  r = runCaps("scan a.ply --out x --size 3x3");
  EXPECT_EQ(r.exitCode, 2) << r.output;

  // A distances file with a wrong class stops before any work, naming the line.
  const fs::path ply = writeScan(folder, 1.0, 1.0);
  std::ofstream(folder / "d.csv") << "name,direction,from_theta_deg,from_z_mm,to_theta_deg,to_z_mm,measured_mm\n"
                                  << "mouth,sideways,-110,-30,-70,-30,50\n";
  r = runCaps("scan " + quoted(ply.string()) + " --out " + quoted((folder / "o").string()) + " --calibrate " +
              quoted((folder / "d.csv").string()));
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("line 2"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("horizontal or vertical"), std::string::npos) << r.output;
  // Only horizontal distances: the vertical factor is not determined.
  std::ofstream(folder / "h.csv") << "name,direction,from_theta_deg,from_z_mm,to_theta_deg,to_z_mm,measured_mm\n"
                                  << "mouth,horizontal,-110,-30,-70,-30,50\n";
  r = runCaps("scan " + quoted(ply.string()) + " --out " + quoted((folder / "o").string()) + " --calibrate " +
              quoted((folder / "h.csv").string()));
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_FALSE(r.crashed);
}
