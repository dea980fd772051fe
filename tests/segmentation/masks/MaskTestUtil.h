#pragma once
// Helpers shared by the mask and surface tests: voxel counts, positions,
// surface checks, pictures.

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <utility>

#include <itkBinaryImageToLabelMapFilter.h>
#include <itkImportImageFilter.h>
#include <itkLabelMap.h>
#include <itkLabelObject.h>
#include <vtkCellArray.h>
#include <vtkImageData.h>
#include <vtkMassProperties.h>
#include <vtkMatrix3x3.h>
#include <vtkPNGWriter.h>
#include <vtkPolyData.h>
#include <vtkPolyDataConnectivityFilter.h>
#include <vtkSmartPointer.h>

namespace caps::test {

inline std::size_t countSet(vtkImageData* mask)
{
  const auto* v = static_cast<const unsigned char*>(mask->GetScalarPointer());
  std::size_t n = 0;
  for (vtkIdType i = 0; i < mask->GetNumberOfPoints(); ++i)
    n += v[i] != 0;
  return n;
}

inline double voxelVolume(vtkImageData* image)
{
  const double* s = image->GetSpacing();
  return std::abs(s[0] * s[1] * s[2]);
}

/// LPS position of voxel (i, j, k) (extent starting at 0).
inline std::array<double, 3> worldOf(vtkImageData* image, int i, int j, int k)
{
  const double* o = image->GetOrigin();
  const double* s = image->GetSpacing();
  vtkMatrix3x3* d = image->GetDirectionMatrix();
  std::array<double, 3> p{};
  for (int r = 0; r < 3; ++r)
    p[r] = o[r] + d->GetElement(r, 0) * s[0] * i + d->GetElement(r, 1) * s[1] * j + d->GetElement(r, 2) * s[2] * k;
  return p;
}

/// Calls f(i, j, k, value) for every voxel of a uchar mask.
template <typename F> void forEachVoxel(vtkImageData* mask, F&& f)
{
  int dims[3];
  mask->GetDimensions(dims);
  const auto* v = static_cast<const unsigned char*>(mask->GetScalarPointer());
  std::size_t n = 0;
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i, ++n)
        f(i, j, k, v[n]);
}

/// Number of connected components of the set voxels of a uchar mask
/// (6-connected, or 26-connected when fullyConnected), counted by ITK's
/// run-length labelling on the mask's buffer.
inline std::size_t countComponents(vtkImageData* mask, bool fullyConnected = false)
{
  using Image = itk::Image<unsigned char, 3>;
  auto import = itk::ImportImageFilter<unsigned char, 3>::New();
  int dims[3];
  mask->GetDimensions(dims);
  Image::SizeType size;
  for (int a = 0; a < 3; ++a)
    size[a] = static_cast<itk::SizeValueType>(dims[a]);
  Image::RegionType region;
  region.SetSize(size);
  import->SetRegion(region);
  import->SetImportPointer(static_cast<unsigned char*>(mask->GetScalarPointer()),
                           static_cast<itk::SizeValueType>(mask->GetNumberOfPoints()), false);
  using LabelMap = itk::LabelMap<itk::LabelObject<std::uint32_t, 3>>;
  auto labels = itk::BinaryImageToLabelMapFilter<Image, LabelMap>::New();
  labels->SetInput(import->GetOutput());
  labels->SetInputForegroundValue(1);
  labels->SetFullyConnected(fullyConnected);
  labels->Update();
  return labels->GetOutput()->GetNumberOfLabelObjects();
}

struct SurfaceStats
{
  double volume = 0, area = 0;
  int regions = 0;
  double largestRegionAreaFraction = 0;
  vtkIdType boundaryEdges = 0, nonManifoldEdges = 0;
};

