#pragma once
/// @file ContinuumMesher.h
/// @brief Extrusion of the skin's surface mesh down to the bone into layers
/// of 20-node bricks and 15-node wedges (thesis §4.5.2), with the sutures of
/// §4.4.5 and the bone supports of §4.5.

#include "fem/Constraints.h"
#include "fem/InteriorNodeOptimization.h"
#include "fem/Mesh.h"
#include "fem/SurfaceMesh.h"

#include <Eigen/Core>

#include <array>
#include <functional>
#include <limits>
#include <optional>
#include <vector>

namespace caps::fem {

/**
 * @brief Where the tissue lies under the chart, supplied by the caller (who
 *        reads the skin and bone range maps, §4.2.1 eq. 4.9, and maps chart
 *        (u, v) to (θ, z)). fem/ knows nothing of range maps.
 *
 * All three are called with chart points (mm) of surface vertices and of
 * surface edge midpoints.
 */
struct TissueGeometry
{
  /// Skin point in the patient frame (LPS, mm).
  std::function<Eigen::Vector3d(const ChartPoint&)> skinPoint;
  /// Soft-tissue depth (mm) from the skin to the bone along inwardDirection;
  /// NaN where the bone range map has no bone (ContinuumMeshOptions say what
  /// to do there).
  std::function<double(const ChartPoint&)> tissueDepth;
  /// Direction towards the bone (−radial, towards the head axis, §4.5); need
  /// not be unit length, it is normalised.
  std::function<Eigen::Vector3d(const ChartPoint&)> inwardDirection;
};

/// What holds the outer rim of the meshed region.
enum class RimCondition
{
  Free,    ///< as in the thesis (§4.5): only the bone layer is fixed
  Clamped, ///< every node of the rim's columns is fixed (tissue beyond the mesh held in place)
};

/// What holds undermined tissue (thesis §3.2.2, §3.2.4 item 2) on the deep
/// plane it was freed from.
enum class UnderminedBase
{
  Sliding, ///< glides over the fascia or periosteum: u . n = 0 there, tangential motion free
  Free,    ///< held by nothing: the deep face of the freed tissue may lift off or sink in
};

/// Options of meshContinuum().
struct ContinuumMeshOptions
{
  /// Number of element layers N_l from the skin to the bone (>= 1).
  int layerCount = 1;
  /// Thickness of each layer as a fraction of the local depth, skin first
  /// (e.g. skin, fat, muscle). Empty: N_l equal layers. Otherwise N_l
  /// positive numbers summing to 1.
  std::vector<double> layerFractions;
  /// Element region (material) of each layer, skin first. Empty: the layer
  /// index. Otherwise N_l ids.
  std::vector<int> layerRegions;
  /// The depth from TissueGeometry::tissueDepth is clamped to
  /// [minDepth, maxDepth] (mm): range data near the bone's edge or over the
  /// sinuses is unreliable, and a thin sliver of tissue makes flat elements.
  double minDepth = 0.0;
  double maxDepth = std::numeric_limits<double>::infinity();
  /// Depth (mm) used where there is no bone (tissueDepth is NaN). Unset: no
  /// bone under a vertex is an error naming the chart point.
  std::optional<double> noBoneDepth;
  RimCondition rim = RimCondition::Free;
  /// Undermining (thesis §3.2.2, §3.2.4 item 2): one flag per surface
  /// vertex, non-zero where the tissue the cut goes through is freed from
  /// what lies beneath, in the plane at the cut's root. For a
  /// full-thickness cut that plane is the bone: the bone node of such a
  /// vertex's column is not fixed, nor the bone node of an edge whose two
  /// vertices are both undermined (the bottom face of the freed elements is
  /// then free as a whole). For a cut of partial depth the plane is inside
  /// the tissue (the fascia under the fat, say): the freed vertices and
  /// edges get a second node there for the layer above, and the tissue
  /// below stays whole and held by the bone. Empty: no undermining. A
  /// clamped rim stays clamped: it holds the tissue beyond the mesh, not the
  /// bone.
  std::vector<char> underminedVertices;
  /// How the undermined bone-layer nodes are held (ContinuumMesh::slidingNodes).
  UnderminedBase underminedBase = UnderminedBase::Sliding;
  /// Incision depth (thesis §3.2.2: cutting to a depth): the number of
  /// layers, from the skin, the cut goes through; 0 (or N_l) is full
  /// thickness, the thesis's model. Below a cut of partial depth the tissue
  /// is whole: the two sides of the cut share their nodes where they touch
  /// (twins not offset apart), the floor of an excision (holeFloor()) is
  /// meshed through the layers below the cut, and sutures sew only the
  /// layers the cut goes through (not the nodes at its root, which the
  /// tissue below holds).
  int cutLayers = 0;
  /// Move the corner nodes between the skin and the bone so the elements
  /// stand upright where the bone is steep against the columns
  /// (optimizeInteriorNodes(); the rim's and the wound's columns are held).
  /// Off: every node on its column's ray, as in §4.5.2.
  bool optimizeInteriorNodes = false;
};

/// A node of undermined tissue that slides on the deep plane beneath it:
/// (u - u_beneath) . normal = 0, u_beneath = 0 on the bone.
struct SlidingNode
{
  int node = -1;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero(); ///< unit normal of the deep surface at the node
  /// The node of the tissue beneath on the same plane (a cut of partial
  /// depth), or -1: the bone, which does not move.
  int beneath = -1;
};

/**
 * @brief The continuum mesh and what the analysis and the display need from
 *        its construction.
 *
 * Node columns: every surface vertex owns 2 N_l + 1 nodes from the skin
 * (index 0) to the bone (index 2 N_l): the layer boundaries at even indices,
 * the middles of the layers' vertical edges at odd ones. Every surface edge
 * owns N_l + 1 nodes, one per layer boundary. So there are
 * N_l (2 N_v + N_e) + N_v + N_e nodes and N_l N_p elements (§4.5.2).
 */
struct ContinuumMesh
{
  Mesh mesh;

