#pragma once

// Symmetric 3x3 tensors as 6-vectors and their fourth-order products as
// 6x6 matrices, in the slot order every fem/ kernel uses: xx, yy, zz, xy,
// yz, zx. These are tensor components; where a strain carries engineering
// shears (2 E_ij) the caller doubles the last three slots.

#include "fem/LinearElasticMaterial.h"

#include <Eigen/Core>

namespace caps::fem {

/// The tensor indices (i, j) of each Voigt slot.
inline constexpr int kVoigtPair[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {1, 2}, {2, 0}};

/// The six components of the symmetric tensor @a t.
inline Vector6d voigtOf(const Eigen::Matrix3d& t)
{
  Vector6d v;
  for (int a = 0; a < 6; ++a)
    v[a] = t(kVoigtPair[a][0], kVoigtPair[a][1]);
  return v;
}

/// The symmetric tensor of six components @a s.
inline Eigen::Matrix3d tensorOf(const Vector6d& s)
{
  Eigen::Matrix3d t;
  t << s[0], s[3], s[5], //
    s[3], s[1], s[4],    //
    s[5], s[4], s[2];
  return t;
}

/// A_ik A_jl + A_il A_jk of a symmetric @a a, rows (ij) and columns (kl):
/// the product behind d(C^-1)/dC and the volumetric tangent.
inline Matrix6d symmetrizedProduct(const Eigen::Matrix3d& a)
{
  Matrix6d m;
  for (int p = 0; p < 6; ++p)
    for (int q = 0; q < 6; ++q)
    {
      const int i = kVoigtPair[p][0], j = kVoigtPair[p][1], k = kVoigtPair[q][0], l = kVoigtPair[q][1];
      m(p, q) = a(i, k) * a(j, l) + a(i, l) * a(j, k);
    }
  return m;
}

} // namespace caps::fem
