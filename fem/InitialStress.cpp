#include "fem/InitialStress.h"

#include "fem/ElementShape.h"
#include "fem/FacePressure.h"
#include "fem/FiniteStrainIntegrator.h"
#include "fem/Quadrature.h"
#include "fem/VoigtNotation.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace caps::fem {

void InitialStress::validate(const Mesh& mesh) const
{
  if (elementStress.empty())
    return;
  if (elementStress.size() != mesh.elements.size())
    throw std::invalid_argument("the initial stress has " + std::to_string(elementStress.size()) +
                                " element stresses for a mesh of " + std::to_string(mesh.elements.size()) +
                                " elements");
  for (std::size_t e = 0; e < elementStress.size(); ++e)
    if (!elementStress[e].allFinite())
      throw std::invalid_argument("the initial stress of element " + std::to_string(e) + " is not finite");
}

Eigen::VectorXd initialStressForces(const Mesh& mesh, const InitialStress& s0, const AssemblyOptions& options)
{
  s0.validate(mesh);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(mesh.dofCount());
  if (s0.empty())
    return f;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Vector6d& s = s0.elementStress[e];
    if (s.isZero(0.0))
      continue;
    const Element& el = mesh.elements[e];
    const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
    const IntegrationRule& rule = integrationRule(el.kind, integrationPointsOf(el, options.gaussPointsPerDirection));
    const ReferencePoints ref = referencePoints(shape, mesh.elementCoordinates(e), rule, int(e));
    // F = I: node a gets sum_g w_g S0 dH_a/dX.
    Eigen::Matrix<double, kHex20NodeCount, 3> forces = Eigen::Matrix<double, kHex20NodeCount, 3>::Zero();
    const Eigen::Matrix3d stress = tensorOf(s);
    for (std::size_t q = 0; q < rule.size(); ++q)
      forces.noalias() += ref.gradients[q] * (ref.weights[q] * stress);
    for (int a = 0; a < kHex20NodeCount; ++a)
      if (el.nodes[std::size_t(a)] >= 0)
        f.segment<3>(3 * el.nodes[std::size_t(a)]) += forces.row(a).transpose();
  }
  return f;
}

Eigen::VectorXd cutFaceTraction(const Mesh& mesh, const InitialStress& s0, const std::vector<ElementFace>& cut)
{
  s0.validate(mesh);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(mesh.dofCount());
  if (s0.empty())
    return f;
  const LineRule& rule = gaussLineRule(3);
  ElementVector unit;
  for (const ElementFace& c : cut)
  {
    if (c.element < 0 || std::size_t(c.element) >= mesh.elements.size())
      throw std::invalid_argument("a cut face names element " + std::to_string(c.element) + ", which the mesh of " +
                                  std::to_string(mesh.elements.size()) + " elements has not");
    const Element& el = mesh.elements[std::size_t(c.element)];
    const Eigen::Matrix3d stress = tensorOf(s0.elementStress[std::size_t(c.element)]);
    if (stress.isZero(0.0))
      continue;
    // A unit pressure gives -integral of h_k N dA at each node; S0 maps it to the traction's force.
    assembleElementFacePressure(ElementShape::fromConnectivity(el.kind, el.nodes),
                                mesh.elementCoordinates(std::size_t(c.element)), c.face, 1.0, rule, unit);
    for (int a = 0; a < kHex20NodeCount; ++a)
      if (el.nodes[std::size_t(a)] >= 0)
        f.segment<3>(3 * el.nodes[std::size_t(a)]) -= stress * unit.segment<3>(3 * a);
  }
  return f;
}

Eigen::VectorXd initialStressBalance(const Mesh& mesh, const InitialStress& s0, const std::vector<ElementFace>& cut,
                                     const AssemblyOptions& options)
{
  return initialStressForces(mesh, s0, options) - cutFaceTraction(mesh, s0, cut);
}

} // namespace caps::fem
