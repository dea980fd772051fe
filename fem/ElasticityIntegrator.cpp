#include "fem/ElasticityIntegrator.h"

namespace caps::fem {

void strainDisplacementMatrix(const PointGeometry& g, StrainDisplacement& b) {
  b.setZero();
  for (int k = 0; k < kHex20NodeCount; ++k) {
    const double dx = g.dhWorld(k, 0), dy = g.dhWorld(k, 1), dz = g.dhWorld(k, 2);
    const int c = 3 * k;
    b(0, c) = dx;
    b(1, c + 1) = dy;
    b(2, c + 2) = dz;
    b(3, c) = dy;
    b(3, c + 1) = dx;
    b(4, c + 1) = dz;
    b(4, c + 2) = dy;
    b(5, c) = dz;
    b(5, c + 2) = dx;
  }
}

void assembleElementStiffness(const ElementShape& shape, const ElementCoordinates& x,
                              const LinearElasticMaterial& material, const IntegrationRule& rule,
                              int elementIndex, ElementMatrix& ke) {
  // B^T C B for an isotropic C, one 3x3 block per node pair (a, b):
  //   K_ab = sum_g alpha_g det J [lambda g_a g_b^T + mu g_b g_a^T + mu (g_a . g_b) I],
  // g = world gradient of h. Only a <= b is computed; the rest is mirrored,
  // so ke is exactly symmetric. Absent nodes have g = 0 and give zero blocks.
  const double e = material.youngsModulus, nu = material.poissonRatio;
  const double lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  const double mu = e / (2.0 * (1.0 + nu));
  ke.setZero();
  // A native wedge uses slots 0..14 only; skip the empty rest.
  const int slots = shape.kind() == ElementKind::Wedge15 ? kWedge15NodeCount : kHex20NodeCount;
  PointGeometry g;
  for (std::size_t q = 0; q < rule.size(); ++q) {
    evaluateGeometry(shape, x, rule.points[q], elementIndex, g);
    const double w = rule.weights[q] * g.detJ;
    const Eigen::Matrix<double, kHex20NodeCount, 3> lg = (w * lambda) * g.dhWorld;
    const Eigen::Matrix<double, kHex20NodeCount, 3> mg = (w * mu) * g.dhWorld;
    for (int b = 0; b < slots; ++b) {
      const double gb0 = g.dhWorld(b, 0), gb1 = g.dhWorld(b, 1), gb2 = g.dhWorld(b, 2);
      for (int a = 0; a <= b; ++a) {
        const double dot = mg(a, 0) * gb0 + mg(a, 1) * gb1 + mg(a, 2) * gb2;
        double* col0 = &ke(3 * a, 3 * b);
        double* col1 = &ke(3 * a, 3 * b + 1);
        double* col2 = &ke(3 * a, 3 * b + 2);
        const double gbv[3] = {gb0, gb1, gb2};
        double* cols[3] = {col0, col1, col2};
        for (int j = 0; j < 3; ++j) {
          for (int i = 0; i < 3; ++i) cols[j][i] += lg(a, i) * gbv[j] + mg(a, j) * g.dhWorld(b, i);
          cols[j][j] += dot;
        }
      }
    }
  }
  for (int b = 0; b < slots; ++b)
    for (int a = 0; a < b; ++a) ke.block<3, 3>(3 * b, 3 * a) = ke.block<3, 3>(3 * a, 3 * b).transpose();
}

void assembleElementBodyForce(const ElementShape& shape, const ElementCoordinates& x,
                              const Eigen::Vector3d& forcePerVolume, const IntegrationRule& rule,
                              int elementIndex, ElementVector& re) {
  re.setZero();
  PointGeometry g;
  for (std::size_t q = 0; q < rule.size(); ++q) {
    evaluateGeometry(shape, x, rule.points[q], elementIndex, g);
    const double w = rule.weights[q] * g.detJ;
    for (int k = 0; k < kHex20NodeCount; ++k) re.segment<3>(3 * k) += (w * g.h[k]) * forcePerVolume;
  }
}

double elementVolume(const ElementShape& shape, const ElementCoordinates& x, const IntegrationRule& rule,
                     int elementIndex) {
  double v = 0.0;
  PointGeometry g;
  for (std::size_t q = 0; q < rule.size(); ++q) {
    evaluateGeometry(shape, x, rule.points[q], elementIndex, g);
    v += rule.weights[q] * g.detJ;
  }
  return v;
}

}  // namespace caps::fem
