#pragma once
/// @file LabelLayout.h
/// @brief Where the names of landmarks go on the unwrapped map so that none
/// covers another or another's dot (the nasion, mid-nasal and rhinion sit a
/// few millimetres apart). No widgets: pixel boxes only.

#include <array>
#include <optional>
#include <vector>

namespace caps {

/// An axis-aligned box in pixels: top-left corner, width and height.
struct LabelBox
{
  double x = 0.0, y = 0.0, width = 0.0, height = 0.0;
  bool intersects(const LabelBox& o) const
  {
    return x < o.x + o.width && o.x < x + width && y < o.y + o.height && o.y < y + height;
  }
};

/// For each dot @a anchors[k] (pixels) with a label of @a sizes[k] (width,
/// height), in order: the first of right-above, left-above, right-below and
/// left-below the dot (@a gap pixels off it) that lies inside @a bounds and
/// covers no label placed before it and no dot (a square of 2 · @a dotRadius);
/// std::nullopt when all four are taken (the landmark table names it).
std::vector<std::optional<LabelBox>> layOutLabels(const std::vector<std::array<double, 2>>& anchors,
                                                  const std::vector<std::array<double, 2>>& sizes,
                                                  const LabelBox& bounds, double gap = 5.0, double dotRadius = 3.5);

} // namespace caps
