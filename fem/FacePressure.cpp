#include "fem/FacePressure.h"

#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>
#include <string>

namespace caps::fem {

namespace {

// CalculiX C3D20 faces 1..6 (ccx manual, *DLOAD: 1-2-3-4, 5-8-7-6, 1-5-6-2,
// 2-6-7-3, 3-7-8-4, 4-8-5-1): t = -1, t = +1, s = -1, r = +1, s = +1, r = -1.
// With (axis, p, q) cyclic, p × q points to +axis, so sign = side.
FaceChart hexFaceChart(int face)
{
  static const int axis[6] = {2, 2, 1, 0, 1, 0};
  static const double side[6] = {-1, 1, -1, 1, 1, -1};
  const int a = axis[face - 1];
  FaceChart m;
  m.origin = side[face - 1] * Eigen::Vector3d::Unit(a);
  m.p = Eigen::Vector3d::Unit((a + 1) % 3);
  m.q = Eigen::Vector3d::Unit((a + 2) % 3);
  m.sign = side[face - 1];
  return m;
}

// CalculiX C3D15 faces 1..5 (1-2-3, 4-5-6, 1-2-5-4, 2-3-6-5, 3-1-4-6) in the
// wedge's natural coordinates (ElementNumbering.h).
FaceChart wedgeFaceChart(int face)
{
  FaceChart m;
  switch (face)
  {
  case 1:
    m = {{0, 0, -1}, {1, 0, 0}, {0, 1, 0}, true, -1.0};
    break; // t = -1
  case 2:
    m = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}, true, 1.0};
    break; // t = +1
  case 3:
    m = {{0.5, 0, 0}, {0.5, 0, 0}, {0, 0, 1}, false, 1.0};
    break; // s = 0, p × q = -s
  case 4:
    m = {{0.5, 0.5, 0}, {-0.5, 0.5, 0}, {0, 0, 1}, false, 1.0};
    break; // r + s = 1, p × q = +r +s
  default:
    m = {{0, 0.5, 0}, {0, 0.5, 0}, {0, 0, 1}, false, -1.0};
    break; // r = 0, p × q = +r
  }
  return m;
}

void checkFace(ElementKind kind, int face)
{
  if (face < 1 || face > faceCount(kind))
    throw std::invalid_argument("face " + std::to_string(face) + " does not exist: " +
                                (kind == ElementKind::Wedge15 ? "a native wedge has faces 1..5 (CalculiX C3D15 P1..P5)"
                                                              : "a hexahedron has faces 1..6 (CalculiX C3D20 P1..P6)"));
}

FaceChart faceChartOf(ElementKind kind, int face)
{
  checkFace(kind, face);
  return kind == ElementKind::Wedge15 ? wedgeFaceChart(face) : hexFaceChart(face);
}

/// Visits the integration points of a face: h there and the weighted
/// outward area vector w (dx/da × dx/db).
template <class Visit>
void forEachFacePoint(const ElementShape& shape, const ElementCoordinates& x, int face, const LineRule& rule,
                      Visit&& visit)
{
  const FaceChart m = faceChartOf(shape.kind(), face);
  ShapeVector h;
  ShapeDerivatives dh;
  for (std::size_t i = 0; i < rule.points.size(); ++i)
    for (std::size_t j = 0; j < rule.points.size(); ++j)
    {
      double a = rule.points[i], b = rule.points[j], w = rule.weights[i] * rule.weights[j];
      if (m.triangle)
      {
        // Collapse the square onto the triangle: a = u (1 - b), b = v, u and v in [0, 1].
        const double u = 0.5 * (1.0 + a), v = 0.5 * (1.0 + b);
        a = u * (1.0 - v);
        b = v;
        w *= 0.25 * (1.0 - v);
      }
      shape.evaluate(m.origin + a * m.p + b * m.q, h, dh);
      // World tangents along p and q: chain rule through the natural coordinates.
      const Eigen::Vector3d tp = x.transpose() * (dh * m.p);
      const Eigen::Vector3d tq = x.transpose() * (dh * m.q);
      visit(h, Eigen::Vector3d(m.sign * w * tp.cross(tq)));
    }
}

} // namespace

