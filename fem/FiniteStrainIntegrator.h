#pragma once

#include "fem/ElasticityIntegrator.h"
#include "fem/ElementGeometry.h"
#include "fem/HyperelasticMaterial.h"
#include "fem/Quadrature.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace caps::fem {

/// Displacements of an element's 20 node slots, one per row (mm); rows of
/// absent slots are ignored.
using ElementDisplacements = Eigen::Matrix<double, kHex20NodeCount, 3>;

/// An element turned inside out by a trial displacement: det F <= 0 at an
/// integration point. Newton cuts the step back when it meets one.
class InvertedElementError : public ElementError
{
public:
  InvertedElementError(int element, double detF, const Eigen::Vector3d& natural, const std::string& what)
    : ElementError(element, what), detF_(detF), natural_(natural)
  {}
  double detF() const { return detF_; }
  const Eigen::Vector3d& natural() const { return natural_; }

private:
  double detF_;
  Eigen::Vector3d natural_;
};

/// Kinematics at one integration point of the Total Lagrangian formulation.
struct FiniteStrainPoint
{
  Eigen::Matrix3d deformationGradient; ///< F = I + du/dX
  double detF = 1.0;                   ///< J
  Vector6d secondPiolaKirchhoff;       ///< S (MPa)
  Vector6d cauchy;                     ///< sigma = F S F^T / J (MPa)
  Vector6d greenLagrange;              ///< E = (C - I) / 2, engineering shears
  Eigen::Vector3d principalStretches;  ///< sqrt of the eigenvalues of C, largest first
  Eigen::Vector3d natural;             ///< (r, s, t) of the point in its element
  Eigen::Vector3d world;               ///< X (undeformed position, mm)
};

/// What one element's evaluation saw, for the checks every prediction carries.
struct FiniteStrainElementCheck
{
  double minDetF = 1.0;
  double maxStretch = 1.0; ///< largest principal stretch
  double minStretch = 1.0; ///< smallest principal stretch
  double energy = 0.0;     ///< strain energy (mJ = N mm)
};

/// The checks every large-deformation result carries (DESIGN.md), over all
/// integration points of a model.
struct DeformationCheck
{
  double minDetF = 1.0;
  int minDetFElement = -1;
  double maxStretch = 1.0;
  double minStretch = 1.0;
  double strainEnergy = 0.0; ///< N mm (0 from checkDeformation(), which has no material)
  /// Elements with det F <= 0 at one of their points or more: 0 in a
  /// large-deformation solve, which never accepts one; counted by
  /// checkDeformation() for any displacement field.
  int invertedElements = 0;
};

/// B_L at one point: row (ij) of the Green-Lagrange strain's variation per
/// node DOF (a, k), E_ii: F_ki dh_a,i; 2 E_ij: F_ki dh_a,j + F_kj dh_a,i,
/// for slots 0..@a slots - 1 (the rest zero). Shared by the displacement and
/// the mixed elements.
void greenLagrangeStrainDisplacement(const Eigen::Matrix3d& f, const ShapeDerivatives& dh, int slots,
                                     StrainDisplacement& b);

/// Throws InvertedElementError for @a element, whose @a measure ("det F",
/// "J~") is @a value <= 0 at natural point @a rst, undeformed @a world.
[[noreturn]] void throwInverted(int element, const char* measure, double value, const Eigen::Vector3d& rst,
                                const Eigen::Vector3d& world);

/// Starts @a check for an element (no point seen yet).
void resetCheck(FiniteStrainElementCheck& check);
/// Adds one integration point (C = F^T F, det F, energy w W) to @a check.
void addToCheck(FiniteStrainElementCheck& check, const Eigen::Matrix3d& c, double detF, double energy);

/// What a Total Lagrangian element needs of its reference geometry at the
/// points of its rule. It is the same at every evaluation, so a model that
/// is evaluated many times (Newton) computes it once.
struct ReferencePoints
{
  std::vector<ShapeDerivatives> gradients; ///< dH/dX at each point
  std::vector<double> weights;             ///< w_g det J at each point
};

/// The reference geometry of element @a elementIndex at the points of
/// @a rule; throws ElementError when its Jacobian is bad there.
ReferencePoints referencePoints(const ElementShape& shape, const ElementCoordinates& x, const IntegrationRule& rule,
                                int elementIndex);

/// Bytes one element's ReferencePoints take for a rule of @a points points.
std::size_t referencePointsBytes(std::size_t points);

/**
 * @brief Total Lagrangian internal forces and consistent tangent of one
 *        element (Bathe, Finite Element Procedures, 1996, §6.2.3; the
 *        thesis's §6.1.2 "nonlinear finite element model").
 *
 * On the reference geometry @a x displaced by @a u, at each point of
 * @a rule: F = I + u^T dH/dX, C = F^T F, S and dS/dE from @a material,
 *   f_int = sum_g w_g det J B_L^T S,
 *   K_t   = sum_g w_g det J (B_L^T D B_L + G^T S G)   (material + geometric),
 * B_L the strain-displacement matrix of the Green-Lagrange strain at F. The
 * same shapes, rules and slot layout as the linear integrator, so wedges,
 * degenerate bricks and bricks with any mid-side subset work alike.
 *
 * @a kt may be null (residual only: the line search). Throws
 * InvertedElementError when det F <= 0 at a point, ElementError when the
 * reference Jacobian is bad. @a check gets the smallest det F, the stretches
 * and the energy.
 */
void assembleElementFiniteStrain(const ElementShape& shape, const ElementCoordinates& x, const ElementDisplacements& u,
                                 const HyperelasticMaterial& material, const IntegrationRule& rule, int elementIndex,
                                 ElementVector& fint, ElementMatrix* kt, FiniteStrainElementCheck& check);

/// The same on reference geometry computed before (referencePoints() of the
/// same shape, coordinates and rule); @a shape and @a x name the point in
/// the message of an inversion. @a initialStress, when given, is a second
/// Piola-Kirchhoff stress the element carries in its reference state (skin
/// pre-tension, InitialStress.h): S = S(C) + S0 at every point, in the
/// forces and in the geometric (initial-stress) stiffness.
void assembleElementFiniteStrain(const ElementShape& shape, const ElementCoordinates& x,
                                 const ReferencePoints& reference, const ElementDisplacements& u,
                                 const HyperelasticMaterial& material, const IntegrationRule& rule, int elementIndex,
                                 ElementVector& fint, ElementMatrix* kt, FiniteStrainElementCheck& check,
                                 const Eigen::Matrix3d* initialStress = nullptr);

/// Kinematics and stresses at natural point @a rst of one element (for
/// output), @a initialStress included in S and sigma when given; throws as
/// assembleElementFiniteStrain().
FiniteStrainPoint evaluateFiniteStrainPoint(const ElementShape& shape, const ElementCoordinates& x,
                                            const ElementDisplacements& u, const HyperelasticMaterial& material,
                                            const Eigen::Vector3d& rst, int elementIndex,
                                            const Eigen::Matrix3d* initialStress = nullptr);

} // namespace caps::fem
