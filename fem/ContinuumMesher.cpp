#include "fem/ContinuumMesher.h"

#include "fem/ElasticityIntegrator.h"
#include "fem/ElementShape.h"
#include "fem/HoleFloor.h"
#include "fem/Quadrature.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace caps::fem {
namespace {

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("continuum mesher: " + what); }

std::string chartText(const ChartPoint& p) {
  std::ostringstream s;
  s << "(u, v) = (" << p.x() << ", " << p.y() << ") mm";
  return s.str();
}

std::array<int, 2> edgeKey(int a, int b) { return a < b ? std::array<int, 2>{a, b} : std::array<int, 2>{b, a}; }

void validateOptions(const ContinuumMeshOptions& o) {
  if (o.layerCount < 1)
    fail("the mesh needs at least one layer of elements from skin to bone (layerCount = " +
         std::to_string(o.layerCount) + ")");
  if (!o.layerFractions.empty()) {
    if (int(o.layerFractions.size()) != o.layerCount)
      fail(std::to_string(o.layerFractions.size()) + " layer fractions given for " + std::to_string(o.layerCount) +
           " layers");
    double sum = 0.0;
    for (std::size_t k = 0; k < o.layerFractions.size(); ++k) {
      const double f = o.layerFractions[k];
      if (!std::isfinite(f) || f <= 0.0)
        fail("layer " + std::to_string(k) + " has thickness fraction " + std::to_string(f) + "; it must be positive");
      sum += f;
    }
    if (std::abs(sum - 1.0) > 1e-9) fail("the layer fractions sum to " + std::to_string(sum) + ", not 1");
  }
  if (!o.layerRegions.empty() && int(o.layerRegions.size()) != o.layerCount)
    fail(std::to_string(o.layerRegions.size()) + " layer regions given for " + std::to_string(o.layerCount) +
         " layers");
  if (!std::isfinite(o.minDepth) || o.minDepth < 0.0)
    fail("the minimum tissue depth must be finite and >= 0 mm (got " + std::to_string(o.minDepth) + ")");
  if (std::isnan(o.maxDepth) || o.maxDepth <= 0.0 || o.maxDepth < o.minDepth)
    fail("the maximum tissue depth (" + std::to_string(o.maxDepth) + " mm) must be positive and >= the minimum (" +
         std::to_string(o.minDepth) + " mm)");
  if (o.noBoneDepth && (!std::isfinite(*o.noBoneDepth) || *o.noBoneDepth <= 0.0))
    fail("the depth used where there is no bone must be positive (got " + std::to_string(*o.noBoneDepth) + " mm)");
  if (o.cutLayers < 0 || o.cutLayers > o.layerCount)
    fail("the cut goes through " + std::to_string(o.cutLayers) + " layers of a mesh with " +
         std::to_string(o.layerCount) + "; give 1.." + std::to_string(o.layerCount) + " (0: full thickness)");
}

/// Cumulative fractions of the depth at the N_l + 1 layer boundaries; the
/// last is exactly 1 so the bone layer lies at the full depth.
std::vector<double> levelFractionsOf(const ContinuumMeshOptions& o) {
  std::vector<double> levels(std::size_t(o.layerCount) + 1, 0.0);
  for (int k = 0; k < o.layerCount; ++k)
    levels[std::size_t(k) + 1] =
        levels[std::size_t(k)] + (o.layerFractions.empty() ? 1.0 / o.layerCount : o.layerFractions[std::size_t(k)]);
  levels.back() = 1.0;
  return levels;
}

/// Union-find over nodes, to merge suture groups (three points closing
/// together, or a chain of edge pairs through one vertex).
struct NodeGroups {
  std::map<int, int> parent;
  int find(int n) {
    auto it = parent.find(n);
    if (it == parent.end()) {
      parent[n] = n;
      return n;
    }
    if (it->second == n) return n;
    const int root = find(it->second);
    parent[n] = root;
    return root;
  }
  /// The root of b's group becomes the root of a's, so a lone pair keeps the
  /// thesis direction: a0 onto b0.
  void join(int a, int b) {
    const int ra = find(a), rb = find(b);
    if (ra != rb) parent[ra] = rb;
  }
};

}  // namespace