  /// Suture constraints (§4.4.5): node ends where target ends. Node pairs of
  /// all layers of the sutured edges' vertex and mid-edge columns, with the
  /// corner rule applied. A node met by several suture edge pairs (three
  /// points closing together) is sutured once, onto one node of its group.
  std::vector<Suture> sutures;
  /// Nodes fixed in x, y, z (ascending): the bone layer (§4.5) less the
  /// undermined nodes, plus the rim columns if RimCondition::Clamped, less
  /// every sutured node.
  std::vector<int> fixedNodes;
  /// Every node of the bone layer (ascending), sutured or not.
  std::vector<int> boneNodes;
  /// The nodes of the undermined tissue's deep face (ascending;
  /// ContinuumMeshOptions::underminedVertices): for a full-thickness cut
  /// the bone-layer nodes the bone no longer holds; for a cut of partial
  /// depth the raised tissue's own nodes on the plane at the cut's root,
  /// each beside the node of the tissue below, which stays whole and held.
  std::vector<int> underminedNodes;
  /// The undermined nodes that slide on the deep plane
  /// (UnderminedBase::Sliding; ascending by node): the freed tissue glides
  /// over what lies beneath, neither glued to it nor lifting off. Normals
  /// are the deep surface's (the plane's faces around the node,
  /// area-weighted), so on a curved plane the node slides on its tangent
  /// plane in the reference state (no contact search: good while the slide
  /// is short against the plane's radius of curvature). A sutured group (a
  /// node and those sewn onto it) slides once, at its root, on the mean
  /// plane of its members; nodes the clamped rim holds stay held.
  std::vector<SlidingNode> slidingNodes;
  /// Every node of the rim's vertex and edge columns (ascending).
  std::vector<int> rimNodes;

  /// Surface edges (smaller vertex index first), in order of first use by
  /// the polygons, then the new edges of the hole's floor (cut of partial
  /// depth); indices into edgeColumns.
  std::vector<std::array<int, 2>> edges;
  /// Node column of each surface vertex (2 N_l + 1 nodes, skin to bone).
  /// Under a cut of partial depth, twins share the nodes below the cut.
  std::vector<std::vector<int>> vertexColumns;
  /// Node column of each surface edge (N_l + 1 nodes, skin to bone); under
  /// a cut of partial depth the edges of the hole's floor follow, with -1
  /// above the cut where they have no node.
  std::vector<std::vector<int>> edgeColumns;
  /// Depth used at each vertex and at each edge's chart midpoint (mm,
  /// after clamping and the no-bone default).
  std::vector<double> vertexDepths;
  std::vector<double> edgeDepths;
  /// Fraction of the local depth at each layer boundary: N_l + 1 values from
  /// 0 (skin) to 1 (bone).
  std::vector<double> levelFractions;

  /// For each element, its surface polygon and its layer (0 at the skin).
  /// Elements of the hole's floor under a cut of partial depth have
  /// polygon index surface.polygons.size() + their floor triangle.
  std::vector<int> elementPolygon;
  std::vector<int> elementLayer;
  /// What ContinuumMeshOptions::optimizeInteriorNodes did (nothing movable
  /// when off).
  InteriorNodeOptimization nodeOptimization;

