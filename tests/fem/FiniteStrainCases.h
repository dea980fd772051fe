#pragma once

// Models shared by the finite-strain tests: one element of each kind, the
// outer nodes of a mesh, the constraints of a uniaxial stretch.

#include "fem/Constraints.h"
#include "fem/Mesh.h"

#include "FemTestMeshes.h"

#include <algorithm>
#include <map>
#include <string>
#include <vector>

namespace caps::fem::test {

/// One element of each kind, distorted, with its own node numbering 0..n-1.
struct ElementCase
{
  std::string name;
  Mesh mesh;
};

/// Hex20, Hex20 with 17 nodes, a degenerate 20-node wedge, a native Wedge15.
inline std::vector<ElementCase> elementCases()
{
  std::vector<ElementCase> cases;
  Mesh brick = boxMesh(1, 1, 1, 4, 3, 2);
  for (Eigen::Index i = 0; i < brick.nodeCount(); ++i)
    brick.nodes.col(i) = wobble(brick.nodes.col(i), 0.2);
  cases.push_back({"Hex20", brick});
  Mesh partial = brick;
  for (int k : {9, 14, 17})
    partial.elements[0].nodes[std::size_t(k)] = -1; // a mid-side subset
  cases.push_back({"Hex20 with 17 nodes", partial});
  Mesh wedges = boxMesh(1, 1, 1, 4, 3, 2, Eigen::Vector3d::Zero(), true);
  for (Eigen::Index i = 0; i < wedges.nodeCount(); ++i)
    wedges.nodes.col(i) = wobble(wedges.nodes.col(i), 0.2);
  Mesh degenerate = wedges;
  degenerate.elements.resize(1);
  cases.push_back({"degenerate wedge", degenerate});
  Mesh native = withNativeWedges(wedges);
  native.elements.resize(1);
  cases.push_back({"Wedge15", native});
  return cases;
}

/// Per node, whether it lies on the outside of a brick mesh: on an element
/// face (Table 4.8's node sets) that no other element shares.
inline std::vector<char> outerNodes(const Mesh& mesh)
{
  std::map<std::vector<int>, int> faceCount;
  static const int kFaces[6][8] = {{0, 1, 2, 3, 8, 9, 10, 11},   {4, 5, 6, 7, 12, 13, 14, 15},
                                   {0, 1, 5, 4, 8, 17, 12, 16},  {1, 2, 6, 5, 9, 18, 13, 17},
                                   {2, 3, 7, 6, 10, 19, 14, 18}, {3, 0, 4, 7, 11, 16, 15, 19}};
  for (const Element& el : mesh.elements)
    for (const auto& face : kFaces)
    {
      std::vector<int> key;
      for (int s : face)
        key.push_back(el.nodes[std::size_t(s)]);
      std::sort(key.begin(), key.end());
      ++faceCount[key];
    }
  std::vector<char> outer(std::size_t(mesh.nodeCount()), 0);
  for (const auto& [key, count] : faceCount)
    if (count == 1)
      for (int n : key)
        outer[std::size_t(n)] = 1;
  return outer;
}

/// A box [0, length] x [0, side] x [0, side] pulled along x to @a stretch
/// times its length: x = 0 held in x (one corner fully, one more in z
/// against rotation), x = length moved; the lateral faces free.
inline Constraints uniaxialStretch(const Mesh& mesh, double length, double side, double stretch)
{
  Constraints c;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    const Eigen::Vector3d x = mesh.nodes.col(i);
    if (x[0] < 1e-9)
      c.fix(int(i), 0);
    if (x[0] > length - 1e-9)
      c.prescribe(int(i), 0, (stretch - 1) * length);
    if (x[0] < 1e-9 && x[1] < 1e-9 && x[2] < 1e-9)
    {
      c.fix(int(i), 1);
      c.fix(int(i), 2);
    }
    if (x[0] < 1e-9 && x[1] > side - 1e-9 && x[2] < 1e-9)
      c.fix(int(i), 2);
  }
  return c;
}

} // namespace caps::fem::test
