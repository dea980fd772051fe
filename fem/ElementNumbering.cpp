#include "fem/ElementNumbering.h"

#include <stdexcept>
#include <string>

namespace caps::fem {

namespace {

// Thesis Table 4.1, row k = Bathe node k.
constexpr std::array<std::array<int, 3>, kHex20NodeCount> kBatheCoordinates{{
  {1, 1, 1},  {-1, 1, 1},  {-1, -1, 1},  {1, -1, 1},  // 0..3   corners, t = +1
  {1, 1, -1}, {-1, 1, -1}, {-1, -1, -1}, {1, -1, -1}, // 4..7   corners, t = -1
  {0, 1, 1},  {-1, 0, 1},  {0, -1, 1},   {1, 0, 1},   // 8..11  mid-edges, t = +1
  {0, 1, -1}, {-1, 0, -1}, {0, -1, -1},  {1, 0, -1},  // 12..15 mid-edges, t = -1
  {1, 1, 0},  {-1, 1, 0},  {-1, -1, 0},  {1, -1, 0},  // 16..19 vertical edges
}};

// DESIGN.md conventions: Bathe 0..19 -> C3D20 1..20.
constexpr std::array<int, kHex20NodeCount> kBatheToC3D20{7,  8,  5,  6,  3, 4,  1,  2,  15, 16,
                                                         13, 14, 11, 12, 9, 10, 19, 20, 17, 18};

constexpr std::array<int, kHex20NodeCount> invert(const std::array<int, kHex20NodeCount>& forward)
{
  std::array<int, kHex20NodeCount> inverse{};
  for (int k = 0; k < kHex20NodeCount; ++k)
    inverse[forward[k] - 1] = k;
  return inverse;
}

constexpr std::array<int, kHex20NodeCount> kC3D20ToBathe = invert(kBatheToC3D20);

// Wedge numbering (ElementNumbering.h): r, s doubled to stay integers.
constexpr std::array<std::array<int, 3>, kWedge15NodeCount> kWedgeCoordinates2{{
  {0, 0, 1},
  {2, 0, 1},
  {0, 2, 1}, // 0..2   corners, t = +1
  {0, 0, -1},
  {2, 0, -1},
  {0, 2, -1}, // 3..5   corners, t = -1
  {1, 0, 1},
  {1, 1, 1},
  {0, 1, 1}, // 6..8   mid-edges, t = +1
  {1, 0, -1},
  {1, 1, -1},
  {0, 1, -1}, // 9..11  mid-edges, t = -1
  {0, 0, 0},
  {2, 0, 0},
  {0, 2, 0}, // 12..14 edges along t
}};

// Wedge 0..14 -> C3D15 1..15: the same natural point in both (ccx shape15w).
constexpr std::array<int, kWedge15NodeCount> kWedgeToC3D15{4, 5, 6, 1, 2, 3, 10, 11, 12, 7, 8, 9, 13, 14, 15};

constexpr std::array<int, kWedge15NodeCount> invertWedge(const std::array<int, kWedge15NodeCount>& forward)
{
  std::array<int, kWedge15NodeCount> inverse{};
  for (int k = 0; k < kWedge15NodeCount; ++k)
    inverse[forward[k] - 1] = k;
  return inverse;
}

constexpr std::array<int, kWedge15NodeCount> kC3D15ToWedge = invertWedge(kWedgeToC3D15);

void checkRange(int value, int first, int last, const char* what)
{
  if (value < first || value > last)
  {
    throw std::out_of_range(std::string(what) + " " + std::to_string(value) + " is outside " + std::to_string(first) +
                            ".." + std::to_string(last));
  }
}

} // namespace

int batheToC3D20(int batheNode)
{
  checkRange(batheNode, 0, kHex20NodeCount - 1, "Bathe node");
  return kBatheToC3D20[batheNode];
}

int c3d20ToBathe(int c3d20Node)
{
  checkRange(c3d20Node, 1, kHex20NodeCount, "C3D20 node");
  return kC3D20ToBathe[c3d20Node - 1];
}

const std::array<int, kHex20NodeCount>& batheToC3D20Table()
{
  return kBatheToC3D20;
}

const std::array<int, kHex20NodeCount>& c3d20ToBatheTable()
{
  return kC3D20ToBathe;
}

Eigen::Vector3d batheNaturalCoordinates(int batheNode)
{
  checkRange(batheNode, 0, kHex20NodeCount - 1, "Bathe node");
  const auto& c = kBatheCoordinates[batheNode];
  return {double(c[0]), double(c[1]), double(c[2])};
}

int wedge15ToC3D15(int wedgeNode)
{
  checkRange(wedgeNode, 0, kWedge15NodeCount - 1, "wedge node");
  return kWedgeToC3D15[wedgeNode];
}

int c3d15ToWedge15(int c3d15Node)
{
  checkRange(c3d15Node, 1, kWedge15NodeCount, "C3D15 node");
  return kC3D15ToWedge[c3d15Node - 1];
}

Eigen::Vector3d wedge15NaturalCoordinates(int wedgeNode)
{
  checkRange(wedgeNode, 0, kWedge15NodeCount - 1, "wedge node");
  const auto& c = kWedgeCoordinates2[wedgeNode];
  return {0.5 * c[0], 0.5 * c[1], double(c[2])};
}

} // namespace caps::fem
