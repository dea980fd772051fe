#pragma once
/// @file SurfaceScanColourMap.h
/// @brief The colour channel of a surface scan: RGB per (θ, z) sample (§3.2.1, §4.2.1).

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "segmentation/CylindricalFrame.h"

namespace caps::seg {

/// One 24-bit colour sample (the Cyberware's r, g, b channels, §4.2.1).
using Rgb8 = std::array<std::uint8_t, 3>;

/// @class ColourMap
/// @brief nθ × nz RGB samples on a cylindrical frame's grid, stored like RangeMap (index j · nθ + i).
///
/// It goes with a RangeMap on the same frame: where the range is NaN the
/// colour means nothing and is black.
class ColourMap
{
public:
  ColourMap() = default;
  explicit ColourMap(const CylindricalFrame& frame, Rgb8 value = {0, 0, 0})
    : frame_(frame), values_(static_cast<std::size_t>(frame.nTheta()) * frame.nZ(), value)
  {}

  const CylindricalFrame& frame() const { return frame_; }
  /// Replace the frame by one with the same grid (calibration rescales z, §4.3).
  void setFrame(const CylindricalFrame& frame) { frame_ = frame; }
  int nTheta() const { return frame_.nTheta(); }
  int nZ() const { return frame_.nZ(); }
  bool empty() const { return values_.empty(); }

  Rgb8& at(int i, int j) { return values_[static_cast<std::size_t>(j) * nTheta() + i]; }
  const Rgb8& at(int i, int j) const { return values_[static_cast<std::size_t>(j) * nTheta() + i]; }
  std::vector<Rgb8>& values() { return values_; }
  const std::vector<Rgb8>& values() const { return values_; }

private:
  CylindricalFrame frame_;
  std::vector<Rgb8> values_;
};

} // namespace caps::seg
