#include "fem/StressRecovery.h"

#include "fem/ElasticityIntegrator.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <stdexcept>
#include <string>
#include <thread>

namespace caps::fem {

namespace {

void checkElement(const Mesh& mesh, int element)
{
  if (element < 0 || std::size_t(element) >= mesh.elements.size())
    throw std::invalid_argument("stress requested in element " + std::to_string(element) +
                                ", but the mesh has elements 0.." + std::to_string(int(mesh.elements.size()) - 1));
}

} // namespace

double StressPoint::vonMises() const
{
  const Vector6d& s = stress;
  const double a = s[0] - s[1], b = s[1] - s[2], c = s[2] - s[0];
  return std::sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
}

double StressPoint::meanStress() const
{
  return (stress[0] + stress[1] + stress[2]) / 3.0;
}

StressPoint recoverStress(const Mesh& mesh, const MaterialTable& materials, const Eigen::VectorXd& u, int element,
                          const Eigen::Vector3d& rst)
{
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
    if (el.nodes[k] >= 0)
      ue.segment<3>(3 * k) = u.segment<3>(3 * el.nodes[k]);
  StressPoint p;
  p.natural = rst;
  p.world = g.world;
  p.strain = b * ue;
  p.stress = materials.at(el.region).elasticityMatrix() * p.strain;
  return p;
}

std::vector<StressPoint> recoverStressAtGaussPoints(const Mesh& mesh, const MaterialTable& materials,
                                                    const Eigen::VectorXd& u, int element, int pointsPerDirection)
{
  checkElement(mesh, element);
  if (u.size() != mesh.dofCount())
    throw std::invalid_argument("recoverStress: the displacement vector must have 3N entries");
  const Element& el = mesh.elements[std::size_t(element)];
  const IntegrationRule& rule = integrationRule(el.kind, integrationPointsOf(el, pointsPerDirection));
  // recoverStress() at each point, with what does not depend on the point
  // (shape, coordinates, nodal displacements, C) taken once.
  const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
  const ElementCoordinates x = mesh.elementCoordinates(std::size_t(element));
  ElementVector ue = ElementVector::Zero();
  for (int k = 0; k < kHex20NodeCount; ++k)
    if (el.nodes[k] >= 0)
      ue.segment<3>(3 * k) = u.segment<3>(3 * el.nodes[k]);
  const Matrix6d c = materials.at(el.region).elasticityMatrix();
  PointGeometry g;
  StrainDisplacement b;
  std::vector<StressPoint> out(rule.size());
  for (std::size_t i = 0; i < rule.size(); ++i)
  {
    evaluateGeometry(shape, x, rule.points[i], element, g);
    strainDisplacementMatrix(g, b);
    StressPoint& p = out[i];
    p.natural = rule.points[i];
    p.world = g.world;
    p.strain = b * ue;
    p.stress = c * p.strain;
  }
  return out;
}

std::vector<std::vector<StressPoint>> recoverStressAtAllGaussPoints(const Mesh& mesh, const MaterialTable& materials,
                                                                    const Eigen::VectorXd& u, int pointsPerDirection,
                                                                    int threads)
{
  if (u.size() != mesh.dofCount())
    throw std::invalid_argument("recoverStress: the displacement vector must have 3N entries");
  const std::size_t m = mesh.elements.size();
  std::vector<std::vector<StressPoint>> out(m);
  const std::size_t workers =
    std::clamp<std::size_t>(std::size_t(std::max(1, threads)), 1, std::max<std::size_t>(1, m / 64));
  // Each worker a contiguous block, stopping at its first failure; the
  // failure of the lowest block is the one a single thread meets first.
  std::vector<std::exception_ptr> errors(workers);
  auto work = [&](std::size_t w) {
    const std::size_t begin = m * w / workers, end = m * (w + 1) / workers;
    try
    {
      for (std::size_t e = begin; e < end; ++e)
        out[e] = recoverStressAtGaussPoints(mesh, materials, u, int(e), pointsPerDirection);
    }
    catch (...)
    {
      errors[w] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (std::size_t w = 1; w < workers; ++w)
    pool.emplace_back(work, w);
  work(0);
  for (auto& t : pool)
    t.join();
  for (const auto& e : errors)
    if (e)
      std::rethrow_exception(e);
  return out;
}

} // namespace caps::fem
