#include "segmentation/SurfaceScan.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>
#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkDataArray.h>
#include <vtkOBJReader.h>
#include <vtkPLYReader.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkTriangleFilter.h>
#include <vtkUnsignedCharArray.h>

#include "segmentation/RangeMapFromPoints.h"

namespace caps::seg {

namespace {

std::string lowerExtension(const std::string& path)
{
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

/// Colours from "v x y z r g b" lines, in file order; empty if the file has none.
std::vector<Eigen::Vector3d> objVertexLines(const std::string& path, std::vector<Eigen::Vector3d>& colours)
{
  std::ifstream in(path);
  std::vector<Eigen::Vector3d> positions;
  std::string line;
  bool allColoured = true;
  while (std::getline(in, line))
  {
    if (line.size() < 2 || line[0] != 'v' || !std::isspace(static_cast<unsigned char>(line[1])))
      continue;
    std::istringstream s(line.substr(1));
    std::vector<double> v;
    double x = 0.0;
    while (s >> x)
      v.push_back(x);
    if (v.size() < 3)
      continue;
    positions.emplace_back(v[0], v[1], v[2]);
    if (v.size() >= 6)
      colours.emplace_back(v[3], v[4], v[5]);
    else
      allColoured = false;
  }
  if (!allColoured)
    colours.clear();
  return positions;
}

/// Attach OBJ vertex colours when vtkOBJReader kept the file's vertices in order.
void addObjColours(const std::string& path, vtkPolyData* mesh)
{
  std::vector<Eigen::Vector3d> colours;
  const std::vector<Eigen::Vector3d> positions = objVertexLines(path, colours);
  if (colours.empty() || static_cast<vtkIdType>(positions.size()) != mesh->GetNumberOfPoints())
    return;
  for (vtkIdType k = 0; k < mesh->GetNumberOfPoints(); ++k)
  {
    double p[3];
    mesh->GetPoint(k, p);
    if ((Eigen::Vector3d(p[0], p[1], p[2]) - positions[static_cast<std::size_t>(k)]).cwiseAbs().maxCoeff() >
        1e-4 * (1.0 + positions[static_cast<std::size_t>(k)].cwiseAbs().maxCoeff()))
      return; // the reader reordered or duplicated vertices: colours cannot be matched
  }
  double maxValue = 0.0;
  for (const Eigen::Vector3d& c : colours)
    maxValue = std::max(maxValue, c.maxCoeff());
  const double scale = maxValue <= 1.0 ? 255.0 : 1.0;
  auto rgb = vtkSmartPointer<vtkUnsignedCharArray>::New();
  rgb->SetName("RGB");
  rgb->SetNumberOfComponents(3);
  rgb->SetNumberOfTuples(mesh->GetNumberOfPoints());
  for (vtkIdType k = 0; k < mesh->GetNumberOfPoints(); ++k)
    for (int c = 0; c < 3; ++c)
      rgb->SetValue(3 * k + c, static_cast<unsigned char>(
                                 std::clamp(std::lround(colours[static_cast<std::size_t>(k)][c] * scale), 0L, 255L)));
  mesh->GetPointData()->SetScalars(rgb);
}

vtkUnsignedCharArray* colourArray(vtkPolyData* mesh)
{
  auto usable = [](vtkDataArray* a) -> vtkUnsignedCharArray* {
    auto* u = vtkUnsignedCharArray::SafeDownCast(a);
    return u && u->GetNumberOfComponents() >= 3 ? u : nullptr;
  };
  vtkPointData* pd = mesh->GetPointData();
  if (auto* u = usable(pd->GetScalars()))
    return u;
  for (const char* name : {"RGB", "RGBA", "Colors"})
    if (auto* u = usable(pd->GetArray(name)))
      return u;
  return nullptr;
}

Eigen::Vector3d vertexColour(vtkUnsignedCharArray* colours, vtkIdType id)
{
  const int n = colours->GetNumberOfComponents();
  return {static_cast<double>(colours->GetValue(n * id)), static_cast<double>(colours->GetValue(n * id + 1)),
          static_cast<double>(colours->GetValue(n * id + 2))};
}

Rgb8 toRgb8(const Eigen::Vector3d& c)
{
  Rgb8 out{};
  for (int k = 0; k < 3; ++k)
    out[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(std::clamp(std::lround(c[k]), 0L, 255L));
  return out;
}

/// Ray casting: outermost crossing of each sample's ray with each triangle.
void rayCast(const CylindricalFrame& frame, vtkPolyData* mesh, vtkUnsignedCharArray* colours, SurfaceScan& scan)
{
  const int nt = frame.nTheta();
  const int nz = frame.nZ();
  const double dTheta = frame.thetaStep();
  // Vertices in axis-frame coordinates (x, y, z): the ray of sample (i, j) is
  // (0, 0, z_j) + t (cos θ_i, sin θ_i, 0), and t is r.
  const vtkIdType nPoints = mesh->GetNumberOfPoints();
  std::vector<Eigen::Vector3d> local(static_cast<std::size_t>(nPoints));
  for (vtkIdType k = 0; k < nPoints; ++k)
  {
    double p[3];
    mesh->GetPoint(k, p);
    const Eigen::Vector3d d = Eigen::Vector3d(p[0], p[1], p[2]) - frame.origin();
    local[static_cast<std::size_t>(k)] = {d.dot(frame.xAxis()), d.dot(frame.yAxis()), d.dot(frame.direction())};
  }
  std::vector<double> cosT(static_cast<std::size_t>(nt)), sinT(static_cast<std::size_t>(nt));
  for (int i = 0; i < nt; ++i)
  {
    cosT[static_cast<std::size_t>(i)] = std::cos(frame.indexToTheta(i));
    sinT[static_cast<std::size_t>(i)] = std::sin(frame.indexToTheta(i));
  }
  constexpr double eps = 1e-9;

  vtkCellArray* polys = mesh->GetPolys();
  auto it = vtk::TakeSmartPointer(polys->NewIterator());
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell())
  {
    vtkIdType n = 0;
    const vtkIdType* ids = nullptr;
    it->GetCurrentCell(n, ids);
    if (n != 3)
      continue;
    const Eigen::Vector3d& a = local[static_cast<std::size_t>(ids[0])];
    const Eigen::Vector3d& b = local[static_cast<std::size_t>(ids[1])];
    const Eigen::Vector3d& c = local[static_cast<std::size_t>(ids[2])];
    if (!a.allFinite() || !b.allFinite() || !c.allFinite())
      continue;

    // Rows whose z lies in the triangle's z extent.
    const double zLo = std::min({a.z(), b.z(), c.z()});
    const double zHi = std::max({a.z(), b.z(), c.z()});
    const int j0 = std::max(0, static_cast<int>(std::ceil(frame.zToIndex(zLo) - 1e-7)));
    const int j1 = std::min(nz - 1, static_cast<int>(std::floor(frame.zToIndex(zHi) + 1e-7)));
    if (j0 > j1)
      continue;

    // Columns: the θ interval the triangle subtends seen from the axis; all
    // columns if its projection along the axis contains the axis (a cap).
    auto cross2 = [](const Eigen::Vector3d& p, const Eigen::Vector3d& q) { return p.x() * q.y() - p.y() * q.x(); };
    const double s0 = cross2(a, b), s1 = cross2(b, c), s2 = cross2(c, a);
    const bool aroundAxis = (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
    long k0 = 0, k1 = nt - 1;
    if (!aroundAxis)
    {
      const double t0 = std::atan2(a.y(), a.x());
      double lo = t0, hi = t0;
      for (const Eigen::Vector3d* v : {&b, &c})
      {
        const double t = t0 + std::remainder(std::atan2(v->y(), v->x()) - t0, 2.0 * std::numbers::pi);
        lo = std::min(lo, t);
        hi = std::max(hi, t);
      }
      k0 = static_cast<long>(std::ceil((lo + std::numbers::pi) / dTheta - 1e-7));
      k1 = static_cast<long>(std::floor((hi + std::numbers::pi) / dTheta + 1e-7));
    }

    // Möller–Trumbore against each ray.
    const Eigen::Vector3d e1 = b - a, e2 = c - a;
    for (long k = k0; k <= k1; ++k)
    {
      const int i = static_cast<int>(((k % nt) + nt) % nt);
      const Eigen::Vector3d dir(cosT[static_cast<std::size_t>(i)], sinT[static_cast<std::size_t>(i)], 0.0);
      const Eigen::Vector3d p = dir.cross(e2);
      const double det = e1.dot(p);
      if (std::abs(det) < 1e-14 * (e1.squaredNorm() + e2.squaredNorm()))
        continue; // triangle parallel to the ray
      const double inv = 1.0 / det;
      for (int j = j0; j <= j1; ++j)
      {
        const Eigen::Vector3d s = Eigen::Vector3d(0.0, 0.0, frame.indexToZ(j)) - a;
        const double u = s.dot(p) * inv;
        if (u < -eps || u > 1.0 + eps)
          continue;
        const Eigen::Vector3d q = s.cross(e1);
        const double v = dir.dot(q) * inv;
        if (v < -eps || u + v > 1.0 + eps)
          continue;
        const double t = e2.dot(q) * inv;
        if (!(t > 0.0))
          continue;
        float& r = scan.range.at(i, j);
        if (r >= t)
          continue;
        r = static_cast<float>(t);
        if (colours)
          scan.colour.at(i, j) = toRgb8((1.0 - u - v) * vertexColour(colours, ids[0]) +
                                        u * vertexColour(colours, ids[1]) + v * vertexColour(colours, ids[2]));
      }
    }
  }
}

/// The §3.2.7 rule on the vertices, with the colour of the vertex that gave the maximum.
void bucketVertices(const CylindricalFrame& frame, vtkPolyData* mesh, vtkUnsignedCharArray* colours, SurfaceScan& scan)
{
  std::vector<Eigen::Vector3d> points(static_cast<std::size_t>(mesh->GetNumberOfPoints()));
  for (vtkIdType k = 0; k < mesh->GetNumberOfPoints(); ++k)
  {
    double p[3];
    mesh->GetPoint(k, p);
    points[static_cast<std::size_t>(k)] = {p[0], p[1], p[2]};
  }
  scan.range = rangeMapFromPoints(frame, points);
  if (!colours)
    return;
  // Same bucket rule as rangeMapFromPoints; the vertex whose r is the bucket's value gives the colour.
  for (vtkIdType k = 0; k < mesh->GetNumberOfPoints(); ++k)
  {
    const Eigen::Vector3d& p = points[static_cast<std::size_t>(k)];
    if (!p.allFinite())
      continue;
    const CylindricalPoint c = frame.toCylindrical(p);
    int i = static_cast<int>(std::floor(frame.thetaToIndex(c.theta) + 0.5));
    if (i >= frame.nTheta())
      i -= frame.nTheta();
    const double v = std::floor(frame.zToIndex(c.z) + 0.5);
    if (!(v >= 0.0 && v <= frame.nZ() - 1))
      continue;
    const int j = static_cast<int>(v);
    if (scan.range.at(i, j) == static_cast<float>(c.r))
      scan.colour.at(i, j) = toRgb8(vertexColour(colours, k));
  }
}

} // namespace

vtkSmartPointer<vtkPolyData> readSurfaceMesh(const std::string& path)
{
  if (!std::filesystem::is_regular_file(path))
    throw std::runtime_error("the surface scan file " + path + " does not exist or is not a file");
  const std::string ext = lowerExtension(path);
  vtkSmartPointer<vtkPolyData> raw;
  if (ext == ".ply")
  {
    auto reader = vtkSmartPointer<vtkPLYReader>::New();
    reader->SetFileName(path.c_str());
    reader->Update();
    raw = reader->GetOutput();
  }
  else if (ext == ".obj")
  {
    auto reader = vtkSmartPointer<vtkOBJReader>::New();
    reader->SetFileName(path.c_str());
    reader->Update();
    raw = reader->GetOutput();
    if (raw && !colourArray(raw))
      addObjColours(path, raw);
  }
  else
    throw std::runtime_error("the surface scan " + path + " is not a PLY or OBJ file (extension '" + ext + "')");
  if (!raw || raw->GetNumberOfPolys() == 0)
    throw std::runtime_error("the surface scan " + path + " has no polygons (unreadable, or a point cloud)");
  auto triangles = vtkSmartPointer<vtkTriangleFilter>::New();
  triangles->SetInputData(raw);
  triangles->PassVertsOff();
  triangles->PassLinesOff();
  triangles->Update();
  vtkSmartPointer<vtkPolyData> mesh = triangles->GetOutput();
  if (vtkUnsignedCharArray* rgb = colourArray(mesh))
  {
    if (!rgb->GetName())
      rgb->SetName("RGB");
    mesh->GetPointData()->SetScalars(rgb);
  }
  return mesh;
}

SurfaceScan surfaceScanFromMesh(const CylindricalFrame& frame, vtkPolyData* mesh, SurfaceScanSampling sampling)
{
  SurfaceScan scan{RangeMap(frame), ColourMap(frame), false};
  if (!mesh)
    return scan;
  vtkUnsignedCharArray* colours = colourArray(mesh);
  scan.hasColours = colours != nullptr;
  if (sampling == SurfaceScanSampling::RayCast)
    rayCast(frame, mesh, colours, scan);
  else
    bucketVertices(frame, mesh, colours, scan);
  return scan;
}

SurfaceScan readSurfaceScan(const std::string& path, const CylindricalFrame& frame, SurfaceScanSampling sampling)
{
  vtkSmartPointer<vtkPolyData> mesh = readSurfaceMesh(path);
  return surfaceScanFromMesh(frame, mesh, sampling);
}

} // namespace caps::seg
