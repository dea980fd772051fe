#pragma once

#include "fem/FiniteStrainIntegrator.h"

#include <Eigen/Core>

namespace caps::fem {

/// Number of pressure (and dilatation) parameters of the mixed element:
/// the discontinuous linear field 1, r, s, t in the element's natural
/// coordinates (the brick's and the wedge's alike).
inline constexpr int kMixedPressureCount = 4;
using MixedFieldVector = Eigen::Matrix<double, kMixedPressureCount, 1>;

/// The condensed fields of one element at the displacement it was evaluated
/// at: p~ = N . pressure, J~ = N . dilatation with N = (1, r, s, t).
struct MixedElementFields
{
  MixedFieldVector pressure = MixedFieldVector::Zero();   ///< MPa, positive in tension
  MixedFieldVector dilatation = MixedFieldVector::Zero(); ///< J~ coefficients
};

/**
 * @brief Internal forces and consistent tangent of one element in the
 *        three-field Hu-Washizu (u, p~, J~) formulation, with the pressure
 *        and the dilatation condensed out, so the element has displacement
 *        DOFs only: the near-incompressible element that does not lock.
 *
 * Simo, Taylor and Pister, "Variational and projection methods for the
 * volume constraint in finite deformation elasto-plasticity", CMAME
 * 51:177-208, 1985; as in deal.II's step-44 (Pelteret and McBride), here
 * with the 20-node brick (any mid-side subset) or the native 15-node wedge
 * for u and the discontinuous linear P1 field N = (1, r, s, t) for p~ and
 * J~ (4 parameters each; for the brick the pressure space of the 20/4 u/p
 * element of Bathe, Finite Element Procedures, 1996, mixed u/p elements).
 *
 * The functional of a split law W = W_dev(C) + U(J) is
 *   Pi = int [W_dev(C) + U(J~) + p~ (J - J~)] dV.
 * Its stationarity in p~ makes J~ the L2 projection of J = det F on the P1
 * field (M j = int N J dV, M = int N N^T dV), and in J~ makes p~ that of
 * U'(J~) (M p = int N U'(J~) dV). Both are solved in the element for the
 * given @a u (no history), so
 *   f_int = int B_L^T (S_dev + p~ J C^-1) dV,
 *   K_t   = int [B_L^T (D_dev + p~ D_J) B_L + G^T S G] dV + K_up M^-1 H M^-1 K_up^T,
 * with D_J = d(J C^-1)/dE, K_up = int B_L^T J C^-1 N^T dV and
 * H = int U''(J~) N N^T dV, is the exact derivative of f_int (symmetric:
 * Pi(u) is a potential). The deviatoric part is evaluated at F, the
 * volumetric at J~. A homogeneous deformation gives J~ = J and p~ = U'(J):
 * then it equals assembleElementFiniteStrain().
 *
 * Arguments, @a kt = null and @a check as assembleElementFiniteStrain()
 * (check.energy = int W_dev + U(J~)); @a fields, if given, gets p~ and J~.
 * Throws InvertedElementError where det F <= 0 or J~ <= 0 at a point,
 * ElementError for a bad reference Jacobian, std::invalid_argument for a
 * law without the split (St. Venant-Kirchhoff).
 *
 * @warning Stresses recovered with evaluateFiniteStrainPoint() use the
 *          displacement element's pressure U'(J), not p~.
 * @sa assembleElementFiniteStrain, HyperelasticMaterial::deviatoricResponse
 */
void assembleElementMixedFiniteStrain(const ElementShape& shape, const ElementCoordinates& x,
                                      const ElementDisplacements& u, const HyperelasticMaterial& material,
                                      const IntegrationRule& rule, int elementIndex, ElementVector& fint,
                                      ElementMatrix* kt, FiniteStrainElementCheck& check,
                                      MixedElementFields* fields = nullptr);

/// The same on reference geometry computed before (referencePoints() of the
/// same shape, coordinates and rule), with the element's @a initialStress
/// (S0, InitialStress.h) added to S when given.
void assembleElementMixedFiniteStrain(const ElementShape& shape, const ElementCoordinates& x,
                                      const ReferencePoints& reference, const ElementDisplacements& u,
                                      const HyperelasticMaterial& material, const IntegrationRule& rule,
                                      int elementIndex, ElementVector& fint, ElementMatrix* kt,
                                      FiniteStrainElementCheck& check, MixedElementFields* fields = nullptr,
                                      const Eigen::Matrix3d* initialStress = nullptr);

} // namespace caps::fem