FaceChart faceChart(ElementKind kind, int face)
{
  return faceChartOf(kind, face);
}

int faceCount(ElementKind kind)
{
  return kind == ElementKind::Wedge15 ? 5 : 6;
}

std::vector<int> faceNodes(ElementKind kind, int face)
{
  const FaceChart m = faceChartOf(kind, face);
  const Eigen::Vector3d normal = m.p.cross(m.q);
  const bool wedge = kind == ElementKind::Wedge15;
  std::vector<int> slots;
  for (int k = 0; k < (wedge ? kWedge15NodeCount : kHex20NodeCount); ++k)
  {
    const Eigen::Vector3d xi = wedge ? wedge15NaturalCoordinates(k) : batheNaturalCoordinates(k);
    if (std::abs((xi - m.origin).dot(normal)) < 1e-12)
      slots.push_back(k);
  }
  return slots;
}

void assembleElementFacePressure(const ElementShape& shape, const ElementCoordinates& x, int face, double pressure,
                                 const LineRule& rule, ElementVector& re)
{
  re.setZero();
  forEachFacePoint(shape, x, face, rule, [&](const ShapeVector& h, const Eigen::Vector3d& area) {
    // Traction -p n: pushes into the element for p > 0.
    const Eigen::Vector3d f = -pressure * area;
    for (int k = 0; k < kHex20NodeCount; ++k)
      if (h[k] != 0.0)
        re.segment<3>(3 * k) += h[k] * f;
  });
}

double elementFaceArea(const ElementShape& shape, const ElementCoordinates& x, int face, const LineRule& rule)
{
  double area = 0.0;
  forEachFacePoint(shape, x, face, rule, [&](const ShapeVector&, const Eigen::Vector3d& a) { area += a.norm(); });
  return area;
}

void validateFacePressures(const Mesh& mesh, const std::vector<FacePressure>& loads)
{
  for (std::size_t i = 0; i < loads.size(); ++i)
  {
    const FacePressure& l = loads[i];
    const std::string which = "face pressure " + std::to_string(i);
    if (l.element < 0 || std::size_t(l.element) >= mesh.elements.size())
      throw std::invalid_argument(which + " is applied to element " + std::to_string(l.element) +
                                  ", but the mesh has elements 0.." + std::to_string(long(mesh.elements.size()) - 1));
    const ElementKind kind = mesh.elements[std::size_t(l.element)].kind;
    if (l.face < 1 || l.face > faceCount(kind))
      throw std::invalid_argument(
        which + " (element " + std::to_string(l.element) + ") names face " + std::to_string(l.face) + ": " +
        (kind == ElementKind::Wedge15 ? "a native wedge has faces 1..5 (CalculiX C3D15 P1..P5)"
                                      : "a hexahedron has faces 1..6 (CalculiX C3D20 P1..P6)"));
    if (!std::isfinite(l.pressure))
      throw std::invalid_argument(which + " (element " + std::to_string(l.element) + ", face " +
                                  std::to_string(l.face) + ") has a non-finite pressure");
  }
}

Eigen::VectorXd assembleFacePressureLoad(const Mesh& mesh, const std::vector<FacePressure>& loads,
                                         int pointsPerDirection)
{
  validateFacePressures(mesh, loads);
  const LineRule& rule = gaussLineRule(pointsPerDirection);
  Eigen::VectorXd r = Eigen::VectorXd::Zero(mesh.dofCount());
  ElementVector re;
  for (const FacePressure& l : loads)
  {
    if (l.pressure == 0.0)
      continue;
    const Element& el = mesh.elements[std::size_t(l.element)];
    assembleElementFacePressure(ElementShape::fromConnectivity(el.kind, el.nodes),
                                mesh.elementCoordinates(std::size_t(l.element)), l.face, l.pressure, rule, re);
    for (int k = 0; k < kHex20NodeCount; ++k)
      if (el.nodes[k] >= 0)
        r.segment<3>(3 * el.nodes[k]) += re.segment<3>(3 * k);
  }
  return r;
}

} // namespace caps::fem
