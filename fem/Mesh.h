#pragma once

#include "fem/ElementGeometry.h"
#include "fem/ElementNumbering.h"
#include "fem/LinearElasticMaterial.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace caps::fem {

/// One element: global node indices per slot. Hex20 (default): Bathe order
/// (0..19), -1 marks an absent mid-side node, repeated indices make the
/// degenerate wedge of Fig. 3.2. Wedge15: the native wedge's 15 nodes in
/// wedge order (ElementNumbering.h) in slots 0..14, slots 15..19 = -1.
struct Element
{
  std::array<int, kHex20NodeCount> nodes{};
  int region = 0;                        ///< selects the material in a MaterialTable
  ElementKind kind = ElementKind::Hex20; ///< how the slots are read
  /// Points per direction of this element's own rule: 0 takes the
  /// analysis's (AssemblyOptions::gaussPointsPerDirection); 2 is the reduced
  /// rule (C3D20R's 2x2x2; a wedge's 9 points, CalculiX's C3D15 rule), 3 the
  /// full one. A deck's element type says which (CalculixReader).
  std::uint8_t integrationPoints = 0;
};

/// Points per direction element @a el is integrated with, when the
/// analysis's default is @a analysisDefault.
inline int integrationPointsOf(const Element& el, int analysisDefault)
{
  return el.integrationPoints ? int(el.integrationPoints) : analysisDefault;
}

/**
 * @brief Finite element mesh: node coordinates (mm, one column per node) and
 *        elements. Node i carries DOFs 3i, 3i+1, 3i+2 (x, y, z).
 */
struct Mesh
{
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
 *        out of range, a missing corner, a native wedge without all 15
 *        nodes (or with slots 15..19 used), a region with no material in
 *        @a materials, or a bad material.
 */
void validateMesh(const Mesh& mesh, const MaterialTable& materials);

/**
 * @brief Recognises a 20-node element degenerated into a wedge (Fig. 3.2:
 *        two parallel edges of one face pair collapsed, along any natural
 *        axis, leaving six distinct corners).
 *
 * On success fills @a slots with the Bathe slot (0..19) that holds each
 * node of the equivalent 15-node wedge, in wedge order (ElementNumbering.h,
 * which is also VTK's quadratic wedge order), oriented so the wedge has a
 * positive Jacobian: the right-hand normal of triangle (0, 1, 2) points away
 * from (3, 4, 5) at the world positions @a nodes. Mid-edge slots are
 * returned even if absent (node -1). Returns false for any other element
 * (a brick, another degeneration, or a native wedge).
 */
bool degenerateWedgeSlots(const Element& el, const Eigen::Matrix3Xd& nodes, std::array<int, kWedge15NodeCount>& slots);

/**
 * @brief The same mesh with every degenerate 20-node wedge (Fig. 3.2) that
 *        has all nine mid-edge nodes replaced by the native 15-node wedge on
 *        the same nodes and region. Other elements are kept as they are (a
 *        wedge without its mid-edge nodes has no native form here).
 *
 * Throws std::invalid_argument naming the element if a collapsed edge
 * carries a mid-side node of its own (a node the native wedge cannot hold).
 */
Mesh withNativeWedges(const Mesh& mesh);

} // namespace caps::fem
