#include "planning/WoundStress.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "fem/FiniteStrainIntegrator.h"
#include "fem/FiniteStrainStress.h"
#include "fem/NodalStress.h"

namespace caps::planning {

double distanceToHoleBorder(const fem::HoleLoop& hole, const fem::ChartPoint& p)
{
  const std::size_t n = hole.points.size();
  if (n == 0)
    throw std::invalid_argument("the hole loop has no vertices: there is no wound to measure from");
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i)
  {
    const fem::ChartPoint& a = hole.points[i];
    const fem::ChartPoint d = hole.points[(i + 1) % n] - a;
    const double length2 = d.squaredNorm();
    const double t = length2 > 0.0 ? std::clamp((p - a).dot(d) / length2, 0.0, 1.0) : 0.0;
    best = std::min(best, (p - (a + t * d)).norm());
  }
  return best;
}

namespace {

// The skin's stress at each skin node, in the solve's constitutive law.
struct SkinNodeStress
{
  fem::RegionNodeLayout layout;
  fem::NodalStressMatrix regionStress, nodeStress;
  int skinRegion = -1;

  fem::Vector6d at(int node) const
  {
    const int column = layout.column(skinRegion, node);
    return column >= 0 ? fem::Vector6d(regionStress.col(column)) : fem::Vector6d(nodeStress.col(node));
  }
};

SkinNodeStress recoverSkinNodeStress(const PlanPrediction& prediction)
{
  // §4.7: σ at the Gauss points, extrapolated to the nodes, averaged within
  // each region; a skin node takes the skin's value (the top layer's region),
  // not the fat's below it, where the skin is one element thick.
  // The large-deformation prediction's stress is the Cauchy stress of its
  // hyperelastic layers (per deformed area); the linear one's, Hooke's law.
  const fem::ContinuumMesh& continuum = prediction.continuum;
  SkinNodeStress out;
  if (prediction.check.model == TissueModel::LargeDeformation)
  {
    fem::FiniteStrainNodalField field = [&] {
      try
      {
        return fem::recoverFiniteStrainNodalField(continuum.mesh, prediction.hyperelasticMaterials,
                                                  prediction.displacements);
      }
      catch (const fem::InvertedElementError&)
      {
        // A solve stopped short of the closure can leave a point between the
        // solve's own 3 x 3 x 3 points turned over; its stress (shown under
        // its failed check) is read at the points the solve used.
        if (prediction.check.admissible())
          throw;
        return fem::recoverFiniteStrainNodalField(continuum.mesh, prediction.hyperelasticMaterials,
                                                  prediction.displacements, 3);
      }
    }();
    out.layout = std::move(field.layout);
    out.regionStress = std::move(field.regionCauchy);
    out.nodeStress = std::move(field.cauchy);
  }
  else
  {
    fem::NodalStressField field =
      fem::recoverNodalStresses(continuum.mesh, prediction.materials, prediction.displacements);
    out.layout = std::move(field.layout);
    out.regionStress = std::move(field.regionStress);
    out.nodeStress = std::move(field.stress);
  }
  for (std::size_t e = 0; e < continuum.elementLayer.size() && e < continuum.mesh.elements.size(); ++e)
    if (continuum.elementLayer[e] == 0)
    {
      out.skinRegion = continuum.mesh.elements[e].region;
      break;
    }
  return out;
}

// Each vertex's share of the chart area of its polygons, for the mean.
std::vector<double> chartAreaPerVertex(const DisplacedSkin& skin)
{
  std::vector<double> area(skin.chart.size(), 0.0);
  for (const auto& polygon : skin.polygons)
  {
    double twice = 0.0;
    for (std::size_t k = 0; k < polygon.size(); ++k)
    {
      const fem::ChartPoint& a = skin.chart[std::size_t(polygon[k])];
      const fem::ChartPoint& b = skin.chart[std::size_t(polygon[(k + 1) % polygon.size()])];
      twice += a.x() * b.y() - a.y() * b.x();
    }
    for (const int v : polygon)
      area[std::size_t(v)] += 0.5 * std::abs(twice) / double(polygon.size());
  }
  return area;
}

} // namespace

WoundStress woundSkinStress(const PlanPrediction& prediction, double radius)
{
  if (!std::isfinite(radius) || radius <= 0.0)
    throw std::invalid_argument(
      "the distance from the wound for the skin stress must be a positive number of mm (got " + std::to_string(radius) +
      ")");
  const DisplacedSkin& skin = prediction.skin;
  const std::size_t vertexCount = skin.nodes.size();
  if (vertexCount == 0 || skin.chart.size() != vertexCount || skin.original.size() != vertexCount ||
      skin.displaced.size() != vertexCount)
    throw std::invalid_argument("the prediction has no skin to measure the stress on");
  if (prediction.hole.points.empty())
    throw std::invalid_argument("the prediction has no hole loop: there is no wound to measure from");

  const SkinNodeStress stress = recoverSkinNodeStress(prediction);
  const std::vector<double> area = chartAreaPerVertex(skin);

  WoundStress out;
  out.radius = radius;
  out.peakVonMises = -1.0;
  out.peakMaxPrincipal = -std::numeric_limits<double>::infinity();
  double weighted = 0.0, weight = 0.0, plainSum = 0.0;
  for (std::size_t v = 0; v < vertexCount; ++v)
  {
    const double distance = distanceToHoleBorder(prediction.hole, skin.chart[v]);
    if (distance > radius)
      continue;
    const int node = skin.nodes[v];
    const fem::Vector6d sigma = stress.at(node);
    const double vonMises = fem::vonMisesStress(sigma);
    const double maxPrincipal = fem::principalStresses(sigma)[0];
    ++out.vertexCount;
    weighted += area[v] * vonMises;
    weight += area[v];
    plainSum += vonMises;
    if (vonMises > out.peakVonMises)
    {
      out.peakVonMises = vonMises;
      out.vertex = int(v);
      out.node = node;
      out.chart = skin.chart[v];
      out.distance = distance;
      out.original = skin.original[v];
      out.displaced = skin.displaced[v];
    }
    if (maxPrincipal > out.peakMaxPrincipal)
    {
      out.peakMaxPrincipal = maxPrincipal;
      out.maxPrincipalVertex = int(v);
    }
  }
  // The border vertices are at distance 0, so the band is empty only when
  // the skin is not the mesh grown from this hole.
  if (out.vertexCount == 0)
    throw std::invalid_argument("no skin vertex lies within " + std::to_string(radius) +
                                " mm of the hole border: the skin and the hole loop do not belong together");
  out.meanVonMises = weight > 0.0 ? weighted / weight : plainSum / double(out.vertexCount);
  return out;
}

} // namespace caps::planning
