#pragma once

#include "fem/LinearElasticMaterial.h"
#include "fem/Mesh.h"

#include <Eigen/Core>

#include <vector>

namespace caps::fem {

/// Strain and stress at one point (Voigt xx, yy, zz, xy, yz, zx; engineering
/// shear strain; stress in MPa).
struct StressPoint
{
  Eigen::Vector3d natural; ///< (r, s, t)
  Eigen::Vector3d world;   ///< x(r, s, t), undeformed, mm
  Vector6d strain;
  Vector6d stress;

  /// von Mises equivalent stress (MPa).
  double vonMises() const;
  /// Mean stress (sigma_xx + sigma_yy + sigma_zz) / 3 (MPa); pressure is its negative.
  double meanStress() const;
};

/**
 * @brief Strain and stress at body coordinate (element, r, s, t) (thesis
 *        eq. 4.47-4.48): epsilon = B U^(m), sigma = C epsilon.
 *        (r, s, t) are the natural coordinates of the element's kind (the
 *        cube, or the wedge's triangle times t). @a u holds the 3N nodal
 *        displacements. Throws ElementError if the Jacobian is bad there.
 */
StressPoint recoverStress(const Mesh& mesh, const MaterialTable& materials, const Eigen::VectorXd& u, int element,
                          const Eigen::Vector3d& rst);

/// The same at every point of the element's own rule, integrationRule(kind,
/// integrationPointsOf(element, @a pointsPerDirection)): the n x n x n Gauss
/// points of a brick (C3D20R's 2x2x2, C3D20's 3x3x3), or wedgeRule(n) of a
/// native wedge. @a pointsPerDirection is the default for elements whose
/// integrationPoints is 0. Points in gaussRule()/wedgeRule() order.
std::vector<StressPoint> recoverStressAtGaussPoints(const Mesh& mesh, const MaterialTable& materials,
                                                    const Eigen::VectorXd& u, int element, int pointsPerDirection = 3);

/// recoverStressAtGaussPoints() of every element (element e's points at
/// [e]), the elements shared among @a threads threads in contiguous blocks;
/// the same values for any thread count. Throws what the first failing
/// element (lowest index) throws.
std::vector<std::vector<StressPoint>> recoverStressAtAllGaussPoints(const Mesh& mesh, const MaterialTable& materials,
                                                                    const Eigen::VectorXd& u,
                                                                    int pointsPerDirection = 3, int threads = 1);

} // namespace caps::fem
