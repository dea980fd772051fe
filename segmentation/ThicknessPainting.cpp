#include "segmentation/ThicknessPainting.h"

#include <cmath>
#include <stdexcept>

#include <vtkFloatArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>

namespace caps::seg {

long long paintThickness(vtkPolyData* surface, const RangeMap& thickness, const std::string& arrayName)
{
  if (surface == nullptr)
    throw std::invalid_argument("No surface to paint the thickness on.");
  if (thickness.empty())
    throw std::invalid_argument("The thickness map is empty.");
  const vtkIdType n = surface->GetNumberOfPoints();
  vtkNew<vtkFloatArray> values;
  values->SetName(arrayName.c_str());
  values->SetNumberOfComponents(1);
  values->SetNumberOfTuples(n);
  const CylindricalFrame& frame = thickness.frame();
  long long finite = 0;
  for (vtkIdType k = 0; k < n; ++k)
  {
    double p[3];
    surface->GetPoint(k, p);
    const CylindricalPoint c = frame.toCylindrical(Eigen::Vector3d(p[0], p[1], p[2]));
    // On the axis θ is undefined.
    const double value = c.r > 1e-9 ? thickness.sample(c.theta, c.z) : RangeMap::quietNaN();
    values->SetValue(k, static_cast<float>(value));
    if (std::isfinite(value))
      ++finite;
  }
  vtkPointData* pointData = surface->GetPointData();
  pointData->RemoveArray(arrayName.c_str());
  pointData->AddArray(values);
  pointData->SetActiveScalars(arrayName.c_str());
  return finite;
}

} // namespace caps::seg
