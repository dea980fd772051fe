#pragma once

#include <Eigen/Core>

#include <map>

namespace caps::fem {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/**
 * @brief Linear isotropic elastic material: Young's modulus E (MPa),
 *        Poisson's ratio nu, density (tonnes/mm^3).
 *
 * Voigt order of strain and stress everywhere in fem/: xx, yy, zz, xy, yz, zx,
 * with engineering shear strains (gamma = 2 epsilon).
 */
struct LinearElasticMaterial
{
  double youngsModulus = 0.0;
  double poissonRatio = 0.0;
  double density = 0.0;

  /// Throws std::invalid_argument unless E > 0, -1 < nu < 0.5, density >= 0
  /// (all finite). @a context names the culprit in the message (e.g. "region 2").
  void validate(const char* context = "material") const;
  /// Elasticity matrix C with sigma = C epsilon.
  Matrix6d elasticityMatrix() const;
};

/// Material of each region id (the region of an element selects its material).
using MaterialTable = std::map<int, LinearElasticMaterial>;

} // namespace caps::fem
