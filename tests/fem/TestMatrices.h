#pragma once

// Small SPD (and deliberately singular) test matrices with known structure.

#include <Eigen/SparseCore>

#include <cmath>
#include <vector>

namespace caps::fem::test {

using SparseMatrix = Eigen::SparseMatrix<double>;

/// Chain of springs k[0..m-1] in series along one axis. With @a fixedFirst the
/// node left of spring 0 is fixed (its DOF removed), leaving m unknowns;
/// without it all m + 1 nodes are free and the chain can translate.
inline SparseMatrix springChain(const std::vector<double>& k, bool fixedFirst)
{
  const int nodes = static_cast<int>(k.size()) + 1;
  const int offset = fixedFirst ? 1 : 0; // node i -> DOF i - offset
  const int n = nodes - offset;
  std::vector<Eigen::Triplet<double>> t;
  for (int e = 0; e < static_cast<int>(k.size()); ++e)
  {
    const int dofs[2] = {e - offset, e + 1 - offset};
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b)
        if (dofs[a] >= 0 && dofs[b] >= 0)
          t.emplace_back(dofs[a], dofs[b], a == b ? k[e] : -k[e]);
  }
  SparseMatrix m(n, n);
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

/// Elasticity-like stiffness on an n x n x n node grid, 3 DOFs per node
/// (interleaved): every pair of nodes in a 3x3x3 neighbourhood is joined by a
/// bar k (d d^T + 0.1 I), d the unit direction. With @a fixBottom the z = 0
/// layer is clamped (its DOFs removed), which makes the matrix SPD; without it
/// the body is free and the matrix is singular.
inline SparseMatrix latticeStiffness(int n, bool fixBottom = true, double stiffnessSpread = 0.0)
{
  const auto node = [n](int x, int y, int z) { return (z * n + y) * n + x; };
  const int firstFree = fixBottom ? n * n : 0; // nodes are numbered z-major
  const int dofs = 3 * (n * n * n - firstFree);
  std::vector<Eigen::Triplet<double>> t;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        for (int dz = 0; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx)
            {
              // Each unordered pair once: forward half of the neighbourhood.
              if (dz == 0 && (dy < 0 || (dy == 0 && dx <= 0)))
                continue;
              const int x2 = x + dx, y2 = y + dy, z2 = z + dz;
              if (x2 < 0 || y2 < 0 || x2 >= n || y2 >= n || z2 >= n)
                continue;
              const int a = node(x, y, z), b = node(x2, y2, z2);
              Eigen::Vector3d d(dx, dy, dz);
              d.normalize();
              // Deterministic variation so values are not all integers.
              const double k = 1.0 + stiffnessSpread * std::sin(0.37 * a + 0.11 * b);
              const Eigen::Matrix3d block = k * (d * d.transpose() + 0.1 * Eigen::Matrix3d::Identity());
              const int nodesAB[2] = {a, b};
              for (int i = 0; i < 2; ++i)
                for (int j = 0; j < 2; ++j)
                {
                  if (nodesAB[i] < firstFree || nodesAB[j] < firstFree)
                    continue;
                  const int ri = 3 * (nodesAB[i] - firstFree), cj = 3 * (nodesAB[j] - firstFree);
                  for (int p = 0; p < 3; ++p)
                    for (int q = 0; q < 3; ++q)
                      t.emplace_back(ri + p, cj + q, (i == j ? 1.0 : -1.0) * block(p, q));
                }
            }
  SparseMatrix m(dofs, dofs);
  m.setFromTriplets(t.begin(), t.end());
  m.prune(0.0); // keep the pattern symmetric but without explicit zeros
  return m;
}

} // namespace caps::fem::test
