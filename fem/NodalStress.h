#pragma once

#include "fem/LinearElasticMaterial.h"
#include "fem/Mesh.h"
#include "fem/StressRecovery.h"

#include <Eigen/Core>

#include <functional>
#include <map>
#include <vector>

namespace caps::fem {

/// Stress (Voigt xx, yy, zz, xy, yz, zx) at every node, one column per node.
using NodalStressMatrix = Eigen::Matrix<double, 6, Eigen::Dynamic>;

/**
 * @brief The (region, node) pairs of a mesh: the columns of a nodal field
 *        averaged within each region.
 *
 * A node inside one region has one column; a node on the interface of k
 * regions has k, one per region, since the stress jumps there (skin, fat and
 * muscle differ up to 15x in stiffness). Columns are grouped by node, in node
 * order, regions ascending within a node: node n's columns are
 * firstColumn[n] .. firstColumn[n + 1] - 1 (none for a node in no element).
 *
 * Each node also has a representative column, for callers that need one
 * value per node: the column of its stiffest region (largest small-strain
 * shear modulus, the lowest region id on a tie), the layer that carries the
 * load across an interface, so a one-value-per-node field keeps the larger
 * stress there. A node on the skin surface lies in skin elements only, so it
 * takes the skin's value whatever the rule.
 */
struct RegionNodeLayout
{
  Eigen::VectorXi regionOf;       ///< region of each column (R)
  Eigen::VectorXi nodeOf;         ///< mesh node of each column (R)
  Eigen::VectorXi elementCount;   ///< elements of that region sharing that node (R)
  Eigen::VectorXi firstColumn;    ///< N + 1 offsets into the columns
  Eigen::VectorXi representative; ///< column standing for each node (N); -1 for a node in no element

  Eigen::Index size() const { return regionOf.size(); }
  /// Column of (@a region, @a node); -1 when no element of @a region holds @a node.
  int column(int region, int node) const;

  /**
   * @brief The layout of @a mesh. @a stiffness gives each region's
   *        small-strain shear modulus, for the representative columns; a
   *        region missing from it ranks as 0. Throws std::invalid_argument
   *        for an element node out of range.
   */
  static RegionNodeLayout of(const Mesh& mesh, const std::map<int, double>& stiffness);
};

/**
 * @brief Values at the integration points of each element extrapolated to
 *        its nodes and averaged (plain mean) over the elements of the same
 *        region sharing each node: the scheme of recoverNodalStresses(), for
 *        any quantity.
 *
 * @a gaussValues(e, values) fills @a values (@a rows x points) with the
 * values at the points of element e's own rule, integrationRule(kind,
 * integrationPointsOf(element, @a pointsPerDirection)), in its order. Each
 * element's values are extrapolated by gaussToNodeExtrapolation() of its
 * kind and rule; a node repeated in a degenerate (wedge) element takes the
 * mean of its slots first, so the element counts once. Returns
 * @a rows x layout.size().
 */
Eigen::MatrixXd averageAtRegionNodes(const Mesh& mesh, const RegionNodeLayout& layout, int rows, int pointsPerDirection,
                                     const std::function<void(int element, Eigen::MatrixXd& values)>& gaussValues);

/// The representative column of each node taken from @a regionValues
/// (rows x layout.size()); zero for a node in no element (rows x N).
Eigen::MatrixXd representativeValues(const RegionNodeLayout& layout, const Eigen::MatrixXd& regionValues);

/**
 * @brief Stresses averaged at the nodes within each region (thesis §4.7),
 *        with the derived scalar fields.
 *
 * regionStress holds one column per (region, node) pair of layout; stress
 * one per node, the value of its representative region (RegionNodeLayout:
 * the stiffest region at an interface, the only one elsewhere), which
 * vonMises(), meanStress() and principal() derive from. A node in no
 * element has zero stress and elementCount 0.
 */
struct NodalStressField
{
  RegionNodeLayout layout;
  NodalStressMatrix regionStress; ///< 6 x R (MPa), one column per (region, node)
  NodalStressMatrix stress;       ///< 6 x N (MPa), the representative region's value
  Eigen::VectorXi elementCount;   ///< elements averaged into each column of stress (N)

  /// The stress of @a region at @a node (MPa); throws std::out_of_range when
  /// no element of that region holds the node.
  Vector6d valueAt(int region, int node) const;
  /// The region whose value stress.col(@a node) is; -1 for a node in no element.
  int regionAt(int node) const;

  /// von Mises stress at each node (N).
  Eigen::VectorXd vonMises() const;
  /// Mean stress (sxx + syy + szz) / 3 at each node (N); pressure is its negative.
  Eigen::VectorXd meanStress() const;
  /// Principal stresses at each node, largest first (3 x N).
  Eigen::Matrix3Xd principal() const;
  /// von Mises stress of each (region, node) column (R).
  Eigen::VectorXd regionVonMises() const;
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
 * @brief Extrapolation for elements of @a kind. Hex20: gaussToNodeExtrapolation(n).
 *        Wedge15 (points of wedgeRule(n), rows 15..19 zero): for n = 2 the
 *        polynomial linear in (r, s) times linear in t fitted by least squares
 *        to the 3 x 3 values (it reproduces any stress linear in r, s, t
 *        exactly and, like the brick's 2x2x2 trilinear extrapolation, does not
 *        magnify the higher-order noise); for n = 3 the quadratic-in-(r, s)
 *        times quadratic-in-t interpolant of the 6 x 3 values.
 */
Eigen::MatrixXd gaussToNodeExtrapolation(ElementKind kind, int pointsPerDirection);

/**
 * @brief Nodal stresses: in each element, sigma at the Gauss points
 *        (recoverStressAtGaussPoints), extrapolated to the element's nodes by
 *        gaussToNodeExtrapolation() of its kind, then averaged (plain mean)
 *        over the elements of the same region sharing each node
 *        (averageAtRegionNodes()).
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
 * never averaged (they jump across material interfaces): a node on an
 * interface has one value per region (NodalStressField::valueAt), and
 * NodalStressField::stress takes its stiffest region's.
 *
 * @a u holds the 3N nodal displacements. Throws ElementError for a bad
 * Jacobian at a Gauss point, std::invalid_argument for a wrong @a u size.
 */
NodalStressField recoverNodalStresses(const Mesh& mesh, const MaterialTable& materials, const Eigen::VectorXd& u,
                                      int pointsPerDirection = 2, int threads = 1);

/**
 * @brief recoverNodalStresses() from the stresses already recovered at the
 *        points of each element's own rule: @a gaussStress[e] as
 *        recoverStressAtGaussPoints(mesh, materials, u, e,
 *        @a pointsPerDirection) gives them (recoverStressAtAllGaussPoints()),
 *        so a caller that needs both computes them once.
 *
 * Throws std::invalid_argument when @a gaussStress does not have one entry
 * per element, std::logic_error when an entry does not have the points of
 * its element's rule (averageAtRegionNodes()).
 */
NodalStressField nodalStressesFromGaussPoints(const Mesh& mesh, const MaterialTable& materials,
                                              const std::vector<std::vector<StressPoint>>& gaussStress,
                                              int pointsPerDirection = 2);

} // namespace caps::fem
