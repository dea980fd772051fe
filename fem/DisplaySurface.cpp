#include "fem/DisplaySurface.h"

#include "fem/ElementGeometry.h"
#include "fem/ElementShape.h"
#include "fem/FacePressure.h"
#include "fem/NodalStress.h"
#include "fem/Quadrature.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

namespace caps::fem {

namespace {

int cornerCount(ElementKind kind)
{
  return kind == ElementKind::Wedge15 ? kWedge15CornerCount : kHex20CornerCount;
}

/// Corner slots of a face in the order of its chart's corners: (a, b) =
/// (-1,-1), (1,-1), (1,1), (-1,1) for a quadrilateral, (0,0), (1,0), (0,1)
/// for a triangle.
std::vector<int> faceCornerSlots(const ElementShape& shape, const FaceChart& chart)
{
  static const double quad[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  static const double tri[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  const int n = chart.triangle ? 3 : 4;
  std::vector<int> slots;
  for (int c = 0; c < n; ++c)
  {
    const double a = chart.triangle ? tri[c][0] : quad[c][0], b = chart.triangle ? tri[c][1] : quad[c][1];
    const Eigen::Vector3d rst = chart.origin + a * chart.p + b * chart.q;
    int found = -1;
    for (int k = 0; k < cornerCount(shape.kind()) && found < 0; ++k)
      if ((shape.naturalCoordinates(k) - rst).cwiseAbs().maxCoeff() < 1e-12)
        found = k;
    if (found < 0)
      throw std::logic_error("DisplaySurface: a face corner is not a corner node");
    slots.push_back(found);
  }
  return slots;
}

/// Name of a vertex shared between faces: a corner node {node, -1, 0}, or
/// the point k steps from node A along the edge to node B, A < B: {A, B, k}.
using VertexKey = std::array<int, 3>;

VertexKey cornerKey(int node)
{
  return {node, -1, 0};
}

VertexKey edgeKey(int from, int to, int step, int steps)
{
  if (from == to || step == 0)
    return cornerKey(from); // an edge collapsed to one node
  if (step == steps)
    return cornerKey(to);
  return from < to ? VertexKey{from, to, step} : VertexKey{to, from, steps - step};
}

/// The shared name of grid point (i, j) of a face with corner nodes @a c (in
/// chart order) and @a n steps per edge, if it lies on the face's border.
std::optional<VertexKey> borderKey(const FaceChart& chart, const std::vector<int>& c, int n, int i, int j)
{
  if (chart.triangle)
  {
    if (j == 0)
      return edgeKey(c[0], c[1], i, n);
    if (i + j == n)
      return edgeKey(c[1], c[2], j, n);
    if (i == 0)
      return edgeKey(c[0], c[2], j, n);
  }
  else
  {
    if (j == 0)
      return edgeKey(c[0], c[1], i, n);
    if (i == n)
      return edgeKey(c[1], c[2], j, n);
    if (j == n)
      return edgeKey(c[3], c[2], i, n);
    if (i == 0)
      return edgeKey(c[0], c[3], j, n);
  }
  return std::nullopt;
}

/// The polygons of face @a f over its grid of vertex indices (row by row, a
/// fastest, @a n steps per edge) into @a polygons and @a polygonFace.
void addGridPolygons(const FaceChart& chart, int n, const std::vector<int>& grid, int f,
                     std::vector<std::vector<int>>& polygons, std::vector<int>& polygonFace)
{
  auto at = [&](int i, int j) { return grid[std::size_t(j * (n + 1) + i)]; };
  // Counter-clockwise in (a, b): outward when p × q points out (sign > 0).
  auto addPolygon = [&](std::vector<int> polygon) {
    if (chart.sign < 0)
      std::reverse(polygon.begin(), polygon.end());
    // Drop the repeats a collapsed edge leaves.
    std::vector<int> distinct;
    for (std::size_t k = 0; k < polygon.size(); ++k)
      if (polygon[k] != polygon[(k + 1) % polygon.size()])
        distinct.push_back(polygon[k]);
    if (distinct.size() < 3)
      return;
    polygons.push_back(std::move(distinct));
    polygonFace.push_back(f);
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < (chart.triangle ? n - j : n); ++i)
    {
      if (!chart.triangle)
      {
        addPolygon({at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
        continue;
      }
      addPolygon({at(i, j), at(i + 1, j), at(i, j + 1)});
      if (i + j + 1 < n)
        addPolygon({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
    }
}

} // namespace

std::vector<ElementFace> boundaryFacesOnNodes(const Mesh& mesh, const std::vector<int>& nodes)
{
  std::vector<char> inSet(std::size_t(mesh.nodeCount()), 0);
  for (int n : nodes)
    if (n >= 0 && n < mesh.nodeCount())
      inSet[std::size_t(n)] = 1;
  struct Candidate
  {
    ElementFace face;
    std::vector<int> corners; // distinct, ascending
  };
  std::vector<Candidate> candidates;
  std::map<std::vector<int>, int> uses;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Element& el = mesh.elements[e];
    for (int f = 1; f <= faceCount(el.kind); ++f)
    {
      bool inside = true;
      std::vector<int> corners;
      for (int slot : faceNodes(el.kind, f))
      {
        const int node = el.nodes[std::size_t(slot)];
        if (node < 0)
          continue; // an absent mid-side node
        if (node >= mesh.nodeCount() || !inSet[std::size_t(node)])
        {
          inside = false;
          break;
        }
        if (slot < cornerCount(el.kind))
          corners.push_back(node);
      }
      if (!inside)
        continue;
      std::sort(corners.begin(), corners.end());
      corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
      if (corners.size() < 3)
        continue; // collapsed: no area to show
      ++uses[corners];
      candidates.push_back({{int(e), f}, std::move(corners)});
    }
  }
  std::vector<ElementFace> out;
  for (const auto& c : candidates)
    if (uses[c.corners] == 1)
      out.push_back(c.face);
  return out;
}

std::vector<ElementFace> skinFaces(const ContinuumMesh& continuum)
{
  std::vector<ElementFace> out;
  for (std::size_t e = 0; e < continuum.elementLayer.size(); ++e)
    if (continuum.elementLayer[e] == 0)
      out.push_back({int(e), 2});
  return out;
}

/// The constructor's state while it adds the faces: the vertices shared
/// between faces, the display node of each mesh node, the interpolation
/// weights as triplets and the stress rows.
struct DisplaySurface::Construction
{
  Construction(const Mesh& mesh, int resolution, std::vector<BodyPoint>& bodyPoints, std::vector<int>& displayNodes)
    : mesh(mesh), n(resolution), bodyPoints(bodyPoints), displayNodes(displayNodes),
      displayIndex(std::size_t(mesh.nodeCount()), -1)
  {}

  /// A new vertex at grid point (i, j) of a face of @a el (element @a element).
  int addVertex(const Element& el, int element, const ElementShape& shape, const FaceChart& chart, int i, int j);

  const Mesh& mesh;
  const int n;
  std::vector<BodyPoint>& bodyPoints;
  std::vector<int>& displayNodes;
  std::map<VertexKey, int> shared;
  std::vector<int> displayIndex;
  std::vector<Eigen::Triplet<double>> triplets;
  // The stress rows: one per (display node, region of the vertices' elements).
  std::map<std::pair<int, int>, int> regionRow;
  std::vector<int> regionRows; // mesh node of each
  std::vector<Eigen::Triplet<double>> regionTriplets;
  ShapeVector h;
};

int DisplaySurface::Construction::addVertex(const Element& el, int element, const ElementShape& shape,
                                            const FaceChart& chart, int i, int j)
{
  const double a = chart.triangle ? double(i) / n : double(2 * i - n) / n;
  const double b = chart.triangle ? double(j) / n : double(2 * j - n) / n;
  const Eigen::Vector3d rst = chart.origin + a * chart.p + b * chart.q;
  const int v = int(bodyPoints.size());
  bodyPoints.push_back({element, rst});
  shape.values(rst, h);
  for (int k = 0; k < kHex20NodeCount; ++k)
  {
    const int node = el.nodes[std::size_t(k)];
    if (node < 0 || h[k] == 0.0)
      continue;
    int& d = displayIndex[std::size_t(node)];
    if (d < 0)
    {
      d = int(displayNodes.size());
      displayNodes.push_back(node);
    }
    triplets.emplace_back(d, v, h[k]); // repeated nodes of a wedge add up
    const auto [row, inserted] = regionRow.emplace(std::make_pair(node, el.region), int(regionRows.size()));
    if (inserted)
      regionRows.push_back(node);
    regionTriplets.emplace_back(row->second, v, h[k]);
  }
  return v;
}

DisplaySurface::DisplaySurface(const Mesh& mesh, const std::vector<ElementFace>& faces, int resolution)
  : resolution_(resolution), meshNodeCount_(mesh.nodeCount()), faces_(faces)
{
  if (resolution < 1)
    throw std::invalid_argument("the display resolution must be at least 1 step per element edge, not " +
                                std::to_string(resolution));
  Construction build(mesh, resolution, bodyPoints_, displayNodes_);
  for (std::size_t f = 0; f < faces.size(); ++f)
    addFace(f, build);
  setWeights(mesh, build);
  addSupportElements(mesh, build);
}

void DisplaySurface::addFace(std::size_t f, Construction& build)
{
  const Mesh& mesh = build.mesh;
  const int n = build.n;
  const ElementFace& face = faces_[f];
  if (face.element < 0 || std::size_t(face.element) >= mesh.elements.size())
    throw std::invalid_argument("display face " + std::to_string(f) + " names element " + std::to_string(face.element) +
                                ", but the mesh has elements 0.." + std::to_string(int(mesh.elements.size()) - 1));
  const Element& el = mesh.elements[std::size_t(face.element)];
  FaceChart chart;
  try
  {
    chart = faceChart(el.kind, face.face);
  }
  catch (const std::invalid_argument& e)
  {
    throw std::invalid_argument("display face " + std::to_string(f) + " of element " + std::to_string(face.element) +
                                ": " + e.what());
  }
  for (int node : el.nodes)
    if (node >= mesh.nodeCount())
      throw std::invalid_argument("element " + std::to_string(face.element) + " refers to node " +
                                  std::to_string(node) + ", but the mesh has " + std::to_string(mesh.nodeCount()) +
                                  " nodes");
  const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
  const std::vector<int> cornerSlots = faceCornerSlots(shape, chart);
  std::vector<int> c; // corner nodes in chart order
  for (int slot : cornerSlots)
    c.push_back(el.nodes[std::size_t(slot)]);

  // Vertex index of every grid point, row by row (a fastest).
  std::vector<int> grid(std::size_t((n + 1) * (n + 1)), -1);
  auto at = [&](int i, int j) -> int& { return grid[std::size_t(j * (n + 1) + i)]; };
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= (chart.triangle ? n - j : n); ++i)
    {
      if (const auto key = borderKey(chart, c, n, i, j))
      {
        const auto [it, inserted] = build.shared.emplace(*key, -1);
        if (inserted)
          it->second = build.addVertex(el, face.element, shape, chart, i, j);
        at(i, j) = it->second;
      }
      else
      {
        at(i, j) = build.addVertex(el, face.element, shape, chart, i, j);
      }
    }
  addGridPolygons(chart, n, grid, int(f), polygons_, polygonFace_);
}

void DisplaySurface::setWeights(const Mesh& mesh, const Construction& build)
{
  const Eigen::Index vertices = Eigen::Index(bodyPoints_.size());
  const Eigen::Index d = Eigen::Index(displayNodes_.size());
  weights_.resize(d, vertices);
  weights_.setFromTriplets(build.triplets.begin(), build.triplets.end());
  regionWeights_.resize(Eigen::Index(build.regionRows.size()), vertices);
  regionWeights_.setFromTriplets(build.regionTriplets.begin(), build.regionTriplets.end());
  Eigen::Matrix3Xd nodeX(3, d);
  for (Eigen::Index i = 0; i < d; ++i)
    nodeX.col(i) = mesh.nodes.col(displayNodes_[std::size_t(i)]);
  positions_ = nodeX * weights_; // eq. 4.13 at every vertex
  rangeDetail_ = Eigen::Matrix3Xd::Zero(3, vertices);
  displacements_ = Eigen::Matrix3Xd::Zero(3, vertices);
  strains_ = Matrix6Xd::Zero(6, vertices);
  stresses_ = Matrix6Xd::Zero(6, vertices);
}

void DisplaySurface::addSupportElements(const Mesh& mesh, const Construction& build)
{
  const std::map<std::pair<int, int>, int>& regionRow = build.regionRow;
  // Every element holding a display node contributes to its nodal average,
  // so its Gauss-point derivatives are kept (Jacobians checked once, here).
  hexExtrapolation_ = gaussToNodeExtrapolation(ElementKind::Hex20, 2);
  displayElementCount_ = Eigen::VectorXi::Zero(Eigen::Index(build.regionRows.size()));
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Element& el = mesh.elements[e];
    bool touches = false;
    for (int node : el.nodes)
      touches = touches || (node >= 0 && node < mesh.nodeCount() && regionRow.count({node, el.region}));
    if (!touches)
      continue;
    SupportElement s;
    s.region = el.region;
    s.nodes = el.nodes;
    s.wedge = el.kind == ElementKind::Wedge15;
    if (s.wedge && wedgeExtrapolation_.size() == 0)
      wedgeExtrapolation_ = gaussToNodeExtrapolation(ElementKind::Wedge15, 2);
    for (int k = 0; k < kHex20NodeCount; ++k)
    {
      const int node = el.nodes[std::size_t(k)];
      const auto row = node >= 0 ? regionRow.find({node, el.region}) : regionRow.end();
      s.displaySlot[std::size_t(k)] = row == regionRow.end() ? -1 : row->second;
      s.slotWeight[std::size_t(k)] = int(std::count(el.nodes.begin(), el.nodes.end(), node));
    }
    // Each distinct display node counts this element once.
    for (int k = 0; k < kHex20NodeCount; ++k)
    {
      const int node = el.nodes[std::size_t(k)];
      if (s.displaySlot[std::size_t(k)] < 0 ||
          std::find(el.nodes.begin(), el.nodes.begin() + k, node) != el.nodes.begin() + k)
        continue;
      displayElementCount_[s.displaySlot[std::size_t(k)]] += 1;
    }
    const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
    const ElementCoordinates x = mesh.elementCoordinates(e);
    PointGeometry g;
    for (const Eigen::Vector3d& point : integrationRule(el.kind, 2).points)
    {
      evaluateGeometry(shape, x, point, int(e), g);
      s.gradients.push_back(g.dhWorld);
    }
    support_.push_back(std::move(s));
  }
}

void DisplaySurface::setRangeDetail(const Eigen::Matrix3Xd& offsets)
{
  if (offsets.cols() != vertexCount())
    throw std::invalid_argument("the range detail needs one offset per display vertex (" +
                                std::to_string(vertexCount()) + "), not " + std::to_string(offsets.cols()));
  if (!offsets.allFinite())
    throw std::invalid_argument("the range detail must be finite (0 where there is no scan)");
  rangeDetail_ = offsets;
}

void DisplaySurface::setSolution(const Eigen::VectorXd& u, const MaterialTable& materials)
{
  std::map<int, Matrix6d> elasticity;
  for (const SupportElement& s : support_)
    if (!elasticity.count(s.region))
    {
      const auto m = materials.find(s.region);
      if (m == materials.end())
        throw std::invalid_argument("no material for region " + std::to_string(s.region) +
                                    " of the displayed elements");
      elasticity[s.region] = m->second.elasticityMatrix();
    }
  // Small strain: e = sym(du/dx) (engineering shears), sigma = C e.
  recoverAtTheDisplayNodes(u, [&](int region, const Eigen::Matrix3d& l, Vector6d& strain, Vector6d& stress) {
    strain << l(0, 0), l(1, 1), l(2, 2), l(0, 1) + l(1, 0), l(1, 2) + l(2, 1), l(2, 0) + l(0, 2);
    stress = elasticity.at(region) * strain;
  });
}

void DisplaySurface::setSolution(const Eigen::VectorXd& u, const HyperelasticTable& materials)
{
  for (const SupportElement& s : support_)
    if (!materials.count(s.region))
      throw std::invalid_argument("no material for region " + std::to_string(s.region) + " of the displayed elements");
  // Large deformation: F = I + du/dX, the Green-Lagrange strain E (engineering
  // shears) and the Cauchy stress sigma = F S F^T / J of the material's S. A
  // point turned inside out (det F <= 0; never in a converged large-deformation
  // solve) has no stress: NaN, which the display leaves uncoloured.
  recoverAtTheDisplayNodes(u, [&](int region, const Eigen::Matrix3d& l, Vector6d& strain, Vector6d& stress) {
    const Eigen::Matrix3d f = Eigen::Matrix3d::Identity() + l;
    const Eigen::Matrix3d c = f.transpose() * f;
    strain << 0.5 * (c(0, 0) - 1.0), 0.5 * (c(1, 1) - 1.0), 0.5 * (c(2, 2) - 1.0), c(0, 1), c(1, 2), c(2, 0);
    const double j = f.determinant();
    if (!(j > 0.0))
    {
      stress.setConstant(std::numeric_limits<double>::quiet_NaN());
      return;
    }
    const Vector6d sv = materials.at(region).response(c, j, ResponseParts::Stress).stress;
    Eigen::Matrix3d pk2;
    pk2 << sv[0], sv[3], sv[5], sv[3], sv[1], sv[4], sv[5], sv[4], sv[2];
    const Eigen::Matrix3d sigma = f * pk2 * f.transpose() / j;
    stress << sigma(0, 0), sigma(1, 1), sigma(2, 2), sigma(0, 1), sigma(1, 2), sigma(2, 0);
  });
}

void DisplaySurface::recoverAtTheDisplayNodes(const Eigen::VectorXd& u, const PointResponse& response)
{
  if (u.size() != 3 * meshNodeCount_)
    throw std::invalid_argument("the solution has " + std::to_string(u.size()) +
                                " displacements, but the displayed mesh has 3 x " + std::to_string(meshNodeCount_));
  // Nodal averages of the strain and stress extrapolated from the Gauss
  // points, within each region, at the display nodes only.
  const Eigen::Index d = regionWeights_.rows();
  Matrix6Xd nodalStrain = Matrix6Xd::Zero(6, d), nodalStress = Matrix6Xd::Zero(6, d);
  Eigen::Matrix<double, 3, kHex20NodeCount> ue;
  Matrix6Xd gaussStrain, gaussStress;
  for (const SupportElement& s : support_)
  {
    for (int k = 0; k < kHex20NodeCount; ++k)
    {
      const int node = s.nodes[std::size_t(k)];
      ue.col(k) = node >= 0 ? Eigen::Vector3d(u.segment<3>(3 * Eigen::Index(node))) : Eigen::Vector3d::Zero();
    }
    gaussStrain.resize(6, Eigen::Index(s.gradients.size()));
    gaussStress.resize(6, Eigen::Index(s.gradients.size()));
    for (std::size_t p = 0; p < s.gradients.size(); ++p)
    {
      const Eigen::Matrix3d l = ue * s.gradients[p]; // l(i, j) = du_i / dX_j
      Vector6d strain, stress;
      response(s.region, l, strain, stress);
      gaussStrain.col(Eigen::Index(p)) = strain;
      gaussStress.col(Eigen::Index(p)) = stress;
    }
    const Eigen::MatrixXd& extrapolation = s.wedge ? wedgeExtrapolation_ : hexExtrapolation_;
    for (int k = 0; k < kHex20NodeCount; ++k)
    {
      const int target = s.displaySlot[std::size_t(k)];
      if (target < 0)
        continue;
      const Eigen::VectorXd weights = extrapolation.row(k).transpose() / s.slotWeight[std::size_t(k)];
      nodalStrain.col(target) += gaussStrain * weights;
      nodalStress.col(target) += gaussStress * weights;
    }
  }
  for (Eigen::Index i = 0; i < d; ++i)
  {
    nodalStrain.col(i) /= displayElementCount_[i];
    nodalStress.col(i) /= displayElementCount_[i];
  }

  Eigen::Matrix3Xd nodalDisplacement(3, Eigen::Index(displayNodes_.size()));
  for (Eigen::Index i = 0; i < nodalDisplacement.cols(); ++i)
    nodalDisplacement.col(i) = u.segment<3>(3 * Eigen::Index(displayNodes_[std::size_t(i)]));
  displacements_ = nodalDisplacement * weights_; // eq. 4.14
  strains_ = nodalStrain * regionWeights_;
  stresses_ = nodalStress * regionWeights_;
  hasSolution_ = true;
}

Eigen::Matrix3Xd DisplaySurface::positions(const DisplayMapping& mapping) const
{
  Eigen::Matrix3Xd out(3, vertexCount());
  positions(mapping, out);
  return out;
}

void DisplaySurface::positions(const DisplayMapping& mapping, Eigen::Matrix3Xd& out) const
{
  if (out.cols() != vertexCount())
    throw std::invalid_argument("DisplaySurface::positions: the output must have one column per vertex");
  if (mapping.rangeDetail)
    out.noalias() = positions_ + rangeDetail_ + mapping.scale * displacements_;
  else
    out.noalias() = positions_ + mapping.scale * displacements_;
}

Eigen::VectorXd DisplaySurface::displacementMagnitude() const
{
  return displacements_.colwise().norm().transpose();
}

Eigen::VectorXd DisplaySurface::vonMises() const
{
  Eigen::VectorXd v(vertexCount());
  for (Eigen::Index i = 0; i < vertexCount(); ++i)
    v[i] = vonMisesStress(stresses_.col(i));
  return v;
}

Eigen::VectorXd DisplaySurface::meanStress() const
{
  return stresses_.topRows<3>().colwise().sum().transpose() / 3.0;
}

Eigen::VectorXd DisplaySurface::volumetricStrain() const
{
  return strains_.topRows<3>().colwise().sum().transpose();
}

Eigen::VectorXd DisplaySurface::equivalentStrain() const
{
  Eigen::VectorXd v(vertexCount());
  for (Eigen::Index i = 0; i < vertexCount(); ++i)
  {
    const auto e = strains_.col(i);
    const double a = e[0] - e[1], b = e[1] - e[2], c = e[2] - e[0];
    // sqrt(2/3 e':e') with tensor shears gamma / 2.
    v[i] = std::sqrt(2.0) / 3.0 * std::sqrt(a * a + b * b + c * c + 1.5 * (e[3] * e[3] + e[4] * e[4] + e[5] * e[5]));
  }
  return v;
}

} // namespace caps::fem
