#pragma once

#include "fem/ElementGeometry.h"
#include "fem/LinearElasticMaterial.h"
#include "fem/Quadrature.h"

#include <Eigen/Core>

namespace caps::fem {

/// Element DOFs: 3 k + d for node slot k (Bathe node, or wedge node 0..14),
/// direction d (x, y, z).
inline constexpr int kHex20DofCount = 3 * kHex20NodeCount;
using ElementMatrix = Eigen::Matrix<double, kHex20DofCount, kHex20DofCount>;
using ElementVector = Eigen::Matrix<double, kHex20DofCount, 1>;
/// Strain-displacement matrix B (eq. 4.47), Voigt order xx, yy, zz, xy, yz, zx.
using StrainDisplacement = Eigen::Matrix<double, 6, kHex20DofCount>;

/// B at one point from the world derivatives in @a geometry.
void strainDisplacementMatrix(const PointGeometry& geometry, StrainDisplacement& b);

/**
 * @brief Linear elasticity on one element: K^(m) = sum_g alpha_g B^T C B det J.
 *
 * Sees one element only: its shape, node coordinates and material; knows
 * nothing of the global numbering. Each integration point's Jacobian is
 * checked (evaluateGeometry), so an inverted element throws ElementError
 * naming @a elementIndex. Rows/columns of absent nodes (and of slots 15..19
 * of a native wedge) are zero. @a rule must suit the element's kind
 * (integrationRule()).
 */
void assembleElementStiffness(const ElementShape& shape, const ElementCoordinates& x,
                              const LinearElasticMaterial& material, const IntegrationRule& rule, int elementIndex,
                              ElementMatrix& ke);

/**
 * @brief Consistent nodal loads of a uniform body force per unit volume
 *        @a forcePerVolume (N/mm^3), eq. 4.37-4.39: R = sum_g alpha_g H^T f det J.
 *        For gravity pass density * acceleration.
 */
void assembleElementBodyForce(const ElementShape& shape, const ElementCoordinates& x,
                              const Eigen::Vector3d& forcePerVolume, const IntegrationRule& rule, int elementIndex,
                              ElementVector& re);

/// Volume of the element (mm^3) by the same rule.
double elementVolume(const ElementShape& shape, const ElementCoordinates& x, const IntegrationRule& rule,
                     int elementIndex);

} // namespace caps::fem
