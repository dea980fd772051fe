#include "fem/Quadrature.h"

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace caps::fem {

namespace {

LineRule makeLineRule(int n)
{
  std::vector<double> x, w;
  switch (n)
  {
  case 1:
    x = {0.0};
    w = {2.0};
    break;
  case 2:
    x = {-1.0 / std::sqrt(3.0), 1.0 / std::sqrt(3.0)};
    w = {1.0, 1.0};
    break;
  case 3:
    x = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)};
    w = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
    break;
  case 4:
  {
    const double a = std::sqrt(3.0 / 7.0 - 2.0 / 7.0 * std::sqrt(1.2));
    const double b = std::sqrt(3.0 / 7.0 + 2.0 / 7.0 * std::sqrt(1.2));
    const double wa = (18.0 + std::sqrt(30.0)) / 36.0, wb = (18.0 - std::sqrt(30.0)) / 36.0;
    x = {-b, -a, a, b};
    w = {wb, wa, wa, wb};
    break;
  }
  default:
    break;
  }
  return {x, w};
}

IntegrationRule makeRule(int n)
{
  const LineRule line = makeLineRule(n);
  const std::vector<double>& x = line.points;
  const std::vector<double>& w = line.weights;
  IntegrationRule rule;
  rule.pointsPerDirection = n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
      {
        rule.points.emplace_back(x[i], x[j], x[k]);
        rule.weights.push_back(w[i] * w[j] * w[k]);
      }
  return rule;
}

void checkPointCount(int n)
{
  if (n < 1 || n > 4)
    throw std::invalid_argument("Gauss rule with " + std::to_string(n) +
                                " points per direction is not available (1..4)");
}

// Triangle rule (r, s, weight) times the 3-point Gauss rule along t.
IntegrationRule makeWedgeRule(int level)
{
  std::vector<std::array<double, 3>> triangle;
  if (level == 2)
  {
    for (const auto& [r, s] : {std::pair{1.0 / 6.0, 1.0 / 6.0}, {2.0 / 3.0, 1.0 / 6.0}, {1.0 / 6.0, 2.0 / 3.0}})
      triangle.push_back({r, s, 1.0 / 6.0});
  }
  else
  {
    // Dunavant's degree-4 rule: two orbits (a, a, 1 - 2a), weights over area 1/2.
    const double q = std::sqrt(10.0), root = std::sqrt(38.0 - 44.0 * std::sqrt(0.4));
    const double wroot = std::sqrt(213125.0 - 53320.0 * q);
    for (int sign : {1, -1})
    {
      const double a = (8.0 - q + sign * root) / 18.0;
      const double w = 0.5 * (620.0 + sign * wroot) / 3720.0;
      for (const auto& [r, s] : {std::pair{a, a}, {1.0 - 2.0 * a, a}, {a, 1.0 - 2.0 * a}})
        triangle.push_back({r, s, w});
    }
  }
  const LineRule line = makeLineRule(3);
  IntegrationRule rule;
  rule.pointsPerDirection = 3;
  for (std::size_t k = 0; k < line.points.size(); ++k)
    for (const auto& p : triangle)
    {
      rule.points.emplace_back(p[0], p[1], line.points[k]);
      rule.weights.push_back(p[2] * line.weights[k]);
    }
  return rule;
}

} // namespace

const LineRule& gaussLineRule(int points)
{
  static const LineRule rules[4] = {makeLineRule(1), makeLineRule(2), makeLineRule(3), makeLineRule(4)};
  checkPointCount(points);
  return rules[points - 1];
}

const IntegrationRule& gaussRule(int pointsPerDirection)
{
  static const IntegrationRule rules[4] = {makeRule(1), makeRule(2), makeRule(3), makeRule(4)};
  checkPointCount(pointsPerDirection);
  return rules[pointsPerDirection - 1];
}

const IntegrationRule& wedgeRule(int level)
{
  static const IntegrationRule rules[2] = {makeWedgeRule(2), makeWedgeRule(3)};
  if (level != 2 && level != 3)
    throw std::invalid_argument("the 15-node wedge has integration levels 2 (9 points) and 3 (18 points), not " +
                                std::to_string(level));
  return rules[level - 2];
}

const IntegrationRule& integrationRule(ElementKind kind, int pointsPerDirection)
{
  return kind == ElementKind::Wedge15 ? wedgeRule(pointsPerDirection) : gaussRule(pointsPerDirection);
}

} // namespace caps::fem
