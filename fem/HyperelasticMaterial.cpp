#include "fem/HyperelasticMaterial.h"

#include "fem/VoigtNotation.h"

#include <Eigen/LU>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace caps::fem {

namespace {

/// d(C^-1)/dC as a 6x6 of tensor components: -(Ci_ik Ci_jl + Ci_il Ci_jk) / 2.
Matrix6d inverseDerivative(const Eigen::Matrix3d& ci)
{
  return -0.5 * symmetrizedProduct(ci);
}

/// The symmetric fourth-order identity (d_ik d_jl + d_il d_jk) / 2.
Matrix6d symmetricIdentity()
{
  Matrix6d m = Matrix6d::Zero();
  for (int a = 0; a < 3; ++a)
    m(a, a) = 1.0;
  for (int a = 3; a < 6; ++a)
    m(a, a) = 0.5;
  return m;
}

Matrix6d outer(const Vector6d& a, const Vector6d& b)
{
  return a * b.transpose();
}

/// The derivatives of W(I1b, I2b, J) the stress and tangent need; W is a sum
/// of a deviatoric part in (I1b, I2b) and a volumetric part in J.
struct EnergyDerivatives
{
  double w = 0.0;
  double w1 = 0.0, w2 = 0.0, wj = 0.0;
  double w11 = 0.0, w22 = 0.0, w12 = 0.0, wjj = 0.0;
};

EnergyDerivatives invariantDerivatives(const HyperelasticMaterial& m, double i1b, double i2b, double j, bool volumetric)
{
  EnergyDerivatives d;
  switch (m.law)
  {
  case HyperelasticLaw::NeoHookean:
  case HyperelasticLaw::MooneyRivlin:
    d.w = m.c10 * (i1b - 3.0) + m.c01 * (i2b - 3.0);
    d.w1 = m.c10;
    d.w2 = m.c01;
    break;
  case HyperelasticLaw::VerondaWestmann:
  {
    const double e = std::exp(m.c2 * (i1b - 3.0));
    d.w = m.c10 * (e - 1.0) - 0.5 * m.c10 * m.c2 * (i2b - 3.0);
    d.w1 = m.c10 * m.c2 * e;
    d.w11 = m.c10 * m.c2 * m.c2 * e;
    d.w2 = -0.5 * m.c10 * m.c2;
    break;
  }
  case HyperelasticLaw::StVenantKirchhoff:
    break; // not an invariant law; handled apart
  }
  if (!volumetric)
    return d;
  // U(J) = (J - 1)^2 / D1.
  d.w += (j - 1.0) * (j - 1.0) / m.d1;
  d.wj = 2.0 * (j - 1.0) / m.d1;
  d.wjj = 2.0 / m.d1;
  return d;
}

MaterialResponse stVenantKirchhoffResponse(const HyperelasticMaterial& m, const Eigen::Matrix3d& c)
{
  const LinearElasticMaterial linear{m.youngsModulus, m.poissonRatio, m.density};
  const Eigen::Matrix3d e = 0.5 * (c - Eigen::Matrix3d::Identity());
  Vector6d strain = voigtOf(e);
  strain.tail<3>() *= 2.0; // engineering shears
  MaterialResponse r;
  r.tangent = linear.elasticityMatrix();
  r.stress = r.tangent * strain;
  r.energy = 0.5 * strain.dot(r.stress);
  return r;
}

} // namespace

const char* lawName(HyperelasticLaw law)
{
  switch (law)
  {
  case HyperelasticLaw::StVenantKirchhoff:
    return "St. Venant-Kirchhoff";
  case HyperelasticLaw::NeoHookean:
    return "neo-Hookean";
  case HyperelasticLaw::MooneyRivlin:
    return "Mooney-Rivlin";
  case HyperelasticLaw::VerondaWestmann:
    return "Veronda-Westmann";
  }
  return "unknown";
}

HyperelasticMaterial HyperelasticMaterial::neoHookean(double c10, double d1, double density)
{
  HyperelasticMaterial m;
  m.law = HyperelasticLaw::NeoHookean;
  m.c10 = c10;
  m.d1 = d1;
  m.density = density;
  return m;
}

HyperelasticMaterial HyperelasticMaterial::mooneyRivlin(double c10, double c01, double d1, double density)
{
  HyperelasticMaterial m = neoHookean(c10, d1, density);
  m.law = HyperelasticLaw::MooneyRivlin;
  m.c01 = c01;
  return m;
}

HyperelasticMaterial HyperelasticMaterial::verondaWestmann(double c1, double c2, double d1, double density)
{
  HyperelasticMaterial m = neoHookean(c1, d1, density);
  m.law = HyperelasticLaw::VerondaWestmann;
  m.c2 = c2;
  return m;
}

