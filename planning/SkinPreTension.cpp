#include "planning/SkinPreTension.h"

#include "fem/DisplaySurface.h"
#include "planning/SkinTensionLines.h"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace caps::planning {

namespace {

/// Voigt (xx, yy, zz, xy, yz, zx) of a symmetric 3 x 3 tensor.
fem::Vector6d voigt(const Eigen::Matrix3d& s)
{
  fem::Vector6d v;
  v << s(0, 0), s(1, 1), s(2, 2), s(0, 1), s(1, 2), s(2, 0);
  return v;
}

/// d(skin point)/d(chart point) over one skin polygon: the least-squares
/// linear map from its vertices' chart points to their skin nodes. The
/// element's own geometry, so the membrane lies on the skin the model has.
Eigen::Matrix<double, 3, 2> polygonTangents(const fem::ContinuumMesh& continuum, const fem::SurfaceMesh& surface,
                                            const std::vector<int>& polygon, ChartPoint& centroid)
{
  const int k = int(polygon.size());
  Eigen::MatrixXd chart(2, k), skin(3, k);
  for (int i = 0; i < k; ++i)
  {
    const int v = polygon[std::size_t(i)];
    chart.col(i) = surface.vertices[std::size_t(v)];
    skin.col(i) = continuum.mesh.nodes.col(continuum.vertexColumns[std::size_t(v)].front());
  }
  const Eigen::Vector2d chartMean = chart.rowwise().mean();
  const Eigen::Vector3d skinMean = skin.rowwise().mean();
  chart.colwise() -= chartMean;
  skin.colwise() -= skinMean;
  centroid = chartMean;
  // skin = J chart: J = skin chart^T (chart chart^T)^-1.
  const Eigen::Matrix2d gram = chart * chart.transpose();
  return skin * chart.transpose() * gram.inverse();
}

} // namespace

SkinPreTension SkinPreTension::facial(const SkinTensionLines* lines)
{
  SkinPreTension t;
  if (lines)
    t.lineDirection = [lines](const SkinPoint& p) { return lines->directionAt(p.theta, p.z); };
  return t;
}

void SkinPreTension::validate() const
{
  if (!(alongLines >= 0.0 && alongLines <= 1.0) || !(acrossLines >= 0.0 && acrossLines <= 1.0))
    throw std::invalid_argument("The skin's pre-tension must be a tension from 0 to 1000 N/m along and across "
                                "the tension lines, e.g. 10 and 5 N/m.");
}

std::string SkinPreTension::describe(const std::string& why) const
{
  char text[160];
  if (anisotropic())
    std::snprintf(text, sizeof text, "%.3g N/m along the relaxed skin tension lines, %.3g N/m across them",
                  alongLines * 1000.0, acrossLines * 1000.0);
  else
    std::snprintf(text, sizeof text, "%.3g N/m in every direction", 0.5 * (alongLines + acrossLines) * 1000.0);
  std::string out = text;
  if (followsLines && !lineDirection && alongLines != acrossLines)
    out += " (the tension lines are not known" + (why.empty() ? std::string() : ": " + why) + ")";
  return out;
}

fem::InitialStress skinPreStress(const fem::ContinuumMesh& continuum, const fem::SurfaceMesh& surface,
                                 const SkinChart& chart, const SkinPreTension& tension)
{
  tension.validate();
  const fem::Mesh& mesh = continuum.mesh;
  fem::InitialStress s0;
  s0.elementStress.assign(mesh.elements.size(), fem::Vector6d::Zero());
  const double isotropicTension = 0.5 * (tension.alongLines + tension.acrossLines);
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const int polygon = continuum.elementPolygon[e];
    if (continuum.elementLayer[e] != 0 || polygon < 0 || polygon >= int(surface.polygons.size()))
      continue; // deeper tissue, or the floor under a cut of partial depth
    ChartPoint centroid;
    const std::vector<int>& corners = surface.polygons[std::size_t(polygon)];
    const Eigen::Matrix<double, 3, 2> tangents = polygonTangents(continuum, surface, corners, centroid);
    // The skin layer's thickness under the element: tension / thickness = stress.
    double depth = 0.0;
    for (int v : corners)
      depth += continuum.vertexDepths[std::size_t(v)];
    const double thickness =
      depth / double(corners.size()) * (continuum.levelFractions[1] - continuum.levelFractions[0]);
    if (!(thickness > 0.0))
      continue; // no layer to carry it
    const Eigen::Vector3d normal = tangents.col(0).cross(tangents.col(1)).normalized();
    const Eigen::Matrix3d plane = Eigen::Matrix3d::Identity() - normal * normal.transpose();
    const double isotropic = isotropicTension / thickness;
    if (!tension.anisotropic())
    {
      s0.elementStress[e] = voigt(isotropic * plane);
      continue;
    }
    // The line direction is given per millimetre of skin (u = r dθ at the
    // point); the chart's u is r0 dθ (SkinChart), so scale u by r0 / r.
    const SkinPoint at = chart.fromChart(centroid);
    const Eigen::Vector2d local = tension.lineDirection(at);
    double r = chart.skin().sample(at.theta, at.z);
    if (!std::isfinite(r) || r <= 0.0)
      r = chart.radius();
    const Eigen::Vector2d inChart(local.x() * chart.radius() / r, local.y());
    const Eigen::Vector3d along = (plane * (tangents * inChart)).normalized();
    const Eigen::Vector3d across = normal.cross(along).normalized();
    if (!along.allFinite() || !across.allFinite())
    {
      s0.elementStress[e] = voigt(isotropic * plane); // a degenerate direction: no preferred one
      continue;
    }
    s0.elementStress[e] = voigt(
      (tension.alongLines * along * along.transpose() + tension.acrossLines * across * across.transpose()) / thickness);
  }
  return s0;
}

std::vector<fem::ElementFace> woundFaces(const fem::ContinuumMesh& continuum, const fem::SurfaceMesh& surface)
{
  std::vector<int> woundNodes;
  const int loop = surface.holeVertexCount;
  for (int i = 0; i < loop; ++i)
  {
    for (int node : continuum.vertexColumns[std::size_t(i)])
      woundNodes.push_back(node);
    const int edge = continuum.edgeIndex(i, (i + 1) % loop);
    if (edge >= 0)
      for (int node : continuum.edgeColumns[std::size_t(edge)])
        woundNodes.push_back(node);
  }
  std::vector<fem::ElementFace> faces;
  for (const fem::ElementFace& f : fem::boundaryFacesOnNodes(continuum.mesh, woundNodes))
    if (continuum.elementLayer[std::size_t(f.element)] == 0 && f.face != 2)
      faces.push_back(f);
  return faces;
}

} // namespace caps::planning
