#pragma once
/// @file SurfaceMesh.h
/// @brief The surface mesh grown from an incision's hole (thesis §4.5.1) and
/// handed to the continuum mesher (§4.5.2): shared by SurfaceMesher and
/// ContinuumMesher, and by the plan code that builds the hole loop.

#include <Eigen/Core>

#include <array>
#include <vector>

namespace caps::fem {

/// A 2D chart of the skin around the incision, in millimetres: u along the
/// skin around the head (r0 · (θ − θc), θ unwrapped about the hole's centre θc,
/// so the θ = ±π seam never splits a mesh), v along the axis (z − zc). The
/// chart is nearly isometric near the hole, so angles and element sizes in it
/// are the surgeon's angles and sizes; the caller maps (u, v) back to (θ, z)
/// and to the skin (§4.2.2).
using ChartPoint = Eigen::Vector2d;

/// The hole the incision makes (Fig. 4.11): a closed loop of border vertices
/// with twins for every inner cut-path point.
struct HoleLoop
{
  /// Border vertices in loop order. The cut path p0..p(n-1) becomes
  /// p0, p1, ..., p(n-1), p(n-2)', ..., p1': the end points once, each inner
  /// point twice (one per side of the cut). Twins start at the same position;
  /// an excision offsets one of them (§4.4.4).
  std::vector<ChartPoint> points;
  /// For each loop vertex, the cut-path point it came from (twins share it).
  std::vector<int> pathIndex;
  /// Orientation: the loop runs clockwise around the hole in the chart (u
  /// right, v up, i.e. seen from outside the head), as the inner boundary of
  /// the skin region around it: the skin to be meshed lies to the left of
  /// each border edge (i, i+1).
};

/// Two border edges to be sewn together (§4.4.5): edge a = (a0, a1) meets
/// edge b = (b0, b1), a0 onto b0 and a1 onto b1, as loop vertex indices.
/// When a0 == b0 (or a1 == b1) the corner is being closed and that vertex
/// gets no suture (the thesis's corner rule).
struct SutureEdgePair
{
  std::array<int, 2> a;
  std::array<int, 2> b;
};

/// Triangles and quadrilaterals covering the skin around the hole in the
/// chart. Vertices 0 .. hole.points.size()-1 are the hole loop's vertices in
/// loop order; the rest are added by the mesher. Polygons are
/// counter-clockwise in the chart (u right, v up), i.e. seen from outside the
/// head, with 3 or 4 vertex indices.
struct SurfaceMesh
{
  std::vector<ChartPoint> vertices;
  std::vector<std::vector<int>> polygons;
  /// Number of leading vertices that are the hole loop.
  int holeVertexCount = 0;
  /// The outer border of the meshed region, counter-clockwise (the rim).
  std::vector<int> outerBorder;
};

} // namespace caps::fem
