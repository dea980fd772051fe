#pragma once

#include <Eigen/Core>

#include <vector>

namespace caps::fem {

/// Gauss-Legendre points and weights over the cube [-1, 1]^3.
struct IntegrationRule {
  std::vector<Eigen::Vector3d> points;  ///< (r, s, t) of each point
  std::vector<double> weights;          ///< alpha_i alpha_j alpha_k (thesis eq. 4.39)
  int pointsPerDirection = 0;
  std::size_t size() const { return points.size(); }
};

/// Product Gauss rule with @a pointsPerDirection = 1..4 points along each
/// axis (thesis Table 4.6 is the 3-point rule). Returns a reference to a
/// shared, immutable rule. Throws std::invalid_argument otherwise.
const IntegrationRule& gaussRule(int pointsPerDirection);

}  // namespace caps::fem
