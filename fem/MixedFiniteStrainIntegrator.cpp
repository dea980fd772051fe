#include "fem/MixedFiniteStrainIntegrator.h"

#include "fem/VoigtNotation.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace caps::fem {

namespace {

using FieldMatrix = Eigen::Matrix<double, kMixedPressureCount, kMixedPressureCount>;
using CouplingMatrix = Eigen::Matrix<double, kHex20DofCount, kMixedPressureCount>;

/// D_J = d(J C^-1)/dE = J (C^-1 (x) C^-1) - J (Ci_ik Ci_jl + Ci_il Ci_jk)
/// (tensor components in Voigt rows and columns).
Matrix6d volumetricTangent(const Eigen::Matrix3d& ci, double j)
{
  const Vector6d vci = voigtOf(ci);
  return j * (vci * vci.transpose() - symmetrizedProduct(ci));
}

/// What the three passes over the points share.
struct MixedPoint
{
  const ShapeDerivatives* dh = nullptr; ///< dH/dX on the reference geometry
  Eigen::Matrix3d f;
  double detF = 1.0;
  double weight = 0.0; ///< w_g det J
  MixedFieldVector n;  ///< (1, r, s, t)
  Eigen::Vector3d rst;
};

} // namespace

void assembleElementMixedFiniteStrain(const ElementShape& shape, const ElementCoordinates& x,
                                      const ElementDisplacements& u, const HyperelasticMaterial& material,
                                      const IntegrationRule& rule, int elementIndex, ElementVector& fint,
                                      ElementMatrix* kt, FiniteStrainElementCheck& check, MixedElementFields* fields)
{
  assembleElementMixedFiniteStrain(shape, x, referencePoints(shape, x, rule, elementIndex), u, material, rule,
                                   elementIndex, fint, kt, check, fields);
}

