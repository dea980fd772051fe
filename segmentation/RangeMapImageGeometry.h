#pragma once
/// @file RangeMapImageGeometry.h
/// @brief Image index ↔ world (LPS mm) through a volume's origin, spacing and direction.

#include <array>

#include <Eigen/Core>

class vtkImageData;

namespace caps::seg {

/// The grid of a CT or a mask: voxel (i, j, k) sits at
/// origin + direction · diag(spacing) · (i, j, k) in LPS mm (VTK's and ITK's
/// convention; indices are VTK structured indices, so an extent that does not
/// start at 0 is honoured).
struct ImageGeometry
{
  std::array<int, 6> extent = {0, -1, 0, -1, 0, -1};
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d spacing = Eigen::Vector3d::Ones();
  Eigen::Matrix3d direction = Eigen::Matrix3d::Identity();

  /// The geometry of a VTK image (direction from GetDirectionMatrix()).
  static ImageGeometry of(vtkImageData* image);

  /// Voxels along each index axis.
  std::array<int, 3> dimensions() const;
  /// direction · diag(spacing): index steps to world steps.
  Eigen::Matrix3d indexToWorldMatrix() const;
  Eigen::Vector3d indexToWorld(const Eigen::Vector3d& index) const;
  Eigen::Vector3d worldToIndex(const Eigen::Vector3d& world) const;
  /// True if the two grids place every voxel within tolerance mm of each other.
  bool sameGrid(const ImageGeometry& other, double tolerance = 1e-3) const;
  /// Sets extent, origin, spacing and direction on an image (no allocation).
  void applyTo(vtkImageData* image) const;
};

} // namespace caps::seg
