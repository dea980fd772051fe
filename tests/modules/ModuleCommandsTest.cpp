// `caps segment` and `caps rangemap` run as a user would, on a synthetic head
// CT written as NRRD (fast; the sample CT is covered by SampleThicknessTest
// and `caps demo`): files written, NRRD headers, PNG sizes, exit codes.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkMath.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include "HeadPhantom.h"
#include "app/RunProcess.h"
#include "scene/NrrdIO.h"
#include "segmentation/Landmarks.h"
#include "TestPaths.h"

namespace fs = std::filesystem;
using caps::test::quoted;
using caps::test::runProcess;

namespace {

caps::test::ProcessResult runCaps(const std::string& args)
{
  return runProcess(quoted(CAPS_EXECUTABLE) + " " + args);
}

// The phantom CT as a NRRD file in the test's scratch folder.
fs::path phantomCt(const fs::path& folder)
{
  const fs::path file = folder / "phantom-ct.nrrd";
  caps::NrrdIO::writeImage(caps::test::HeadPhantom::instance().images.ct, file);
  return file;
}

// The text header of a NRRD file (up to the blank line).
std::string nrrdHeader(const fs::path& file)
{
  std::ifstream in(file, std::ios::binary);
  std::string header, line;
  while (std::getline(in, line) && !line.empty())
    header += line + "\n";
  return header;
}

std::string fileText(const fs::path& file)
{
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::array<int, 2> pngSize(const fs::path& file)
{
  auto reader = vtkSmartPointer<vtkPNGReader>::New();
  reader->SetFileName(file.c_str());
  reader->Update();
  int dims[3] = {0, 0, 0};
  reader->GetOutput()->GetDimensions(dims);
  return {dims[0], dims[1]};
}

} // namespace

TEST(ModuleCommands, SegmentWritesLabelsAndSurfaces)
{
  const fs::path folder = caps::test::scratchFolder();
  const fs::path ct = phantomCt(folder);
  const fs::path out = folder / "segment";
  const auto r = runCaps("segment " + quoted(ct.string()) + " --out " + quoted(out.string()) +
                         " --skin-threshold -480 --bone-threshold 520");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("(skin -480.0 HU, bone 520.0 HU)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("cm3"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("cm2"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Segmentation notes:"), std::string::npos) << r.output;
  for (const char* file : {"labels.nrrd", "skin.vtp", "bone.vtp", "skin.stl", "bone.stl"})
  {
    EXPECT_TRUE(fs::exists(out / file)) << file;
    EXPECT_GT(fs::file_size(out / file), 1000u) << file;
  }
  // The label map: 3D unsigned char on the CT's grid, in LPS.
  const std::string header = nrrdHeader(out / "labels.nrrd");
  EXPECT_NE(header.find("NRRD000"), std::string::npos) << header;
  EXPECT_NE(header.find("dimension: 3"), std::string::npos) << header;
  EXPECT_NE(header.find("type: unsigned char"), std::string::npos) << header;
  EXPECT_NE(header.find("space: left-posterior-superior"), std::string::npos) << header;
  int dims[3];
  caps::test::HeadPhantom::instance().images.ct->GetDimensions(dims);
  EXPECT_NE(
    header.find("sizes: " + std::to_string(dims[0]) + " " + std::to_string(dims[1]) + " " + std::to_string(dims[2])),
    std::string::npos)
    << header;
  const auto labels = caps::NrrdIO::readImage(out / "labels.nrrd");
  double range[2];
  labels->GetScalarRange(range);
  EXPECT_EQ(range[0], 0.0);
  EXPECT_EQ(range[1], 2.0);
  // Binary STL: 84 bytes of header and count, 50 bytes per triangle.
  std::ifstream stl(out / "skin.stl", std::ios::binary);
  char head[80];
  std::uint32_t triangles = 0;
  stl.read(head, 80);
  stl.read(reinterpret_cast<char*>(&triangles), 4);
  EXPECT_GT(triangles, 10000u);
  EXPECT_EQ(fs::file_size(out / "skin.stl"), 84u + 50u * triangles);
}

TEST(ModuleCommands, SegmentWithoutSurfaceFiles)
{
  const fs::path folder = caps::test::scratchFolder();
  const fs::path ct = phantomCt(folder);
  const fs::path out = folder / "out";
  auto r = runCaps("segment " + quoted(ct.string()) + " --out " + quoted(out.string()) + " --surfaces none");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_TRUE(fs::exists(out / "labels.nrrd"));
  for (const char* file : {"skin.vtp", "bone.vtp", "skin.stl", "bone.stl"})
    EXPECT_FALSE(fs::exists(out / file)) << file;
  r = runCaps("segment " + quoted(ct.string()) + " --out " + quoted(out.string()) + " --surfaces obj");
  EXPECT_EQ(r.exitCode, 2) << r.output;
}

