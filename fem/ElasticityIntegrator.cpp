#include "fem/ElasticityIntegrator.h"

#include <cmath>

namespace caps::fem {

void strainDisplacementMatrix(const PointGeometry& g, StrainDisplacement& b)
{
  b.setZero();
  for (int k = 0; k < kHex20NodeCount; ++k)
  {
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
                              const LinearElasticMaterial& material, const IntegrationRule& rule, int elementIndex,
                              ElementMatrix& ke)
{
  // B^T C B for an isotropic C, one 3x3 block per node pair (a, b):
  //   K_ab(i, j) = sum_g alpha_g det J [lambda g_a,i g_b,j + mu g_a,j g_b,i + mu (g_a . g_b) delta_ij],
  // g = world gradient of h. All three terms are entries of one Gram matrix
  //   S(20 i + a, 20 j + b) = sum_g alpha_g det J g_a,i g_b,j,
  // which a single symmetric rank-k update (BLAS-3 style, vectorised) gives
  // for all pairs at once; the pair loop then only gathers. Absent nodes have
  // g = 0 and give zero blocks.
  const double e = material.youngsModulus, nu = material.poissonRatio;
  const double lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  const double mu = e / (2.0 * (1.0 + nu));
  // A native wedge uses slots 0..14 only; skip the empty rest.
  const int slots = shape.kind() == ElementKind::Wedge15 ? kWedge15NodeCount : kHex20NodeCount;
  constexpr int kMaxPoints = 64; // 4 x 4 x 4, the largest rule
  Eigen::Matrix<double, 3 * kHex20NodeCount, Eigen::Dynamic, Eigen::ColMajor, 3 * kHex20NodeCount, kMaxPoints>
    gradients(3 * kHex20NodeCount, Eigen::Index(rule.size()));
  PointGeometry g;
  for (std::size_t q = 0; q < rule.size(); ++q)
  {
    evaluateGeometry(shape, x, rule.points[q], elementIndex, g);
    const double root = std::sqrt(rule.weights[q] * g.detJ); // weights and det J are positive
    for (int i = 0; i < 3; ++i)
      gradients.col(Eigen::Index(q)).segment<kHex20NodeCount>(kHex20NodeCount * i) = root * g.dhWorld.col(i);
  }
  Eigen::Matrix<double, 3 * kHex20NodeCount, 3 * kHex20NodeCount> gram;
  gram.setZero();
  gram.selfadjointView<Eigen::Upper>().rankUpdate(gradients);
  const auto s = [&gram](int p, int q) { return p <= q ? gram(p, q) : gram(q, p); };

  ke.setZero();
  for (int b = 0; b < slots; ++b)
    for (int a = 0; a <= b; ++a)
    {
      const double trace =
        s(a, b) + s(kHex20NodeCount + a, kHex20NodeCount + b) + s(2 * kHex20NodeCount + a, 2 * kHex20NodeCount + b);
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i)
        {
          double v = lambda * s(kHex20NodeCount * i + a, kHex20NodeCount * j + b) +
                     mu * s(kHex20NodeCount * j + a, kHex20NodeCount * i + b);
          if (i == j)
            v += mu * trace;
          ke(3 * a + i, 3 * b + j) = v;
        }
    }
  for (int b = 0; b < slots; ++b)
    for (int a = 0; a < b; ++a)
      ke.block<3, 3>(3 * b, 3 * a) = ke.block<3, 3>(3 * a, 3 * b).transpose();
}

void assembleElementBodyForce(const ElementShape& shape, const ElementCoordinates& x,
                              const Eigen::Vector3d& forcePerVolume, const IntegrationRule& rule, int elementIndex,
                              ElementVector& re)
{
  re.setZero();
  PointGeometry g;
  for (std::size_t q = 0; q < rule.size(); ++q)
  {
    evaluateGeometry(shape, x, rule.points[q], elementIndex, g);
    const double w = rule.weights[q] * g.detJ;
    for (int k = 0; k < kHex20NodeCount; ++k)
      re.segment<3>(3 * k) += (w * g.h[k]) * forcePerVolume;
  }
}

double elementVolume(const ElementShape& shape, const ElementCoordinates& x, const IntegrationRule& rule,
                     int elementIndex)
{
  double v = 0.0;
  PointGeometry g;
  for (std::size_t q = 0; q < rule.size(); ++q)
  {
    evaluateGeometry(shape, x, rule.points[q], elementIndex, g);
    v += rule.weights[q] * g.detJ;
  }
  return v;
}

} // namespace caps::fem
