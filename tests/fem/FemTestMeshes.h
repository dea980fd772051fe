#pragma once

// Structured meshes of 20-node bricks and degenerate 20-node wedges for the
// fem tests. Nodes live on a doubled integer grid (corners at even indices,
// mid-side nodes with one odd index, wedge diagonals at odd-odd points) so
// neighbouring elements share nodes exactly.

#include "fem/ElementNumbering.h"
#include "fem/Mesh.h"

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <functional>
#include <map>

namespace caps::fem::test {

/// A smooth distortion of a point (mm), to make straight meshes curved and
/// uneven without inverting them; @a amplitude in mm.
inline Eigen::Vector3d wobble(const Eigen::Vector3d& x, double amplitude = 0.4)
{
  return x + amplitude * Eigen::Vector3d(std::sin(0.3 * x[1] + 0.2 * x[2]), std::sin(0.25 * x[0]),
                                         std::sin(0.2 * x[0] + 0.3 * x[1]));
}

/// In-plane doubled-grid positions of the natural corners (r, s) = (1,1),
/// (-1,1), (-1,-1), (1,-1); a wedge repeats the first position twice.
struct Cell
{
  std::array<Eigen::Vector2i, 4> corners;
  int layer = 0; ///< z layer
  int region = 0;
};

class MeshBuilder
{
public:
  /// @a spacing: physical size of one doubled-grid step in x, y, z.
  explicit MeshBuilder(Eigen::Vector3d spacing, Eigen::Vector3d origin = Eigen::Vector3d::Zero())
    : spacing_(spacing), origin_(origin)
  {}

  void addCell(const Cell& c)
  {
    Element el;
    el.region = c.region;
    for (int k = 0; k < kHex20NodeCount; ++k)
    {
      const Eigen::Vector3d n = batheNaturalCoordinates(k);
      // Bilinear map of the natural (r, s) onto the cell's corners; exact
      // integers at corners and mid-sides.
      const double r = n[0], s = n[1];
      Eigen::Vector2d q =
        0.25 * ((1 + r) * (1 + s) * c.corners[0].cast<double>() + (1 - r) * (1 + s) * c.corners[1].cast<double>() +
                (1 - r) * (1 - s) * c.corners[2].cast<double>() + (1 + r) * (1 - s) * c.corners[3].cast<double>());
      const std::array<int, 3> key{int(std::lround(q[0])), int(std::lround(q[1])), 2 * c.layer + 1 + int(n[2])};
      el.nodes[k] = nodeAt(key);
    }
    mesh_.elements.push_back(el);
  }

  /// Hex (i, j, k) of a structured grid.
  void addHex(int i, int j, int k, int region = 0)
  {
    Cell c;
    c.corners = {Eigen::Vector2i(2 * i + 2, 2 * j + 2), Eigen::Vector2i(2 * i, 2 * j + 2),
                 Eigen::Vector2i(2 * i, 2 * j), Eigen::Vector2i(2 * i + 2, 2 * j)};
    c.layer = k;
    c.region = region;
    addCell(c);
  }

  /// The two wedges (degenerate 20-node bricks) splitting hex cell (i, j, k)
  /// along its diagonal.
  void addWedgePair(int i, int j, int k, int region = 0)
  {
    const Eigen::Vector2i c00(2 * i, 2 * j), c10(2 * i + 2, 2 * j), c11(2 * i + 2, 2 * j + 2), c01(2 * i, 2 * j + 2);
    addCell({{c11, c11, c00, c10}, k, region});
    addCell({{c00, c00, c11, c01}, k, region});
  }

  /// Moves every node by @a f (applied to its undistorted position).
  void distort(const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& f) { distortion_ = f; }

  Mesh build() const
  {
    Mesh m = mesh_;
    m.nodes.resize(3, Eigen::Index(grid_.size()));
    for (const auto& [key, id] : grid_)
    {
      Eigen::Vector3d x = origin_ + Eigen::Vector3d(key[0] * spacing_[0], key[1] * spacing_[1], key[2] * spacing_[2]);
      if (distortion_)
        x = distortion_(x);
      m.nodes.col(id) = x;
    }
    return m;
  }

  /// Index of the node at doubled-grid point @a key, or -1.
  int find(const std::array<int, 3>& key) const
  {
    auto it = grid_.find(key);
    return it == grid_.end() ? -1 : it->second;
  }

private:
  int nodeAt(const std::array<int, 3>& key)
  {
    auto [it, inserted] = grid_.emplace(key, int(grid_.size()));
    return it->second;
  }

  Eigen::Vector3d spacing_, origin_;
  std::map<std::array<int, 3>, int> grid_;
  Mesh mesh_;
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> distortion_;
};

/// nx x ny x nz box of 20-node bricks, size lx x ly x lz, corner at @a origin.
inline Mesh boxMesh(int nx, int ny, int nz, double lx, double ly, double lz,
                    Eigen::Vector3d origin = Eigen::Vector3d::Zero(), bool wedges = false)
{
  MeshBuilder b(Eigen::Vector3d(lx / (2 * nx), ly / (2 * ny), lz / (2 * nz)), origin);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
      {
        if (wedges)
          b.addWedgePair(i, j, k);
        else
          b.addHex(i, j, k);
      }
  return b.build();
}

/// Appends @a b to @a a (nodes and elements renumbered); returns b's node offset.
inline int appendMesh(Mesh& a, const Mesh& b)
{
  const int offset = int(a.nodeCount());
  Eigen::Matrix3Xd nodes(3, a.nodeCount() + b.nodeCount());
  nodes << a.nodes, b.nodes;
  a.nodes = nodes;
  for (Element e : b.elements)
  {
    for (int& n : e.nodes)
      if (n >= 0)
        n += offset;
    a.elements.push_back(e);
  }
  return offset;
}

} // namespace caps::fem::test