TEST(ModuleCommands, RangeMapWritesMapsAndPreviews)
{
  const fs::path folder = caps::test::scratchFolder();
  const fs::path ct = phantomCt(folder);
  const fs::path out = folder / "rangemap";
  const auto r =
    runCaps("rangemap " + quoted(ct.string()) + " --out " + quoted(out.string()) + " --size 360x120 --smooth");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("360 x 120, smoothed"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Axis: through"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("radial r_skin - r_bone"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("along the skin normal"), std::string::npos) << r.output;
  for (const char* file : {"skin-range.nrrd", "bone-range.nrrd", "thickness.nrrd", "thickness-normal.nrrd"})
  {
    ASSERT_TRUE(fs::exists(out / file)) << file;
    const std::string header = nrrdHeader(out / file);
    EXPECT_NE(header.find("dimension: 2"), std::string::npos) << file << "\n" << header;
    EXPECT_NE(header.find("type: float"), std::string::npos) << file << "\n" << header;
    EXPECT_NE(header.find("sizes: 360 120"), std::string::npos) << file << "\n" << header;
    const Eigen::MatrixXf m = caps::NrrdIO::readMatrix(out / file);
    EXPECT_EQ(m.rows(), 360);
    EXPECT_EQ(m.cols(), 120);
  }
  // Thickness on the phantom's equator is 8..16 mm (8 on the axes).
  const Eigen::MatrixXf t = caps::NrrdIO::readMatrix(out / "thickness.nrrd");
  EXPECT_NEAR(t(90, 60), 8.0 + 0.0, 1.0); // θ = -π/2: the front, 8 mm along y
  for (const char* file : {"skin-range.png", "thickness.png", "thickness-normal.png"})
  {
    ASSERT_TRUE(fs::exists(out / file)) << file;
    const auto size = pngSize(out / file);
    // 2 pixels per sample plus the margins for the text and the colour bar.
    EXPECT_GT(size[0], 2 * 360) << file;
    EXPECT_LT(size[0], 2 * 360 + 300) << file;
    EXPECT_GT(size[1], 2 * 120) << file;
    EXPECT_LT(size[1], 2 * 120 + 200) << file;
  }
}

// The axis set by hand (off the head's centre) and landmarks from the user's
// CSV, one placed by its world point, one by (theta, z): the thickness under
// each is the phantom's along the ray from that axis.
TEST(ModuleCommands, RangeMapWithTheUsersAxisAndLandmarks)
{
  const auto& phantom = caps::test::HeadPhantom::instance();
  const fs::path folder = caps::test::scratchFolder();
  const fs::path ct = phantomCt(folder);
  const fs::path out = folder / "rangemap";
  const Eigen::Vector3d axisPoint = phantom.centre + Eigen::Vector3d(20, 0, 0);
  const Eigen::Vector3d front = phantom.centre - Eigen::Vector3d(0, phantom.skinB, 0); // on the skin
  const fs::path landmarks = folder / "mine.csv";
  std::ofstream(landmarks) << "name,theta_deg,z_mm,x,y,z,radial_mm,normal_mm\n"
                           << "front_point,0,0," << front.x() << "," << front.y() << "," << front.z() << ",,\n"
                           << "front_ray,-90,0,,,,,\n";
  std::ostringstream axis;
  axis << axisPoint.x() << "," << axisPoint.y() << "," << axisPoint.z() << ",0,0,-1";
  const auto r = runCaps("rangemap " + quoted(ct.string()) + " --out " + quoted(out.string()) + " --axis " +
                         axis.str() + " --landmarks " + quoted(landmarks.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("set by the user"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("direction (0.000, 0.000, 1.000)"), std::string::npos) << "the axis points superior\n"
                                                                                 << r.output;
  EXPECT_NE(r.output.find("landmarks of"), std::string::npos) << r.output;

  // rangemap segments with the default thresholds (-400, 250 HU), not the
  // phantom's mid-step ones: its bone comes out about 1 mm thicker, hence 1.5 mm.
  constexpr double tolerance = 1.5;
  const auto rows = caps::seg::readLandmarkCsv(out / "landmarks.csv");
  ASSERT_EQ(rows.size(), 2u);
  // By world point: theta is where the point lies seen from the user's axis.
  const Eigen::Vector3d toFront = front - axisPoint;
  EXPECT_EQ(rows[0].landmark.name, "front_point");
  EXPECT_NEAR(rows[0].landmark.theta, std::atan2(toFront.y(), toFront.x()), 1e-9);
  EXPECT_NEAR(rows[0].landmark.z, 0.0, 1e-9);
  EXPECT_NEAR(rows[0].radial, phantom.radialThickness(axisPoint, toFront.normalized()), tolerance);
  // By (theta, z): straight to the front from the axis point.
  EXPECT_EQ(rows[1].landmark.name, "front_ray");
  EXPECT_NEAR(rows[1].radial, phantom.radialThickness(axisPoint, -Eigen::Vector3d::UnitY()), tolerance);
  EXPECT_NEAR((rows[1].position -
               (axisPoint - phantom.skin.outermostHit(axisPoint, -Eigen::Vector3d::UnitY()) * Eigen::Vector3d::UnitY()))
                .norm(),
              0.0, 1.0);

  // A landmark file that cannot be read stops the command before the long part.
  std::ofstream(folder / "bad.csv") << "name,theta\nnasion,3\n";
  const auto bad = runCaps("rangemap " + quoted(ct.string()) + " --out " + quoted(out.string()) + " --landmarks " +
                           quoted((folder / "bad.csv").string()));
  EXPECT_EQ(bad.exitCode, 1) << bad.output;
  EXPECT_NE(bad.output.find("bad.csv"), std::string::npos) << bad.output;
  EXPECT_EQ(bad.output.find("Range maps of"), std::string::npos) << bad.output;
}

namespace {

// Every component of a point-data (or, with @a cells, cell-data) array of a
// VTU file, read back with VTK.
std::vector<double> vtuArray(const fs::path& file, const char* name, bool cells = false)
{
  auto reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
  reader->SetFileName(file.c_str());
  reader->Update();
  vtkDataArray* array =
    cells ? reader->GetOutput()->GetCellData()->GetArray(name) : reader->GetOutput()->GetPointData()->GetArray(name);
  std::vector<double> values;
  if (!array)
    return values;
  for (vtkIdType t = 0; t < array->GetNumberOfTuples(); ++t)
    for (int c = 0; c < array->GetNumberOfComponents(); ++c)
      values.push_back(array->GetComponent(t, c));
  return values;
}

} // namespace

// `caps plan` end to end on the phantom head: an elliptical excision on the
// front closes (its sutures meet) and the files are written; usage errors.
TEST(ModuleCommands, PlanClosesAnExcisionOnThePhantom)
{
  const fs::path folder = caps::test::scratchFolder();
  const fs::path ct = phantomCt(folder);
  const fs::path out = folder / "plan";
  auto r = runCaps("plan " + quoted(ct.string()) + " --procedure elliptical-excision --at -90,0 --param length=20 " +
                   "--element-size 2.5 --cut-depth 3 --out " + quoted(out.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(
    std::regex_search(r.output, m, std::regex("Wound ([0-9.]+) mm wide before, sutures within ([0-9.e+-]+) mm")))
    << r.output;
  EXPECT_GT(std::stod(m[1]), 2.0) << r.output;  // the excision is open before
  EXPECT_LT(std::stod(m[2]), 1e-9) << r.output; // and closed after
  for (const char* file : {"measurements.csv", "skin-before.vtp", "skin-after.vtp", "model.vtu"})
    EXPECT_TRUE(fs::exists(out / file)) << file;
  // model.vtu holds each element's layer and shape, as plan.json counts them.
  const nlohmann::json check = nlohmann::json::parse(fileText(out / "plan.json"))["prediction"];
  const std::vector<double> layer = vtuArray(out / "model.vtu", "tissue_layer", true);
  const std::vector<double> jacobian = vtuArray(out / "model.vtu", "scaled_jacobian", true);
  const std::vector<double> edgeRatio = vtuArray(out / "model.vtu", "edge_ratio", true);
  ASSERT_EQ(jacobian.size(), std::size_t(check["meshElements"].get<int>()));
  ASSERT_EQ(edgeRatio.size(), jacobian.size());
  ASSERT_EQ(layer.size(), jacobian.size());
  EXPECT_EQ(*std::min_element(layer.begin(), layer.end()), 1.0);
  EXPECT_EQ(*std::max_element(layer.begin(), layer.end()), 3.0);
  EXPECT_EQ(std::count_if(jacobian.begin(), jacobian.end(), [](double q) { return q < 0.2; }),
            check["meshElementsBelowScaledJacobianLimit"].get<long>());
  EXPECT_EQ(std::count_if(edgeRatio.begin(), edgeRatio.end(), [](double q) { return q > 10.0; }),
            check["meshElementsAboveEdgeRatioLimit"].get<long>());
  EXPECT_DOUBLE_EQ(*std::min_element(jacobian.begin(), jacobian.end()), check["meshMinScaledJacobian"].get<double>());
  // The edge ratio again from the file's own points: longest over shortest
  // corner edge (12 of a brick, 9 of a wedge; a collapsed one left out).
  auto reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
  reader->SetFileName((out / "model.vtu").c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  ASSERT_EQ(std::size_t(grid->GetNumberOfCells()), edgeRatio.size());
  const int brickEdges[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                 {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  const int wedgeEdges[9][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {0, 3}, {1, 4}, {2, 5}};
  for (vtkIdType c = 0; c < grid->GetNumberOfCells(); ++c)
  {
    const bool brick = grid->GetCellType(c) == VTK_QUADRATIC_HEXAHEDRON;
    ASSERT_TRUE(brick || grid->GetCellType(c) == VTK_QUADRATIC_WEDGE) << "cell " << c;
    vtkIdType count = 0;
    const vtkIdType* ids = nullptr;
    grid->GetCellPoints(c, count, ids);
    double shortest = 1e300, longest = 0.0;
    for (int e = 0; e < (brick ? 12 : 9); ++e)
    {
      const int* edge = brick ? brickEdges[e] : wedgeEdges[e];
      double a[3], b[3];
      grid->GetPoint(ids[edge[0]], a);
      grid->GetPoint(ids[edge[1]], b);
      const double length = std::sqrt(vtkMath::Distance2BetweenPoints(a, b));
      if (length > 0.0)
        shortest = std::min(shortest, length), longest = std::max(longest, length);
    }
    EXPECT_NEAR(edgeRatio[std::size_t(c)], longest / shortest, 1e-9 * longest / shortest) << "cell " << c;
  }
  std::ifstream csv(out / "measurements.csv");
  const std::string text((std::istreambuf_iterator<char>(csv)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("excised area,hole,,"), std::string::npos) << text;
  // The excised volume from the elements of the excised tissue (full
  // thickness here) and, as a second method, the range maps' integral.
  auto csvValue = [](const std::string& csvText, const std::string& quantity) {
    const auto at = csvText.find(quantity + ",");
    if (at == std::string::npos)
      return std::nan("");
    std::stringstream line(csvText.substr(at, csvText.find('\n', at) - at));
    std::string cell;
    for (int i = 0; i < 4; ++i)
      std::getline(line, cell, ',');
    return std::stod(cell);
  };
  const double excisedFull = csvValue(text, "excised volume (elements; cut through 3 of 3 layers)");
  const double excisedMaps = csvValue(text, "excised volume to the bone (range maps)");
  EXPECT_GT(excisedFull, 0.0) << text;
  EXPECT_NEAR(excisedFull, excisedMaps, 0.05 * excisedMaps) << text;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("Closure force: ([0-9.]+) N over all sutures"))) << r.output;
  EXPECT_GT(std::stod(m[1]), 0.0) << r.output;
  // The peak skin stress near the wound: printed in kPa with where, and in the table.
  ASSERT_TRUE(std::regex_search(
    r.output, m,
    std::regex("Skin stress within 10.0 mm of the wound: peak von Mises ([0-9.]+) kPa at theta ([0-9.+-]+) deg, z "
               "([0-9.+-]+) mm \\(([0-9.]+) mm from the wound edge\\)")))
    << r.output;
  const double peakKpa = std::stod(m[1]);
  EXPECT_GT(peakKpa, 0.0) << r.output;
  EXPECT_LE(std::stod(m[4]), 10.0) << r.output;
  EXPECT_NEAR(std::stod(m[2]), -90.0, 30.0) << r.output; // on the front, near the plan
  EXPECT_NE(text.find("peak skin von Mises near wound,skin within 10 mm of the wound,,"), std::string::npos) << text;
  EXPECT_NE(text.find("mean skin von Mises near wound,"), std::string::npos) << text;
  // The ellipse undermines its own band unless told otherwise, and the freed tissue slides on the deep plane.
  std::smatch u;
  ASSERT_TRUE(std::regex_search(r.output, u,
                                std::regex("Undermined: ([0-9.]+) mm band along the sutured edges \\(the procedure's "
                                           "default\\); ([0-9]+) deep nodes freed, ([0-9]+) of them sliding")))
    << r.output;
  EXPECT_NEAR(std::stod(u[1]), 7.0, 1e-9) << r.output;
  EXPECT_GT(std::stoi(u[3]), 0) << r.output;
  EXPECT_LE(std::stoi(u[3]), std::stoi(u[2])) << r.output;

  // A cut through the skin layer only (§3.2.2: cutting to a depth): less
  // tissue removed, the depth kept in plan.json and replayed the same.
  const fs::path shallow = folder / "shallow", shallowAgain = folder / "shallow-replay";
  r = runCaps("plan " + quoted(ct.string()) + " --procedure elliptical-excision --at -90,0 --param length=20 " +
              "--element-size 2.5 --cut-depth 1 --out " + quoted(shallow.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("cut through 1 of 3 tissue layers"), std::string::npos) << r.output;
  const std::string shallowText = fileText(shallow / "measurements.csv");
  const double excisedShallow = csvValue(shallowText, "excised volume (elements; cut through 1 of 3 layers)");
  EXPECT_GT(excisedShallow, 0.2 * excisedFull) << shallowText;
  EXPECT_LT(excisedShallow, 0.5 * excisedFull) << shallowText;
  EXPECT_EQ(nlohmann::json::parse(fileText(shallow / "plan.json"))["simulation"]["cutLayers"], 1);
  // Left to the procedure, the ellipse is cut through the skin and the fat
  // (its file's depth = fascia) and plan.json records no depth of its own.
  const fs::path ownDepth = folder / "own-depth";
  r = runCaps("plan " + quoted(ct.string()) + " --procedure elliptical-excision --at -90,0 --param length=20 " +
              "--element-size 2.5 --out " + quoted(ownDepth.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("cut through 2 of 3 tissue layers (the procedure's depth)"), std::string::npos) << r.output;
  const double excisedOwn =
    csvValue(fileText(ownDepth / "measurements.csv"), "excised volume (elements; cut through 2 of 3 layers)");
  EXPECT_GT(excisedOwn, excisedShallow);
  EXPECT_LT(excisedOwn, excisedFull);
  EXPECT_FALSE(nlohmann::json::parse(fileText(ownDepth / "plan.json"))["simulation"].contains("cutLayers"));
  r = runCaps("plan " + quoted(ct.string()) + " --replay " + quoted((shallow / "plan.json").string()) + " --out " +
              quoted(shallowAgain.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_EQ(fileText(shallowAgain / "measurements.csv"), shallowText);
  EXPECT_EQ(runCaps("plan " + quoted(ct.string()) + " --procedure elliptical-excision --at -90,0 --cut-depth 4 " +
                    "--out " + quoted(shallow.string()))
              .exitCode,
            2);

  // The undermining study: one row per width, the force falls as the band widens.
  const fs::path study = folder / "undermined";
  r = runCaps("plan " + quoted(ct.string()) + " --procedure elliptical-excision --at -90,0 --param length=20 " +
              "--element-size 2.5 --cut-depth 3 --undermine 0,7 --out " + quoted(study.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  std::ifstream rows(study / "undermining.csv");
  std::string header, line;
  std::getline(rows, header);
  std::vector<std::vector<double>> table;
  while (std::getline(rows, line))
  {
    std::vector<double> row;
    std::stringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');)
      row.push_back(std::stod(cell));
    table.push_back(row);
  }
  ASSERT_EQ(table.size(), 2u) << header;
  ASSERT_EQ(table[0].size(), 7u);
  ASSERT_EQ(table[1].size(), 7u);
  EXPECT_NE(header.find(",peak skin von Mises near wound (kPa)"), std::string::npos) << header;
  EXPECT_EQ(table[0][0], 0.0);
  EXPECT_EQ(table[0][1], 0.0); // no bone node released without undermining
  EXPECT_GT(table[1][1], 0.0);
  EXPECT_GT(table[0][2], table[1][2]) << r.output;
  EXPECT_LT(table[1][4], 1e-9);
  // The study's 7 mm row is the plain run (same plan, same mesh, the
  // procedure's own band: 0.35 x the 20 mm length).
  EXPECT_GT(table[0][5], 0.0);
  EXPECT_GT(table[1][5], 0.0);
  for (const auto& row : table) // the band's mean is below its peak
  {
    EXPECT_GT(row[6], 0.0);
    EXPECT_LT(row[6], row[5]);
  }
  EXPECT_NEAR(table[1][5], peakKpa, 0.051 + 1e-3 * peakKpa) << r.output;
  // And the plot of both against the width.
  ASSERT_TRUE(fs::exists(study / "undermining.png")) << r.output;
  {
    std::ifstream png(study / "undermining.png", std::ios::binary);
    char signature[8] = {};
    png.read(signature, 8);
    EXPECT_EQ(std::string(signature, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  }
  EXPECT_EQ(pngSize(study / "undermining.png"), (std::array<int, 2>{1000, 600}));
  EXPECT_NE(r.output.find("wrote " + (study / "undermining.png").string()), std::string::npos) << r.output;
  EXPECT_EQ(runCaps("plan " + quoted(ct.string()) + " --procedure elliptical-excision --at -90,0 --undermine 5,-1 " +
                    "--out " + quoted(study.string()))
              .exitCode,
            2);

  r = runCaps("plan " + quoted(ct.string()) + " --procedure face-lift --at -90,0 --out " + quoted(out.string()));
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("z-plasty"), std::string::npos) << "lists the procedures there are\n" << r.output;
  EXPECT_EQ(r.output.find("Reading"), std::string::npos) << "stops before reading the CT\n" << r.output;
  r = runCaps("plan " + quoted(ct.string()) + " --procedure z-plasty --out " + quoted(out.string()));
  EXPECT_EQ(r.exitCode, 2) << r.output;
  EXPECT_NE(r.output.find("--at THETA,Z missing"), std::string::npos) << r.output;
  r = runCaps("plan " + quoted(ct.string()) + " --procedure z-plasty --at -90,0 --param limb_angle=150 --out " +
              quoted(out.string()));
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_FALSE(r.crashed);
}

TEST(ModuleCommands, BadInputAndUsage)
{
  const fs::path folder = caps::test::scratchFolder();
  const fs::path text = folder / "report.txt";
  std::ofstream(text) << "Operative report: not an image.\n";
  for (const char* command : {"segment", "rangemap"})
  {
    const std::string name = command;
    auto r = runCaps(name + " " + quoted(text.string()) + " --out " + quoted((folder / "o").string()));
    EXPECT_EQ(r.exitCode, 1) << name << ": " << r.output;
    EXPECT_FALSE(r.crashed);
    EXPECT_NE(r.output.find("caps " + name + ": "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("is not an image CAPS can read"), std::string::npos) << r.output;

    r = runCaps(name + " " + quoted((folder / "missing").string()) + " --out " + quoted((folder / "o").string()));
    EXPECT_EQ(r.exitCode, 1) << name << ": " << r.output;

    r = runCaps(name + " " + quoted(text.string()));
    EXPECT_EQ(r.exitCode, 2) << name << ": " << r.output;
    EXPECT_NE(r.output.find("--out DIR missing"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("usage: caps " + name), std::string::npos) << r.output;

    r = runCaps(name);
    EXPECT_EQ(r.exitCode, 2) << name << ": " << r.output;
    EXPECT_NE(r.output.find("CT missing"), std::string::npos) << r.output;

    r = runCaps(name + " --help");
    EXPECT_EQ(r.exitCode, 0) << name << ": " << r.output;
    EXPECT_NE(r.output.find("usage: caps " + name), std::string::npos) << r.output;

    r = runCaps(name + " a b --out x");
    EXPECT_EQ(r.exitCode, 2) << name << ": " << r.output;
    r = runCaps(name + " a --frobnicate --out x");
    EXPECT_EQ(r.exitCode, 2) << name << ": " << r.output;
  }
  auto r = runCaps("segment x --out y --skin-threshold soft");
  EXPECT_EQ(r.exitCode, 2) << r.output;
  EXPECT_NE(r.output.find("--skin-threshold needs a number"), std::string::npos) << r.output;
  r = runCaps("segment x --out y --skin-threshold 300 --bone-threshold 200");
  EXPECT_EQ(r.exitCode, 2) << r.output;
  for (const char* size : {"512", "512x", "3x3", "512x256x2", "ax256"})
  {
    r = runCaps(std::string("rangemap x --out y --size ") + size);
    EXPECT_EQ(r.exitCode, 2) << size << ": " << r.output;
    EXPECT_NE(r.output.find("--size needs"), std::string::npos) << r.output;
  }
  for (const char* axis : {"1,2,3", "1,2,3,0,0,0", "1,2,3,0,0,1,5", "a,b,c,d,e,f", "1,2,nan,0,0,1"})
  {
    r = runCaps(std::string("rangemap x --out y --axis ") + axis);
    EXPECT_EQ(r.exitCode, 2) << axis << ": " << r.output;
    EXPECT_NE(r.output.find("--axis needs"), std::string::npos) << r.output;
  }
  // The output folder cannot be made (a file is in the way): exit 1, said so.
  r = runCaps("rangemap " + quoted(text.string()) + " --out " + quoted((text / "sub").string()));
  EXPECT_EQ(r.exitCode, 1) << r.output;
}

// A plan saved as the operations that made it, replayed on
// the same CT, predicts the same displacements bit for bit; on a CT that
// differs by one voxel it is refused.
// A cut through the CT slices that a filling's streaks spoil is refused
// before anything is solved or saved, saying where and what to do. (The
// same Z-plasty at the same place on the phantom without the filling is
// PlanRefusesBadPlansAndBadReplayFiles's accepted one.)
TEST(ModuleCommands, PlanRefusesACutThroughMetalStreaks)
{
  const fs::path folder = caps::test::scratchFolder();
  const caps::test::HeadPhantom& phantom = caps::test::HeadPhantom::instance();
  const fs::path ct = folder / "phantom-with-metal.nrrd";
  caps::NrrdIO::writeImage(phantom.withFilling(phantom.centre + Eigen::Vector3d(0.0, -40.0, 0.0)), ct);
  const fs::path out = folder / "out";
  const auto r = runCaps("plan " + quoted(ct.string()) + " --procedure z-plasty --at -90,0 --param central_length=16 " +
                         "--out " + quoted(out.string()));
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("The plan cannot be cut where it is: the cut runs through skin"), std::string::npos)
    << r.output;
  EXPECT_NE(r.output.find("in CT slices that streaks spoil: metal"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Place the plan away from those slices"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / "plan.json"));
  EXPECT_FALSE(fs::exists(out / "model.vtu"));
}

TEST(ModuleCommands, PlanReplaysToTheSamePredictionBitForBit)
{
  const fs::path folder = caps::test::scratchFolder();
  const fs::path ct = phantomCt(folder);
  const fs::path first = folder / "plan", again = folder / "replay";
  // A Z-plasty on the front of the face, its p2 moved 1 mm up and p1's
  // left side opened 0.7 mm into the flap (an excision).
  auto r = runCaps("plan " + quoted(ct.string()) + " --procedure z-plasty --at -90,0 --param central_length=16 " +
                   "--move 2=-84,1 --offset 1=0.6,0.35 --element-size 2.5 --out " + quoted(first.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("3 operations"), std::string::npos) << r.output;
  const auto recipe = nlohmann::json::parse(fileText(first / "plan.json"));
  ASSERT_EQ(recipe["operations"].size(), 3u) << recipe.dump(2);
  EXPECT_EQ(recipe["operations"][1]["operation"], "move") << recipe.dump(2);
  EXPECT_EQ(recipe["operations"][2]["operation"], "offset") << recipe.dump(2);
  EXPECT_EQ(recipe["ctSha256"].get<std::string>().size(), 64u) << recipe.dump(2);
  EXPECT_EQ(recipe["simulation"]["elementSize"], 2.5) << recipe.dump(2);

  r = runCaps("plan " + quoted(ct.string()) + " --replay " + quoted((first / "plan.json").string()) + " --out " +
              quoted(again.string()));
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("Replayed 3 operations"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("warning"), std::string::npos) << "same CT, same CAPS\n" << r.output;
  EXPECT_EQ(fileText(again / "measurements.csv"), fileText(first / "measurements.csv"));
  EXPECT_EQ(fileText(again / "plan.json"), fileText(first / "plan.json"));
  const auto u = vtuArray(first / "model.vtu", "displacement_mm");
  const auto v = vtuArray(again / "model.vtu", "displacement_mm");
  ASSERT_FALSE(u.empty());
  ASSERT_EQ(u.size(), v.size());
  EXPECT_EQ(std::memcmp(u.data(), v.data(), u.size() * sizeof(double)), 0);
  double largest = 0.0;
  for (double d : u)
    largest = std::max(largest, std::abs(d));
  EXPECT_GT(largest, 0.5); // the wound closed: not a trivial match

  // The same head with one voxel changed is another scan: refused before the long part.
  auto changed = vtkSmartPointer<vtkImageData>::New();
  changed->DeepCopy(caps::test::HeadPhantom::instance().images.ct);
  vtkDataArray* voxels = changed->GetPointData()->GetScalars();
  voxels->SetComponent(1000, 0, voxels->GetComponent(1000, 0) + 1.0);
  const fs::path otherCt = folder / "other-ct.nrrd";
  caps::NrrdIO::writeImage(changed, otherCt);
  r = runCaps("plan " + quoted(otherCt.string()) + " --replay " + quoted((first / "plan.json").string()) + " --out " +
              quoted((folder / "other").string()));
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("was made on a CT of SHA-256 " + recipe["ctSha256"].get<std::string>() + ", not on this CT"),
            std::string::npos)
    << r.output;
  EXPECT_NE(r.output.find("give --other-ct"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(folder / "other" / "model.vtu"));
}

TEST(ModuleCommands, PlanRefusesBadPlansAndBadReplayFiles)
{
  const fs::path folder = caps::test::scratchFolder();
  const fs::path ct = phantomCt(folder);
  const std::string out = " --out " + quoted((folder / "out").string());
  const auto replay = [&](const std::string& name, const std::string& text) {
    std::ofstream(folder / name) << text;
    return runCaps("plan " + quoted(ct.string()) + " --replay " + quoted((folder / name).string()) + out);
  };
  // Files that are not plans: refused before the CT is read.
  auto r = replay("notes.json", "Z-plasty, left cheek, 60 degrees");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("notes.json is not a plan file: it is not JSON"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("Reading"), std::string::npos) << "stops before reading the CT\n" << r.output;
  const std::string head = R"({"format": "caps-plan", "formatVersion": 1, "softwareVersion": "0.0.1", )"
                           R"("ctSha256": ")" +
                           std::string(64, 'a') + R"(", "operations": [)";
  const std::string placeZ = R"({"operation": "place", "procedure": "z-plasty", "theta": -1.5707963267948966, )"
                             R"("z": 0, "values": {"central_length": 16}})";
  r = replay("rotate.json", head + placeZ + R"(, {"operation": "rotate", "degrees": 15}]})");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("operation 2 is 'rotate', which this CAPS does not know"), std::string::npos) << r.output;
  r = replay("face-lift.json", head + R"({"operation": "place", "procedure": "face-lift", "theta": 0, "z": 0, )"
                                      R"("values": {}}]})");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("there is no procedure 'face-lift' (there are: "), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("Reading"), std::string::npos) << r.output;

  // Another CT (the hash in the file is not this phantom's): refused, or
  // replayed with warnings under --other-ct.
  r = replay("z.json", head + placeZ + "]}");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("another scan or another patient"), std::string::npos) << r.output;
  r = runCaps("plan " + quoted(ct.string()) + " --replay " + quoted((folder / "z.json").string()) +
              " --other-ct --element-size 3" + out);
  EXPECT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("warning: " + (folder / "z.json").string() + " was made on a CT of SHA-256 aaaa"),
            std::string::npos)
    << r.output;
  EXPECT_NE(r.output.find("was made by CAPS 0.0.1, this is CAPS "), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(folder / "out" / "model.vtu"));

  // A move that makes the Z's limbs cross: p3 (below-left of p2) taken up
  // through the first limb.
  r = runCaps("plan " + quoted(ct.string()) + " --procedure z-plasty --at -90,0 --param central_length=16 " +
              "--move 3=-96,8" + out);
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("operation 2 (move cut point 3): limb 0 (cut points 0–1) crosses limb 2"), std::string::npos)
    << r.output;
  // A procedure file with inconsistent sutures (a copy of the Z whose third
  // suture sews edge (2,3) again), in a data folder of its own: left out of
  // the library, and the message names the file, the line and the fault.
  const fs::path data = folder / "data";
  fs::create_directories(data / "procedures");
  std::ifstream shipped(fs::path(CAPS_TEST_DATA_DIR) / "procedures" / "z-plasty.procedure");
  std::string text((std::istreambuf_iterator<char>(shipped)), std::istreambuf_iterator<char>());
  text.replace(text.find("procedure = z-plasty"), 20, "procedure = lopsided-z");
  text.replace(text.find("suture = ((0,1),(3,4))"), 22, "suture = ((0,1),(2,3))");
  std::ofstream(data / "procedures" / "lopsided-z.procedure") << text;
  r = runProcess("CAPS_DATA_DIR=" + quoted(data.string()) + " " + quoted(CAPS_EXECUTABLE) + " plan " +
                 quoted(ct.string()) + " --procedure lopsided-z --at -90,0" + out);
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("there is no procedure 'lopsided-z'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("lopsided-z.procedure:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("is already sewn by suture 2"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("Reading"), std::string::npos) << r.output;

  // Usage: edits that do not parse, --replay with a procedure, --other-ct alone.
  for (const char* args : {"--move 1=-90", "--move x=1,2", "--offset 2=a,b", "--offset -1=0,1"})
  {
    r = runCaps("plan " + quoted(ct.string()) + " --procedure z-plasty --at -90,0 " + args + out);
    EXPECT_EQ(r.exitCode, 2) << args << ": " << r.output;
    EXPECT_NE(r.output.find("needs"), std::string::npos) << r.output;
  }
  r = runCaps("plan " + quoted(ct.string()) + " --replay x.json --procedure z-plasty" + out);
  EXPECT_EQ(r.exitCode, 2) << r.output;
  EXPECT_NE(r.output.find("leave out --procedure"), std::string::npos) << r.output;
  r = runCaps("plan " + quoted(ct.string()) + " --procedure z-plasty --at -90,0 --other-ct" + out);
  EXPECT_EQ(r.exitCode, 2) << r.output;
}
