#include "segmentation/MetalArtefacts.h"

#include "segmentation/RangeMapImageGeometry.h"

#include <vtkImageData.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

namespace caps::seg {

namespace {

/// The linear indices of the voxels at or above @a threshold.
template <typename T> std::vector<std::int64_t> voxelsAbove(const T* data, std::int64_t count, double threshold)
{
  std::vector<std::int64_t> out;
  for (std::int64_t v = 0; v < count; ++v)
    if (double(data[v]) >= threshold)
      out.push_back(v);
  return out;
}

Eigen::Vector3d extentStart(const ImageGeometry& g)
{
  return Eigen::Vector3d(g.extent[0], g.extent[2], g.extent[4]);
}

} // namespace

std::vector<MetalPiece> findMetal(vtkImageData* ct, const MetalOptions& options)
{
  if (!ct || ct->GetNumberOfScalarComponents() != 1 || !ct->GetScalarPointer())
    throw std::invalid_argument("The metal search needs a CT with one value per voxel.");
  const ImageGeometry geometry = ImageGeometry::of(ct);
  const auto dims = geometry.dimensions();
  const std::int64_t nx = dims[0], ny = dims[1], nz = dims[2], count = nx * ny * nz;
  std::vector<std::int64_t> metal;
  switch (ct->GetScalarType())
  {
    vtkTemplateMacro(metal = voxelsAbove(static_cast<const VTK_TT*>(ct->GetScalarPointer()), count, options.metalHu));
  default:
    throw std::invalid_argument("The CT's voxel type is not supported.");
  }
  // Pieces: 26-connected groups of metal voxels, grown from each unvisited one.
  std::sort(metal.begin(), metal.end());
  std::vector<char> visited(metal.size(), 0);
  auto indexOf = [&metal](std::int64_t v) {
    const auto at = std::lower_bound(metal.begin(), metal.end(), v);
    return at != metal.end() && *at == v ? std::int64_t(at - metal.begin()) : std::int64_t(-1);
  };
  const int spoilSlices = int(std::ceil(options.streakMargin / std::abs(geometry.spacing.z())));
  std::vector<MetalPiece> pieces;
  std::vector<std::int64_t> stack;
  for (std::size_t seed = 0; seed < metal.size(); ++seed)
  {
    if (visited[seed])
      continue;
    MetalPiece piece;
    piece.firstSlice = int(nz);
    piece.lastSlice = -1;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    visited[seed] = 1;
    stack.assign(1, std::int64_t(seed));
    while (!stack.empty())
    {
      const std::int64_t v = metal[std::size_t(stack.back())];
      stack.pop_back();
      const std::int64_t i = v % nx, j = (v / nx) % ny, k = v / (nx * ny);
      ++piece.voxels;
      sum += Eigen::Vector3d(double(i), double(j), double(k));
      piece.peakHu =
        std::max(piece.peakHu, ct->GetScalarComponentAsDouble(int(i + geometry.extent[0]), int(j + geometry.extent[2]),
                                                              int(k + geometry.extent[4]), 0));
      piece.firstSlice = std::min(piece.firstSlice, int(k));
      piece.lastSlice = std::max(piece.lastSlice, int(k));
      for (int dk = -1; dk <= 1; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di)
          {
            const std::int64_t a = i + di, b = j + dj, c = k + dk;
            if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz)
              continue;
            const std::int64_t n = indexOf(a + nx * (b + ny * c));
            if (n >= 0 && !visited[std::size_t(n)])
            {
              visited[std::size_t(n)] = 1;
              stack.push_back(n);
            }
          }
    }
    if (piece.voxels < options.smallestPiece)
      continue;
    piece.centroid = geometry.indexToWorld(sum / double(piece.voxels) + extentStart(geometry));
    piece.firstSpoiled = std::max(0, piece.firstSlice - spoilSlices);
    piece.lastSpoiled = std::min(int(nz) - 1, piece.lastSlice + spoilSlices);
    pieces.push_back(piece);
  }
  std::sort(pieces.begin(), pieces.end(), [](const MetalPiece& a, const MetalPiece& b) { return a.voxels > b.voxels; });
  return pieces;
}

const MetalPiece* streaksAt(const std::vector<MetalPiece>& pieces, vtkImageData* ct, const Eigen::Vector3d& p)
{
  if (pieces.empty() || !ct || !p.allFinite())
    return nullptr;
  const ImageGeometry geometry = ImageGeometry::of(ct);
  const double k = (geometry.worldToIndex(p) - extentStart(geometry)).z();
  for (const MetalPiece& piece : pieces)
    if (k >= piece.firstSpoiled - 0.5 && k <= piece.lastSpoiled + 0.5)
      return &piece;
  return nullptr;
}

std::string describe(const MetalPiece& piece, vtkImageData* ct)
{
  const ImageGeometry geometry = ImageGeometry::of(ct);
  const Eigen::Vector3d centre = geometry.worldToIndex(piece.centroid);
  auto sliceZ = [&](int k) {
    return geometry.indexToWorld(Eigen::Vector3d(centre.x(), centre.y(), double(k + geometry.extent[4]))).z();
  };
  const double z0 = sliceZ(piece.firstSpoiled), z1 = sliceZ(piece.lastSpoiled);
  std::ostringstream s;
  s.precision(1);
  s << std::fixed << "metal or undiluted contrast (" << piece.peakHu << " HU, " << piece.voxels << " voxels) at ("
    << piece.centroid.x() << ", " << piece.centroid.y() << ", " << piece.centroid.z()
    << ") mm: its streaks spoil the slices from z " << std::min(z0, z1) << " to " << std::max(z0, z1) << " mm";
  return s.str();
}

} // namespace caps::seg
