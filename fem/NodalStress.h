#pragma once

#include "fem/LinearElasticMaterial.h"
#include "fem/Mesh.h"

#include <Eigen/Core>

namespace caps::fem {

/// Stress (Voigt xx, yy, zz, xy, yz, zx) at every node, one column per node.
using NodalStressMatrix = Eigen::Matrix<double, 6, Eigen::Dynamic>;

/**
 * @brief Stresses averaged at the nodes (thesis §4.7), with the derived
 *        scalar fields.
 *
 * A node in no element has zero stress and elementCount 0.
 */
struct NodalStressField {
  NodalStressMatrix stress;     ///< 6 x N (MPa)
  Eigen::VectorXi elementCount;  ///< elements averaged at each node

  /// von Mises stress at each node (N).
  Eigen::VectorXd vonMises() const;
  /// Mean stress (sxx + syy + szz) / 3 at each node (N); pressure is its negative.
  Eigen::VectorXd meanStress() const;
  /// Principal stresses at each node, largest first (3 x N).
  Eigen::Matrix3Xd principal() const;
};

/// von Mises equivalent of one Voigt stress.
double vonMisesStress(const Vector6d& s);
/// Eigenvalues of the symmetric stress tensor of @a s, largest first.
Eigen::Vector3d principalStresses(const Vector6d& s);

/**
 * @brief Extrapolation matrix from the Gauss points to the 20 Bathe nodes.
 *
 * Row k, column p: weight of Gauss point p (in gaussRule(@a pointsPerDirection)
 * order) in the value at Bathe node k. The n^3 Gauss values define exactly one
 * tensor-product Lagrange polynomial of degree n - 1 in each of r, s, t
 * (trilinear for 2x2x2, triquadratic for 3x3x3); the row is that polynomial
 * evaluated at the node's natural coordinates. For 2x2x2 this is the inverse of
 * the usual "corner nodes to Gauss points" trilinear interpolation. Returns a
 * 20 x n^3 matrix; throws std::invalid_argument unless n is 2 or 3.
 */
Eigen::MatrixXd gaussToNodeExtrapolation(int pointsPerDirection);

/**
 * @brief Nodal stresses: in each element, sigma at the Gauss points
 *        (recoverStressAtGaussPoints), extrapolated to the element's nodes by
 *        gaussToNodeExtrapolation() of its kind, then averaged (plain mean)
 *        over the elements sharing each node.
 *
 * Each element uses its own rule, integrationPointsOf(element,
 * @a pointsPerDirection): a deck's C3D20R extrapolates from its 2x2x2
 * points, a C3D20 from its 3x3x3 ones (as ccx does); @a pointsPerDirection
 * is the choice for elements that leave it to the analysis (0).
 *
 * The default 2x2x2 points are the Barlow (superconvergent) points of the
 * 20-node brick; its trilinear extrapolation reproduces any stress field
 * linear in (r, s, t) exactly and does not amplify the cubic noise of the
 * 3x3x3 values near the corners (the 3x3x3 Lagrange extrapolation
 * magnifies it by up to ~(1 + sqrt(5/3))^3 / 8 per direction). A node
 * repeated in a degenerate (wedge) element takes the mean of its slots
 * first, so the element counts once. Stresses of different regions are
 * averaged too (they jump across material interfaces).
 *
 * @a u holds the 3N nodal displacements. Throws ElementError for a bad
 * Jacobian at a Gauss point, std::invalid_argument for a wrong @a u size.
 */
/**
 * @brief The same for elements of @a kind. Hex20: gaussToNodeExtrapolation(n).
 *        Wedge15 (points of wedgeRule(n), rows 15..19 zero): for n = 2 the
 *        polynomial linear in (r, s) times linear in t fitted by least squares
 *        to the 3 x 3 values (it reproduces any stress linear in r, s, t
 *        exactly and, like the brick's 2x2x2 trilinear extrapolation, does not
 *        magnify the higher-order noise); for n = 3 the quadratic-in-(r, s)
 *        times quadratic-in-t interpolant of the 6 x 3 values.
 */
Eigen::MatrixXd gaussToNodeExtrapolation(ElementKind kind, int pointsPerDirection);

NodalStressField recoverNodalStresses(const Mesh& mesh, const MaterialTable& materials, const Eigen::VectorXd& u,
                                      int pointsPerDirection = 2);

}  // namespace caps::fem
