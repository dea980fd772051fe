// `caps scan`: a coloured surface scan (the thesis's Cyberware input, §3.2.1,
// §4.2.1) unwrapped into range and colour maps written as pictures that an
// image program can edit and CAPS reads back, optionally calibrated by
// landmark distances measured on the patient (§4.3, Tables 4.2–4.3).

#include "modules/rangemap/RangeMapCommands.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <sstream>

#include <vtkPoints.h>
#include <vtkPolyData.h>

#include "modules/rangemap/RangeMapLogic.h"
#include "modules/rangemap/RangeMapPreview.h"
#include "modules/volumes/CommandLine.h"
#include "scene/NrrdIO.h"
#include "segmentation/Calibration.h"
#include "segmentation/RangeMapImage.h"
#include "segmentation/SurfaceScan.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

const char* kScanUsage =
  "usage: caps scan MESH --out DIR [--size NTHETAxNZ] [--axis PX,PY,PZ,DX,DY,DZ]\n"
  "                 [--vertices] [--calibrate DISTANCES.csv]\n"
  "\n"
  "Unwraps a surface scan of the face (PLY or OBJ, with vertex colours if it has\n"
  "them) into a cylindrical range map r(theta, z) and a colour map, and writes into DIR:\n"
  "  range.png          r as a 16-bit grey picture (edit it in an image program;\n"
  "                     the frame and the mm per grey step travel in its text chunks)\n"
  "  colour.png         the colours, RGB, on the same grid\n"
  "  range.nrrd         r in mm as floats (NaN: no surface)\n"
  "  range-preview.png  r with a colour bar in mm, the face in the middle\n"
  "\n"
  "  --size NTHETAxNZ   samples around the head and along the axis (default 512x256)\n"
  "  --axis PX,PY,PZ,DX,DY,DZ\n"
  "                     the cylinder's axis through P along D (mm, the mesh's\n"
  "                     coordinates); default: through the centre of the mesh's\n"
  "                     bounding box along +z. theta = -90 deg looks along -y.\n"
  "  --vertices         the thesis's rule (§3.2.7): each sample keeps the outermost\n"
  "                     vertex in its bucket (holes where the mesh is coarse);\n"
  "                     default: a ray from the axis to each sample, no holes\n"
  "  --calibrate FILE   scale the maps by distances measured on the patient (§4.3):\n"
  "                     a CSV with the header\n"
  "                     name,direction,from_theta_deg,from_z_mm,to_theta_deg,to_z_mm,measured_mm\n"
  "                     (direction: horizontal or vertical; theta, z where the two\n"
  "                     landmarks are on the uncalibrated map). Prints the table and\n"
  "                     writes the calibrated maps.\n"
  "\n"
  "Exit status: 0 when written, 1 when the mesh or the distances cannot be read or\n"
  "the files cannot be written, 2 on wrong usage.\n";

struct ScanArgs
{
  fs::path mesh;
  fs::path out;
  fs::path distances;
  int nTheta = 512;
  int nZ = 256;
  bool vertices = false;
  std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> axis;
  bool help = false;
};

std::optional<std::string> parse(const std::vector<std::string>& argv, ScanArgs& parsed)
{
  return cli::parseInputOutputCommand(
    argv, parsed.mesh, parsed.out, parsed.help,
    [&parsed](const std::string& a, const std::vector<std::string>& args,
              std::size_t& i) -> std::optional<std::string> {
      const bool hasValue = i + 1 < args.size();
      if (a == "--size")
      {
        char tail = 0;
        if (!hasValue || std::sscanf(args[++i].c_str(), "%dx%d%c", &parsed.nTheta, &parsed.nZ, &tail) != 2 ||
            parsed.nTheta < 8 || parsed.nZ < 4 || parsed.nTheta > 8192 || parsed.nZ > 8192)
          return "--size needs NTHETAxNZ, e.g. 512x256 (at least 8x4, at most 8192x8192)";
      }
      else if (a == "--axis")
      {
        Eigen::Vector3d p, d;
        if (!hasValue || !parseAxis(args[++i], p, d))
          return "--axis needs a point and a non-zero direction, PX,PY,PZ,DX,DY,DZ";
        parsed.axis = std::pair{p, d};
      }
      else if (a == "--vertices")
        parsed.vertices = true;
      else if (a == "--calibrate")
      {
        if (!hasValue)
          return "--calibrate needs a CSV file of measured distances";
        parsed.distances = args[++i];
      }
      else
        return "unknown option " + a;
      return std::nullopt;
    },
    "MESH");
}

