#pragma once

#include "fem/ElementNumbering.h"

#include <Eigen/Core>

#include <vector>

namespace caps::fem {

/// Gauss-Legendre points and weights over the cube [-1, 1]^3 (or, from
/// wedgeRule(), over the reference wedge).
struct IntegrationRule
{
  std::vector<Eigen::Vector3d> points; ///< (r, s, t) of each point
  std::vector<double> weights;         ///< alpha_i alpha_j alpha_k (thesis eq. 4.39)
  int pointsPerDirection = 0;          ///< Gauss points along t (and r, s for the cube)
  std::size_t size() const { return points.size(); }
};

/// Gauss-Legendre points and weights on the interval [-1, 1].
struct LineRule
{
  std::vector<double> points;
  std::vector<double> weights;
};

/// The @a points = 1..4 point Gauss-Legendre rule on [-1, 1] (the factors of
/// gaussRule(); face integrals use it twice). Throws std::invalid_argument otherwise.
const LineRule& gaussLineRule(int points);

/// Product Gauss rule with @a pointsPerDirection = 1..4 points along each
/// axis (thesis Table 4.6 is the 3-point rule). Returns a reference to a
/// shared, immutable rule. Throws std::invalid_argument otherwise.
const IntegrationRule& gaussRule(int pointsPerDirection);

/**
 * @brief Rule over the reference wedge (r, s >= 0, r + s <= 1, -1 <= t <= 1;
 *        volume 1) of the native 15-node wedge: a symmetric triangle rule
 *        times the 3-point Gauss rule along t.
 *
 * @a level 3 (default, 18 points): the 6-point degree-4 triangle rule
 * (Dunavant), so the stiffness of an undistorted wedge (degree 4 in r, s and
 * in t) is integrated exactly, as 3x3x3 does for the brick. @a level 2
 * (9 points): the 3-point degree-2 rule at (1/6, 1/6), (2/3, 1/6),
 * (1/6, 2/3), which is CalculiX's C3D15 rule; the lower option, like 2x2x2
 * for the brick. Fewer points along t (3 x 2 = 6 points, 36 strain samples
 * for 39 deformation modes) would leave zero-energy modes. Points run over
 * the triangle fastest, t slowest (ccx order). Throws std::invalid_argument
 * unless @a level is 2 or 3.
 */
const IntegrationRule& wedgeRule(int level);

/// The rule for elements of @a kind: gaussRule(@a pointsPerDirection) for
/// Hex20, wedgeRule(@a pointsPerDirection) for Wedge15 (3 full, 2 lower).
const IntegrationRule& integrationRule(ElementKind kind, int pointsPerDirection);

} // namespace caps::fem
