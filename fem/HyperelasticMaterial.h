#pragma once

#include "fem/LinearElasticMaterial.h"

#include <Eigen/Core>

#include <map>
#include <string>

namespace caps::fem {

/// Which strain energy a HyperelasticMaterial uses.
enum class HyperelasticLaw
{
  /// S = lambda tr(E) I + 2 mu E: the linear material in large deformation,
  /// what CalculiX uses for *ELASTIC under NLGEOM. Not for large compression.
  StVenantKirchhoff,
  /// U = C10 (I1b - 3) + (1/D1) (J - 1)^2, I1b = J^(-2/3) I1 (CalculiX and
  /// Abaqus NEO HOOKE, the same form and constants).
  NeoHookean,
  /// U = C10 (I1b - 3) + C01 (I2b - 3) + (1/D1) (J - 1)^2,
  /// I2b = J^(-4/3) I2 (CalculiX and Abaqus MOONEY-RIVLIN).
  MooneyRivlin,
  /// U = C1 [exp(C2 (I1b - 3)) - 1] - (C1 C2 / 2) (I2b - 3) + (1/D1) (J - 1)^2:
  /// Veronda and Westmann's skin law (J. Biomech. 3:111-124, 1970, fitted
  /// to cat skin; FEBio's "Veronda-Westmann" uses the same deviatoric part).
  /// Stiffens exponentially with stretch, as skin does.
  VerondaWestmann,
};

/// "St. Venant-Kirchhoff", "neo-Hookean", "Mooney-Rivlin", "Veronda-Westmann".
const char* lawName(HyperelasticLaw law);

/// Second Piola-Kirchhoff stress and material tangent at one point.
struct MaterialResponse
{
  Vector6d stress;     ///< S (Voigt xx, yy, zz, xy, yz, zx), MPa
  Matrix6d tangent;    ///< dS/dE with E in Voigt form, engineering shears (symmetric)
  double energy = 0.0; ///< strain energy per reference volume (mJ/mm^3 = MPa)
};

/// What a material evaluation computes: a residual needs S only; the
/// tangent dS/dE costs several times more.
enum class ResponseParts
{
  Stress,          ///< S and the energy; the tangent is left zero
  StressAndTangent ///< S, dS/dE and the energy
};

/// The volumetric part U(J) of a split law and its first two derivatives
/// (for the mixed u/p/J element, which evaluates it at an independent J~).
struct VolumetricResponse
{
  double energy = 0.0;    ///< U (MPa)
  double pressure = 0.0;  ///< U'(J) (MPa; positive in tension)
  double stiffness = 0.0; ///< U''(J) (MPa)
};

/**
 * @brief An isotropic hyperelastic material for the Total Lagrangian
 *        formulation (thesis §1.4 and §6.1.2: the linear model's limits).
 *
 * Constants in CalculiX/Abaqus terms so decks compare one to one: C10, C01,
 * D1 in MPa and 1/MPa; Veronda-Westmann C1 (MPa) and C2 (dimensionless);
 * St. Venant-Kirchhoff takes E and nu. The small-strain limit is
 * mu = 2 (C10 + C01) (Veronda-Westmann: C1 C2), K = 2 / D1.
 * Density in tonnes/mm^3, as LinearElasticMaterial.
 */
struct HyperelasticMaterial
{
  HyperelasticLaw law = HyperelasticLaw::NeoHookean;
  double c10 = 0.0, c01 = 0.0;                    ///< MPa (C1 of Veronda-Westmann in c10)
  double c2 = 0.0;                                ///< Veronda-Westmann's exponent C2
  double d1 = 0.0;                                ///< 1/MPa; 2/D1 is the bulk modulus
  double youngsModulus = 0.0, poissonRatio = 0.0; ///< St. Venant-Kirchhoff only
  double density = 0.0;

  /// The material whose small-strain limit is @a linear (same E, nu,
  /// density). Mooney-Rivlin splits mu evenly (C10 = C01); Veronda-Westmann
  /// needs its exponent C2 (@a verondaExponent), which E and nu do not give.
  static HyperelasticMaterial fromLinear(HyperelasticLaw law, const LinearElasticMaterial& linear,
                                         double verondaExponent = 0.0);
  static HyperelasticMaterial neoHookean(double c10, double d1, double density = 0.0);
  static HyperelasticMaterial mooneyRivlin(double c10, double c01, double d1, double density = 0.0);
  static HyperelasticMaterial verondaWestmann(double c1, double c2, double d1, double density = 0.0);
  static HyperelasticMaterial stVenantKirchhoff(double e, double nu, double density = 0.0);

  /// Small-strain shear and bulk moduli (MPa).
  double shearModulus() const;
  double bulkModulus() const;
  /// The linear material it equals at small strain (E, nu, density).
  LinearElasticMaterial smallStrainLimit() const;

  /// Throws std::invalid_argument unless the constants give a stable
  /// material (positive shear and bulk moduli, finite, C2 > 0 ...), naming
  /// @a context.
  void validate(const std::string& context = "material") const;

  /**
   * @brief S (and dS/dE, per @a parts) at the right Cauchy-Green tensor @a c = F^T F.
   *
   * @a jacobian = det F, given so the caller's check of it is the one used
   * (sqrt(det C) would lose the sign). Throws std::domain_error if
   * @a jacobian <= 0 (the caller checks first, to cut the step back).
   */
  MaterialResponse response(const Eigen::Matrix3d& c, double jacobian,
                            ResponseParts parts = ResponseParts::StressAndTangent) const;

  /// True if the law is split W = W_dev(I1b, I2b) + U(J) (every law but
  /// St. Venant-Kirchhoff), which the mixed formulation needs.
  bool hasVolumetricSplit() const;

  /**
   * @brief The deviatoric part alone: S_dev = 2 dW_dev/dC, dS_dev/dE and
   *        W_dev at @a c, with the volumetric part left out, so that
   *        response(c, J) = deviatoricResponse(c, J) + the U(J) terms.
   *
   * Throws std::domain_error as response() and std::invalid_argument for
   * St. Venant-Kirchhoff (no split).
   */
  MaterialResponse deviatoricResponse(const Eigen::Matrix3d& c, double jacobian,
                                      ResponseParts parts = ResponseParts::StressAndTangent) const;

  /// U(J) = (J - 1)^2 / D1 and its derivatives at @a jacobian (any value;
  /// the caller checks its sign). Throws std::invalid_argument for St.
  /// Venant-Kirchhoff.
  VolumetricResponse volumetricResponse(double jacobian) const;
};

/// Hyperelastic material of each region id, as MaterialTable.
using HyperelasticTable = std::map<int, HyperelasticMaterial>;

} // namespace caps::fem
