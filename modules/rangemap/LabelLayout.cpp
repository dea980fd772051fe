#include "modules/rangemap/LabelLayout.h"

#include <algorithm>
#include <stdexcept>

namespace caps {

std::vector<std::optional<LabelBox>> layOutLabels(const std::vector<std::array<double, 2>>& anchors,
                                                  const std::vector<std::array<double, 2>>& sizes,
                                                  const LabelBox& bounds, double gap, double dotRadius)
{
  if (anchors.size() != sizes.size())
    throw std::invalid_argument("layOutLabels: one size per anchor");
  std::vector<LabelBox> taken;
  for (const auto& a : anchors)
    taken.push_back({a[0] - dotRadius, a[1] - dotRadius, 2 * dotRadius, 2 * dotRadius});
  auto inside = [&bounds](const LabelBox& b) {
    return b.x >= bounds.x && b.y >= bounds.y && b.x + b.width <= bounds.x + bounds.width &&
           b.y + b.height <= bounds.y + bounds.height;
  };
  std::vector<std::optional<LabelBox>> out(anchors.size());
  for (std::size_t k = 0; k < anchors.size(); ++k)
  {
    const double x = anchors[k][0], y = anchors[k][1], w = sizes[k][0], h = sizes[k][1];
    const LabelBox candidates[] = {
      {x + gap, y - gap - h, w, h}, // right, above
      {x - gap - w, y - gap - h, w, h},
      {x + gap, y + gap, w, h},
      {x - gap - w, y + gap, w, h},
    };
    for (const LabelBox& c : candidates)
    {
      // Its own dot is beside the box, never in it; the others' must not be.
      const bool free =
        inside(c) && std::none_of(taken.begin(), taken.end(), [&c](const LabelBox& t) { return c.intersects(t); });
      if (free)
      {
        out[k] = c;
        taken.push_back(c);
        break;
      }
    }
  }
  return out;
}

} // namespace caps
