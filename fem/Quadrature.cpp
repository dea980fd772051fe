#include "fem/Quadrature.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace caps::fem {

namespace {

IntegrationRule makeRule(int n) {
  std::vector<double> x, w;
  switch (n) {
    case 1: x = {0.0}; w = {2.0}; break;
    case 2: x = {-1.0 / std::sqrt(3.0), 1.0 / std::sqrt(3.0)}; w = {1.0, 1.0}; break;
    case 3: x = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)}; w = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0}; break;
    case 4: {
      const double a = std::sqrt(3.0 / 7.0 - 2.0 / 7.0 * std::sqrt(1.2));
      const double b = std::sqrt(3.0 / 7.0 + 2.0 / 7.0 * std::sqrt(1.2));
      const double wa = (18.0 + std::sqrt(30.0)) / 36.0, wb = (18.0 - std::sqrt(30.0)) / 36.0;
      x = {-b, -a, a, b};
      w = {wb, wa, wa, wb};
      break;
    }
    default: break;
  }
  IntegrationRule rule;
  rule.pointsPerDirection = n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        rule.points.emplace_back(x[i], x[j], x[k]);
        rule.weights.push_back(w[i] * w[j] * w[k]);
      }
  return rule;
}

}  // namespace

const IntegrationRule& gaussRule(int pointsPerDirection) {
  static const IntegrationRule rules[4] = {makeRule(1), makeRule(2), makeRule(3), makeRule(4)};
  if (pointsPerDirection < 1 || pointsPerDirection > 4)
    throw std::invalid_argument("Gauss rule with " + std::to_string(pointsPerDirection) +
                                " points per direction is not available (1..4)");
  return rules[pointsPerDirection - 1];
}

}  // namespace caps::fem
