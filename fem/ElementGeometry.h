#pragma once

#include "fem/ElementShape.h"

#include <Eigen/Core>

#include <stdexcept>
#include <string>

namespace caps::fem {

/// World coordinates of an element's 20 node slots, one per row in Bathe
/// order (or wedge order for a native wedge); rows of absent nodes are ignored.
using ElementCoordinates = Eigen::Matrix<double, kHex20NodeCount, 3>;

/// An element that cannot be analysed (inverted, collapsed, distorted).
class ElementError : public std::runtime_error
{
public:
  ElementError(int element, const std::string& what) : std::runtime_error(what), element_(element) {}
  int element() const { return element_; }

private:
  int element_;
};

/**
 * @brief Isoparametric mapping of one element at one point (thesis eq. 4.13):
 *        shape values, Jacobian, its determinant and the world derivatives.
 *
 * J(i, j) = d x_j / d r_i (Bathe's convention), so the world derivatives are
 * dh/dx = dh/dr * J^{-T}.
 */
struct PointGeometry
{
  ShapeVector h;
  ShapeDerivatives dhNatural;
  ShapeDerivatives dhWorld;
  Eigen::Matrix3d jacobian;
  double detJ = 0.0;
  Eigen::Vector3d world; ///< x(r, s, t)
};

/// Smallest accepted scaled Jacobian det J / (|J_r| |J_s| |J_t|); below it
/// the element is too distorted (or collapsed) at that point.
inline constexpr double kMinScaledJacobian = 1e-6;

/**
 * @brief Evaluates the mapping of element @a elementIndex at @a rst and checks
 *        the Jacobian.
 *
 * Throws ElementError naming the element, the natural point and its world
 * position when det J <= 0 (inverted) or the scaled Jacobian is below
 * kMinScaledJacobian (collapsed or badly distorted). Pass @a check = false to
 * evaluate on a collapsed edge (e.g. to map a point of a wedge for display).
 * A native wedge (ElementShape::wedge15()) is checked the same way, its
 * natural point given in the wedge's (r, s, t).
 */
void evaluateGeometry(const ElementShape& shape, const ElementCoordinates& x, const Eigen::Vector3d& rst,
                      int elementIndex, PointGeometry& out, bool check = true);

} // namespace caps::fem
