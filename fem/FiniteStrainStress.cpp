#include "fem/FiniteStrainStress.h"

#include "fem/ElementShape.h"
#include "fem/Quadrature.h"

#include <Eigen/Eigenvalues>

#include <limits>
#include <map>
#include <stdexcept>
#include <string>

namespace caps::fem {

namespace {

/// Rows of the quantities averaged together: sigma, S, F.
constexpr int kCauchyRow = 0, kSecondPiolaKirchhoffRow = 6, kDeformationGradientRow = 12, kRows = 21;

const HyperelasticMaterial& materialOf(const HyperelasticTable& materials, const Element& el, std::size_t e)
{
  const auto m = materials.find(el.region);
  if (m == materials.end())
    throw std::invalid_argument("no hyperelastic material for region " + std::to_string(el.region) + " of element " +
                                std::to_string(e));
  return m->second;
}

Eigen::Matrix3d reshapeDeformationGradient(const Eigen::Matrix<double, 9, 1>& column)
{
  return Eigen::Map<const Eigen::Matrix3d>(column.data());
}

} // namespace

std::vector<FiniteStrainPoint> recoverFiniteStrainAtGaussPoints(const Mesh& mesh, const HyperelasticTable& materials,
                                                                const Eigen::VectorXd& u, int element,
                                                                int pointsPerDirection)
{
  if (u.size() != mesh.dofCount())
    throw std::invalid_argument("recoverFiniteStrainAtGaussPoints: the displacement vector must have 3N entries");
  if (element < 0 || std::size_t(element) >= mesh.elements.size())
    throw std::invalid_argument("stress requested in element " + std::to_string(element) +
                                ", but the mesh has elements 0.." + std::to_string(int(mesh.elements.size()) - 1));
  const std::size_t e = std::size_t(element);
  const Element& el = mesh.elements[e];
  const HyperelasticMaterial& material = materialOf(materials, el, e);
  ElementDisplacements ue = ElementDisplacements::Zero();
  for (int k = 0; k < kHex20NodeCount; ++k)
    if (el.nodes[std::size_t(k)] >= 0)
      ue.row(k) = u.segment<3>(3 * Eigen::Index(el.nodes[std::size_t(k)])).transpose();
  const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
  const ElementCoordinates x = mesh.elementCoordinates(e);
  const IntegrationRule& rule = integrationRule(el.kind, integrationPointsOf(el, pointsPerDirection));
  std::vector<FiniteStrainPoint> out;
  out.reserve(rule.size());
  for (const auto& p : rule.points)
    out.push_back(evaluateFiniteStrainPoint(shape, x, ue, material, p, element));
  return out;
}

Vector6d FiniteStrainNodalField::cauchyAt(int region, int node) const
{
  const int c = layout.column(region, node);
  if (c < 0)
    throw std::out_of_range("no element of region " + std::to_string(region) + " holds node " + std::to_string(node));
  return regionCauchy.col(c);
}

Eigen::Matrix3d FiniteStrainNodalField::deformationGradientAt(int region, int node) const
{
  const int c = layout.column(region, node);
  if (c < 0)
    throw std::out_of_range("no element of region " + std::to_string(region) + " holds node " + std::to_string(node));
  return reshapeDeformationGradient(regionDeformationGradient.col(c));
}

Eigen::VectorXd FiniteStrainNodalField::vonMises() const
{
  Eigen::VectorXd v(cauchy.cols());
  for (Eigen::Index i = 0; i < cauchy.cols(); ++i)
    v[i] = vonMisesStress(cauchy.col(i));
  return v;
}

Eigen::Matrix3Xd FiniteStrainNodalField::principalCauchy() const
{
  Eigen::Matrix3Xd p(3, cauchy.cols());
  for (Eigen::Index i = 0; i < cauchy.cols(); ++i)
    p.col(i) = principalStresses(cauchy.col(i));
  return p;
}

FiniteStrainNodalField recoverFiniteStrainNodalField(const Mesh& mesh, const HyperelasticTable& materials,
                                                     const Eigen::VectorXd& u, int pointsPerDirection)
{
  if (u.size() != mesh.dofCount())
    throw std::invalid_argument("recoverFiniteStrainNodalField: the displacement vector must have 3N entries");
  std::map<int, double> shearModulus;
  for (const auto& [region, m] : materials)
    shearModulus[region] = m.shearModulus();
  FiniteStrainNodalField field;
  field.layout = RegionNodeLayout::of(mesh, shearModulus);
  const Eigen::MatrixXd averaged =
    averageAtRegionNodes(mesh, field.layout, kRows, pointsPerDirection, [&](int e, Eigen::MatrixXd& values) {
      const auto points = recoverFiniteStrainAtGaussPoints(mesh, materials, u, e, pointsPerDirection);
      values.resize(kRows, Eigen::Index(points.size()));
      for (std::size_t p = 0; p < points.size(); ++p)
      {
        const FiniteStrainPoint& q = points[p];
        values.col(Eigen::Index(p)) << q.cauchy, q.secondPiolaKirchhoff,
          Eigen::Map<const Eigen::Matrix<double, 9, 1>>(q.deformationGradient.data());
      }
    });
  field.regionCauchy = averaged.middleRows<6>(kCauchyRow);
  field.regionSecondPiolaKirchhoff = averaged.middleRows<6>(kSecondPiolaKirchhoffRow);
  field.regionDeformationGradient = averaged.middleRows<9>(kDeformationGradientRow);

  const Eigen::MatrixXd atNodes = representativeValues(field.layout, averaged);
  const Eigen::Index n = mesh.nodeCount();
  field.cauchy = atNodes.middleRows<6>(kCauchyRow);
  field.secondPiolaKirchhoff = atNodes.middleRows<6>(kSecondPiolaKirchhoffRow);
  field.detF = Eigen::VectorXd::Ones(n);
  field.principalStretches = Eigen::Matrix3Xd::Ones(3, n);
  for (Eigen::Index i = 0; i < n; ++i)
  {
    if (field.layout.representative[i] < 0)
      continue;
    const Eigen::Matrix3d f = reshapeDeformationGradient(atNodes.block<9, 1>(kDeformationGradientRow, i));
    field.detF[i] = f.determinant();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(f.transpose() * f, Eigen::EigenvaluesOnly);
    const Eigen::Vector3d c = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt(); // ascending
    field.principalStretches.col(i) << c[2], c[1], c[0];
  }
  return field;
}

DeformationCheck checkDeformation(const Mesh& mesh, const Eigen::VectorXd& u, int pointsPerDirection)
{
  if (u.size() != mesh.dofCount())
    throw std::invalid_argument("checkDeformation: the displacement vector has " + std::to_string(u.size()) +
                                " entries for a model of " + std::to_string(mesh.dofCount()) + " DOFs");
  DeformationCheck check;
  if (mesh.elements.empty())
    return check;
  check.minDetF = check.minStretch = std::numeric_limits<double>::infinity();
  check.maxStretch = 0.0;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Element& el = mesh.elements[e];
    ElementDisplacements ue = ElementDisplacements::Zero();
    for (int k = 0; k < kHex20NodeCount; ++k)
      if (el.nodes[std::size_t(k)] >= 0)
        ue.row(k) = u.segment<3>(3 * Eigen::Index(el.nodes[std::size_t(k)])).transpose();
    const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
    const IntegrationRule& rule = integrationRule(el.kind, integrationPointsOf(el, pointsPerDirection));
    const ReferencePoints reference = referencePoints(shape, mesh.elementCoordinates(e), rule, int(e));
    bool inverted = false;
    for (const ShapeDerivatives& dh : reference.gradients)
    {
      const Eigen::Matrix3d f = Eigen::Matrix3d::Identity() + ue.transpose() * dh; // F = I + du/dX
      const double j = f.determinant();
      if (j < check.minDetF)
      {
        check.minDetF = j;
        check.minDetFElement = int(e);
      }
      if (j <= 0.0)
      {
        inverted = true;
        continue;
      }
      const Eigen::Vector3d stretch =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(f.transpose() * f, Eigen::EigenvaluesOnly)
          .eigenvalues()
          .cwiseSqrt();
      check.maxStretch = std::max(check.maxStretch, stretch.maxCoeff());
      check.minStretch = std::min(check.minStretch, stretch.minCoeff());
    }
    check.invertedElements += inverted ? 1 : 0;
  }
  if (check.maxStretch == 0.0) // every point inverted
    check.maxStretch = check.minStretch = std::numeric_limits<double>::quiet_NaN();
  return check;
}

} // namespace caps::fem
