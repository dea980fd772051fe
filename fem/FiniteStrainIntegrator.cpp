#include "fem/FiniteStrainIntegrator.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace caps::fem {

namespace {

Eigen::Matrix3d tensorOf(const Vector6d& s) {
  Eigen::Matrix3d t;
  t << s[0], s[3], s[5],  //
      s[3], s[1], s[4],   //
      s[5], s[4], s[2];
  return t;
}

Vector6d voigtOf(const Eigen::Matrix3d& t) {
  Vector6d s;
  s << t(0, 0), t(1, 1), t(2, 2), t(0, 1), t(1, 2), t(2, 0);
  return s;
}

[[noreturn]] void throwInverted(int element, double detF, const Eigen::Vector3d& rst, const Eigen::Vector3d& world) {
  std::ostringstream m;
  m.precision(4);
  m << "element " << element << " is turned inside out by the displacement (det F = " << detF
    << ") at natural point (" << rst[0] << ", " << rst[1] << ", " << rst[2] << "), undeformed position ("
    << world[0] << ", " << world[1] << ", " << world[2] << ") mm";
  throw InvertedElementError(element, detF, rst, m.str());
}

/// F = I + u^T G at a point whose reference world gradients are @a g.
Eigen::Matrix3d deformationGradient(const ElementDisplacements& u, const ShapeDerivatives& g) {
  return Eigen::Matrix3d::Identity() + u.transpose() * g;
}

}  // namespace

void assembleElementFiniteStrain(const ElementShape& shape, const ElementCoordinates& x,
                                 const ElementDisplacements& u, const HyperelasticMaterial& material,
                                 const IntegrationRule& rule, int elementIndex, ElementVector& fint,
                                 ElementMatrix* kt, FiniteStrainElementCheck& check) {
  // A native wedge uses slots 0..14 only; absent slots have zero gradients.
  const int slots = shape.kind() == ElementKind::Wedge15 ? kWedge15NodeCount : kHex20NodeCount;
  fint.setZero();
  if (kt) kt->setZero();
  check.minDetF = std::numeric_limits<double>::infinity();
  check.maxStretch = 0.0;
  check.minStretch = std::numeric_limits<double>::infinity();
  check.energy = 0.0;
  PointGeometry g;
  StrainDisplacement b;
  for (std::size_t q = 0; q < rule.size(); ++q) {
    evaluateGeometry(shape, x, rule.points[q], elementIndex, g);
    const ShapeDerivatives& dh = g.dhWorld;  // dH/dX on the reference geometry
    const Eigen::Matrix3d f = deformationGradient(u, dh);
    const double detF = f.determinant();
    if (!(detF > 0.0)) throwInverted(elementIndex, detF, rule.points[q], g.world);
    const Eigen::Matrix3d c = f.transpose() * f;
    const MaterialResponse response = material.response(c, detF);
    const double w = rule.weights[q] * g.detJ;

    // B_L: row (ij) of E = sym(F^T dU/dX) per node DOF (a, k):
    //   E_ii: F_ki dh_a,i;   2E_ij: F_ki dh_a,j + F_kj dh_a,i.
    b.setZero();
    for (int a = 0; a < slots; ++a) {
      const double gx = dh(a, 0), gy = dh(a, 1), gz = dh(a, 2);
      for (int k = 0; k < 3; ++k) {
        const int col = 3 * a + k;
        b(0, col) = f(k, 0) * gx;
        b(1, col) = f(k, 1) * gy;
        b(2, col) = f(k, 2) * gz;
        b(3, col) = f(k, 0) * gy + f(k, 1) * gx;
        b(4, col) = f(k, 1) * gz + f(k, 2) * gy;
        b(5, col) = f(k, 2) * gx + f(k, 0) * gz;
      }
    }
    fint.noalias() += w * (b.transpose() * response.stress);

    check.energy += w * response.energy;
    check.minDetF = std::min(check.minDetF, detF);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(c, Eigen::EigenvaluesOnly);
    check.maxStretch = std::max(check.maxStretch, std::sqrt(std::max(0.0, eig.eigenvalues()[2])));
    check.minStretch = std::min(check.minStretch, std::sqrt(std::max(0.0, eig.eigenvalues()[0])));

    if (!kt) continue;
    // Material part B^T D B, then the geometric part (dh_a . S dh_b) I3.
    const Eigen::Matrix<double, 6, kHex20DofCount> db = (w * response.tangent) * b;
    kt->noalias() += b.transpose() * db;
    const Eigen::Matrix<double, kHex20NodeCount, 3> ds = dh * (w * tensorOf(response.stress));
    const Eigen::Matrix<double, kHex20NodeCount, kHex20NodeCount> geometric = ds * dh.transpose();
    for (int a = 0; a < slots; ++a)
      for (int bb = 0; bb < slots; ++bb) {
        const double v = geometric(a, bb);
        for (int k = 0; k < 3; ++k) (*kt)(3 * a + k, 3 * bb + k) += v;
      }
  }
  // Symmetric by construction; even out the rounding of the two halves.
  if (kt) *kt = 0.5 * (*kt + kt->transpose()).eval();
}

FiniteStrainPoint evaluateFiniteStrainPoint(const ElementShape& shape, const ElementCoordinates& x,
                                            const ElementDisplacements& u, const HyperelasticMaterial& material,
                                            const Eigen::Vector3d& rst, int elementIndex) {
  PointGeometry g;
  evaluateGeometry(shape, x, rst, elementIndex, g);
  FiniteStrainPoint p;
  p.natural = rst;
  p.world = g.world;
  p.deformationGradient = deformationGradient(u, g.dhWorld);
  p.detF = p.deformationGradient.determinant();
  if (!(p.detF > 0.0)) throwInverted(elementIndex, p.detF, rst, g.world);
  const Eigen::Matrix3d c = p.deformationGradient.transpose() * p.deformationGradient;
  const MaterialResponse response = material.response(c, p.detF);
  p.secondPiolaKirchhoff = response.stress;
  const Eigen::Matrix3d f = p.deformationGradient;
  p.cauchy = voigtOf(f * tensorOf(response.stress) * f.transpose() / p.detF);
  p.greenLagrange = voigtOf(0.5 * (c - Eigen::Matrix3d::Identity()));
  p.greenLagrange.tail<3>() *= 2.0;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(c, Eigen::EigenvaluesOnly);
  const Eigen::Vector3d l = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  p.principalStretches = Eigen::Vector3d(l[2], l[1], l[0]);
  return p;
}

}  // namespace caps::fem