HyperelasticMaterial HyperelasticMaterial::stVenantKirchhoff(double e, double nu, double density)
{
  HyperelasticMaterial m;
  m.law = HyperelasticLaw::StVenantKirchhoff;
  m.youngsModulus = e;
  m.poissonRatio = nu;
  m.density = density;
  return m;
}

HyperelasticMaterial HyperelasticMaterial::fromLinear(HyperelasticLaw law, const LinearElasticMaterial& linear,
                                                      double verondaExponent)
{
  linear.validate("the small-strain material");
  const double e = linear.youngsModulus, nu = linear.poissonRatio;
  const double mu = e / (2.0 * (1.0 + nu)), k = e / (3.0 * (1.0 - 2.0 * nu));
  const double d1 = 2.0 / k;
  switch (law)
  {
  case HyperelasticLaw::StVenantKirchhoff:
    return stVenantKirchhoff(e, nu, linear.density);
  case HyperelasticLaw::NeoHookean:
    return neoHookean(mu / 2.0, d1, linear.density);
  // Split evenly between the two invariants: mu = 2 (C10 + C01).
  case HyperelasticLaw::MooneyRivlin:
    return mooneyRivlin(mu / 4.0, mu / 4.0, d1, linear.density);
  // The exponent is the material's own (how fast it stiffens); C1 then gives mu = C1 C2.
  case HyperelasticLaw::VerondaWestmann:
    if (!(verondaExponent > 0.0))
      throw std::invalid_argument("a Veronda-Westmann material needs its exponent C2 > 0 besides E and nu");
    return verondaWestmann(mu / verondaExponent, verondaExponent, d1, linear.density);
  }
  throw std::invalid_argument("unknown hyperelastic law");
}

double HyperelasticMaterial::shearModulus() const
{
  switch (law)
  {
  case HyperelasticLaw::StVenantKirchhoff:
    return youngsModulus / (2.0 * (1.0 + poissonRatio));
  case HyperelasticLaw::VerondaWestmann:
    return c10 * c2;
  default:
    return 2.0 * (c10 + c01);
  }
}

double HyperelasticMaterial::bulkModulus() const
{
  if (law == HyperelasticLaw::StVenantKirchhoff)
    return youngsModulus / (3.0 * (1.0 - 2.0 * poissonRatio));
  return 2.0 / d1;
}

LinearElasticMaterial HyperelasticMaterial::smallStrainLimit() const
{
  const double mu = shearModulus(), k = bulkModulus();
  LinearElasticMaterial m;
  m.youngsModulus = 9.0 * k * mu / (3.0 * k + mu);
  m.poissonRatio = (3.0 * k - 2.0 * mu) / (2.0 * (3.0 * k + mu));
  m.density = density;
  return m;
}

void HyperelasticMaterial::validate(const std::string& context) const
{
  std::ostringstream m;
  const bool finite = std::isfinite(c10) && std::isfinite(c01) && std::isfinite(c2) && std::isfinite(d1) &&
                      std::isfinite(youngsModulus) && std::isfinite(poissonRatio);
  if (!finite)
  {
    m << context << ": the " << lawName(law) << " constants must be finite";
  }
  else if (law == HyperelasticLaw::StVenantKirchhoff)
  {
    try
    {
      LinearElasticMaterial{youngsModulus, poissonRatio, density}.validate(context.c_str());
    }
    catch (const std::invalid_argument& e)
    {
      m << e.what();
    }
  }
  else if (!(d1 > 0.0))
  {
    m << context << ": D1 = " << d1 << " 1/MPa must be positive (the bulk modulus is 2/D1; "
      << "D1 = 0, incompressible, is not supported)";
  }
  else if (law == HyperelasticLaw::VerondaWestmann && !(c10 > 0.0 && c2 > 0.0))
  {
    m << context << ": Veronda-Westmann needs C1 > 0 and C2 > 0 (C1 = " << c10 << " MPa, C2 = " << c2 << ")";
  }
  else if (!(shearModulus() > 0.0))
  {
    m << context << ": the small-strain shear modulus 2 (C10 + C01) = " << shearModulus()
      << " MPa must be positive (C10 = " << c10 << ", C01 = " << c01 << ")";
  }
  if (m.str().empty() && !(std::isfinite(density) && density >= 0.0))
    m << context << ": density " << density << " t/mm^3 must be zero or positive";
  if (!m.str().empty())
    throw std::invalid_argument(m.str());
}

