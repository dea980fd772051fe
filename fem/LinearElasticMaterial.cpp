#include "fem/LinearElasticMaterial.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace caps::fem {

void LinearElasticMaterial::validate(const char* context) const
{
  std::ostringstream m;
  if (!std::isfinite(youngsModulus) || youngsModulus <= 0.0)
    m << context << ": Young's modulus E = " << youngsModulus << " MPa must be positive";
  else if (!std::isfinite(poissonRatio) || poissonRatio >= 0.5 || poissonRatio <= -1.0)
    m << context << ": Poisson's ratio nu = " << poissonRatio
      << " must lie strictly between -1 and 0.5 (0.5 is incompressible and not supported)";
  else if (!std::isfinite(density) || density < 0.0)
    m << context << ": density " << density << " t/mm^3 must be zero or positive";
  if (!m.str().empty())
    throw std::invalid_argument(m.str());
}

Matrix6d LinearElasticMaterial::elasticityMatrix() const
{
  const double e = youngsModulus, nu = poissonRatio;
  const double lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  const double mu = e / (2.0 * (1.0 + nu));
  Matrix6d c = Matrix6d::Zero();
  c.topLeftCorner<3, 3>().setConstant(lambda);
  for (int i = 0; i < 3; ++i)
    c(i, i) = lambda + 2.0 * mu;
  for (int i = 3; i < 6; ++i)
    c(i, i) = mu;
  return c;
}

} // namespace caps::fem
