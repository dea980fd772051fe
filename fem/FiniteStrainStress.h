#pragma once
/// @file FiniteStrainStress.h
/// @brief Stress output of the large-deformation path: Cauchy and
/// second Piola-Kirchhoff stress at the integration points and at the nodes,
/// with det F and the principal stretches.

#include "fem/FiniteStrainIntegrator.h"
#include "fem/HyperelasticMaterial.h"
#include "fem/Mesh.h"
#include "fem/NodalStress.h"

#include <Eigen/Core>

#include <vector>

namespace caps::fem {

/**
 * @brief Kinematics and stresses (evaluateFiniteStrainPoint()) at every point
 *        of element @a element's own rule, integrationRule(kind,
 *        integrationPointsOf(element, @a pointsPerDirection)), in its order.
 *
 * @a u holds the 3N nodal displacements of the reference mesh. Throws
 * std::invalid_argument for a wrong @a u size, an element out of range or a
 * region without a material; InvertedElementError where det F <= 0 at a
 * point; ElementError for a bad reference Jacobian.
 */
std::vector<FiniteStrainPoint> recoverFiniteStrainAtGaussPoints(const Mesh& mesh, const HyperelasticTable& materials,
                                                                const Eigen::VectorXd& u, int element,
                                                                int pointsPerDirection = 2);

/**
 * @brief Large-deformation stresses at the nodes, averaged within each
 *        region, and the kinematics there.
 *
 * The region-node columns (layout, RegionNodeLayout) and the per-node fields
 * (the representative region's value: the stiffest at an interface) are
 * those of NodalStressField. Cauchy stress sigma, PK2 S and F are each
 * extrapolated from the Gauss points and averaged as the linear stresses are
 * (averageAtRegionNodes()); J and the principal stretches are those of the
 * averaged F (det F, sqrt of the eigenvalues of F^T F), so they belong to
 * one deformation. Stresses in MPa, Voigt xx, yy, zz, xy, yz, zx; sigma is
 * per deformed area, S per reference area mapped back by F^-1.
 */
struct FiniteStrainNodalField
{
  RegionNodeLayout layout;
  /// @name One column per (region, node) pair (R)
  ///@{
  NodalStressMatrix regionCauchy;
  NodalStressMatrix regionSecondPiolaKirchhoff;
  Eigen::Matrix<double, 9, Eigen::Dynamic> regionDeformationGradient; ///< F, column-major 3 x 3 in each column
  ///@}
  /// @name One column per node (N): its representative region's value, zero in no element
  ///@{
  NodalStressMatrix cauchy;
  NodalStressMatrix secondPiolaKirchhoff;
  Eigen::VectorXd detF;                ///< J = det F (1 at a node in no element)
  Eigen::Matrix3Xd principalStretches; ///< largest first (1 at a node in no element)
  ///@}

  /// Cauchy stress of @a region at @a node; throws std::out_of_range when
  /// no element of that region holds the node.
  Vector6d cauchyAt(int region, int node) const;
  /// F of @a region at @a node; throws as cauchyAt().
  Eigen::Matrix3d deformationGradientAt(int region, int node) const;

  /// von Mises stress of the Cauchy stress at each node (N).
  Eigen::VectorXd vonMises() const;
  /// Principal Cauchy stresses at each node, largest first (3 x N).
  Eigen::Matrix3Xd principalCauchy() const;
  /// Largest principal stretch at each node (N).
  Eigen::VectorXd maxStretch() const { return principalStretches.row(0).transpose(); }
};

/// The Gauss rule the nodal stresses are recovered from (per direction):
/// the 2 x 2 x 2 points, whose extrapolation to the nodes is the trilinear
/// one (§4.7).
inline constexpr int kStressRecoveryPointsPerDirection = 2;

/**
 * @brief recoverFiniteStrainAtGaussPoints() in every element, extrapolated
 *        to the nodes and averaged within each region (as
 *        recoverNodalStresses(): each element's own rule, @a pointsPerDirection
 *        for those that leave it to the analysis, the 2x2x2 Barlow points by
 *        default).
 *
 * Throws as recoverFiniteStrainAtGaussPoints(), and std::invalid_argument
 * for a wrong @a u size.
 */
FiniteStrainNodalField recoverFiniteStrainNodalField(const Mesh& mesh, const HyperelasticTable& materials,
                                                     const Eigen::VectorXd& u,
                                                     int pointsPerDirection = kStressRecoveryPointsPerDirection);

/**
 * @brief det F and the principal stretches of x -> x + @a u at every point of
 *        each element's own rule (@a pointsPerDirection for those that
 *        leave it to the analysis, 3 as AssemblyOptions), for any displacement field: a linear
 *        solve's too, to tell whether its deformed mesh is still a body.
 *
 * Needs no material and does not throw on an inverted element: it counts
 * them (DeformationCheck::invertedElements). Stretches are left out at
 * points where det F <= 0. Throws std::invalid_argument for a wrong @a u
 * size, ElementError for a bad reference Jacobian.
 */
DeformationCheck checkDeformation(const Mesh& mesh, const Eigen::VectorXd& u, int pointsPerDirection = 3);

} // namespace caps::fem