namespace {

/// S, dS/dE and W of a split law at C; the volumetric part U(J) only if
/// @a volumetric (response() and deviatoricResponse() share every operation).
MaterialResponse splitLawResponse(const HyperelasticMaterial& m, const Eigen::Matrix3d& c, double j, bool volumetric,
                                  ResponseParts parts = ResponseParts::StressAndTangent)
{
  // Invariants and their first derivatives with respect to C:
  //   dI1b/dC = J^(-2/3) (I - I1/3 C^-1),
  //   dI2b/dC = J^(-4/3) (I1 I - C - 2/3 I2 C^-1),   dJ/dC = J C^-1 / 2,
  // and S = 2 dW/dC, dS/dE = 4 d2W/dC2 (Holzapfel, Nonlinear Solid
  // Mechanics, 2000, §6.4).
  const Eigen::Matrix3d id = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d ci = c.inverse();
  const double i1 = c.trace();
  const double i2 = 0.5 * (i1 * i1 - (c * c).trace());
  const double jm23 = std::pow(j, -2.0 / 3.0), jm43 = jm23 * jm23;
  const double i1b = jm23 * i1, i2b = jm43 * i2;
  const Vector6d vi = voigtOf(id), vci = voigtOf(ci), vc = voigtOf(c);
  const Vector6d a1 = jm23 * (vi - (i1 / 3.0) * vci);
  const Vector6d b2 = i1 * vi - vc; // dI2/dC
  const Vector6d a2 = jm43 * (b2 - (2.0 / 3.0) * i2 * vci);
  const Vector6d aj = 0.5 * j * vci;

  const EnergyDerivatives w = invariantDerivatives(m, i1b, i2b, j, volumetric);
  MaterialResponse r;
  r.energy = w.w;
  r.stress = 2.0 * (w.w1 * a1 + w.w2 * a2 + w.wj * aj);
  if (parts == ResponseParts::Stress)
  {
    r.tangent.setZero();
    return r;
  }

  // Second derivatives of the invariants.
  const Matrix6d dci = inverseDerivative(ci);
  const Matrix6d ciCi = outer(vci, vci);
  Matrix6d h = w.w11 * outer(a1, a1) + w.wjj * outer(aj, aj);
  if (w.w1 != 0.0)
    h += w.w1 * (-jm23 / 3.0) * (outer(vi, vci) + outer(vci, vi) - (i1 / 3.0) * ciCi + i1 * dci);
  if (w.w2 != 0.0 || w.w22 != 0.0 || w.w12 != 0.0)
  {
    h += w.w22 * outer(a2, a2) + w.w12 * (outer(a1, a2) + outer(a2, a1));
    h += w.w2 * jm43 *
         (outer(vi, vi) - symmetricIdentity() - (2.0 / 3.0) * (outer(b2, vci) + outer(vci, b2)) +
          (4.0 / 9.0) * i2 * ciCi - (2.0 / 3.0) * i2 * dci);
  }
  h += w.wj * (0.25 * j * ciCi + 0.5 * j * dci);
  r.tangent = 4.0 * h;
  return r;
}

void requireSplit(const HyperelasticMaterial& m, const char* what)
{
  if (m.law == HyperelasticLaw::StVenantKirchhoff)
    throw std::invalid_argument(std::string("the St. Venant-Kirchhoff material has no deviatoric/volumetric split (") +
                                what + "); use neo-Hookean, Mooney-Rivlin or Veronda-Westmann");
}

[[noreturn]] void throwNonPositive(const HyperelasticMaterial& m, double j)
{
  std::ostringstream s;
  s << "the " << lawName(m.law) << " material was asked for its stress at det F = " << j
    << " (an inverted or collapsed element)";
  throw std::domain_error(s.str());
}

} // namespace

MaterialResponse HyperelasticMaterial::response(const Eigen::Matrix3d& c, double j, ResponseParts parts) const
{
  if (!(j > 0.0))
  {
    std::ostringstream m;
    m << "the " << lawName(law) << " material was asked for its stress at det F = " << j
      << " (an inverted or collapsed element)";
    throw std::domain_error(m.str());
  }
  if (law == HyperelasticLaw::StVenantKirchhoff)
    return stVenantKirchhoffResponse(*this, c);
  return splitLawResponse(*this, c, j, true, parts);
}

bool HyperelasticMaterial::hasVolumetricSplit() const
{
  return law != HyperelasticLaw::StVenantKirchhoff;
}

MaterialResponse HyperelasticMaterial::deviatoricResponse(const Eigen::Matrix3d& c, double j, ResponseParts parts) const
{
  requireSplit(*this, "deviatoric response");
  if (!(j > 0.0))
    throwNonPositive(*this, j);
  return splitLawResponse(*this, c, j, false, parts);
}

VolumetricResponse HyperelasticMaterial::volumetricResponse(double j) const
{
  requireSplit(*this, "volumetric response");
  // U(J) = (J - 1)^2 / D1, as invariantDerivatives().
  VolumetricResponse v;
  v.energy = (j - 1.0) * (j - 1.0) / d1;
  v.pressure = 2.0 * (j - 1.0) / d1;
  v.stiffness = 2.0 / d1;
  return v;
}

} // namespace caps::fem
