// Checks the Bathe <-> CalculiX C3D20 node translation against the C3D20 node
// coordinates from CalculiX's documentation and the structure of thesis
// Table 4.1.

#include "fem/ElementNumbering.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <set>
#include <stdexcept>

namespace caps::fem {
namespace {

// CalculiX C3D20, nodes 1..20 (CalculiX User's Manual, "Three-dimensional
// elements", C3D20): corners counter-clockwise at t = -1 then t = +1,
// mid-edges of the bottom face, of the top face, then the vertical edges.
constexpr std::array<std::array<int, 3>, 20> kC3D20Coordinates{{
  {-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}, // 1..4
  {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1},  // 5..8
  {0, -1, -1},  {1, 0, -1},  {0, 1, -1}, {-1, 0, -1}, // 9..12  (1-2, 2-3, 3-4, 4-1)
  {0, -1, 1},   {1, 0, 1},   {0, 1, 1},  {-1, 0, 1},  // 13..16 (5-6, 6-7, 7-8, 8-5)
  {-1, -1, 0},  {1, -1, 0},  {1, 1, 0},  {-1, 1, 0},  // 17..20 (1-5, 2-6, 3-7, 4-8)
}};

Eigen::Vector3d c3d20Coordinates(int node)
{
  const auto& c = kC3D20Coordinates[static_cast<size_t>(node - 1)];
  return {double(c[0]), double(c[1]), double(c[2])};
}

TEST(ElementNumbering, MatchesTheDesignTable)
{
  const std::array<int, 20> design{7, 8, 5, 6, 3, 4, 1, 2, 15, 16, 13, 14, 11, 12, 9, 10, 19, 20, 17, 18};
  EXPECT_EQ(batheToC3D20Table(), design);
}

TEST(ElementNumbering, PermutationIsABijection)
{
  std::set<int> seen(batheToC3D20Table().begin(), batheToC3D20Table().end());
  EXPECT_EQ(seen.size(), 20u);
  EXPECT_EQ(*seen.begin(), 1);
  EXPECT_EQ(*seen.rbegin(), 20);
  std::set<int> seenInverse(c3d20ToBatheTable().begin(), c3d20ToBatheTable().end());
  EXPECT_EQ(seenInverse.size(), 20u);
  EXPECT_EQ(*seenInverse.begin(), 0);
  EXPECT_EQ(*seenInverse.rbegin(), 19);
}

TEST(ElementNumbering, InverseRoundTrips)
{
  for (int k = 0; k < kHex20NodeCount; ++k)
  {
    EXPECT_EQ(c3d20ToBathe(batheToC3D20(k)), k);
    EXPECT_EQ(batheToC3D20Table()[static_cast<size_t>(k)], batheToC3D20(k));
  }
  for (int c = 1; c <= kHex20NodeCount; ++c)
  {
    EXPECT_EQ(batheToC3D20(c3d20ToBathe(c)), c);
    EXPECT_EQ(c3d20ToBatheTable()[static_cast<size_t>(c - 1)], c3d20ToBathe(c));
  }
}

TEST(ElementNumbering, BatheNodeMapsToTheC3D20NodeAtTheSameCoordinates)
{
  for (int k = 0; k < kHex20NodeCount; ++k)
  {
    EXPECT_EQ(batheNaturalCoordinates(k), c3d20Coordinates(batheToC3D20(k)))
      << "Bathe node " << k << " -> C3D20 node " << batheToC3D20(k);
  }
}

TEST(ElementNumbering, CoordinatesFollowThesisTable41Layout)
{
  std::set<std::array<double, 3>> distinct;
  for (int k = 0; k < kHex20NodeCount; ++k)
  {
    const Eigen::Vector3d x = batheNaturalCoordinates(k);
    distinct.insert({x.x(), x.y(), x.z()});
    const auto zeros = std::count(x.data(), x.data() + 3, 0.0);
    EXPECT_EQ(zeros, k < kHex20CornerCount ? 0 : 1) << "node " << k;
    // Face 0 (t = +1): 0..3 and 8..11; face 1 (t = -1): 4..7 and 12..15.
    const bool top = k < 4 || (k >= 8 && k < 12);
    const bool bottom = (k >= 4 && k < 8) || (k >= 12 && k < 16);
    EXPECT_EQ(x.z(), top ? 1.0 : bottom ? -1.0 : 0.0) << "node " << k;
    if (k >= 4 && k < 8)
    { // each bottom corner sits under top corner k - 4
      EXPECT_EQ(x.head<2>(), batheNaturalCoordinates(k - 4).head<2>()) << "node " << k;
    }
  }
  EXPECT_EQ(distinct.size(), 20u);
  // Spot values straight from Table 4.1.
  EXPECT_EQ(batheNaturalCoordinates(0), Eigen::Vector3d(1, 1, 1));
  EXPECT_EQ(batheNaturalCoordinates(6), Eigen::Vector3d(-1, -1, -1));
  EXPECT_EQ(batheNaturalCoordinates(9), Eigen::Vector3d(-1, 0, 1));
  EXPECT_EQ(batheNaturalCoordinates(14), Eigen::Vector3d(0, -1, -1));
  EXPECT_EQ(batheNaturalCoordinates(19), Eigen::Vector3d(1, -1, 0));
}

TEST(ElementNumbering, RejectsOutOfRangeNodes)
{
  EXPECT_THROW(batheToC3D20(-1), std::out_of_range);
  EXPECT_THROW(batheToC3D20(20), std::out_of_range);
  EXPECT_THROW(c3d20ToBathe(0), std::out_of_range);
  EXPECT_THROW(c3d20ToBathe(21), std::out_of_range);
  EXPECT_THROW(batheNaturalCoordinates(20), std::out_of_range);
}

} // namespace
} // namespace caps::fem
