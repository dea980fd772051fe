/// @file SurfaceExtraction.cpp
/// @brief Flying edges on a padded crop of a mask, mapped to the patient frame.

#include "segmentation/SurfaceExtraction.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include <vtkCellArray.h>
#include <vtkFlyingEdges3D.h>
#include <vtkMatrix3x3.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyDataNormals.h>
#include <vtkDecimatePro.h>
#include <vtkReverseSense.h>
#include <vtkWindowedSincPolyDataFilter.h>
#include <vtkXMLPolyDataWriter.h>

namespace caps::seg {
namespace {

/// Copies the voxels of `mask` inside [lo, hi] (inclusive, 0-based indices)
/// into a 0/1 image with one voxel of background on every side.
template <typename T>
void copyPadded(const T* mask, const int dims[3], const std::array<int, 3>& lo, const std::array<int, 3>& hi,
                unsigned char* out)
{
  const int px = hi[0] - lo[0] + 3, py = hi[1] - lo[1] + 3;
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
    {
      const T* row = mask + (static_cast<std::int64_t>(k) * dims[1] + j) * dims[0];
      unsigned char* outRow = out + (static_cast<std::int64_t>(k - lo[2] + 1) * py + (j - lo[1] + 1)) * px + 1;
      for (int i = lo[0]; i <= hi[0]; ++i)
        outRow[i - lo[0]] = row[i] != 0 ? 1 : 0;
    }
}

/// Bounding box (0-based indices) of the non-zero voxels; false when none.
template <typename T> bool boundingBox(const T* mask, const int dims[3], std::array<int, 3>& lo, std::array<int, 3>& hi)
{
  lo = {dims[0], dims[1], dims[2]};
  hi = {-1, -1, -1};
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
    {
      const T* row = mask + (static_cast<std::int64_t>(k) * dims[1] + j) * dims[0];
      int first = -1, last = -1;
      for (int i = 0; i < dims[0]; ++i)
        if (row[i] != 0)
        {
          if (first < 0)
            first = i;
          last = i;
        }
      if (first < 0)
        continue;
      lo = {std::min(lo[0], first), std::min(lo[1], j), std::min(lo[2], k)};
      hi = {std::max(hi[0], last), std::max(hi[1], j), std::max(hi[2], k)};
    }
  return hi[0] >= 0;
}

/// Six times the signed volume enclosed by the triangles (divergence theorem).
double signedVolume6(vtkPolyData* surface)
{
  vtkPoints* points = surface->GetPoints();
  double sum = 0;
  vtkIdType n = 0;
  const vtkIdType* ids = nullptr;
  auto polys = surface->GetPolys();
  for (polys->InitTraversal(); polys->GetNextCell(n, ids);)
  {
    if (n != 3)
      continue;
    double a[3], b[3], c[3];
    points->GetPoint(ids[0], a);
    points->GetPoint(ids[1], b);
    points->GetPoint(ids[2], c);
    sum += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
  }
  return sum;
}

/// 1. The mask's bounding box, padded with background, in index space
/// (spacing 1, origin at the first voxel's absolute index); null for an
/// empty mask.
vtkSmartPointer<vtkImageData> paddedMask(vtkImageData* mask)
{
  int dims[3];
  mask->GetDimensions(dims);
  std::array<int, 3> lo{}, hi{};
  bool any = false;
  switch (mask->GetScalarType())
  {
    vtkTemplateMacro(any = boundingBox(static_cast<const VTK_TT*>(mask->GetScalarPointer()), dims, lo, hi));
  default:
    throw std::invalid_argument("extractSurface: unsupported voxel type.");
  }
  if (!any)
    return nullptr;
  const int* extent = mask->GetExtent();
  auto padded = vtkSmartPointer<vtkImageData>::New();
  padded->SetDimensions(hi[0] - lo[0] + 3, hi[1] - lo[1] + 3, hi[2] - lo[2] + 3);
  padded->SetOrigin(extent[0] + lo[0] - 1, extent[2] + lo[1] - 1, extent[4] + lo[2] - 1);
  padded->SetSpacing(1, 1, 1);
  padded->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  std::fill_n(static_cast<unsigned char*>(padded->GetScalarPointer()), padded->GetNumberOfPoints(),
              static_cast<unsigned char>(0));
  switch (mask->GetScalarType())
  {
    vtkTemplateMacro(copyPadded(static_cast<const VTK_TT*>(mask->GetScalarPointer()), dims, lo, hi,
                                static_cast<unsigned char*>(padded->GetScalarPointer())));
  }
  return padded;
}

/// 2. Flying edges at 0.5: vertices halfway between inside and outside voxels.
vtkSmartPointer<vtkPolyData> flyingEdgesAtHalf(vtkImageData* padded)
{
  auto flyingEdges = vtkSmartPointer<vtkFlyingEdges3D>::New();
  flyingEdges->SetInputData(padded);
  flyingEdges->SetValue(0, 0.5);
  flyingEdges->ComputeNormalsOff();
  flyingEdges->ComputeGradientsOff();
  flyingEdges->ComputeScalarsOff();
  flyingEdges->Update();
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  surface->ShallowCopy(flyingEdges->GetOutput());
  return surface;
}

/// 3. Index to patient frame: x = origin + D * diag(spacing) * ijk, with
/// ijk the structured index (vtkImageData's origin is the position of index
/// (0,0,0) even when the extent does not start at 0); then outward: a
/// closed surface with outward normals encloses a positive volume (a
/// left-handed direction matrix or negative spacing turns the flying-edges
/// orientation inside out).
vtkSmartPointer<vtkPolyData> inPatientFrameOutward(vtkSmartPointer<vtkPolyData> surface, vtkImageData* mask)
{
  double origin[3], spacing[3], d[3][3];
  mask->GetOrigin(origin);
  mask->GetSpacing(spacing);
  vtkMatrix3x3* direction = mask->GetDirectionMatrix();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      d[r][c] = (direction ? direction->GetElement(r, c) : (r == c ? 1.0 : 0.0)) * spacing[c];
  {
    auto points = vtkSmartPointer<vtkPoints>::New();
    points->SetDataTypeToDouble();
    vtkPoints* in = surface->GetPoints();
    points->SetNumberOfPoints(in->GetNumberOfPoints());
    for (vtkIdType p = 0; p < in->GetNumberOfPoints(); ++p)
    {
      double q[3], x[3];
      in->GetPoint(p, q);
      for (int r = 0; r < 3; ++r)
        x[r] = origin[r] + d[r][0] * q[0] + d[r][1] * q[1] + d[r][2] * q[2];
      points->SetPoint(p, x);
    }
    surface->SetPoints(points);
  }
  if (signedVolume6(surface) < 0)
  {
    auto reverse = vtkSmartPointer<vtkReverseSense>::New();
    reverse->SetInputData(surface);
    reverse->ReverseCellsOn();
    reverse->ReverseNormalsOff();
    reverse->Update();
    surface = reverse->GetOutput();
  }
  return surface;
}

/// 4. Smoothing in mm (rotation invariant, so after the mapping).
vtkSmartPointer<vtkPolyData> smoothed(vtkPolyData* surface, const SurfaceOptions& options)
{
  auto smoother = vtkSmartPointer<vtkWindowedSincPolyDataFilter>::New();
  smoother->SetInputData(surface);
  smoother->SetNumberOfIterations(options.smoothingIterations);
  smoother->SetPassBand(options.smoothingPassBand);
  smoother->BoundarySmoothingOff();
  smoother->FeatureEdgeSmoothingOff();
  smoother->NonManifoldSmoothingOn();
  smoother->NormalizeCoordinatesOn();
  smoother->Update();
  return smoother->GetOutput();
}

/// 5. Decimation for display.
vtkSmartPointer<vtkPolyData> decimated(vtkPolyData* surface, const SurfaceOptions& options)
{
  auto decimate = vtkSmartPointer<vtkDecimatePro>::New();
  decimate->SetInputData(surface);
  decimate->SetTargetReduction(std::min(options.targetReduction, 0.99));
  decimate->PreserveTopologyOn();
  decimate->SplittingOff();
  decimate->BoundaryVertexDeletionOff();
  decimate->SetFeatureAngle(45.0);
  decimate->SetMaximumError(VTK_DOUBLE_MAX);
  decimate->Update();
  return decimate->GetOutput();
}

/// 6. Point normals (the surface is already consistent and outward).
vtkSmartPointer<vtkPolyData> withPointNormals(vtkPolyData* surface)
{
  auto normals = vtkSmartPointer<vtkPolyDataNormals>::New();
  normals->SetInputData(surface);
  normals->SplittingOff();
  normals->ConsistencyOff(); // already consistent and outward
  normals->AutoOrientNormalsOff();
  normals->ComputePointNormalsOn();
  normals->ComputeCellNormalsOff();
  normals->Update();
  return normals->GetOutput();
}

} // namespace

vtkSmartPointer<vtkPolyData> extractSurface(vtkImageData* mask, const SurfaceOptions& options)
{
  if (!mask || !mask->GetPointData()->GetScalars())
    throw std::invalid_argument("extractSurface: no mask image.");
  if (mask->GetNumberOfScalarComponents() != 1)
    throw std::invalid_argument("extractSurface: the mask must have one component per voxel.");
  vtkSmartPointer<vtkImageData> padded = paddedMask(mask);
  if (!padded)
    return vtkSmartPointer<vtkPolyData>::New();
  vtkSmartPointer<vtkPolyData> surface = flyingEdgesAtHalf(padded);
  padded = nullptr;
  surface = inPatientFrameOutward(surface, mask);
  if (options.smoothingIterations > 0)
    surface = smoothed(surface, options);
  if (options.targetReduction > 0)
    surface = decimated(surface, options);
  if (options.computeNormals)
    surface = withPointNormals(surface);
  return surface;
}

void writeSurfaceVtp(vtkPolyData* surface, const std::filesystem::path& file)
{
  auto writer = vtkSmartPointer<vtkXMLPolyDataWriter>::New();
  writer->SetInputData(surface);
  writer->SetFileName(file.string().c_str());
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();
  writer->SetCompressorTypeToZLib();
  if (writer->Write() != 1)
    throw std::runtime_error("Could not write " + file.string() + ": is the folder writable?");
}

} // namespace caps::seg
