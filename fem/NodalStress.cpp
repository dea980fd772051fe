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
#include <vector>

namespace caps::fem {

double vonMisesStress(const Vector6d& s) {
  const double a = s[0] - s[1], b = s[1] - s[2], c = s[2] - s[0];
  return std::sqrt(0.5 * (a * a + b * b + c * c) + 3.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
}

Eigen::Vector3d principalStresses(const Vector6d& s) {
  Eigen::Matrix3d t;
  t << s[0], s[3], s[5],  //
      s[3], s[1], s[4],   //
      s[5], s[4], s[2];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(t, Eigen::EigenvaluesOnly);
  const Eigen::Vector3d ascending = eig.eigenvalues();
  return {ascending[2], ascending[1], ascending[0]};
}

Eigen::VectorXd NodalStressField::vonMises() const {
  Eigen::VectorXd v(stress.cols());
  for (Eigen::Index i = 0; i < stress.cols(); ++i) v[i] = vonMisesStress(stress.col(i));
  return v;
}

Eigen::VectorXd NodalStressField::meanStress() const { return stress.topRows<3>().colwise().sum().transpose() / 3.0; }

Eigen::Matrix3Xd NodalStressField::principal() const {
  Eigen::Matrix3Xd p(3, stress.cols());
  for (Eigen::Index i = 0; i < stress.cols(); ++i) p.col(i) = principalStresses(stress.col(i));
  return p;
}

Eigen::MatrixXd gaussToNodeExtrapolation(int pointsPerDirection) {
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
      if (std::abs(b - a) > 1e-12) v *= (x - b) / (a - b);
    return v;
  };
  Eigen::MatrixXd e(kHex20NodeCount, Eigen::Index(rule.size()));
  for (int k = 0; k < kHex20NodeCount; ++k) {
    const Eigen::Vector3d node = batheNaturalCoordinates(k);
    for (std::size_t p = 0; p < rule.size(); ++p) {
      const Eigen::Vector3d& g = rule.points[p];
      e(k, Eigen::Index(p)) = lagrange(g[0], node[0]) * lagrange(g[1], node[1]) * lagrange(g[2], node[2]);
    }
  }
  return e;
}

Eigen::MatrixXd gaussToNodeExtrapolation(ElementKind kind, int pointsPerDirection) {
  if (kind == ElementKind::Hex20) return gaussToNodeExtrapolation(pointsPerDirection);
  const IntegrationRule& rule = wedgeRule(pointsPerDirection);
  // The fitted polynomial: linear in (r, s) times linear in t (least squares
  // over the 3 x 3 points), or quadratic times quadratic (interpolating the
  // 6 x 3 points).
  const bool quadratic = pointsPerDirection == 3;
  auto basis = [&](const Eigen::Vector3d& p) {
    const double r = p[0], s = p[1], t = p[2];
    std::vector<double> inPlane = {1.0, r, s};
    std::vector<double> along = {1.0, t};
    if (quadratic) {
      inPlane.insert(inPlane.end(), {r * r, r * s, s * s});
      along.push_back(t * t);
    }
    Eigen::RowVectorXd b(Eigen::Index(inPlane.size() * along.size()));
    Eigen::Index i = 0;
    for (double u : inPlane)
      for (double v : along) b[i++] = u * v;
    return b;
  };
  const Eigen::Index m = basis(rule.points[0]).size();
  Eigen::MatrixXd v(Eigen::Index(rule.size()), m);
  for (std::size_t p = 0; p < rule.size(); ++p) v.row(Eigen::Index(p)) = basis(rule.points[p]);
  // Coefficients = (V^T V)^-1 V^T g: the least-squares fit (the interpolant when V is square).
  const Eigen::MatrixXd fit = (v.transpose() * v).ldlt().solve(v.transpose());
  Eigen::MatrixXd e = Eigen::MatrixXd::Zero(kHex20NodeCount, Eigen::Index(rule.size()));
  for (int k = 0; k < kWedge15NodeCount; ++k) e.row(k) = basis(wedge15NaturalCoordinates(k)) * fit;
  return e;
}

NodalStressField recoverNodalStresses(const Mesh& mesh, const MaterialTable& materials, const Eigen::VectorXd& u,
                                      int pointsPerDirection) {
  if (u.size() != mesh.dofCount())
    throw std::invalid_argument("recoverNodalStresses: the displacement vector must have 3N entries");
  // Extrapolation of each (kind, rule) in use: each element's own points.
  std::map<std::pair<ElementKind, int>, Eigen::MatrixXd> extrapolations;
  for (const Element& el : mesh.elements) {
    const std::pair<ElementKind, int> key{el.kind, integrationPointsOf(el, pointsPerDirection)};
    if (!extrapolations.count(key)) extrapolations[key] = gaussToNodeExtrapolation(key.first, key.second);
  }
  NodalStressField field;
  field.stress = NodalStressMatrix::Zero(6, mesh.nodeCount());
  field.elementCount = Eigen::VectorXi::Zero(mesh.nodeCount());
  Eigen::Matrix<double, 6, Eigen::Dynamic> gauss;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e) {
    const Element& el = mesh.elements[e];
    const Eigen::MatrixXd& extrapolation = extrapolations.at({el.kind, integrationPointsOf(el, pointsPerDirection)});
    const auto points = recoverStressAtGaussPoints(mesh, materials, u, int(e), pointsPerDirection);
    gauss.resize(6, Eigen::Index(points.size()));
    for (std::size_t p = 0; p < points.size(); ++p) gauss.col(Eigen::Index(p)) = points[p].stress;
    const Eigen::Matrix<double, 6, kHex20NodeCount> atNodes = gauss * extrapolation.transpose();
    // Mean over the slots of each distinct node (repeated in a wedge).
    const auto& nodes = mesh.elements[e].nodes;
    for (int k = 0; k < kHex20NodeCount; ++k) {
      const int n = nodes[std::size_t(k)];
      if (n < 0) continue;
      bool first = true;
      for (int j = 0; j < k; ++j) first = first && nodes[std::size_t(j)] != n;
      if (!first) continue;
      Vector6d sum = atNodes.col(k);
      int slots = 1;
      for (int j = k + 1; j < kHex20NodeCount; ++j)
        if (nodes[std::size_t(j)] == n) {
          sum += atNodes.col(j);
          ++slots;
        }
      field.stress.col(n) += sum / slots;
      field.elementCount[n] += 1;
    }
  }
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    if (field.elementCount[i] > 0) field.stress.col(i) /= field.elementCount[i];
  return field;
}

}  // namespace caps::fem
