#include "modules/incision/PlanDisplay.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIntArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkUnsignedCharArray.h>

#include "modules/segment/SegmentCommands.h"
#include "segmentation/SkinShade.h"

namespace caps::incision {
namespace {

constexpr double kKiloPascalPerMegaPascal = 1000.0;

template <class Array>
vtkSmartPointer<Array> namedArray(const char* name, int components, vtkIdType tuples)
{
  auto a = vtkSmartPointer<Array>::New();
  a->SetName(name);
  a->SetNumberOfComponents(components);
  a->SetNumberOfTuples(tuples);
  return a;
}

/// One double array from the rows of @a values (components × points), times @a factor.
vtkSmartPointer<vtkDoubleArray> pointArray(const char* name, const Eigen::MatrixXd& values, double factor = 1.0)
{
  auto a = namedArray<vtkDoubleArray>(name, int(values.rows()), vtkIdType(values.cols()));
  for (Eigen::Index v = 0; v < values.cols(); ++v)
    for (Eigen::Index c = 0; c < values.rows(); ++c)
      a->SetTypedComponent(vtkIdType(v), int(c), factor * values(c, v));
  return a;
}

vtkSmartPointer<vtkDoubleArray> fieldValue(const char* name, double value)
{
  auto a = namedArray<vtkDoubleArray>(name, 1, 1);
  a->SetValue(0, value);
  return a;
}

} // namespace

PlanDisplay buildPlanDisplay(const PlanPrediction& prediction, const seg::RangeMap& skin, const seg::ColourMap* colour,
                             const PlanDisplayOptions& options)
{
  if (skin.empty())
    throw std::invalid_argument("the display of the plan needs the skin range map it was simulated on");
  const fem::ContinuumMesh& continuum = prediction.continuum;
  PlanDisplay out;
  out.rangeDetail = options.rangeDetail;
  out.surface = fem::DisplaySurface(continuum.mesh, fem::skinFaces(continuum), options.resolution);
  out.surface.setSolution(prediction.displacements, prediction.materials);

  // Table 4.9's range displacement and source colour, both read at the
  // vertex's undeformed (θ, z) (§4.7).
  const seg::CylindricalFrame& frame = skin.frame();
  const Eigen::Matrix3Xd& x = out.surface.undeformedPositions();
  Eigen::Matrix3Xd detail = Eigen::Matrix3Xd::Zero(3, x.cols());
  out.skinShade.assign(std::size_t(x.cols()), seg::kNoSourceColour);
  for (Eigen::Index v = 0; v < x.cols(); ++v)
  {
    const seg::CylindricalPoint c = frame.toCylindrical(x.col(v));
    const double r = skin.sample(c.theta, c.z);
    if (!std::isfinite(r))
      ++out.verticesWithoutScan;
    else if (const Eigen::Vector3d d = frame.toWorld(r, c.theta, c.z) - x.col(v); d.norm() <= options.maxRangeDetail)
      detail.col(v) = d;
    else
      ++out.verticesBeyondDetailLimit;
    if (colour)
      out.skinShade[std::size_t(v)] = seg::sampleColour(*colour, c.theta, c.z);
  }
  out.largestRangeDetail = x.cols() > 0 ? detail.colwise().norm().maxCoeff() : 0.0;
  out.surface.setRangeDetail(detail);
  return out;
}

vtkSmartPointer<vtkPolyData> planDisplayPolyData(const PlanDisplay& display, double scale)
{
  const fem::DisplaySurface& s = display.surface;
  const vtkIdType n = vtkIdType(s.vertexCount());
  const Eigen::Matrix3Xd x = display.positions(scale);

  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  for (vtkIdType v = 0; v < n; ++v)
    points->SetPoint(v, x.col(v).data());
  auto polys = vtkSmartPointer<vtkCellArray>::New();
  for (const auto& polygon : s.polygons())
  {
    polys->InsertNextCell(vtkIdType(polygon.size()));
    for (int v : polygon)
      polys->InsertCellPoint(v);
  }
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  surface->SetPoints(points);
  surface->SetPolys(polys);

  vtkPointData* pd = surface->GetPointData();
  pd->AddArray(pointArray("displacement_mm", s.displacements()));
  pd->AddArray(pointArray("displacement_magnitude_mm", s.displacementMagnitude().transpose()));
  pd->AddArray(pointArray("von_mises_kPa", s.vonMises().transpose(), kKiloPascalPerMegaPascal));
  pd->AddArray(pointArray("mean_stress_kPa", s.meanStress().transpose(), kKiloPascalPerMegaPascal));
  pd->AddArray(pointArray("stress_kPa", s.stresses(), kKiloPascalPerMegaPascal));
  pd->AddArray(pointArray("strain", s.strains()));
  pd->AddArray(pointArray("equivalent_strain", s.equivalentStrain().transpose()));
  pd->AddArray(pointArray("volumetric_strain", s.volumetricStrain().transpose()));
  pd->AddArray(pointArray("range_detail_mm", s.rangeDetail()));
  auto shade = namedArray<vtkUnsignedCharArray>("skin_shade", 3, n);
  auto element = namedArray<vtkIntArray>("element", 1, n);
  auto rst = namedArray<vtkDoubleArray>("rst", 3, n);
  for (vtkIdType v = 0; v < n; ++v)
  {
    const seg::Rgb8& c = display.skinShade[std::size_t(v)];
    for (int k = 0; k < 3; ++k)
      shade->SetTypedComponent(v, k, c[k]);
    const fem::BodyPoint& p = s.bodyPoints()[std::size_t(v)];
    element->SetValue(v, p.element);
    for (int k = 0; k < 3; ++k)
      rst->SetTypedComponent(v, k, p.rst[k]);
  }
  pd->AddArray(element);
  pd->AddArray(rst);
  pd->SetScalars(shade); // what a viewer shows first: the skin

  vtkFieldData* fd = surface->GetFieldData();
  fd->AddArray(fieldValue("displacement_scale", scale));
  fd->AddArray(fieldValue("resolution", s.resolution()));
  fd->AddArray(fieldValue("range_detail", display.rangeDetail ? 1.0 : 0.0));
  return surface;
}

void writePlanDisplay(const PlanDisplay& display, const std::filesystem::path& before,
                      const std::filesystem::path& after)
{
  cli::writeVtp(planDisplayPolyData(display, 0.0), before);
  cli::writeVtp(planDisplayPolyData(display, 1.0), after);
}

} // namespace caps::incision