std::vector<std::string> splitCsv(const std::string& line)
{
  std::vector<std::string> fields;
  std::stringstream in(line);
  std::string field;
  while (std::getline(in, field, ','))
  {
    while (!field.empty() && (field.back() == ' ' || field.back() == '\r'))
      field.pop_back();
    while (!field.empty() && field.front() == ' ')
      field.erase(field.begin());
    fields.push_back(field);
  }
  if (!line.empty() && line.back() == ',')
    fields.emplace_back();
  return fields;
}

/// The measured distances of --calibrate (angles in degrees in the file).
std::vector<seg::LandmarkDistance> readDistances(const fs::path& file)
{
  std::ifstream in(file);
  if (!in)
    throw std::runtime_error("cannot read " + file.string() + ": check the path.");
  const char* header = "name,direction,from_theta_deg,from_z_mm,to_theta_deg,to_z_mm,measured_mm";
  std::string line;
  int number = 0;
  std::vector<seg::LandmarkDistance> distances;
  auto fail = [&](const std::string& what) {
    throw std::runtime_error(file.string() + ", line " + std::to_string(number) + ": " + what);
  };
  while (std::getline(in, line))
  {
    ++number;
    if (!line.empty() && line.back() == '\r')
      line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos)
      continue;
    const auto f = splitCsv(line);
    if (number == 1)
    {
      if (line != header)
        fail(std::string("the first line must be the header ") + header);
      continue;
    }
    if (f.size() != 7)
      fail("expected 7 fields, found " + std::to_string(f.size()));
    seg::LandmarkDistance d;
    d.name = f[0];
    if (f[1] == "horizontal")
      d.direction = seg::CalibrationDirection::Horizontal;
    else if (f[1] == "vertical")
      d.direction = seg::CalibrationDirection::Vertical;
    else
      fail("direction must be horizontal or vertical, not '" + f[1] + "'");
    double v[5];
    for (int k = 0; k < 5; ++k)
      if (!cli::parseNumber(f[static_cast<std::size_t>(2 + k)], v[k]))
        fail("'" + f[static_cast<std::size_t>(2 + k)] + "' is not a number");
    constexpr double deg = std::numbers::pi / 180.0;
    d.from = {v[0] * deg, v[1]};
    d.to = {v[2] * deg, v[3]};
    d.measuredMm = v[4];
    if (!(d.measuredMm > 0.0))
      fail("the measured distance must be positive (mm)");
    distances.push_back(d);
  }
  if (number == 0)
    throw std::runtime_error(file.string() + " is empty: it needs the header " + header +
                             " and one row per measured distance.");
  return distances;
}

/// Default cylinder: through the centre of the bounding box along +z,
/// spanning the mesh's z.
seg::CylindricalFrame defaultFrame(vtkPolyData* mesh, const ScanArgs& args)
{
  double b[6];
  mesh->GetBounds(b);
  Eigen::Vector3d point(0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 0.5 * (b[4] + b[5]));
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  if (args.axis)
  {
    point = args.axis->first;
    direction = args.axis->second.normalized();
  }
  double zMin = std::numeric_limits<double>::max(), zMax = std::numeric_limits<double>::lowest();
  vtkPoints* points = mesh->GetPoints();
  for (vtkIdType k = 0; k < points->GetNumberOfPoints(); ++k)
  {
    double p[3];
    points->GetPoint(k, p);
    const double z = (Eigen::Vector3d(p[0], p[1], p[2]) - point).dot(direction);
    zMin = std::min(zMin, z);
    zMax = std::max(zMax, z);
  }
  if (!(zMax > zMin))
    throw std::runtime_error("the mesh is flat along the axis: choose another --axis.");
  return seg::CylindricalFrame(point, direction, zMin, zMax, args.nTheta, args.nZ);
}

void printCalibration(std::ostream& out, const std::vector<seg::LandmarkDistance>& distances,
                      const std::vector<seg::CalibrationMeasurement>& rows, const seg::CalibrationResult& c)
{
  out << "Calibration by measured distances (thesis §4.3, Tables 4.2-4.3; mm):\n"
      << "  distance                          class       model  measured   ratio  residual\n";
  out << std::fixed;
  for (std::size_t k = 0; k < rows.size(); ++k)
  {
    std::string name = distances[k].name;
    name.resize(std::max<std::size_t>(name.size(), 32), ' ');
    out << "  " << name << "  "
        << (rows[k].direction == seg::CalibrationDirection::Horizontal ? "horizontal" : "vertical  ")
        << std::setprecision(1) << std::setw(8) << rows[k].model.length() << std::setw(10) << rows[k].measuredMm
        << std::setprecision(3) << std::setw(8) << rows[k].ratio() << std::setprecision(2) << std::setw(10)
        << c.residualsMm[k] << "\n";
  }
  out << std::setprecision(4) << "Scale factors (least squares): horizontal " << c.horizontalScale << ", vertical "
      << c.verticalScale << "; RMS residual " << std::setprecision(2) << c.rmsResidualMm << " mm\n"
      << std::setprecision(4) << "  (the thesis's class means: horizontal " << c.thesisHorizontalScale << ", vertical "
      << c.thesisVerticalScale << ")\n";
  out.unsetf(std::ios::floatfield);
}