inline SurfaceStats surfaceStats(vtkPolyData* surface)
{
  SurfaceStats stats;
  auto mass = vtkSmartPointer<vtkMassProperties>::New();
  mass->SetInputData(surface);
  mass->Update();
  stats.volume = mass->GetVolume();
  stats.area = mass->GetSurfaceArea();

  auto connectivity = vtkSmartPointer<vtkPolyDataConnectivityFilter>::New();
  connectivity->SetInputData(surface);
  connectivity->SetExtractionModeToLargestRegion();
  connectivity->Update();
  stats.regions = connectivity->GetNumberOfExtractedRegions();
  auto largest = vtkSmartPointer<vtkMassProperties>::New();
  largest->SetInputConnection(connectivity->GetOutputPort());
  largest->Update();
  stats.largestRegionAreaFraction = stats.area > 0 ? largest->GetSurfaceArea() / stats.area : 0;

  // Edge use counts over the triangles: 1 = boundary, > 2 = non-manifold.
  // (Counted here: vtkFeatureEdges of VTK 9.1 runs out of memory on the
  // two-million-triangle surfaces of the sample.)
  std::unordered_map<std::uint64_t, int> uses;
  uses.reserve(static_cast<std::size_t>(surface->GetNumberOfCells()) * 2);
  vtkIdType n = 0;
  const vtkIdType* ids = nullptr;
  auto polys = surface->GetPolys();
  for (polys->InitTraversal(); polys->GetNextCell(n, ids);)
    for (vtkIdType e = 0; e < n; ++e)
    {
      auto a = static_cast<std::uint64_t>(ids[e]), b = static_cast<std::uint64_t>(ids[(e + 1) % n]);
      if (a > b)
        std::swap(a, b);
      ++uses[(a << 32) | b];
    }
  for (const auto& [edge, count] : uses)
  {
    stats.boundaryEdges += count == 1;
    stats.nonManifoldEdges += count > 2;
  }
  return stats;
}

/// A grey picture of slice `index` along `axis` of a HU image (window
/// [-1000, 1500]) with the body tinted green and the bone red.
inline void writeSlicePicture(vtkImageData* ct, vtkImageData* body, vtkImageData* bone, int axis, int index,
                              const std::filesystem::path& file)
{
  int dims[3];
  ct->GetDimensions(dims);
  const int u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : 2;
  const std::int64_t stride[3] = {1, dims[0], std::int64_t{dims[0]} * dims[1]};
  auto picture = vtkSmartPointer<vtkImageData>::New();
  picture->SetDimensions(dims[u], dims[v], 1);
  picture->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* out = static_cast<unsigned char*>(picture->GetScalarPointer());
  const auto* b = body ? static_cast<const unsigned char*>(body->GetScalarPointer()) : nullptr;
  const auto* s = bone ? static_cast<const unsigned char*>(bone->GetScalarPointer()) : nullptr;
  for (int y = 0; y < dims[v]; ++y)
    for (int x = 0; x < dims[u]; ++x)
    {
      const std::int64_t n = index * stride[axis] + x * stride[u] + y * stride[v];
      const double hu = ct->GetScalarComponentAsDouble(axis == 0 ? index : x, axis == 1 ? index : (axis == 0 ? x : y),
                                                       axis == 2 ? index : y, 0);
      const double g = std::clamp((hu + 1000.0) / 2500.0, 0.0, 1.0) * 255.0;
      double rgb[3] = {g, g, g};
      if (b && b[n])
        rgb[1] = 0.6 * g + 0.4 * 255;
      if (s && s[n])
        rgb[0] = 0.5 * g + 0.5 * 255, rgb[1] = 0.5 * g;
      // Flip vertically so that the picture's top is row 0 for axial slices
      // (anterior up) and superior for the others.
      const int row = axis == 2 ? dims[v] - 1 - y : y;
      unsigned char* o = out + 3 * (std::int64_t{row} * dims[u] + x);
      for (int c = 0; c < 3; ++c)
        o[c] = static_cast<unsigned char>(rgb[c]);
    }
  auto writer = vtkSmartPointer<vtkPNGWriter>::New();
  writer->SetInputData(picture);
  writer->SetFileName(file.string().c_str());
  writer->Write();
}

} // namespace caps::test
