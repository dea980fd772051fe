#pragma once
/// @file HoleFloor.h
/// @brief What lies under the hole of an incision: the twins of the hole loop
/// that still touch (a cut with no excision there) and a triangulation of the
/// area the loop encloses (an excision). The continuum mesher uses it for
/// cuts of partial depth, where the tissue under the cut stays whole, and
/// for the elements of the excised tissue (thesis §3.1.3, §3.2.2).

#include "fem/SurfaceMesh.h"

#include <array>
#include <vector>

namespace caps::fem {

/// The floor of a hole loop: vertices are the surface mesh's hole vertices
/// (0 .. holeVertexCount - 1).
struct HoleFloor
{
  /// For each hole vertex, the first hole vertex at the same chart point
  /// (within the tolerance): itself unless it is the twin of an earlier one
  /// that was not offset away.
  std::vector<int> representative;
  /// Triangles covering the area the loop encloses, counter-clockwise in the
  /// chart (seen from outside the head), over representative vertices only,
  /// using no vertex that is not on the loop; their border edges are the
  /// loop's edges with area on one side. Empty for a cut with no excision.
  std::vector<std::array<int, 3>> triangles;
};

/**
 * @brief The floor of the hole of @a surface: twins merged where they touch,
 *        then every part of the loop that encloses area triangulated.
 *
 * The loop, with touching twins merged, is split into simple cycles where a
 * vertex repeats (a slit between two excised parts, or the cut's ends);
 * cycles of fewer than three vertices or no area are slits and have no floor.
 * Each cycle is triangulated by ear clipping (points on the border of a
 * candidate ear block it, so collinear border points are kept) and then
 * made Delaunay by edge flips (Lawson), which removes the slivers ear
 * clipping leaves along straight sides.
 *
 * @param tolerance chart distance (mm) under which two hole vertices are one
 *        point.
 * Throws std::invalid_argument if a cycle cannot be triangulated (it crosses
 * itself).
 */
HoleFloor holeFloor(const SurfaceMesh& surface, double tolerance = 1e-9);

} // namespace caps::fem
