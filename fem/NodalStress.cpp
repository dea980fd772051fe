#include "fem/NodalStress.h"

#include "fem/ElementNumbering.h"
#include "fem/Quadrature.h"
#include "fem/StressRecovery.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace caps::fem {

double vonMisesStress(const Vector6d& s)
{
  const double a = s[0] - s[1], b = s[1] - s[2], c = s[2] - s[0];
  return std::sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
}

Eigen::Vector3d principalStresses(const Vector6d& s)
{
  Eigen::Matrix3d t;
  t << s[0], s[3], s[5], //
    s[3], s[1], s[4],    //
    s[5], s[4], s[2];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(t, Eigen::EigenvaluesOnly);
  const Eigen::Vector3d ascending = eig.eigenvalues();
  return {ascending[2], ascending[1], ascending[0]};
}

int RegionNodeLayout::column(int region, int node) const
{
  if (node < 0 || node + 1 >= firstColumn.size())
    return -1;
  for (int c = firstColumn[node]; c < firstColumn[node + 1]; ++c)
    if (regionOf[c] == region)
      return c;
  return -1;
}

RegionNodeLayout RegionNodeLayout::of(const Mesh& mesh, const std::map<int, double>& stiffness)
{
  const Eigen::Index n = mesh.nodeCount();
  // The regions at each node, ascending, with their element counts.
  std::vector<std::map<int, int>> regions(static_cast<std::size_t>(n));
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Element& el = mesh.elements[e];
    for (int k = 0; k < kHex20NodeCount; ++k)
    {
      const int node = el.nodes[std::size_t(k)];
      if (node < 0)
        continue;
      if (node >= n)
        throw std::invalid_argument("element " + std::to_string(e) + " refers to node " + std::to_string(node) +
                                    ", but the mesh has " + std::to_string(n) + " nodes");
      bool first = true; // a node repeated in a degenerate element counts once
      for (int j = 0; j < k; ++j)
        first = first && el.nodes[std::size_t(j)] != node;
      if (first)
        ++regions[std::size_t(node)][el.region];
    }
  }
  Eigen::Index columns = 0;
  for (const auto& r : regions)
    columns += Eigen::Index(r.size());
  RegionNodeLayout layout;
  layout.regionOf.resize(columns);
  layout.nodeOf.resize(columns);
  layout.elementCount.resize(columns);
  layout.firstColumn.resize(n + 1);
  layout.representative = Eigen::VectorXi::Constant(n, -1);
  auto stiffnessOf = [&](int region) {
    const auto it = stiffness.find(region);
    return it == stiffness.end() ? 0.0 : it->second;
  };
  int c = 0;
  for (Eigen::Index i = 0; i < n; ++i)
  {
    layout.firstColumn[i] = c;
    for (const auto& [region, count] : regions[std::size_t(i)])
    {
      layout.regionOf[c] = region;
      layout.nodeOf[c] = int(i);
      layout.elementCount[c] = count;
      // Regions ascend: a strictly stiffer one replaces, a tie keeps the lower id.
      const int best = layout.representative[i];
      if (best < 0 || stiffnessOf(region) > stiffnessOf(layout.regionOf[best]))
        layout.representative[i] = c;
      ++c;
    }
  }
  layout.firstColumn[n] = c;
  return layout;
}

Eigen::MatrixXd representativeValues(const RegionNodeLayout& layout, const Eigen::MatrixXd& regionValues)
{
  if (regionValues.cols() != layout.size())
    throw std::invalid_argument("representativeValues: one column per (region, node) pair expected");
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(regionValues.rows(), layout.representative.size());
  for (Eigen::Index i = 0; i < layout.representative.size(); ++i)
    if (layout.representative[i] >= 0)
      out.col(i) = regionValues.col(layout.representative[i]);
  return out;
}

