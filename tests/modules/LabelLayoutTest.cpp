// The landmark names on the unwrapped map: none covers another name or a
// dot, each sits beside its own dot, and a name with no room is left out.

#include <cmath>

#include <gtest/gtest.h>

#include "modules/rangemap/LabelLayout.h"

namespace {

TEST(LabelLayout, NamesCoverNoOtherNameOrDotAndSitBesideTheirOwn)
{
  // The midline of a face: dots 6 px apart (nasion, mid-nasal, rhinion ...),
  // two cheeks beside them; names 60 x 14 px.
  std::vector<std::array<double, 2>> anchors;
  for (int k = 0; k < 8; ++k)
    anchors.push_back({200.0, 100.0 + 6.0 * k});
  anchors.push_back({140.0, 130.0});
  anchors.push_back({260.0, 130.0});
  const std::vector<std::array<double, 2>> sizes(anchors.size(), {60.0, 14.0});
  const caps::LabelBox bounds{0.0, 0.0, 400.0, 300.0};
  const auto boxes = caps::layOutLabels(anchors, sizes, bounds);
  ASSERT_EQ(boxes.size(), anchors.size());
  int placed = 0;
  for (std::size_t a = 0; a < boxes.size(); ++a)
  {
    if (!boxes[a])
      continue;
    ++placed;
    const caps::LabelBox& b = *boxes[a];
    EXPECT_EQ(b.width, 60.0);
    EXPECT_EQ(b.height, 14.0);
    // Beside its dot: a corner 5 px off it both ways.
    const double dx = std::min(std::abs(b.x - anchors[a][0]), std::abs(b.x + b.width - anchors[a][0]));
    const double dy = std::min(std::abs(b.y - anchors[a][1]), std::abs(b.y + b.height - anchors[a][1]));
    EXPECT_DOUBLE_EQ(dx, 5.0) << a;
    EXPECT_DOUBLE_EQ(dy, 5.0) << a;
    EXPECT_TRUE(b.x >= 0 && b.y >= 0 && b.x + b.width <= 400 && b.y + b.height <= 300) << a;
    for (std::size_t o = 0; o < boxes.size(); ++o)
    {
      const caps::LabelBox dot{anchors[o][0] - 3.5, anchors[o][1] - 3.5, 7.0, 7.0};
      EXPECT_FALSE(b.intersects(dot)) << "name " << a << " covers dot " << o;
      if (o != a && boxes[o])
        EXPECT_FALSE(b.intersects(*boxes[o])) << "names " << a << " and " << o;
    }
  }
  // The crowded midline cannot hold all eight names, but holds several, and
  // a lone dot's name goes right and above it.
  EXPECT_GE(placed, 5);
  EXPECT_LT(placed, int(anchors.size()));
  const auto lone = caps::layOutLabels({{100.0, 100.0}}, {{60.0, 14.0}}, bounds);
  ASSERT_TRUE(lone[0]);
  EXPECT_DOUBLE_EQ(lone[0]->x, 105.0);
  EXPECT_DOUBLE_EQ(lone[0]->y, 81.0);
  // At the right edge it goes left instead.
  const auto edge = caps::layOutLabels({{380.0, 100.0}}, {{60.0, 14.0}}, bounds);
  ASSERT_TRUE(edge[0]);
  EXPECT_DOUBLE_EQ(edge[0]->x, 315.0);
  EXPECT_THROW(caps::layOutLabels({{1.0, 1.0}}, {}, bounds), std::invalid_argument);
}

} // namespace
