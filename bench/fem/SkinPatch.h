#pragma once
// The benchmarks' model: a patch of skin 80 x 80 x 8 mm in three layers of
// 20-node bricks through the thickness (one region per layer).

#include "fem/ElementNumbering.h"
#include "fem/LinearElasticMaterial.h"
#include "fem/Mesh.h"

#include <array>
#include <map>
#include <vector>

namespace caps::bench {

using caps::fem::batheNaturalCoordinates;
using caps::fem::Element;
using caps::fem::kHex20NodeCount;
using caps::fem::MaterialTable;
using caps::fem::Mesh;

// n x n x layers bricks over 80 x 80 x 8 mm; nodes on the doubled grid.
inline Mesh skinPatch(int n, int layers)
{
  Mesh mesh;
  std::map<std::array<int, 3>, int> ids;
  std::vector<Eigen::Vector3d> xs;
  const double hx = 80.0 / (2 * n), hz = 8.0 / (2 * layers);
  for (int k = 0; k < layers; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
      {
        Element el;
        el.region = k;
        for (int b = 0; b < kHex20NodeCount; ++b)
        {
          const Eigen::Vector3d r = batheNaturalCoordinates(b);
          const std::array<int, 3> key{2 * i + 1 + int(r[0]), 2 * j + 1 + int(r[1]), 2 * k + 1 + int(r[2])};
          auto [it, inserted] = ids.emplace(key, int(xs.size()));
          if (inserted)
            xs.emplace_back(key[0] * hx, key[1] * hx, key[2] * hz);
          el.nodes[std::size_t(b)] = it->second;
        }
        mesh.elements.push_back(el);
      }
  mesh.nodes.resize(3, Eigen::Index(xs.size()));
  for (std::size_t i = 0; i < xs.size(); ++i)
    mesh.nodes.col(Eigen::Index(i)) = xs[i];
  return mesh;
}

/// The largest patch of @a layers layers with at most @a dofs DOFs (3 per node; at least 2 x 2 bricks).
inline Mesh skinPatchOfSize(long dofs, int layers)
{
  int n = 2;
  while (3L * skinPatch(n + 1, layers).nodeCount() <= dofs)
    ++n;
  return skinPatch(n, layers);
}

/// The layers' small-strain materials (E MPa, nu, density t/mm^3): skin, fat, muscle.
inline MaterialTable skinPatchMaterials()
{
  return {{0, {0.015, 0.45, 1.1e-9}}, {1, {0.005, 0.45, 0.95e-9}}, {2, {0.03, 0.45, 1.05e-9}}};
}

} // namespace caps::bench
