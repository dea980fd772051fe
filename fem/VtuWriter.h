#pragma once

#include "fem/ElementNumbering.h"
#include "fem/Mesh.h"

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace caps::fem {

/// VTK cell type ids used by the exporter (vtkCellType.h).
inline constexpr int kVtkHexahedron = 12;
inline constexpr int kVtkWedge = 13;
inline constexpr int kVtkQuadraticHexahedron = 25;
inline constexpr int kVtkQuadraticWedge = 26;

/// One element as a VTK cell: its type and the mesh node of each VTK point.
struct VtkCell
{
  int type = kVtkQuadraticHexahedron;
  std::vector<int> nodes;
};

/**
 * @brief Bathe node (0..19) of each point of a VTK_QUADRATIC_HEXAHEDRON
 *        (VTK point order: corners of the bottom t = -1 face counter-clockwise
 *        from (-1,-1,-1), the top corners, bottom mid-edges, top mid-edges,
 *        vertical mid-edges).
 */
const std::array<int, kHex20NodeCount>& vtkQuadraticHexToBathe();

/**
 * @brief The VTK cell of element @a el.
 *
 * All 12 mid-side nodes: VTK_QUADRATIC_HEXAHEDRON; none: VTK_HEXAHEDRON;
 * some: VTK_HEXAHEDRON too (the missing nodes have no VTK equivalent, the
 * present mid-side nodes are dropped from the picture, not from the data).
 * A wedge (two parallel edges of one face collapsed, as written by Fig. 3.2)
 * becomes VTK_QUADRATIC_WEDGE (or VTK_WEDGE without mid-side nodes), with
 * the base triangle (0, 1, 2) ordered so its right-hand normal points away
 * from (3, 4, 5) as vtkWedge documents (checked against VTK 9.1's
 * vtkCellSizeFilter, which then gives a positive volume). @a nodes gives the
 * world position of each mesh node (for that orientation). Any other
 * degenerate element stays a (degenerate) hexahedron. A native 15-node
 * wedge (ElementKind::Wedge15) is a VTK_QUADRATIC_WEDGE with its nodes in
 * their own order, which is VTK's.
 */
VtkCell vtkCell(const Element& el, const Eigen::Matrix3Xd& nodes);

/// A named data array: one column per point (or cell), one row per component.
struct VtuArray
{
  std::string name;
  Eigen::MatrixXd values;
};

/**
 * @brief The mesh as a VTK XML UnstructuredGrid document (ASCII,
 *        ParaView-readable), with @a pointData (columns = nodes) and
 *        @a cellData (columns = elements). A cell array "region" (element
 *        region ids) is always written. Throws std::invalid_argument if an
 *        array has the wrong number of columns.
 */
std::string vtuDocument(const Mesh& mesh, const std::vector<VtuArray>& pointData,
                        const std::vector<VtuArray>& cellData = {});

/// Writes vtuDocument() to @a path; throws std::runtime_error if it cannot.
void writeVtu(const std::string& path, const Mesh& mesh, const std::vector<VtuArray>& pointData,
              const std::vector<VtuArray>& cellData = {});

} // namespace caps::fem
