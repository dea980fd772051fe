#include "fem/MuscleLoad.h"

#include "fem/ElasticityIntegrator.h"

#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace caps::fem {

namespace {

std::string describe(const Muscle& muscle, std::size_t index)
{
  std::string s = "muscle " + std::to_string(index);
  if (!muscle.name.empty())
    s += " (" + muscle.name + ")";
  return s;
}

} // namespace

double attachmentWeight(double distance, double radius, double falloff)
{
  if (radius <= 0.0)
    return 0.0; // origin in bone
  if (distance < radius)
    return 1.0;
  if (falloff <= 0.0 || distance >= radius + falloff)
    return 0.0;
  return 0.5 * (1.0 + std::cos(std::numbers::pi * (distance - radius) / falloff));
}

double attachmentVolume(double radius, double falloff)
{
  if (radius <= 0.0)
    return 0.0;
  const double r = radius, b = std::max(falloff, 0.0), pi = std::numbers::pi;
  // Shells 4 pi d^2 dd: the ball, plus the taper over (r, r + b).
  return 4.0 * pi *
         (r * r * r / 3.0 + (std::pow(r + b, 3) - r * r * r) / 6.0 - (2.0 * r * b * b + b * b * b) / (pi * pi));
}

Eigen::Vector3d muscleForceDensity(const Muscle& muscle, const Eigen::Vector3d& q)
{
  const Eigen::Vector3d pull = muscle.load * (muscle.origin - muscle.insertion);
  const double wi = attachmentWeight((q - muscle.insertion).norm(), muscle.insertionRadius, muscle.falloff);
  const double wo = attachmentWeight((q - muscle.origin).norm(), muscle.originRadius, muscle.falloff);
  return (wi - wo) * pull; // eq. 4.40
}

void validateMuscle(const Muscle& muscle, std::size_t index)
{
  const auto fail = [&](const std::string& what) {
    throw std::invalid_argument(describe(muscle, index) + ": " + what);
  };
  if (!muscle.origin.allFinite() || !muscle.insertion.allFinite())
    fail("the origin or insertion point has a non-finite coordinate");
  if (!std::isfinite(muscle.originRadius) || !std::isfinite(muscle.insertionRadius) || !std::isfinite(muscle.load) ||
      !std::isfinite(muscle.falloff))
    fail("a radius, the load or the fall-off width is not a finite number");
  if (muscle.insertionRadius <= 0.0)
  {
    std::ostringstream m;
    m << "the insertion radius is " << muscle.insertionRadius << " mm; it must be > 0";
    fail(m.str());
  }
  if (muscle.originRadius < 0.0)
  {
    std::ostringstream m;
    m << "the origin radius is " << muscle.originRadius << " mm; it must be > 0, or 0 for an origin in bone";
    fail(m.str());
  }
  if (muscle.load < 0.0)
    fail("the load is negative; a muscle only pulls (swap origin and insertion to reverse it)");
  if (muscle.falloff < 0.0)
    fail("the fall-off width is negative");
  if (muscle.origin == muscle.insertion)
  {
    std::ostringstream m;
    m << "the origin and the insertion are the same point (" << muscle.origin[0] << ", " << muscle.origin[1] << ", "
      << muscle.origin[2] << ") mm, so the muscle has no direction to pull in";
    fail(m.str());
  }
}

MuscleLoad assembleMuscleLoad(const Mesh& mesh, const std::vector<Muscle>& muscles, const AssemblyOptions& options)
{
  for (std::size_t a = 0; a < muscles.size(); ++a)
    validateMuscle(muscles[a], a);

  MuscleLoad out;
  out.load = Eigen::VectorXd::Zero(mesh.dofCount());
  out.muscles.assign(muscles.size(), MuscleForces{});
  std::vector<double> wi(muscles.size()), wo(muscles.size());
  ShapeVector h;
  PointGeometry g;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Element& el = mesh.elements[e];
    const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
    const IntegrationRule& rule = integrationRule(el.kind, options.gaussPointsPerDirection);
    const ElementCoordinates x = mesh.elementCoordinates(e);
    ElementVector re = ElementVector::Zero();
    bool loaded = false;
    for (std::size_t q = 0; q < rule.size(); ++q)
    {
      // The force depends on where the integration point lies in the world
      // (eq. 4.13); the Jacobian is only needed where some weight is non-zero.
      shape.values(rule.points[q], h);
      const Eigen::Vector3d world = x.transpose() * h;
      bool any = false;
      for (std::size_t a = 0; a < muscles.size(); ++a)
      {
        const Muscle& m = muscles[a];
        wi[a] = attachmentWeight((world - m.insertion).norm(), m.insertionRadius, m.falloff);
        wo[a] = attachmentWeight((world - m.origin).norm(), m.originRadius, m.falloff);
        any = any || wi[a] != 0.0 || wo[a] != 0.0;
      }
      if (!any)
        continue;
      evaluateGeometry(shape, x, rule.points[q], int(e), g);
      const double dv = rule.weights[q] * g.detJ;
      Eigen::Vector3d f = Eigen::Vector3d::Zero();
      for (std::size_t a = 0; a < muscles.size(); ++a)
      {
        if (wi[a] == 0.0 && wo[a] == 0.0)
          continue;
        const Muscle& m = muscles[a];
        const Eigen::Vector3d pull = m.load * (m.origin - m.insertion);
        MuscleForces& report = out.muscles[a];
        report.insertionVolume += wi[a] * dv;
        report.originVolume += wo[a] * dv;
        report.insertionForce += (wi[a] * dv) * pull;
        report.originForce -= (wo[a] * dv) * pull;
        f += (wi[a] - wo[a]) * pull; // eq. 4.40, summed over muscles (eq. 4.42)
      }
      for (int k = 0; k < kHex20NodeCount; ++k)
        re.segment<3>(3 * k) += (dv * h[k]) * f;
      loaded = true;
    }
    if (!loaded)
      continue;
    for (int k = 0; k < kHex20NodeCount; ++k)
      if (el.nodes[k] >= 0)
        out.load.segment<3>(3 * el.nodes[k]) += re.segment<3>(3 * k);
  }
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    out.totalForce += out.load.segment<3>(3 * i);
  return out;
}

} // namespace caps::fem
