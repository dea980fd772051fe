#include "planning/PlanDisplay.h"

#include "segmentation/SurfaceExtraction.h"

#include <algorithm>
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

#include "segmentation/SkinShade.h"

namespace caps::planning {
namespace {

constexpr double kKiloPascalPerMegaPascal = 1000.0;

template <class Array> vtkSmartPointer<Array> namedArray(const char* name, int components, vtkIdType tuples)
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

/// Per display vertex, the undermined flags of the surface-mesh vertices
/// interpolated with its shape functions (PlanDisplay::undermined).
std::vector<double> underminedAtVertices(const PlanPrediction& prediction, const fem::DisplaySurface& surface)
{
  const fem::ContinuumMesh& continuum = prediction.continuum;
  const std::vector<char>& flags = prediction.underminedVertices;
  std::vector<double> out(std::size_t(surface.vertexCount()), 0.0);
  if (flags.empty())
    return out;
  if (flags.size() != continuum.vertexColumns.size())
    throw std::invalid_argument("the prediction has " + std::to_string(flags.size()) +
                                " undermining flags for a surface mesh of " +
                                std::to_string(continuum.vertexColumns.size()) + " vertices");
  std::vector<double> atNode(std::size_t(continuum.mesh.nodeCount()), 0.0);
  for (std::size_t v = 0; v < flags.size(); ++v)
    for (int node : continuum.vertexColumns[v])
      atNode[std::size_t(node)] = flags[v] ? 1.0 : 0.0;
  for (std::size_t e = 0; e < continuum.edges.size(); ++e)
  {
    const auto& [a, b] = continuum.edges[e];
    const double mean = 0.5 * ((flags[std::size_t(a)] ? 1.0 : 0.0) + (flags[std::size_t(b)] ? 1.0 : 0.0));
    for (int node : continuum.edgeColumns[e])
      if (node >= 0) // the floor's edges under a cut of partial depth have no node above it
        atNode[std::size_t(node)] = mean;
  }
  const Eigen::SparseMatrix<double>& w = surface.interpolation();
  for (Eigen::Index v = 0; v < w.outerSize(); ++v)
  {
    double sum = 0.0;
    for (Eigen::SparseMatrix<double>::InnerIterator it(w, v); it; ++it)
      sum += it.value() * atNode[std::size_t(surface.displayNodes()[std::size_t(it.row())])];
    out[std::size_t(v)] = std::clamp(sum, 0.0, 1.0); // round-off of the weights' sum
  }
  return out;
}

vtkSmartPointer<vtkDoubleArray> fieldValue(const char* name, double value)
{
  auto a = namedArray<vtkDoubleArray>(name, 1, 1);
  a->SetValue(0, value);
  return a;
}

} // namespace

SkinShade skinShadeOfCt(vtkImageData* ct, const seg::RangeMap& skin)
{
  SkinShade out;
  if (!ct)
    out.note = "the skin is grey: the scene has no CT to read its shade from";
  else
    try
    {
      out.colour = seg::skinShadeFromCt(ct, skin);
    }
    catch (const std::exception& e)
    {
      out.note = std::string("the skin is grey: its shade could not be read from the CT (") + e.what() + ")";
    }
  return out;
}

RangeDetailCounts setRangeDetail(fem::DisplaySurface& surface, const seg::RangeMap& skin, double maxRangeDetail)
{
  RangeDetailCounts counts;
  const seg::CylindricalFrame& frame = skin.frame();
  const Eigen::Matrix3Xd& x = surface.undeformedPositions();
  Eigen::Matrix3Xd detail = Eigen::Matrix3Xd::Zero(3, x.cols());
  for (Eigen::Index v = 0; v < x.cols(); ++v)
  {
    const seg::CylindricalPoint c = frame.toCylindrical(x.col(v));
    const double r = skin.sample(c.theta, c.z);
    if (!std::isfinite(r))
      ++counts.verticesWithoutScan;
    else if (const Eigen::Vector3d d = frame.toWorld(r, c.theta, c.z) - x.col(v); d.norm() <= maxRangeDetail)
      detail.col(v) = d;
    else
      ++counts.verticesBeyondDetailLimit;
  }
  counts.largestRangeDetail = x.cols() > 0 ? detail.colwise().norm().maxCoeff() : 0.0;
  surface.setRangeDetail(detail);
  return counts;
}

PlanDisplay buildPlanDisplay(const PlanPrediction& prediction, const seg::RangeMap& skin, const seg::ColourMap* colour,
                             const PlanDisplayOptions& options)
{
  if (skin.empty())
    throw std::invalid_argument("the display of the plan needs the skin range map it was simulated on");
  if (!(options.underminingHatch >= 0.0) || !std::isfinite(options.underminingHatch))
    throw std::invalid_argument("the undermining hatch must be 0 (a plain tint) or a positive number of mm");
  const fem::ContinuumMesh& continuum = prediction.continuum;
  PlanDisplay out;
  out.rangeDetail = options.rangeDetail;
  out.surface = fem::DisplaySurface(continuum.mesh, fem::skinFaces(continuum), options.resolution);
  // The stress of the model that made the prediction: Cauchy for a large-deformation one.
  if (prediction.check.model == TissueModel::LargeDeformation && !prediction.hyperelasticMaterials.empty())
    out.surface.setSolution(prediction.displacements, prediction.hyperelasticMaterials);
  else
    out.surface.setSolution(prediction.displacements, prediction.materials);

  // Table 4.9's range displacement and source colour, both read at the
  // vertex's undeformed (θ, z) (§4.7).
  const RangeDetailCounts counts = setRangeDetail(out.surface, skin, options.maxRangeDetail);
  out.verticesWithoutScan = counts.verticesWithoutScan;
  out.verticesBeyondDetailLimit = counts.verticesBeyondDetailLimit;
  out.largestRangeDetail = counts.largestRangeDetail;
  const seg::CylindricalFrame& frame = skin.frame();
  const Eigen::Matrix3Xd& x = out.surface.undeformedPositions();
  out.skinShade.assign(std::size_t(x.cols()), seg::kNoSourceColour);
  out.undermined = underminedAtVertices(prediction, out.surface);
  out.underminingTint.assign(std::size_t(x.cols()), 0.0);
  for (Eigen::Index v = 0; v < x.cols(); ++v)
  {
    const seg::CylindricalPoint c = frame.toCylindrical(x.col(v));
    if (colour)
      out.skinShade[std::size_t(v)] = seg::sampleColour(*colour, c.theta, c.z);
    // The hatch: stripes at 45° on the skin (u = r θ around the head, z along it).
    double strength = 0.65;
    if (options.underminingHatch > 0.0)
    {
      const double phase = (c.r * c.theta + c.z) / (std::sqrt(2.0) * options.underminingHatch);
      strength = phase - std::floor(phase) < 0.5 ? 0.85 : 0.45;
    }
    out.underminingTint[std::size_t(v)] = strength * out.undermined[std::size_t(v)];
  }
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
  auto colour = namedArray<vtkUnsignedCharArray>("skin_colour", 3, n);
  auto undermined = namedArray<vtkDoubleArray>("undermined", 1, n);
  auto element = namedArray<vtkIntArray>("element", 1, n);
  auto rst = namedArray<vtkDoubleArray>("rst", 3, n);
  for (vtkIdType v = 0; v < n; ++v)
  {
    const seg::Rgb8& c = display.skinShade[std::size_t(v)];
    const double tint = display.underminingTint.empty() ? 0.0 : display.underminingTint[std::size_t(v)];
    for (int k = 0; k < 3; ++k)
    {
      shade->SetTypedComponent(v, k, c[k]);
      colour->SetTypedComponent(
        v, k, static_cast<unsigned char>(std::lround((1.0 - tint) * c[k] + tint * kUnderminedTint[std::size_t(k)])));
    }
    undermined->SetValue(v, display.undermined.empty() ? 0.0 : display.undermined[std::size_t(v)]);
    const fem::BodyPoint& p = s.bodyPoints()[std::size_t(v)];
    element->SetValue(v, p.element);
    for (int k = 0; k < 3; ++k)
      rst->SetTypedComponent(v, k, p.rst[k]);
  }
  pd->AddArray(element);
  pd->AddArray(rst);
  pd->AddArray(shade);
  pd->AddArray(undermined);
  pd->SetScalars(colour); // what a viewer shows first: the skin, the undermined part hatched

  vtkFieldData* fd = surface->GetFieldData();
  fd->AddArray(fieldValue("displacement_scale", scale));
  fd->AddArray(fieldValue("resolution", s.resolution()));
  fd->AddArray(fieldValue("range_detail", display.rangeDetail ? 1.0 : 0.0));
  return surface;
}

vtkSmartPointer<vtkPolyData> gapingSkinPolyData(const PlanDisplay& display, const PlanPrediction& prediction)
{
  if (!prediction.gape || !prediction.gape->problem.empty())
    return nullptr;
  PlanDisplay gaping = display;
  if (prediction.check.model == TissueModel::LargeDeformation && !prediction.hyperelasticMaterials.empty())
    gaping.surface.setSolution(prediction.gape->displacements, prediction.hyperelasticMaterials);
  else
    gaping.surface.setSolution(prediction.gape->displacements, prediction.materials);
  return planDisplayPolyData(gaping, 1.0);
}

void writePlanDisplay(const PlanDisplay& display, const std::filesystem::path& before,
                      const std::filesystem::path& after)
{
  seg::writeSurfaceVtp(planDisplayPolyData(display, 0.0), before);
  seg::writeSurfaceVtp(planDisplayPolyData(display, 1.0), after);
}

} // namespace caps::planning