double effectiveTissueDepth(double rawDepth, const ContinuumMeshOptions& options, const char* where) {
  double depth = 0.0;
  if (std::isnan(rawDepth)) {
    if (!options.noBoneDepth)
      fail(std::string("no bone under ") + where +
           " and no default depth for missing bone is set (ContinuumMeshOptions::noBoneDepth)");
    depth = *options.noBoneDepth;
  } else if (!std::isfinite(rawDepth)) {
    fail(std::string("the tissue depth at ") + where + " is infinite");
  } else {
    depth = std::clamp(rawDepth, options.minDepth, options.maxDepth);
  }
  if (depth <= 0.0)
    fail(std::string("the tissue depth at ") + where + " is " + std::to_string(depth) +
         " mm; the bone must lie below the skin (set a positive minimum depth to clamp it)");
  return depth;
}

std::vector<char> underminingBand(const SurfaceMesh& surface, const std::vector<SutureEdgePair>& sutures,
                                  double width) {
  if (!std::isfinite(width) || width < 0.0)
    fail("the undermining width must be 0 or a positive number of mm (got " + std::to_string(width) + ")");
  const int vertexCount = int(surface.vertices.size());
  std::vector<char> band(std::size_t(vertexCount), 0);
  if (width == 0.0) return band;
  std::vector<std::array<int, 2>> edges;
  for (const SutureEdgePair& pair : sutures)
    for (const auto& e : {pair.a, pair.b}) {
      for (int v : e)
        if (v < 0 || v >= vertexCount)
          fail("a sutured edge refers to vertex " + std::to_string(v) + " of a mesh with " +
               std::to_string(vertexCount) + " vertices");
      edges.push_back(edgeKey(e[0], e[1]));
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  for (int v = 0; v < vertexCount; ++v) {
    const ChartPoint& p = surface.vertices[std::size_t(v)];
    for (const auto& [a, b] : edges) {
      const ChartPoint& pa = surface.vertices[std::size_t(a)];
      const ChartPoint d = surface.vertices[std::size_t(b)] - pa;
      const double length2 = d.squaredNorm();
      const double t = length2 > 0.0 ? std::clamp((p - pa).dot(d) / length2, 0.0, 1.0) : 0.0;
      if ((p - (pa + t * d)).norm() <= width) {
        band[std::size_t(v)] = 1;
        break;
      }
    }
  }
  return band;
}

Constraints ContinuumMesh::constraints() const {
  Constraints c;
  for (int n : fixedNodes) c.fixNode(n);
  for (const Suture& s : sutures) c.suture(s.node, s.target);
  return c;
}

int ContinuumMesh::edgeIndex(int a, int b) const {
  const auto key = edgeKey(a, b);
  const auto it = std::find(edges.begin(), edges.end(), key);
  return it == edges.end() ? -1 : int(it - edges.begin());
}

ContinuumMesh meshContinuum(const SurfaceMesh& surface, const std::vector<SutureEdgePair>& sutures,
                            const TissueGeometry& geometry, const ContinuumMeshOptions& options) {
  validateOptions(options);
  if (!geometry.skinPoint || !geometry.tissueDepth || !geometry.inwardDirection)
    fail("the tissue geometry needs all three callbacks (skin point, tissue depth, inward direction)");
  const int vertexCount = int(surface.vertices.size());
  const int holeCount = surface.holeVertexCount;
  if (holeCount < 0 || holeCount > vertexCount)
    fail("the hole loop has " + std::to_string(holeCount) + " vertices but the surface mesh only " +
         std::to_string(vertexCount));
  if (surface.polygons.empty()) fail("the surface mesh has no polygons");
  const auto& undermined = options.underminedVertices;
  if (!undermined.empty() && int(undermined.size()) != vertexCount)
    fail(std::to_string(undermined.size()) + " undermining flags given for a surface mesh of " +
         std::to_string(vertexCount) + " vertices");

  ContinuumMesh out;
  const int layers = options.layerCount;
  out.levelFractions = levelFractionsOf(options);

  // 1. Edges of the surface mesh (§4.5.2: each polygon edge, last to first
  //    included), with the polygons on each side, checking the polygons.
  std::map<std::array<int, 2>, int> edgeOf;
  std::vector<std::vector<int>> edgeUses;  // per edge: +1 for a use a->b with a < b, -1 reversed
  std::vector<std::vector<int>> polygonEdges(surface.polygons.size());
  for (std::size_t p = 0; p < surface.polygons.size(); ++p) {
    const auto& poly = surface.polygons[p];
    const std::string name = "surface polygon " + std::to_string(p);
    if (poly.size() != 3 && poly.size() != 4)
      fail(name + " has " + std::to_string(poly.size()) +
           " vertices; only triangles (wedges) and quadrilaterals (bricks) can be extruded (§4.5.2)");
    for (std::size_t i = 0; i < poly.size(); ++i) {
      if (poly[i] < 0 || poly[i] >= vertexCount)
        fail(name + " refers to vertex " + std::to_string(poly[i]) + " of a mesh with " + std::to_string(vertexCount) +
             " vertices");
      for (std::size_t j = 0; j < i; ++j)
        if (poly[i] == poly[j]) fail(name + " repeats vertex " + std::to_string(poly[i]));
    }
    // Counter-clockwise in the chart = seen from outside the head, so the
    // skin face is the top face (t = +1) of a positive-Jacobian element.
    double twiceArea = 0.0;
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const ChartPoint& a = surface.vertices[std::size_t(poly[i])];
      const ChartPoint& b = surface.vertices[std::size_t(poly[(i + 1) % poly.size()])];
      twiceArea += a.x() * b.y() - a.y() * b.x();
    }
    if (!(twiceArea > 0.0))
      fail(name + " is not counter-clockwise in the chart (signed area " + std::to_string(0.5 * twiceArea) +
           " mm^2); polygons must be seen from outside the head");
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const int a = poly[i], b = poly[(i + 1) % poly.size()];
      const auto key = edgeKey(a, b);
      auto [it, added] = edgeOf.emplace(key, int(out.edges.size()));
      if (added) {
        out.edges.push_back(key);
        edgeUses.emplace_back();
      }
      auto& uses = edgeUses[std::size_t(it->second)];
      const int direction = a < b ? 1 : -1;
      if (uses.size() == 2 || (uses.size() == 1 && uses[0] == direction))
        fail("surface edge (" + std::to_string(a) + ", " + std::to_string(b) + ") of " + name +
             (uses.size() == 2
                  ? " is shared by more than two polygons"
                  : " is used twice in the same direction (polygons overlap or are not all counter-clockwise)"));
      uses.push_back(direction);
      polygonEdges[p].push_back(it->second);
    }
  }
  // A cut of partial depth: the hole's floor is meshed below the cut, its
  // new edges (diagonals, edges between merged twins) after the surface's.
  const int cut = options.cutLayers == 0 ? layers : options.cutLayers;
  const bool partial = cut < layers;
  HoleFloor floor;
  std::vector<std::array<int, 3>> floorEdges;
  if (partial) {
    floor = holeFloor(surface);
    for (const auto& triangle : floor.triangles) {
      std::array<int, 3> edgesOfTriangle{};
      for (std::size_t i = 0; i < 3; ++i) {
        auto [it, added] = edgeOf.emplace(edgeKey(triangle[i], triangle[(i + 1) % 3]), int(out.edges.size()));
        if (added) {
          out.edges.push_back(it->first);
          edgeUses.emplace_back();  // no surface polygon uses it: neither hole border nor rim
        }
        edgesOfTriangle[i] = it->second;
      }
      floorEdges.push_back(edgesOfTriangle);
    }
  }
  const int edgeCount = int(out.edges.size());

  // 2. Node positions, layer by layer as in the thesis: the skin level, then
  //    for each layer its vertical mid-edge nodes and its lower boundary.
  auto unitInward = [&](const ChartPoint& c, const std::string& where) {
    const Eigen::Vector3d n = geometry.inwardDirection(c);
    const double len = n.norm();
    if (!std::isfinite(len) || len < 1e-12) fail("the inward direction at " + where + " is zero or not finite");
    return Eigen::Vector3d(n / len);
  };
  auto skinAt = [&](const ChartPoint& c, const std::string& where) {
    const Eigen::Vector3d s = geometry.skinPoint(c);
    if (!s.allFinite()) fail("the skin point at " + where + " is not finite");
    return s;
  };
  struct ColumnGeometry {
    Eigen::Vector3d skin, inward;
    double depth = 0.0;
  };
  std::vector<ColumnGeometry> vertexGeometry(static_cast<std::size_t>(vertexCount));
  out.vertexDepths.resize(std::size_t(vertexCount));
  for (int v = 0; v < vertexCount; ++v) {
    const ChartPoint& c = surface.vertices[std::size_t(v)];
    const std::string where = "vertex " + std::to_string(v) + " " + chartText(c);
    auto& g = vertexGeometry[std::size_t(v)];
    g.skin = skinAt(c, where);
    g.inward = unitInward(c, where);
    g.depth = effectiveTissueDepth(geometry.tissueDepth(c), options, where.c_str());
    out.vertexDepths[std::size_t(v)] = g.depth;
  }
  // Mid-edge columns stand on the skin point of the chart midpoint, so the
  // top mid-edge nodes lie on the skin (§4.5.2: midpoints offset to the skin).
  std::vector<ColumnGeometry> edgeGeometry(static_cast<std::size_t>(edgeCount));
  out.edgeDepths.resize(std::size_t(edgeCount));
  for (int e = 0; e < edgeCount; ++e) {
    const auto& [a, b] = out.edges[std::size_t(e)];
    const ChartPoint c = 0.5 * (surface.vertices[std::size_t(a)] + surface.vertices[std::size_t(b)]);
    const std::string where =
        "the midpoint of edge (" + std::to_string(a) + ", " + std::to_string(b) + ") " + chartText(c);
    auto& g = edgeGeometry[std::size_t(e)];
    g.skin = skinAt(c, where);
    g.inward = unitInward(c, where);
    g.depth = effectiveTissueDepth(geometry.tissueDepth(c), options, where.c_str());
    out.edgeDepths[std::size_t(e)] = g.depth;
  }

  const Eigen::Index nodeTotal = Eigen::Index(layers) * (2 * vertexCount + edgeCount) + vertexCount + edgeCount;
  out.mesh.nodes.resize(3, nodeTotal);
  out.vertexColumns.assign(std::size_t(vertexCount), std::vector<int>(std::size_t(2 * layers + 1), -1));
  out.edgeColumns.assign(std::size_t(edgeCount), std::vector<int>(std::size_t(layers + 1), -1));
  int next = 0;
  auto place = [&](const ColumnGeometry& g, double fraction) {
    out.mesh.nodes.col(next) = g.skin + fraction * g.depth * g.inward;
    return next++;
  };
  for (int level = 0; level <= layers; ++level) {
    const double f = out.levelFractions[std::size_t(level)];
    if (level > 0) {
      // Vertical mid-edge nodes (Bathe 16-19, wedge 12-14) at half the layer.
      const double mid = 0.5 * (out.levelFractions[std::size_t(level) - 1] + f);
      for (int v = 0; v < vertexCount; ++v)
        out.vertexColumns[std::size_t(v)][std::size_t(2 * level - 1)] = place(vertexGeometry[std::size_t(v)], mid);
    }
    for (int v = 0; v < vertexCount; ++v)
      out.vertexColumns[std::size_t(v)][std::size_t(2 * level)] = place(vertexGeometry[std::size_t(v)], f);
    for (int e = 0; e < edgeCount; ++e)
      out.edgeColumns[std::size_t(e)][std::size_t(level)] = place(edgeGeometry[std::size_t(e)], f);
  }
  // The thesis's count (§4.5.2); holds for wedges too (corner, mid-edge and
  // vertical mid-edge nodes only).
  if (next != nodeTotal)
    throw std::logic_error("continuum mesher: node count differs from N_l(2N_v + N_e) + N_v + N_e");

  // Below a cut of partial depth the two sides are one tissue: twins that
  // touch, and the edges between them, share the nodes from the cut's root
  // down (the copies are dropped below).
  auto representativeOf = [&](int v) { return partial && v < holeCount ? floor.representative[std::size_t(v)] : v; };
  if (partial) {
    for (int v = 0; v < holeCount; ++v) {
      const int r = representativeOf(v);
      for (int i = 2 * cut; r != v && i <= 2 * layers; ++i)
        out.vertexColumns[std::size_t(v)][std::size_t(i)] = out.vertexColumns[std::size_t(r)][std::size_t(i)];
    }
    std::map<std::array<int, 2>, int> edgeOfRepresentatives;
    for (int e = 0; e < edgeCount; ++e) {
      const auto& [a, b] = out.edges[std::size_t(e)];
      const auto [it, added] = edgeOfRepresentatives.emplace(edgeKey(representativeOf(a), representativeOf(b)), e);
      for (int level = cut; !added && level <= layers; ++level)
        out.edgeColumns[std::size_t(e)][std::size_t(level)] = out.edgeColumns[std::size_t(it->second)][std::size_t(level)];
    }
  }

  // 3. Elements: one per polygon per layer, node slots read from the columns.
  out.mesh.elements.reserve(surface.polygons.size() * std::size_t(layers));
  for (int k = 0; k < layers; ++k) {
    const int region = options.layerRegions.empty() ? k : options.layerRegions[std::size_t(k)];
    for (std::size_t p = 0; p < surface.polygons.size(); ++p) {
      const auto& poly = surface.polygons[p];
      const int n = int(poly.size());
      Element el;
      el.nodes.fill(-1);
      el.region = region;
      el.kind = n == 4 ? ElementKind::Hex20 : ElementKind::Wedge15;
      // Bathe: corners 0-3 top, 4-7 bottom, 8-11 / 12-15 top / bottom
      // mid-edges i-(i+1), 16-19 vertical. Wedge: 0-2, 3-5, 6-8, 9-11, 12-14.
      for (int i = 0; i < n; ++i) {
        const auto& column = out.vertexColumns[std::size_t(poly[std::size_t(i)])];
        const auto& edgeColumn = out.edgeColumns[std::size_t(polygonEdges[p][std::size_t(i)])];
        el.nodes[std::size_t(i)] = column[std::size_t(2 * k)];
        el.nodes[std::size_t(n + i)] = column[std::size_t(2 * k + 2)];
        el.nodes[std::size_t(2 * n + i)] = edgeColumn[std::size_t(k)];
        el.nodes[std::size_t(3 * n + i)] = edgeColumn[std::size_t(k + 1)];
        el.nodes[std::size_t(4 * n + i)] = column[std::size_t(2 * k + 1)];
      }
      out.mesh.elements.push_back(el);
      out.elementPolygon.push_back(int(p));
      out.elementLayer.push_back(k);
    }
    // The floor of the hole under a cut of partial depth: wedges, top
    // triangle counter-clockwise like the skin's.
    for (std::size_t t = 0; k >= cut && t < floor.triangles.size(); ++t) {
      Element el;
      el.nodes.fill(-1);
      el.region = region;
      el.kind = ElementKind::Wedge15;
      for (std::size_t i = 0; i < 3; ++i) {
        const auto& column = out.vertexColumns[std::size_t(floor.triangles[t][i])];
        const auto& edgeColumn = out.edgeColumns[std::size_t(floorEdges[t][i])];
        el.nodes[i] = column[std::size_t(2 * k)];
        el.nodes[3 + i] = column[std::size_t(2 * k + 2)];
        el.nodes[6 + i] = edgeColumn[std::size_t(k)];
        el.nodes[9 + i] = edgeColumn[std::size_t(k + 1)];
        el.nodes[12 + i] = column[std::size_t(2 * k + 1)];
      }
      out.mesh.elements.push_back(el);
      out.elementPolygon.push_back(int(surface.polygons.size() + t));
      out.elementLayer.push_back(k);
    }
  }

  // Nodes no element uses (merged twins' copies, floor edges above the cut)
  // are dropped; the rest keep their order.
  if (partial) {
    std::vector<int> renumbered(std::size_t(nodeTotal), -1);
    for (const Element& el : out.mesh.elements)
      for (int node : el.nodes)
        if (node >= 0) renumbered[std::size_t(node)] = 0;
    int kept = 0;
    for (int& index : renumbered)
      if (index == 0) index = kept++;
    Eigen::Matrix3Xd nodes(3, kept);
    for (int node = 0; node < nodeTotal; ++node)
      if (renumbered[std::size_t(node)] >= 0) nodes.col(renumbered[std::size_t(node)]) = out.mesh.nodes.col(node);
    out.mesh.nodes = std::move(nodes);
    for (Element& el : out.mesh.elements)
      for (int& node : el.nodes)
        if (node >= 0) node = renumbered[std::size_t(node)];
    for (auto* columns : {&out.vertexColumns, &out.edgeColumns})
      for (auto& column : *columns)
        for (int& node : column)
          if (node >= 0) node = renumbered[std::size_t(node)];
  }
  const int nodeCount = int(out.mesh.nodes.cols());

  // 4. Sutures (§4.4.5): edge a onto edge b through every layer, vertex
  //    columns a0 -> b0, a1 -> b1 (not at a corner being closed) and the
  //    mid-edge columns.
  auto isHoleBorderEdge = [&](int a, int b) {
    if (a < 0 || b < 0 || a >= holeCount || b >= holeCount || a == b) return -1;
    const auto it = edgeOf.find(edgeKey(a, b));
    if (it == edgeOf.end() || edgeUses[std::size_t(it->second)].size() != 1) return -1;
    return it->second;
  };
  NodeGroups groups;
  std::vector<int> joinOrder;  // nodes in order of first suture, for a stable output
  // Only the layers the cut goes through: the nodes at its root and below
  // are held by the tissue under it.
  auto sew = [&](const std::vector<int>& from, const std::vector<int>& onto, std::size_t sewn) {
    for (std::size_t i = 0; i < sewn; ++i) {
      for (int node : {from[i], onto[i]})
        if (groups.parent.find(node) == groups.parent.end()) joinOrder.push_back(node);
      groups.join(from[i], onto[i]);
    }
  };
  for (std::size_t s = 0; s < sutures.size(); ++s) {
    const auto& edgePair = sutures[s];
    const int ea = isHoleBorderEdge(edgePair.a[0], edgePair.a[1]);
    const int eb = isHoleBorderEdge(edgePair.b[0], edgePair.b[1]);
    auto edgeName = [](const std::array<int, 2>& e) {
      std::ostringstream text;
      text << "(" << e[0] << ", " << e[1] << ")";
      return text.str();
    };
    for (const auto& [index, e] : {std::pair{ea, edgePair.a}, std::pair{eb, edgePair.b}})
      if (index < 0)
        fail("suture pair " + std::to_string(s) + " refers to edge " + edgeName(e) +
             ", which is not a border edge of the hole loop (loop vertices 0.." + std::to_string(holeCount - 1) + ")");
    if (ea == eb) fail("suture pair " + std::to_string(s) + " sews edge " + edgeName(edgePair.a) + " onto itself");
    for (int i = 0; i < 2; ++i)
      if (edgePair.a[std::size_t(i)] != edgePair.b[std::size_t(i)])  // corner rule
        sew(out.vertexColumns[std::size_t(edgePair.a[std::size_t(i)])],
            out.vertexColumns[std::size_t(edgePair.b[std::size_t(i)])], std::size_t(partial ? 2 * cut : 2 * layers + 1));
    sew(out.edgeColumns[std::size_t(ea)], out.edgeColumns[std::size_t(eb)], std::size_t(partial ? cut : layers + 1));
  }
  std::vector<char> sutured(std::size_t(nodeCount), 0);
  for (int node : joinOrder) {
    sutured[std::size_t(node)] = 1;
    const int root = groups.find(node);
    if (root != node) out.sutures.push_back({node, root});
  }

  // 5. Supports: the bone layer (§4.5) less the undermined region (§3.2.4
  //    item 2: the skin freed from what lies beneath slides over it) and, if
  //    asked, the rim columns. The rim is every border edge that is not an
  //    edge of the hole loop.
  auto isUndermined = [&](int v) { return !undermined.empty() && undermined[std::size_t(v)] != 0; };
  for (int v = 0; v < vertexCount; ++v) {
    const int node = out.vertexColumns[std::size_t(v)].back();
    out.boneNodes.push_back(node);
    if (isUndermined(v)) out.underminedNodes.push_back(node);
  }
  for (int e = 0; e < edgeCount; ++e) {
    const int node = out.edgeColumns[std::size_t(e)].back();
    out.boneNodes.push_back(node);
    if (isUndermined(out.edges[std::size_t(e)][0]) && isUndermined(out.edges[std::size_t(e)][1]))
      out.underminedNodes.push_back(node);
  }
  // Merged twins share a bone node: keep each once.
  for (auto* nodes : {&out.boneNodes, &out.underminedNodes}) {
    std::sort(nodes->begin(), nodes->end());
    nodes->erase(std::unique(nodes->begin(), nodes->end()), nodes->end());
  }
  std::vector<char> onRim(std::size_t(nodeCount), 0);
  for (int e = 0; e < edgeCount; ++e) {
    if (edgeUses[std::size_t(e)].size() != 1) continue;
    const auto& [a, b] = out.edges[std::size_t(e)];
    const bool holeEdge = a < holeCount && b < holeCount && (b == a + 1 || (a == 0 && b == holeCount - 1));
    if (holeEdge) continue;
    for (int node : out.edgeColumns[std::size_t(e)]) onRim[std::size_t(node)] = 1;
    for (int v : {a, b})
      for (int node : out.vertexColumns[std::size_t(v)]) onRim[std::size_t(node)] = 1;
  }
  for (int node = 0; node < nodeCount; ++node)
    if (onRim[std::size_t(node)]) out.rimNodes.push_back(node);
  std::vector<char> fixed(std::size_t(nodeCount), 0);
  for (int node : out.boneNodes) fixed[std::size_t(node)] = 1;
  for (int node : out.underminedNodes) fixed[std::size_t(node)] = 0;
  if (options.rim == RimCondition::Clamped)
    for (int node : out.rimNodes) fixed[std::size_t(node)] = 1;
  for (int node = 0; node < nodeCount; ++node)
    if (fixed[std::size_t(node)] && !sutured[std::size_t(node)]) out.fixedNodes.push_back(node);
  return out;
}