Eigen::MatrixXd averageAtRegionNodes(const Mesh& mesh, const RegionNodeLayout& layout, int rows, int pointsPerDirection,
                                     const std::function<void(int element, Eigen::MatrixXd& values)>& gaussValues)
{
  if (layout.firstColumn.size() != mesh.nodeCount() + 1)
    throw std::invalid_argument("averageAtRegionNodes: the layout belongs to another mesh");
  // Extrapolation of each (kind, rule) in use: each element's own points.
  std::map<std::pair<ElementKind, int>, Eigen::MatrixXd> extrapolations;
  for (const Element& el : mesh.elements)
  {
    const std::pair<ElementKind, int> key{el.kind, integrationPointsOf(el, pointsPerDirection)};
    if (!extrapolations.count(key))
      extrapolations[key] = gaussToNodeExtrapolation(key.first, key.second);
  }
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(rows, layout.size());
  Eigen::MatrixXd gauss, atNodes;
  Eigen::VectorXd slots(rows);
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Element& el = mesh.elements[e];
    const Eigen::MatrixXd& extrapolation = extrapolations.at({el.kind, integrationPointsOf(el, pointsPerDirection)});
    gaussValues(int(e), gauss);
    if (gauss.rows() != rows || gauss.cols() != extrapolation.cols())
      throw std::logic_error("averageAtRegionNodes: element " + std::to_string(e) + " gave " +
                             std::to_string(gauss.rows()) + " x " + std::to_string(gauss.cols()) + " values, not " +
                             std::to_string(rows) + " x " + std::to_string(extrapolation.cols()));
    atNodes.noalias() = gauss * extrapolation.transpose();
    // Mean over the slots of each distinct node (repeated in a wedge).
    const auto& nodes = el.nodes;
    for (int k = 0; k < kHex20NodeCount; ++k)
    {
      const int n = nodes[std::size_t(k)];
      if (n < 0)
        continue;
      bool first = true;
      for (int j = 0; j < k; ++j)
        first = first && nodes[std::size_t(j)] != n;
      if (!first)
        continue;
      slots = atNodes.col(k);
      int count = 1;
      for (int j = k + 1; j < kHex20NodeCount; ++j)
        if (nodes[std::size_t(j)] == n)
        {
          slots += atNodes.col(j);
          ++count;
        }
      const int c = layout.column(el.region, n);
      if (c < 0)
        throw std::invalid_argument("averageAtRegionNodes: the layout belongs to another mesh");
      sum.col(c) += slots / count;
    }
  }
  for (Eigen::Index c = 0; c < layout.size(); ++c)
    sum.col(c) /= layout.elementCount[c];
  return sum;
}

Vector6d NodalStressField::valueAt(int region, int node) const
{
  const int c = layout.column(region, node);
  if (c < 0)
    throw std::out_of_range("no element of region " + std::to_string(region) + " holds node " + std::to_string(node));
  return regionStress.col(c);
}

int NodalStressField::regionAt(int node) const
{
  const int c = node >= 0 && node < layout.representative.size() ? layout.representative[node] : -1;
  return c < 0 ? -1 : layout.regionOf[c];
}

Eigen::VectorXd NodalStressField::vonMises() const
{
  Eigen::VectorXd v(stress.cols());
  for (Eigen::Index i = 0; i < stress.cols(); ++i)
    v[i] = vonMisesStress(stress.col(i));
  return v;
}

Eigen::VectorXd NodalStressField::regionVonMises() const
{
  Eigen::VectorXd v(regionStress.cols());
  for (Eigen::Index i = 0; i < regionStress.cols(); ++i)
    v[i] = vonMisesStress(regionStress.col(i));
  return v;
}

Eigen::VectorXd NodalStressField::meanStress() const
{
  return stress.topRows<3>().colwise().sum().transpose() / 3.0;
}

Eigen::Matrix3Xd NodalStressField::principal() const
{
  Eigen::Matrix3Xd p(3, stress.cols());
  for (Eigen::Index i = 0; i < stress.cols(); ++i)
    p.col(i) = principalStresses(stress.col(i));
  return p;
}

Eigen::MatrixXd gaussToNodeExtrapolation(int pointsPerDirection)
{
  if (pointsPerDirection != 2 && pointsPerDirection != 3)
    throw std::invalid_argument("nodal stresses are extrapolated from 2x2x2 or 3x3x3 Gauss points, not " +
                                std::to_string(pointsPerDirection) + " per direction");
  const IntegrationRule& rule = gaussRule(pointsPerDirection);
  // The distinct abscissae along one axis.
  std::vector<double> abscissae;
  for (const auto& p : rule.points)
    if (std::none_of(abscissae.begin(), abscissae.end(), [&](double a) { return std::abs(a - p[0]) < 1e-12; }))
      abscissae.push_back(p[0]);
  // 1D Lagrange basis function of abscissa a at x.
  auto lagrange = [&](double a, double x) {
    double v = 1.0;
    for (double b : abscissae)
      if (std::abs(b - a) > 1e-12)
        v *= (x - b) / (a - b);
    return v;
  };
  Eigen::MatrixXd e(kHex20NodeCount, Eigen::Index(rule.size()));
  for (int k = 0; k < kHex20NodeCount; ++k)
  {
    const Eigen::Vector3d node = batheNaturalCoordinates(k);
    for (std::size_t p = 0; p < rule.size(); ++p)
    {
      const Eigen::Vector3d& g = rule.points[p];
      e(k, Eigen::Index(p)) = lagrange(g[0], node[0]) * lagrange(g[1], node[1]) * lagrange(g[2], node[2]);
    }
  }
  return e;
}

