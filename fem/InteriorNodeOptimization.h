#pragma once
/// @file InteriorNodeOptimization.h
/// @brief Moves the nodes inside the tissue (the layer boundaries between the
/// skin and the bone) so that the elements stand upright, leaving every node
/// that carries the geometry or a condition where the mesher put it.

#include "fem/SurfaceMesh.h"

#include <Eigen/Core>

#include <functional>
#include <vector>

namespace caps::fem {

struct ContinuumMesh;

/// Options of optimizeInteriorNodes().
struct InteriorNodeOptions
{
  /// Gauss-Seidel sweeps over the movable nodes at most; the sweeps stop
  /// earlier once no node moves more than @a settledMove.
  int maxSweeps = 12;
  /// A node that moves less than this fraction of its shortest edge in a
  /// sweep counts as settled.
  double settledMove = 1e-3;
  /// No element may fall below the smaller of its own worst scaled Jacobian
  /// before the move and this (so the worst element of the mesh never gets
  /// worse, and a good one does not become poor).
  double acceptableScaledJacobian = 0.3;
};

/// The deep surface (the bone) the deepest nodes may slide on, as the
/// mesher sees it: the point under a chart point (may throw where there is
/// none, e.g. beyond the scan), and the chart point of each vertex column.
struct DeepSurface
{
  std::function<Eigen::Vector3d(const ChartPoint&)> pointUnder;
  std::vector<ChartPoint> vertexCharts;
};

/// What optimizeInteriorNodes() did.
struct InteriorNodeOptimization
{
  int movableNodes = 0;     ///< corner nodes free to move (inner layer boundaries and the deep surface)
  int movableDeepNodes = 0; ///< of those, on the deep surface
  int movedNodes = 0;       ///< of those, moved by more than a micrometre
  int sweeps = 0;
  double largestMove = 0.0; ///< mm, from where the mesher put the node
  /// The mesh as the mesher placed it (checkMeshQuality() with the default
  /// limits): its smallest scaled Jacobian and the elements below the limit.
  double minScaledJacobianBefore = 1.0;
  int poorElementsBefore = 0;
};

/**
 * @brief Improves the shape of @a continuum's elements by moving the corner
 *        nodes of its inner layer boundaries within the plane across their
 *        column.
 *
 * The mesher puts each layer boundary at a fraction of the depth along the
 * ray to the bone (§4.5.2). Where the bone's surface is steep against that
 * ray (the mandible's edge, the teeth, the zygoma) the columns lean against
 * the layers and the elements shear to slivers. The skin and the bone fix
 * the body's shape; the nodes between them only divide it, so they may move
 * without changing the tissue that is modelled. Each movable node in turn
 * (Gauss-Seidel sweeps) minimises the sum, over the elements around it and
 * their nodes and 2 x 2 x 2 points, of 1/h(σ)², σ the scaled Jacobian there
 * (ElementQuality.h, from the elements' own quadratic shape functions) and
 * h(σ) = (σ + sqrt(σ² + 4δ²))/2 the regularisation of Escobar et al.
 * ("Simultaneous untangling and smoothing of tetrahedral meshes", Comput
 * Methods Appl Mech Eng 192, 2003), which stays finite and pulls inverted
 * points back; the metric is Knupp's (Int J Numer Meth Eng 48, 2000). The
 * node moves only across its column (keeping its depth), by NLopt's BOBYQA,
 * and no element around it may get worse than InteriorNodeOptions says.
 * Every mid-edge node on an edge with a moved end goes to the edge's
 * middle. Last, the result is measured as checkMeshQuality() measures it
 * (3 x 3 x 3 points) and any element that came out worse than it was has
 * its moved nodes put back.
 *
 * With @a deep, the deepest corner nodes slide on the deep surface too
 * (each within half its shortest chart edge of where it was, its mid-edge
 * nodes on that surface under the chart middles of their edges): the
 * radial rays meet a steep bone obliquely, which skews the elements' bone
 * faces themselves, and no move of the nodes above can mend a skewed face.
 * The body's shape is the same surface, sampled at other points.
 *
 * Only the nodes of elements below InteriorNodeOptions::acceptableScaledJacobian
 * move: a good mesh is left as the mesher made it.
 *
 * Not moved: the skin layer and the columns of @a heldVertices
 * (one flag per vertex column; the mesher holds the region's rim and the
 * wound's walls, whose surfaces are the body's boundary). Nodes at one
 * place (the two sides of an undermined plane) move as one. The meshContinuum()
 * calls it (ContinuumMeshOptions::optimizeInteriorNodes) after placing the
 * nodes and before it makes the sutures and the sliding planes' normals
 * from their positions; on a finished ContinuumMesh those would be stale.
 */
InteriorNodeOptimization optimizeInteriorNodes(ContinuumMesh& continuum, const std::vector<char>& heldVertices,
                                               const DeepSurface* deep = nullptr,
                                               const InteriorNodeOptions& options = {});

} // namespace caps::fem
