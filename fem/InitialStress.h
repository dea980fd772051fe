#pragma once

#include "fem/Assembly.h"
#include "fem/ElasticityIntegrator.h"
#include "fem/FacePressure.h"
#include "fem/Mesh.h"

#include <Eigen/Core>

#include <vector>

namespace caps::fem {

/**
 * @brief A stress the tissue carries in its reference state: living skin is
 *        under tension before any cut (the reason an incision gapes).
 *
 * One constant second Piola-Kirchhoff stress S0 per element (Voigt xx, yy,
 * zz, xy, yz, zx; MPa), added to the material's: S = S(C) + S0, as
 * CalculiX's *INITIAL CONDITIONS, TYPE=STRESS and FEBio's pre-stress. S0
 * rides with the material: the Cauchy stress it gives after a rotation is
 * F S0 F^T / J.
 *
 * Alone, a stress field is in equilibrium only where it is divergence-free
 * and meets free surfaces without traction; on a curved, layered face it is
 * neither. The intact tissue is held by what surrounds and underlies it:
 * initialStressBalance() is that load, so the intact body carries S0 at
 * zero displacement. A cut opens new faces that carried the traction S0 N
 * before; the balance leaves it out there, so at zero displacement the only
 * out-of-balance force is the traction the cut released,
 *   R = -sum over the cut faces of the integral of h S0 N dA,
 * and the wound gapes under it.
 */
struct InitialStress
{
  std::vector<Vector6d> elementStress; ///< S0 per element (size: the mesh's elements), or empty

  bool empty() const { return elementStress.empty(); }
  /// Throws std::invalid_argument unless there is one finite stress per
  /// element of @a mesh (or none at all).
  void validate(const Mesh& mesh) const;
};

/// The internal force of S0 in the reference state, f0 = sum_e integral of
/// B0^T S0 dV (3N), with the rule each element is integrated with under
/// @a options (so it matches the analysis's own internal force at u = 0).
Eigen::VectorXd initialStressForces(const Mesh& mesh, const InitialStress& s0, const AssemblyOptions& options = {});

/// The traction S0 N the faces @a cut carried in the intact tissue, as
/// consistent nodal forces sum of integral of h S0 N dA (3N; N the outward
/// normal of the face's own element). Integrated exactly (3 x 3 Gauss
/// points, as FacePressure). Throws std::invalid_argument for a face the
/// mesh has not.
Eigen::VectorXd cutFaceTraction(const Mesh& mesh, const InitialStress& s0, const std::vector<ElementFace>& cut);

/// The load that holds the pre-stressed tissue in equilibrium everywhere
/// but across the cut: f0 - cutFaceTraction() (3N). Applied as a dead load
/// with S0 (NonlinearStaticAnalysis::setInitialStress()).
Eigen::VectorXd initialStressBalance(const Mesh& mesh, const InitialStress& s0, const std::vector<ElementFace>& cut,
                                     const AssemblyOptions& options = {});

} // namespace caps::fem