ContinuumMesh meshExcisedTissue(const SurfaceMesh& surface, const TissueGeometry& geometry,
                                const ContinuumMeshOptions& options) {
  validateOptions(options);
  if (!geometry.skinPoint || !geometry.tissueDepth || !geometry.inwardDirection)
    fail("the tissue geometry needs all three callbacks (skin point, tissue depth, inward direction)");
  const HoleFloor floor = holeFloor(surface);
  if (floor.triangles.empty()) return {};
  // The floor as a surface of its own, meshed down to the cut's root: the
  // layers above the cut with their fractions, over the depth they span.
  SurfaceMesh floorSurface;
  floorSurface.vertices.assign(surface.vertices.begin(), surface.vertices.begin() + surface.holeVertexCount);
  for (const auto& t : floor.triangles) floorSurface.polygons.push_back({t[0], t[1], t[2]});
  const int cut = options.cutLayers == 0 ? options.layerCount : options.cutLayers;
  const std::vector<double> levels = levelFractionsOf(options);
  const double rootFraction = levels[std::size_t(cut)];
  ContinuumMeshOptions removed;
  removed.layerCount = cut;
  for (int k = 0; k < cut; ++k) {
    removed.layerFractions.push_back((levels[std::size_t(k) + 1] - levels[std::size_t(k)]) / rootFraction);
    removed.layerRegions.push_back(options.layerRegions.empty() ? k : options.layerRegions[std::size_t(k)]);
  }
  double sum = 0.0;
  for (double f : removed.layerFractions) sum += f;
  removed.layerFractions.back() += 1.0 - sum;  // exactly 1 for the check
  TissueGeometry toRoot = geometry;
  toRoot.tissueDepth = [&](const ChartPoint& c) {
    return rootFraction * effectiveTissueDepth(geometry.tissueDepth(c), options, "a point of the excised tissue");
  };
  ContinuumMesh out = meshContinuum(floorSurface, {}, toRoot, removed);
  out.fixedNodes.clear();  // nothing holds what is cut out
  return out;
}

double meshVolume(const Mesh& mesh) {
  double volume = 0.0;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e) {
    const Element& el = mesh.elements[e];
    volume += elementVolume(ElementShape::fromConnectivity(el.kind, el.nodes), mesh.elementCoordinates(e),
                            integrationRule(el.kind, 3), int(e));
  }
  return volume;
}

}  // namespace caps::fem