void assembleElementMixedFiniteStrain(const ElementShape& shape, const ElementCoordinates& x,
                                      const ReferencePoints& reference, const ElementDisplacements& u,
                                      const HyperelasticMaterial& material, const IntegrationRule& rule,
                                      int elementIndex, ElementVector& fint, ElementMatrix* kt,
                                      FiniteStrainElementCheck& check, MixedElementFields* fields,
                                      const Eigen::Matrix3d* initialStress)
{
  if (!material.hasVolumetricSplit())
    throw std::invalid_argument("element " + std::to_string(elementIndex) +
                                ": the mixed u/p/J formulation needs a law split into deviatoric and volumetric "
                                "parts; the St. Venant-Kirchhoff material has none");
  const int slots = shape.kind() == ElementKind::Wedge15 ? kWedge15NodeCount : kHex20NodeCount;
  fint.setZero();
  if (kt)
    kt->setZero();
  resetCheck(check);

  // 1. Kinematics at every point; J~ = the L2 projection of J (M j = g).
  std::vector<MixedPoint> points(rule.size());
  FieldMatrix mass = FieldMatrix::Zero();
  MixedFieldVector g = MixedFieldVector::Zero();
  // The undeformed position of a point, for the message of an inversion only.
  auto inverted = [&](const char* measure, double value, const Eigen::Vector3d& rst) {
    PointGeometry g;
    evaluateGeometry(shape, x, rst, elementIndex, g, false);
    throwInverted(elementIndex, measure, value, rst, g.world);
  };
  for (std::size_t q = 0; q < rule.size(); ++q)
  {
    MixedPoint& p = points[q];
    p.dh = &reference.gradients[q];
    p.f = Eigen::Matrix3d::Identity() + u.transpose() * *p.dh;
    p.detF = p.f.determinant();
    p.rst = rule.points[q];
    if (!(p.detF > 0.0))
      inverted("det F", p.detF, p.rst);
    p.weight = reference.weights[q];
    p.n << 1.0, p.rst[0], p.rst[1], p.rst[2];
    mass.noalias() += p.weight * (p.n * p.n.transpose());
    g += p.weight * p.detF * p.n;
  }
  const Eigen::LLT<FieldMatrix> massFactor(mass);
  if (massFactor.info() != Eigen::Success)
    throw ElementError(elementIndex, "element " + std::to_string(elementIndex) +
                                       ": the pressure field's mass matrix is singular (too few integration points)");
  const MixedFieldVector dilatation = massFactor.solve(g);

  // 2. U at J~: p~ = the L2 projection of U'(J~), H = int U''(J~) N N^T.
  MixedFieldVector rp = MixedFieldVector::Zero();
  FieldMatrix h = FieldMatrix::Zero();
  for (const MixedPoint& p : points)
  {
    const double jt = p.n.dot(dilatation);
    if (!(jt > 0.0))
      inverted("J~", jt, p.rst);
    const VolumetricResponse v = material.volumetricResponse(jt);
    rp += p.weight * v.pressure * p.n;
    h.noalias() += (p.weight * v.stiffness) * (p.n * p.n.transpose());
    check.energy += p.weight * v.energy;
  }
  const MixedFieldVector pressure = massFactor.solve(rp);

  // 3. Forces and tangent with S = S_dev(F) + p~ J C^-1.
  //    f_int of node a, direction k: sum_g w_g (F S)_kJ dH_a/dX_J.
  StrainDisplacement b;
  CouplingMatrix kup = CouplingMatrix::Zero();
  Eigen::Matrix<double, kHex20NodeCount, 3> forces = Eigen::Matrix<double, kHex20NodeCount, 3>::Zero();
  const ResponseParts parts = kt ? ResponseParts::StressAndTangent : ResponseParts::Stress;
  for (const MixedPoint& p : points)
  {
    const ShapeDerivatives& dh = *p.dh;
    const Eigen::Matrix3d& f = p.f;
    const Eigen::Matrix3d c = f.transpose() * f;
    const Eigen::Matrix3d ci = c.inverse();
    const MaterialResponse dev = material.deviatoricResponse(c, p.detF, parts);
    const double pt = p.n.dot(pressure);
    const Vector6d jci = p.detF * voigtOf(ci); // dJ/dE
    const Vector6d stress =
      initialStress ? Vector6d(dev.stress + pt * jci + voigtOf(*initialStress)) : Vector6d(dev.stress + pt * jci);
    const double w = p.weight;
    forces.noalias() += dh * (w * (f * tensorOf(stress))).transpose();

    addToCheck(check, c, p.detF, w * dev.energy);

    if (!kt)
      continue;
    greenLagrangeStrainDisplacement(f, dh, slots, b);
    const Matrix6d d = dev.tangent + pt * volumetricTangent(ci, p.detF);
    const Eigen::Matrix<double, 6, kHex20DofCount> db = (w * d) * b;
    kt->noalias() += b.transpose() * db;
    const Eigen::Matrix<double, kHex20NodeCount, 3> ds = dh * (w * tensorOf(stress));
    const Eigen::Matrix<double, kHex20NodeCount, kHex20NodeCount> geometric = ds * dh.transpose();
    for (int a = 0; a < slots; ++a)
      for (int bb = 0; bb < slots; ++bb)
      {
        const double v = geometric(a, bb);
        for (int k = 0; k < 3; ++k)
          (*kt)(3 * a + k, 3 * bb + k) += v;
      }
    kup.noalias() += (b.transpose() * (w * jci)) * p.n.transpose();
  }
  Eigen::Map<Eigen::Matrix<double, kHex20NodeCount, 3, Eigen::RowMajor>>(fint.data()) = forces;
  if (fields)
  {
    fields->pressure = pressure;
    fields->dilatation = dilatation;
  }
  if (!kt)
    return;
  // 4. The condensed volumetric stiffness: d p~/du = M^-1 H M^-1 K_up^T.
  const CouplingMatrix a = massFactor.solve(kup.transpose()).transpose(); // K_up M^-1
  kt->noalias() += a * h * a.transpose();
  // Symmetric by construction; even out the rounding of the two halves.
  *kt = 0.5 * (*kt + kt->transpose()).eval();
}

} // namespace caps::fem
