#include "fem/MixedFiniteStrainIntegrator.h"

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

// Voigt slots of the symmetric tensor indices: xx, yy, zz, xy, yz, zx.
constexpr int kPair[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {1, 2}, {2, 0}};

Vector6d voigtOf(const Eigen::Matrix3d& t) {
  Vector6d v;
  for (int i = 0; i < 6; ++i) v[i] = t(kPair[i][0], kPair[i][1]);
  return v;
}

Eigen::Matrix3d tensorOf(const Vector6d& s) {
  Eigen::Matrix3d t;
  t << s[0], s[3], s[5],  //
      s[3], s[1], s[4],   //
      s[5], s[4], s[2];
  return t;
}

/// D_J = d(J C^-1)/dE = J (C^-1 (x) C^-1) - J (Ci_ik Ci_jl + Ci_il Ci_jk)
/// (tensor components in Voigt rows and columns).
Matrix6d volumetricTangent(const Eigen::Matrix3d& ci, double j) {
  Matrix6d m;
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) {
      const int i = kPair[a][0], jj = kPair[a][1], k = kPair[b][0], l = kPair[b][1];
      m(a, b) = j * (ci(i, jj) * ci(k, l) - (ci(i, k) * ci(jj, l) + ci(i, l) * ci(jj, k)));
    }
  return m;
}

[[noreturn]] void throwInverted(int element, double value, const char* what, const Eigen::Vector3d& rst,
                                const Eigen::Vector3d& world) {
  std::ostringstream m;
  m.precision(4);
  m << "element " << element << " is turned inside out by the displacement (" << what << " = " << value
    << ") at natural point (" << rst[0] << ", " << rst[1] << ", " << rst[2] << "), undeformed position ("
    << world[0] << ", " << world[1] << ", " << world[2] << ") mm";
  throw InvertedElementError(element, value, rst, m.str());
}

/// What the three passes over the points share.
struct MixedPoint {
  ShapeDerivatives dh;  ///< dH/dX on the reference geometry
  Eigen::Matrix3d f;
  double detF = 1.0;
  double weight = 0.0;  ///< w_g det J
  MixedFieldVector n;   ///< (1, r, s, t)
  Eigen::Vector3d rst, world;
};

}  // namespace

void assembleElementMixedFiniteStrain(const ElementShape& shape, const ElementCoordinates& x,
                                      const ElementDisplacements& u, const HyperelasticMaterial& material,
                                      const IntegrationRule& rule, int elementIndex, ElementVector& fint,
                                      ElementMatrix* kt, FiniteStrainElementCheck& check,
                                      MixedElementFields* fields) {
  if (!material.hasVolumetricSplit())
    throw std::invalid_argument("element " + std::to_string(elementIndex) +
                                ": the mixed u/p/J formulation needs a law split into deviatoric and volumetric "
                                "parts; the St. Venant-Kirchhoff material has none");
  const int slots = shape.kind() == ElementKind::Wedge15 ? kWedge15NodeCount : kHex20NodeCount;
  fint.setZero();
  if (kt) kt->setZero();
  resetCheck(check);

  // 1. Kinematics at every point; J~ = the L2 projection of J (M j = g).
  std::vector<MixedPoint> points(rule.size());
  FieldMatrix mass = FieldMatrix::Zero();
  MixedFieldVector g = MixedFieldVector::Zero();
  PointGeometry geometry;
  for (std::size_t q = 0; q < rule.size(); ++q) {
    MixedPoint& p = points[q];
    evaluateGeometry(shape, x, rule.points[q], elementIndex, geometry);
    p.dh = geometry.dhWorld;
    p.f = Eigen::Matrix3d::Identity() + u.transpose() * p.dh;
    p.detF = p.f.determinant();
    p.rst = rule.points[q];
    p.world = geometry.world;
    if (!(p.detF > 0.0)) throwInverted(elementIndex, p.detF, "det F", p.rst, p.world);
    p.weight = rule.weights[q] * geometry.detJ;
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
  for (const MixedPoint& p : points) {
    const double jt = p.n.dot(dilatation);
    if (!(jt > 0.0)) throwInverted(elementIndex, jt, "J~", p.rst, p.world);
    const VolumetricResponse v = material.volumetricResponse(jt);
    rp += p.weight * v.pressure * p.n;
    h.noalias() += (p.weight * v.stiffness) * (p.n * p.n.transpose());
    check.energy += p.weight * v.energy;
  }
  const MixedFieldVector pressure = massFactor.solve(rp);

  // 3. Forces and tangent with S = S_dev(F) + p~ J C^-1.
  StrainDisplacement b;
  CouplingMatrix kup = CouplingMatrix::Zero();
  for (const MixedPoint& p : points) {
    const ShapeDerivatives& dh = p.dh;
    const Eigen::Matrix3d& f = p.f;
    const Eigen::Matrix3d c = f.transpose() * f;
    const Eigen::Matrix3d ci = c.inverse();
    const MaterialResponse dev = material.deviatoricResponse(c, p.detF);
    const double pt = p.n.dot(pressure);
    const Vector6d jci = p.detF * voigtOf(ci);  // dJ/dE
    const Vector6d stress = dev.stress + pt * jci;
    const double w = p.weight;

    greenLagrangeStrainDisplacement(f, dh, slots, b);
    fint.noalias() += w * (b.transpose() * stress);

    addToCheck(check, c, p.detF, w * dev.energy);

    if (!kt) continue;
    const Matrix6d d = dev.tangent + pt * volumetricTangent(ci, p.detF);
    const Eigen::Matrix<double, 6, kHex20DofCount> db = (w * d) * b;
    kt->noalias() += b.transpose() * db;
    const Eigen::Matrix<double, kHex20NodeCount, 3> ds = dh * (w * tensorOf(stress));
    const Eigen::Matrix<double, kHex20NodeCount, kHex20NodeCount> geometric = ds * dh.transpose();
    for (int a = 0; a < slots; ++a)
      for (int bb = 0; bb < slots; ++bb) {
        const double v = geometric(a, bb);
        for (int k = 0; k < 3; ++k) (*kt)(3 * a + k, 3 * bb + k) += v;
      }
    kup.noalias() += (b.transpose() * (w * jci)) * p.n.transpose();
  }
  if (fields) {
    fields->pressure = pressure;
    fields->dilatation = dilatation;
  }
  if (!kt) return;
  // 4. The condensed volumetric stiffness: d p~/du = M^-1 H M^-1 K_up^T.
  const CouplingMatrix a = massFactor.solve(kup.transpose()).transpose();  // K_up M^-1
  kt->noalias() += a * h * a.transpose();
  // Symmetric by construction; even out the rounding of the two halves.
  *kt = 0.5 * (*kt + kt->transpose()).eval();
}

}  // namespace caps::fem