  /// The fixed nodes, the sutures and the sliding nodes (one equation
  /// u . n = 0 each, its dependent DOF the normal's largest component) as
  /// constraints for the analyses.
  Constraints constraints() const;
  /// The wound as cut, before any suture (how far it gapes under the skin's
  /// pre-tension): what holds the tissue without the sutures. Every bone
  /// node the bone holds is fixed, the sutured ones too unless undermined;
  /// an undermined sutured node slides on the plane its group slides on in
  /// constraints(), on its own; the rim as in constraints().
  Constraints openWoundConstraints() const;
  /// Index of the surface edge joining vertices @a a and @a b, or -1.
  int edgeIndex(int a, int b) const;
};

/**
 * @brief Extrudes @a surface from the skin to the bone (thesis §4.5.2).
 *
 * Every quadrilateral becomes a 20-node hexahedron (Bathe order, top face
 * t = +1 on the skin) and every triangle a native 15-node wedge (top
 * triangle on the skin), one per layer; edges shared by polygons become
 * shared faces. Corner and mid-edge nodes of the skin lie on the skin
 * (skinPoint of the vertex, and of the edge's chart midpoint, so curved
 * skin is followed); deeper nodes are offset along inwardDirection by the
 * layer boundaries' fractions of the local depth, so the bone layer lies
 * at the full depth. Twins of the hole loop are distinct vertices, so the
 * hole stays open until @a sutures close it: edge a is sewn onto edge b,
 * a0 onto b0 and a1 onto b1, through every layer; a vertex shared by both
 * edges (a corner being closed) gets no suture.
 *
 * Throws std::invalid_argument with a message naming the culprit for: no
 * layers, bad layer fractions or regions, bad depth limits, a polygon with
 * other than 3 or 4 vertices, a vertex index out of range or repeated, a
 * polygon that is not counter-clockwise in the chart, an edge used by more
 * than two polygons or twice in the same direction, a suture edge that is
 * not a border edge of the hole loop, undermining flags not one per surface
 * vertex, a cut depth outside 0..N_l, a hole floor that cannot be
 * triangulated, a missing callback, a non-finite skin
 * point or inward direction, no bone and no default depth, or a depth that
 * is not positive after clamping.
 */
ContinuumMesh meshContinuum(const SurfaceMesh& surface, const std::vector<SutureEdgePair>& sutures,
                            const TissueGeometry& geometry, const ContinuumMeshOptions& options = {});

/**
 * @brief The tissue an excision removes (thesis §3.1.3: volumetric elements
 *        give the volume removed; §3.2.2): the hole's floor (holeFloor() of
 *        @a surface) extruded like the rest of the mesh through the layers
 *        the cut goes through (@a options.cutLayers), down to the same
 *        depths. Its elements are wedges over the floor triangles; the
 *        surface polygons are not meshed. An empty mesh for a cut with no
 *        excision. Undermining and the rim do not apply.
 */
ContinuumMesh meshExcisedTissue(const SurfaceMesh& surface, const TissueGeometry& geometry,
                                const ContinuumMeshOptions& options = {});

/// Volume (mm^3) of a mesh: the sum of its elements' volumes by the full
/// integration rule (3 x 3 x 3 Gauss points, 18-point wedge rule).
double meshVolume(const Mesh& mesh);

/**
 * @brief The default undermining of §3.2.4 item 2: the surface vertices
 *        within @a width (mm, in the chart, i.e. measured on the skin) of a
 *        sutured border edge (either edge of any of @a sutures).
 *
 * Returns one flag per vertex of @a surface, for
 * ContinuumMeshOptions::underminedVertices; all zero for @a width = 0 (the
 * vertices of the sutured edges themselves are at distance 0 and are
 * flagged for any positive width). Throws std::invalid_argument for a
 * negative or non-finite width or a suture vertex out of range.
 */
std::vector<char> underminingBand(const SurfaceMesh& surface, const std::vector<SutureEdgePair>& sutures, double width);

/**
 * @brief The depth the mesher uses for a raw depth @a rawDepth (mm) from
 *        TissueGeometry::tissueDepth: clamped to [minDepth, maxDepth], or
 *        noBoneDepth when @a rawDepth is NaN. Throws std::invalid_argument
 *        if there is no bone and no default, or the result is not positive;
 *        @a where names the point in the message.
 */
double effectiveTissueDepth(double rawDepth, const ContinuumMeshOptions& options, const char* where = "a point");

} // namespace caps::fem
