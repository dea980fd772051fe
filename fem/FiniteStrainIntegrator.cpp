#include "fem/FiniteStrainIntegrator.h"

#include "fem/VoigtNotation.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace caps::fem {

namespace {

/// F = I + u^T G at a point whose reference world gradients are @a g.
Eigen::Matrix3d deformationGradient(const ElementDisplacements& u, const ShapeDerivatives& g)
{
  return Eigen::Matrix3d::Identity() + u.transpose() * g;
}

} // namespace

void greenLagrangeStrainDisplacement(const Eigen::Matrix3d& f, const ShapeDerivatives& dh, int slots,
                                     StrainDisplacement& b)
{
  b.setZero();
  for (int a = 0; a < slots; ++a)
  {
    const double gx = dh(a, 0), gy = dh(a, 1), gz = dh(a, 2);
    for (int k = 0; k < 3; ++k)
    {
      const int col = 3 * a + k;
      b(0, col) = f(k, 0) * gx;
      b(1, col) = f(k, 1) * gy;
      b(2, col) = f(k, 2) * gz;
      b(3, col) = f(k, 0) * gy + f(k, 1) * gx;
      b(4, col) = f(k, 1) * gz + f(k, 2) * gy;
      b(5, col) = f(k, 2) * gx + f(k, 0) * gz;
    }
  }
}

void throwInverted(int element, const char* measure, double value, const Eigen::Vector3d& rst,
                   const Eigen::Vector3d& world)
{
  std::ostringstream m;
  m.precision(4);
  m << "element " << element << " is turned inside out by the displacement (" << measure << " = " << value
    << ") at natural point (" << rst[0] << ", " << rst[1] << ", " << rst[2] << "), undeformed position (" << world[0]
    << ", " << world[1] << ", " << world[2] << ") mm";
  throw InvertedElementError(element, value, rst, m.str());
}

void resetCheck(FiniteStrainElementCheck& check)
{
  check.minDetF = std::numeric_limits<double>::infinity();
  check.maxStretch = 0.0;
  check.minStretch = std::numeric_limits<double>::infinity();
  check.energy = 0.0;
}

void addToCheck(FiniteStrainElementCheck& check, const Eigen::Matrix3d& c, double detF, double energy)
{
  check.energy += energy;
  check.minDetF = std::min(check.minDetF, detF);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
  eig.computeDirect(c, Eigen::EigenvaluesOnly); // closed form: the iterative solver cost as much as the rest
  check.maxStretch = std::max(check.maxStretch, std::sqrt(std::max(0.0, eig.eigenvalues()[2])));
  check.minStretch = std::min(check.minStretch, std::sqrt(std::max(0.0, eig.eigenvalues()[0])));
}

ReferencePoints referencePoints(const ElementShape& shape, const ElementCoordinates& x, const IntegrationRule& rule,
                                int elementIndex)
{
  ReferencePoints r;
  r.gradients.resize(rule.size());
  r.weights.resize(rule.size());
  PointGeometry g;
  for (std::size_t q = 0; q < rule.size(); ++q)
  {
    evaluateGeometry(shape, x, rule.points[q], elementIndex, g);
    r.gradients[q] = g.dhWorld;
    r.weights[q] = rule.weights[q] * g.detJ;
  }
  return r;
}

std::size_t referencePointsBytes(std::size_t points)
{
  return sizeof(ReferencePoints) + points * (sizeof(ShapeDerivatives) + sizeof(double));
}

void assembleElementFiniteStrain(const ElementShape& shape, const ElementCoordinates& x, const ElementDisplacements& u,
                                 const HyperelasticMaterial& material, const IntegrationRule& rule, int elementIndex,
                                 ElementVector& fint, ElementMatrix* kt, FiniteStrainElementCheck& check)
{
  assembleElementFiniteStrain(shape, x, referencePoints(shape, x, rule, elementIndex), u, material, rule, elementIndex,
                              fint, kt, check);
}

