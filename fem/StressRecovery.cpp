#include "fem/StressRecovery.h"

#include "fem/ElasticityIntegrator.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace caps::fem {

namespace {

void checkElement(const Mesh& mesh, int element) {
  if (element < 0 || std::size_t(element) >= mesh.elements.size())
    throw std::invalid_argument("stress requested in element " + std::to_string(element) +
                                ", but the mesh has elements 0.." +
                                std::to_string(int(mesh.elements.size()) - 1));
}

}  // namespace

double StressPoint::vonMises() const {
  const Vector6d& s = stress;
  const double a = s[0] - s[1], b = s[1] - s[2], c = s[2] - s[0];
  return std::sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
}

double StressPoint::meanStress() const { return (stress[0] + stress[1] + stress[2]) / 3.0; }

StressPoint recoverStress(const Mesh& mesh, const MaterialTable& materials, const Eigen::VectorXd& u,
                          int element, const Eigen::Vector3d& rst) {
  checkElement(mesh, element);
  if (u.size() != mesh.dofCount())
    throw std::invalid_argument("recoverStress: the displacement vector must have 3N entries");
  const Element& el = mesh.elements[std::size_t(element)];
  PointGeometry g;
  evaluateGeometry(ElementShape::fromConnectivity(el.kind, el.nodes), mesh.elementCoordinates(std::size_t(element)),
                   rst, element, g);
  StrainDisplacement b;
  strainDisplacementMatrix(g, b);
  ElementVector ue = ElementVector::Zero();
  for (int k = 0; k < kHex20NodeCount; ++k)
    if (el.nodes[k] >= 0) ue.segment<3>(3 * k) = u.segment<3>(3 * el.nodes[k]);
  StressPoint p;
  p.natural = rst;
  p.world = g.world;
  p.strain = b * ue;
  p.stress = materials.at(el.region).elasticityMatrix() * p.strain;
  return p;
}

std::vector<StressPoint> recoverStressAtGaussPoints(const Mesh& mesh, const MaterialTable& materials,
                                                   const Eigen::VectorXd& u, int element,
                                                   int pointsPerDirection) {
  checkElement(mesh, element);
  const Element& el = mesh.elements[std::size_t(element)];
  const IntegrationRule& rule = integrationRule(el.kind, integrationPointsOf(el, pointsPerDirection));
  std::vector<StressPoint> out;
  out.reserve(rule.size());
  for (const auto& p : rule.points) out.push_back(recoverStress(mesh, materials, u, element, p));
  return out;
}

}  // namespace caps::fem
