#pragma once

#include "fem/ElementGeometry.h"
#include "fem/ElementNumbering.h"
#include "fem/LinearElasticMaterial.h"

#include <Eigen/Core>

#include <array>
#include <vector>

namespace caps::fem {

/// One 8-to-20 node element: global node indices in Bathe order (0..19);
/// -1 marks an absent mid-side node. Repeated indices make a wedge.
struct Element {
  std::array<int, kHex20NodeCount> nodes{};
  int region = 0;  ///< selects the material in a MaterialTable
};

/**
 * @brief Finite element mesh: node coordinates (mm, one column per node) and
 *        elements. Node i carries DOFs 3i, 3i+1, 3i+2 (x, y, z).
 */
struct Mesh {
  Eigen::Matrix3Xd nodes;
  std::vector<Element> elements;

  Eigen::Index nodeCount() const { return nodes.cols(); }
  Eigen::Index dofCount() const { return 3 * nodes.cols(); }
  /// Coordinates of element @a e's nodes in Bathe order (absent rows zero).
  ElementCoordinates elementCoordinates(std::size_t e) const;
};

/**
 * @brief Checks a mesh before analysis. Throws std::invalid_argument naming
 *        the culprit: a NaN/infinite node coordinate, an element node index
 *        out of range, a missing corner, a region with no material in
 *        @a materials, or a bad material.
 */
void validateMesh(const Mesh& mesh, const MaterialTable& materials);

}  // namespace caps::fem
