#include "fem/ElementQuality.h"

#include "fem/ElementGeometry.h"
#include "fem/ElementShape.h"
#include "fem/Quadrature.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace caps::fem {

namespace {

/// The scaled Jacobian of the map with Jacobian @a j (rows dx/dr, dx/ds,
/// dx/dt) on an element of @a kind (see elementQuality()).
double scaledJacobian(const Eigen::Matrix3d& j, ElementKind kind)
{
  const double det = j.determinant();
  if (kind == ElementKind::Wedge15)
  {
    const Eigen::Vector3d a = j.row(0), b = j.row(1), c = b - a;
    const double widest = std::max({a.norm() * b.norm(), a.norm() * c.norm(), b.norm() * c.norm()});
    const double scale = widest * j.row(2).norm();
    return scale > 0.0 ? 2.0 / std::sqrt(3.0) * det / scale : 0.0;
  }
  const double scale = j.row(0).norm() * j.row(1).norm() * j.row(2).norm();
  return scale > 0.0 ? det / scale : 0.0;
}

/// Slots whose node is also another slot's (where a degenerate brick collapses).
std::vector<char> collapsedSlots(const Element& el)
{
  std::vector<char> collapsed(kHex20NodeCount, 0);
  for (int a = 0; a < kHex20NodeCount; ++a)
    for (int b = a + 1; b < kHex20NodeCount; ++b)
      if (el.nodes[std::size_t(a)] >= 0 && el.nodes[std::size_t(a)] == el.nodes[std::size_t(b)])
        collapsed[std::size_t(a)] = collapsed[std::size_t(b)] = 1;
  return collapsed;
}

/// Whether natural point @a p is a corner of the reference element of @a kind.
bool isCorner(const Eigen::Vector3d& p, ElementKind kind)
{
  if (std::abs(std::abs(p.z()) - 1.0) > 1e-12)
    return false;
  if (kind == ElementKind::Wedge15)
    return (p.x() == 0.0 || p.x() == 1.0) && (p.y() == 0.0 || p.y() == 1.0) && p.x() + p.y() <= 1.0;
  return std::abs(std::abs(p.x()) - 1.0) <= 1e-12 && std::abs(std::abs(p.y()) - 1.0) <= 1e-12;
}

/// Whether corners at @a p and @a q are joined by an edge: they differ in
/// one direction of the reference element (for a wedge: within a triangle,
/// or along t).
bool joinedByAnEdge(const Eigen::Vector3d& p, const Eigen::Vector3d& q, ElementKind kind)
{
  const Eigen::Vector3d d = (p - q).cwiseAbs();
  if (kind == ElementKind::Wedge15)
    return (d.z() == 0.0) != (d.x() == 0.0 && d.y() == 0.0);
  return (d.array() > 0.0).count() == 1;
}

/// Longest over shortest corner-to-corner edge, edges of zero length (a
/// degenerate brick's collapsed edge) left out.
double edgeRatio(const Mesh& mesh, const Element& el, const ElementShape& shape)
{
  std::vector<int> corners;
  for (int slot = 0; slot < kHex20NodeCount; ++slot)
    if (shape.hasNode(slot) && isCorner(shape.naturalCoordinates(slot), el.kind))
      corners.push_back(slot);
  double shortest = std::numeric_limits<double>::infinity(), longest = 0.0;
  for (std::size_t i = 0; i < corners.size(); ++i)
    for (std::size_t k = i + 1; k < corners.size(); ++k)
    {
      if (!joinedByAnEdge(shape.naturalCoordinates(corners[i]), shape.naturalCoordinates(corners[k]), el.kind))
        continue;
      const double length =
        (mesh.nodes.col(el.nodes[std::size_t(corners[i])]) - mesh.nodes.col(el.nodes[std::size_t(corners[k])])).norm();
      if (length <= 0.0)
        continue;
      shortest = std::min(shortest, length);
      longest = std::max(longest, length);
    }
  return longest > 0.0 ? longest / shortest : 1.0;
}

} // namespace

ElementQuality elementQuality(const Mesh& mesh, int element, int pointsPerDirection)
{
  if (element < 0 || std::size_t(element) >= mesh.elements.size())
    throw std::out_of_range("element " + std::to_string(element) + " is not in the mesh (" +
                            std::to_string(mesh.elements.size()) + " elements)");
  const Element& el = mesh.elements[std::size_t(element)];
  const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
  const ElementCoordinates x = mesh.elementCoordinates(std::size_t(element));
  ElementQuality quality;
  quality.scaledJacobian = std::numeric_limits<double>::infinity();
  ShapeVector h;
  ShapeDerivatives dh;
  const auto at = [&](const Eigen::Vector3d& rst) {
    shape.evaluate(rst, h, dh);
    const Eigen::Matrix3d j = dh.transpose() * x;
    const double value = scaledJacobian(j, el.kind);
    if (value < quality.scaledJacobian)
    {
      quality.scaledJacobian = value;
      quality.worstPoint = rst;
    }
  };
  const std::vector<char> collapsed = collapsedSlots(el);
  for (int slot = 0; slot < kHex20NodeCount; ++slot)
    if (shape.hasNode(slot) && !collapsed[std::size_t(slot)])
      at(shape.naturalCoordinates(slot));
  for (const Eigen::Vector3d& rst : integrationRule(el.kind, pointsPerDirection).points)
    at(rst);
  quality.edgeRatio = edgeRatio(mesh, el, shape);
  return quality;
}

MeshQualityCheck checkMeshQuality(const Mesh& mesh, const ElementQualityLimits& limits, int pointsPerDirection)
{
  MeshQualityCheck check;
  check.elements = int(mesh.elements.size());
  for (int e = 0; e < check.elements; ++e)
  {
    const ElementQuality q = elementQuality(mesh, e, pointsPerDirection);
    const Element& el = mesh.elements[std::size_t(e)];
    const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
    const ElementCoordinates x = mesh.elementCoordinates(std::size_t(e));
    ShapeVector h;
    if (q.scaledJacobian < check.minScaledJacobian)
    {
      check.minScaledJacobian = q.scaledJacobian;
      check.worstJacobianElement = e;
      shape.values(q.worstPoint, h);
      check.worstJacobianAt = x.transpose() * h;
    }
    if (q.edgeRatio > check.maxEdgeRatio)
    {
      check.maxEdgeRatio = q.edgeRatio;
      check.worstEdgeRatioElement = e;
      shape.values(
        el.kind == ElementKind::Wedge15 ? Eigen::Vector3d(1.0 / 3.0, 1.0 / 3.0, 0.0) : Eigen::Vector3d::Zero(), h);
      check.worstEdgeRatioAt = x.transpose() * h;
    }
    check.poorJacobian += q.scaledJacobian < limits.minScaledJacobian ? 1 : 0;
    check.poorEdgeRatio += q.edgeRatio > limits.maxEdgeRatio ? 1 : 0;
    check.poorElements += q.scaledJacobian < limits.minScaledJacobian || q.edgeRatio > limits.maxEdgeRatio ? 1 : 0;
  }
  return check;
}

} // namespace caps::fem