int runScan(ModuleLogic&, const std::vector<std::string>& argv, std::ostream& out, std::ostream& err)
{
  return cli::runCommand<ScanArgs>("scan", kScanUsage, argv, out, err, parse, [&](ScanArgs& args) {
    // Distances first: a bad file stops us before any work.
    std::vector<seg::LandmarkDistance> distances;
    if (!args.distances.empty())
      distances = readDistances(args.distances);
    cli::makeOutputFolder(args.out);
    const auto mesh = seg::readSurfaceMesh(args.mesh.string());
    const seg::CylindricalFrame frame = defaultFrame(mesh, args);
    seg::SurfaceScan scan = seg::surfaceScanFromMesh(
      frame, mesh, args.vertices ? seg::SurfaceScanSampling::Vertices : seg::SurfaceScanSampling::RayCast);
    const Eigen::Vector3d& o = frame.origin();
    const Eigen::Vector3d d = frame.direction().array() + 0.0;
    out << "Scan " << args.mesh.filename().string() << ": " << mesh->GetNumberOfPoints() << " vertices, "
        << mesh->GetNumberOfPolys() << " triangles" << (scan.hasColours ? ", coloured" : ", no colours") << "\n"
        << std::fixed << std::setprecision(1) << "Axis through (" << o.x() << ", " << o.y() << ", " << o.z()
        << ") along (" << std::setprecision(3) << d.x() << ", " << d.y() << ", " << d.z() << "); z from "
        << std::setprecision(1) << frame.zMin() << " to " << frame.zMax() << " mm; " << frame.nTheta() << " x "
        << frame.nZ() << " samples, " << (args.vertices ? "outermost vertex per bucket" : "ray cast") << "\n";
    out.unsetf(std::ios::floatfield);
    out << "Surface found at " << scan.range.validCount() << " of " << scan.range.values().size() << " samples\n";

    if (!distances.empty())
    {
      std::vector<seg::CalibrationMeasurement> rows;
      for (const auto& distance : distances)
        rows.push_back(seg::measureOnMap(scan.range, distance));
      const seg::CalibrationResult c = seg::fitCalibration(rows);
      printCalibration(out, distances, rows, c);
      scan.range = seg::applyCalibration(scan.range, c);
      scan.colour = seg::applyCalibration(scan.colour, c);
      out << "The maps below are calibrated: r times " << c.horizontalScale << ", z times " << c.verticalScale << "\n";
    }

    const auto encoding = seg::writeRangeMapPng(scan.range, (args.out / "range.png").string());
    out << "wrote " << (args.out / "range.png").string() << " (16-bit, " << encoding.stepMm << " mm per step from "
        << encoding.offsetMm << " mm)\n";
    seg::writeColourMapPng(scan.colour, (args.out / "colour.png").string());
    out << "wrote " << (args.out / "colour.png").string() << "\n";
    const seg::CylindricalFrame& f = scan.range.frame();
    const Eigen::MatrixXf values = RangeMapLogic::toMatrix(scan.range);
    NrrdIO::writeMatrix(values, args.out / "range.nrrd");
    out << "wrote " << (args.out / "range.nrrd").string() << "\n";
    const PreviewStyle style = rangeStyle(values, "Scan range r(theta, z): distance from the axis");
    writeRangeMapPreview(values, f.zMin(), f.zMax(), style, args.out / "range-preview.png");
    out << "wrote " << (args.out / "range-preview.png").string() << "\n";
    return 0;
  });
}

} // namespace

bool parseAxis(const std::string& text, Eigen::Vector3d& point, Eigen::Vector3d& direction)
{
  double v[6];
  char tail = 0;
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &tail) != 6)
    return false;
  point = Eigen::Vector3d(v[0], v[1], v[2]);
  direction = Eigen::Vector3d(v[3], v[4], v[5]);
  return point.allFinite() && direction.allFinite() && direction.norm() > 1e-9;
}

ModuleCommand scanCommand()
{
  return {"scan", "a coloured surface scan (PLY/OBJ) to range and colour map pictures, calibrated", kScanUsage,
          runScan};
}

} // namespace caps
