#pragma once
/// @file RangeMap.h
/// @brief A range map: r(θ, z) in mm on a cylindrical frame's sample grid (§4.2.1).

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "segmentation/CylindricalFrame.h"

namespace caps::seg {

/// @class RangeMap
/// @brief nθ × nz float samples in mm (NaN where the surface was not found) with their frame.
///
/// Sample (i, j) is column i (θ_i) and row j (z_j) of frame(); values are
/// stored row by row, index j · nθ + i (eq. 4.1). Reading between samples is
/// bilinear (eq. 4.9) and wraps around in θ: the cell between the last column
/// and column 0 is an ordinary cell.
///
/// Next to a NaN, sampling renormalises the bilinear weights over the finite
/// corners of the cell, and returns NaN when the finite corners carry less
/// than half of the weight: the surface ends half a cell into a hole, a point
/// on a finite sample returns that sample exactly, and a point on a NaN
/// sample returns NaN. Outside [zMin, zMax] (rows [0, nz - 1]) the result is
/// NaN: the surface was not measured there (the thesis clamps, eq. 4.1, which
/// would invent a cylinder above and below the scan).
class RangeMap
{
public:
  /// An empty map (0 × 0) on the default frame.
  RangeMap();
  /// A map on frame's grid with every sample set to value (NaN by default).
  explicit RangeMap(const CylindricalFrame& frame, float value = quietNaN());

  const CylindricalFrame& frame() const { return frame_; }
  int nTheta() const { return frame_.nTheta(); }
  int nZ() const { return frame_.nZ(); }
  bool empty() const { return values_.empty(); }

  /// Sample of column i (θ), row j (z); no bounds check in release builds.
  float& at(int i, int j) { return values_[static_cast<std::size_t>(j) * nTheta() + i]; }
  float at(int i, int j) const { return values_[static_cast<std::size_t>(j) * nTheta() + i]; }
  /// All samples, row by row (size nθ · nz).
  std::vector<float>& values() { return values_; }
  const std::vector<float>& values() const { return values_; }
  /// Number of finite samples.
  std::size_t validCount() const;

  /// Bilinear value at continuous sample indices (u column, v row), eq. 4.9,
  /// u wrapping modulo nθ; see the class comment for NaN and out-of-range rules.
  double sampleIndex(double u, double v) const;
  /// Bilinear value at θ (radians, any value: wrapped) and z (mm along the axis).
  double sample(double theta, double z) const;

  /// World point of sample (i, j): frame().toWorld(at(i, j), θ_i, z_j); NaN if the sample is.
  Eigen::Vector3d surfacePoint(int i, int j) const;
  /// Outward unit normal of the surface r(θ, z) at sample (i, j), from central
  /// differences of r (one-sided next to NaN or at the first/last row, wrapping in θ):
  /// n ∝ r ê_r − ∂r/∂θ ê_θ − r ∂r/∂z â. NaN if the sample or both neighbours along θ or z are NaN.
  Eigen::Vector3d outwardNormal(int i, int j) const;

  static float quietNaN();

private:
  CylindricalFrame frame_;
  std::vector<float> values_;
};

/// 3 × 3 box smoothing (§4.2.1, eq. 4.2) wrapping in θ.
///
/// Each finite sample becomes the mean of the finite samples of its 3 × 3
/// neighbourhood (rows beyond the first and last are absent, not clamped
/// copies); NaN samples stay NaN, so holes neither grow nor shrink and a
/// constant map stays that constant.
RangeMap boxSmooth(const RangeMap& map);

} // namespace caps::seg
