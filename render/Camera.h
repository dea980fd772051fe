#pragma once
/// @file Camera.h
/// @brief A camera as vtkCamera describes it: the value a saved view keeps
/// (scene/SnapshotNode) and a figure renders with (render/Figure.h).
/// Header-only and plain, so the scene holds one without linking rendering.

#include <array>

namespace caps::render {

/// Patient LPS, mm; vertical view angle in degrees, as VTK.
struct Camera
{
  std::array<double, 3> position{0, -500, 0};
  std::array<double, 3> focalPoint{0, 0, 0};
  std::array<double, 3> viewUp{0, 0, 1};
  double viewAngle = 30.0;
  bool operator==(const Camera&) const = default;
};

} // namespace caps::render
