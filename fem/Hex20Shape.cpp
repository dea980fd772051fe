#include "fem/Hex20Shape.h"

#include <stdexcept>
#include <string>

namespace caps::fem {

namespace {

// Mid-side neighbours of each corner, eq. 4.16 (h_0 = g_0 - (g_8 + g_11 + g_16)/2, ...).
constexpr int kCornerNeighbours[8][3] = {{8, 11, 16},  {8, 9, 17},   {9, 10, 18},  {10, 11, 19},
                                         {12, 15, 16}, {12, 13, 17}, {13, 14, 18}, {14, 15, 19}};

// Table 4.1 as integers.
struct NaturalTable
{
  int c[kHex20NodeCount][3];
  NaturalTable() : c{}
  {
    for (int k = 0; k < kHex20NodeCount; ++k)
    {
      const Eigen::Vector3d x = batheNaturalCoordinates(k);
      for (int d = 0; d < 3; ++d)
        c[k][d] = int(x[d]);
    }
  }
};

const NaturalTable& natural()
{
  static const NaturalTable table;
  return table;
}

// G(beta, beta_i) of eq. 4.16 and its derivative.
inline void factor1d(double beta, int betaNode, double& g, double& dg)
{
  if (betaNode == 0)
  {
    g = 1.0 - beta * beta;
    dg = -2.0 * beta;
  }
  else
  {
    g = 0.5 * (1.0 + betaNode * beta);
    dg = 0.5 * betaNode;
  }
}

} // namespace

Hex20Shape::Hex20Shape(std::uint32_t midsideMask) : mask_(midsideMask)
{
  if ((midsideMask & ~kAllMidside) != 0)
  {
    throw std::invalid_argument("Hex20Shape: mid-side mask has bits beyond the 12 mid-side nodes");
  }
}

Hex20Shape Hex20Shape::fromConnectivity(const std::array<int, kHex20NodeCount>& nodes)
{
  std::uint32_t mask = 0;
  for (int k = kHex20CornerCount; k < kHex20NodeCount; ++k)
    if (nodes[k] >= 0)
      mask |= 1u << (k - kHex20CornerCount);
  return Hex20Shape(mask);
}

bool Hex20Shape::hasNode(int batheNode) const
{
  if (batheNode < 0 || batheNode >= kHex20NodeCount)
    throw std::out_of_range("Bathe node " + std::to_string(batheNode) + " is outside 0..19");
  return batheNode < kHex20CornerCount || ((mask_ >> (batheNode - kHex20CornerCount)) & 1u) != 0;
}

int Hex20Shape::nodeCount() const
{
  int n = kHex20CornerCount;
  for (int k = 0; k < 12; ++k)
    n += int((mask_ >> k) & 1u);
  return n;
}

void Hex20Shape::values(const Eigen::Vector3d& rst, ShapeVector& h) const
{
  ShapeDerivatives dh;
  evaluate(rst, h, dh);
}

void Hex20Shape::evaluate(const Eigen::Vector3d& rst, ShapeVector& h, ShapeDerivatives& dh) const
{
  const NaturalTable& n = natural();
  for (int k = 0; k < kHex20NodeCount; ++k)
  {
    if (k >= kHex20CornerCount && ((mask_ >> (k - kHex20CornerCount)) & 1u) == 0)
    {
      h[k] = 0.0;
      dh.row(k).setZero();
      continue;
    }
    double g[3], dg[3];
    for (int d = 0; d < 3; ++d)
      factor1d(rst[d], n.c[k][d], g[d], dg[d]);
    h[k] = g[0] * g[1] * g[2];
    dh(k, 0) = dg[0] * g[1] * g[2];
    dh(k, 1) = g[0] * dg[1] * g[2];
    dh(k, 2) = g[0] * g[1] * dg[2];
  }
  for (int c = 0; c < kHex20CornerCount; ++c)
  {
    for (int m : kCornerNeighbours[c])
    {
      h[c] -= 0.5 * h[m];
      dh.row(c) -= 0.5 * dh.row(m);
    }
  }
}

} // namespace caps::fem