Eigen::MatrixXd gaussToNodeExtrapolation(ElementKind kind, int pointsPerDirection)
{
  if (kind == ElementKind::Hex20)
    return gaussToNodeExtrapolation(pointsPerDirection);
  const IntegrationRule& rule = wedgeRule(pointsPerDirection);
  // The fitted polynomial: linear in (r, s) times linear in t (least squares
  // over the 3 x 3 points), or quadratic times quadratic (interpolating the
  // 6 x 3 points).
  const bool quadratic = pointsPerDirection == 3;
  auto basis = [&](const Eigen::Vector3d& p) {
    const double r = p[0], s = p[1], t = p[2];
    std::vector<double> inPlane = {1.0, r, s};
    std::vector<double> along = {1.0, t};
    if (quadratic)
    {
      inPlane.insert(inPlane.end(), {r * r, r * s, s * s});
      along.push_back(t * t);
    }
    Eigen::RowVectorXd b(Eigen::Index(inPlane.size() * along.size()));
    Eigen::Index i = 0;
    for (double u : inPlane)
      for (double v : along)
        b[i++] = u * v;
    return b;
  };
  const Eigen::Index m = basis(rule.points[0]).size();
  Eigen::MatrixXd v(Eigen::Index(rule.size()), m);
  for (std::size_t p = 0; p < rule.size(); ++p)
    v.row(Eigen::Index(p)) = basis(rule.points[p]);
  // Coefficients = (V^T V)^-1 V^T g: the least-squares fit (the interpolant when V is square).
  const Eigen::MatrixXd fit = (v.transpose() * v).ldlt().solve(v.transpose());
  Eigen::MatrixXd e = Eigen::MatrixXd::Zero(kHex20NodeCount, Eigen::Index(rule.size()));
  for (int k = 0; k < kWedge15NodeCount; ++k)
    e.row(k) = basis(wedge15NaturalCoordinates(k)) * fit;
  return e;
}

NodalStressField recoverNodalStresses(const Mesh& mesh, const MaterialTable& materials, const Eigen::VectorXd& u,
                                      int pointsPerDirection, int threads)
{
  if (u.size() != mesh.dofCount())
    throw std::invalid_argument("recoverNodalStresses: the displacement vector must have 3N entries");
  return nodalStressesFromGaussPoints(mesh, materials,
                                      recoverStressAtAllGaussPoints(mesh, materials, u, pointsPerDirection, threads),
                                      pointsPerDirection);
}

NodalStressField nodalStressesFromGaussPoints(const Mesh& mesh, const MaterialTable& materials,
                                              const std::vector<std::vector<StressPoint>>& gaussStress,
                                              int pointsPerDirection)
{
  if (gaussStress.size() != mesh.elements.size())
    throw std::invalid_argument("nodalStressesFromGaussPoints: " + std::to_string(gaussStress.size()) +
                                " elements' stresses given for a mesh of " + std::to_string(mesh.elements.size()));
  std::map<int, double> shearModulus;
  for (const auto& [region, m] : materials)
    shearModulus[region] = m.youngsModulus / (2.0 * (1.0 + m.poissonRatio));
  NodalStressField field;
  field.layout = RegionNodeLayout::of(mesh, shearModulus);
  field.regionStress =
    averageAtRegionNodes(mesh, field.layout, 6, pointsPerDirection, [&](int e, Eigen::MatrixXd& values) {
      const auto& points = gaussStress[std::size_t(e)];
      values.resize(6, Eigen::Index(points.size()));
      for (std::size_t p = 0; p < points.size(); ++p)
        values.col(Eigen::Index(p)) = points[p].stress;
    });
  field.stress = representativeValues(field.layout, field.regionStress);
  field.elementCount = Eigen::VectorXi::Zero(mesh.nodeCount());
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    if (field.layout.representative[i] >= 0)
      field.elementCount[i] = field.layout.elementCount[field.layout.representative[i]];
  return field;
}

} // namespace caps::fem
