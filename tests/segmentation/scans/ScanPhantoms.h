#pragma once
// Analytic surfaces for the scan tests: a UV sphere and a cylinder as triangle
// meshes, coloured by a function linear in the frame's local coordinates so the
// expected colour at any surface point is known exactly.

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>

#include "segmentation/CylindricalFrame.h"

namespace caps::seg::test {

/// Colour of a world point: 128 + 120 · (local x, y, z) / scale, clamped.
inline std::array<double, 3> linearColour(const CylindricalFrame& f, const Eigen::Vector3d& p, double scale)
{
  const Eigen::Vector3d d = p - f.origin();
  return {std::clamp(128.0 + 120.0 * d.dot(f.xAxis()) / scale, 0.0, 255.0),
          std::clamp(128.0 + 120.0 * d.dot(f.yAxis()) / scale, 0.0, 255.0),
          std::clamp(128.0 + 120.0 * d.dot(f.direction()) / scale, 0.0, 255.0)};
}

/// A surface of revolution about the frame's axis: rings at heights z[k], radius
/// radius(z), nSides vertices per ring at θ = -π + 2π s / nSides + phase, plus
/// optional poles. Coloured by linearColour.
template <class Radius>
vtkSmartPointer<vtkPolyData> revolution(const CylindricalFrame& f, int nSides, int nRings, double z0, double z1,
                                        Radius radius, double colourScale, double phase = 0.0)
{
  auto points = vtkSmartPointer<vtkPoints>::New();
  auto rgb = vtkSmartPointer<vtkUnsignedCharArray>::New();
  rgb->SetName("RGB");
  rgb->SetNumberOfComponents(3);
  auto polys = vtkSmartPointer<vtkCellArray>::New();
  for (int k = 0; k < nRings; ++k)
  {
    const double z = z0 + (z1 - z0) * k / (nRings - 1);
    for (int s = 0; s < nSides; ++s)
    {
      const double theta = -std::numbers::pi + 2.0 * std::numbers::pi * s / nSides + phase;
      const Eigen::Vector3d p = f.toWorld(radius(z), theta, z);
      points->InsertNextPoint(p.data());
      const auto c = linearColour(f, p, colourScale);
      rgb->InsertNextTuple3(std::round(c[0]), std::round(c[1]), std::round(c[2]));
    }
  }
  for (int k = 0; k + 1 < nRings; ++k)
    for (int s = 0; s < nSides; ++s)
    {
      const vtkIdType a = k * nSides + s, b = k * nSides + (s + 1) % nSides;
      const vtkIdType c = a + nSides, d = b + nSides;
      const vtkIdType t1[3] = {a, b, d}, t2[3] = {a, d, c};
      polys->InsertNextCell(3, t1);
      polys->InsertNextCell(3, t2);
    }
  auto mesh = vtkSmartPointer<vtkPolyData>::New();
  mesh->SetPoints(points);
  mesh->SetPolys(polys);
  mesh->GetPointData()->SetScalars(rgb);
  return mesh;
}

} // namespace caps::seg::test
