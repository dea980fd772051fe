#pragma once

#include "fem/ElementNumbering.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>

namespace caps::fem {

/// Values of the 20 interpolation functions at one point (absent nodes give 0).
using ShapeVector = Eigen::Matrix<double, kHex20NodeCount, 1>;
/// Derivatives: row k is (dh_k/dr, dh_k/ds, dh_k/dt).
using ShapeDerivatives = Eigen::Matrix<double, kHex20NodeCount, 3>;

/**
 * @brief Interpolation functions of Bathe's 8-to-20 variable-number-of-nodes
 *        hexahedron (thesis Table 4.1, eq. 4.16).
 *
 * The eight corners are always present; any subset of the twelve mid-side
 * nodes 8..19 may be present. For an absent mid-side node g_i = 0, and the
 * corners are corrected only by the present neighbours (eq. 4.16), so the
 * functions keep the partition of unity and the Kronecker property on the
 * present nodes. A wedge is the same element with repeated node numbers.
 */
class Hex20Shape
{
public:
  /// Bit k of @a midsideMask (k = 0..11) tells whether Bathe node 8 + k exists.
  explicit Hex20Shape(std::uint32_t midsideMask = kAllMidside);

  /// Element with the nodes whose global index is >= 0 (corners must be >= 0).
  static Hex20Shape fromConnectivity(const std::array<int, kHex20NodeCount>& nodes);

  /// True if Bathe node @a batheNode (0..19) is part of this element.
  bool hasNode(int batheNode) const;
  std::uint32_t midsideMask() const { return mask_; }
  int nodeCount() const;

  /// h_k(r, s, t) into @a h (sized 20; absent nodes 0).
  void values(const Eigen::Vector3d& rst, ShapeVector& h) const;
  /// h_k and their natural derivatives at (r, s, t).
  void evaluate(const Eigen::Vector3d& rst, ShapeVector& h, ShapeDerivatives& dh) const;

  static constexpr std::uint32_t kAllMidside = 0xFFFu;

private:
  std::uint32_t mask_;
};

} // namespace caps::fem