void assembleElementFiniteStrain(const ElementShape& shape, const ElementCoordinates& x,
                                 const ReferencePoints& reference, const ElementDisplacements& u,
                                 const HyperelasticMaterial& material, const IntegrationRule& rule, int elementIndex,
                                 ElementVector& fint, ElementMatrix* kt, FiniteStrainElementCheck& check,
                                 const Eigen::Matrix3d* initialStress)
{
  // A native wedge uses slots 0..14 only; absent slots have zero gradients.
  const int slots = shape.kind() == ElementKind::Wedge15 ? kWedge15NodeCount : kHex20NodeCount;
  fint.setZero();
  if (kt)
    kt->setZero();
  resetCheck(check);
  // f_int of node a, direction k: sum_g w_g P_kJ dH_a/dX_J with P = F S
  // (the first Piola-Kirchhoff stress), gathered as a 20 x 3 block.
  Eigen::Matrix<double, kHex20NodeCount, 3> forces = Eigen::Matrix<double, kHex20NodeCount, 3>::Zero();
  StrainDisplacement b;
  // The material part sum_g B^T (w D) B as one symmetric rank update W W^T,
  // W = [B^T L_g ...] with w D = L L^T (Cholesky; the tangent of a stable
  // material is positive definite), which halves the work against the
  // product per point; a point whose D is not positive definite adds its
  // product directly. The geometric part is summed per node pair.
  thread_local Eigen::MatrixXd factors; // 60 x 6 per point; kept, so no allocation per element
  if (kt)
    factors.resize(kHex20DofCount, Eigen::Index(6 * rule.size()));
  Eigen::Index used = 0;
  Eigen::Matrix<double, kHex20NodeCount, kHex20NodeCount> geometric;
  geometric.setZero();
  const ResponseParts parts = kt ? ResponseParts::StressAndTangent : ResponseParts::Stress;
  for (std::size_t q = 0; q < rule.size(); ++q)
  {
    const ShapeDerivatives& dh = reference.gradients[q]; // dH/dX on the reference geometry
    const Eigen::Matrix3d f = deformationGradient(u, dh);
    const double detF = f.determinant();
    if (!(detF > 0.0))
    {
      PointGeometry g;
      evaluateGeometry(shape, x, rule.points[q], elementIndex, g, false);
      throwInverted(elementIndex, "det F", detF, rule.points[q], g.world);
    }
    const Eigen::Matrix3d c = f.transpose() * f;
    const MaterialResponse response = material.response(c, detF, parts);
    const double w = reference.weights[q];
    const Eigen::Matrix3d stress =
      initialStress ? Eigen::Matrix3d(tensorOf(response.stress) + *initialStress) : tensorOf(response.stress);
    forces.noalias() += dh * (w * (f * stress)).transpose();

    addToCheck(check, c, detF, w * response.energy);

    if (!kt)
      continue;
    greenLagrangeStrainDisplacement(f, dh, slots, b);
    const Matrix6d wd = w * response.tangent;
    const Eigen::LLT<Matrix6d> llt(wd);
    if (llt.info() == Eigen::Success)
    {
      const Matrix6d l = llt.matrixL(); // dense: a fixed-size product, not a triangular one
      factors.middleCols<6>(used).noalias() = b.transpose() * l;
      used += 6;
    }
    else
    {
      kt->noalias() += b.transpose() * (wd * b);
    }
    geometric.noalias() += dh * (w * stress) * dh.transpose();
  }
  Eigen::Map<Eigen::Matrix<double, kHex20NodeCount, 3, Eigen::RowMajor>>(fint.data()) = forces;
  if (!kt)
    return;
  if (used > 0)
  {
    ElementMatrix materialPart = ElementMatrix::Zero();
    materialPart.selfadjointView<Eigen::Upper>().rankUpdate(factors.leftCols(used));
    *kt += materialPart.selfadjointView<Eigen::Upper>();
  }
  for (int a = 0; a < slots; ++a)
    for (int bb = 0; bb < slots; ++bb)
    {
      const double v = geometric(a, bb);
      for (int k = 0; k < 3; ++k)
        (*kt)(3 * a + k, 3 * bb + k) += v;
    }
  // Symmetric by construction; even out the rounding of the two halves.
  *kt = 0.5 * (*kt + kt->transpose()).eval();
}

FiniteStrainPoint evaluateFiniteStrainPoint(const ElementShape& shape, const ElementCoordinates& x,
                                            const ElementDisplacements& u, const HyperelasticMaterial& material,
                                            const Eigen::Vector3d& rst, int elementIndex,
                                            const Eigen::Matrix3d* initialStress)
{
  PointGeometry g;
  evaluateGeometry(shape, x, rst, elementIndex, g);
  FiniteStrainPoint p;
  p.natural = rst;
  p.world = g.world;
  p.deformationGradient = deformationGradient(u, g.dhWorld);
  p.detF = p.deformationGradient.determinant();
  if (!(p.detF > 0.0))
    throwInverted(elementIndex, "det F", p.detF, rst, g.world);
  const Eigen::Matrix3d c = p.deformationGradient.transpose() * p.deformationGradient;
  const MaterialResponse response = material.response(c, p.detF);
  const Eigen::Matrix3d s =
    initialStress ? Eigen::Matrix3d(tensorOf(response.stress) + *initialStress) : tensorOf(response.stress);
  p.secondPiolaKirchhoff = voigtOf(s);
  const Eigen::Matrix3d f = p.deformationGradient;
  p.cauchy = voigtOf(f * s * f.transpose() / p.detF);
  p.greenLagrange = voigtOf(0.5 * (c - Eigen::Matrix3d::Identity()));
  p.greenLagrange.tail<3>() *= 2.0;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(c, Eigen::EigenvaluesOnly);
  const Eigen::Vector3d l = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  p.principalStretches = Eigen::Vector3d(l[2], l[1], l[0]);
  return p;
}

} // namespace caps::fem
