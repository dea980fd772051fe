#include "fem/ContinuumMesher.h"

#include "fem/ElasticityIntegrator.h"
#include "fem/ElementShape.h"
#include "fem/HoleFloor.h"
#include "fem/Quadrature.h"

#include <Eigen/Geometry>

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

[[noreturn]] void fail(const std::string& what)
{
  throw std::invalid_argument("continuum mesher: " + what);
}

std::string chartText(const ChartPoint& p)
{
  std::ostringstream s;
  s << "(u, v) = (" << p.x() << ", " << p.y() << ") mm";
  return s.str();
}

std::array<int, 2> edgeKey(int a, int b)
{
  return a < b ? std::array<int, 2>{a, b} : std::array<int, 2>{b, a};
}

void validateOptions(const ContinuumMeshOptions& o)
{
  if (o.layerCount < 1)
    fail("the mesh needs at least one layer of elements from skin to bone (layerCount = " +
         std::to_string(o.layerCount) + ")");
  if (!o.layerFractions.empty())
  {
    if (int(o.layerFractions.size()) != o.layerCount)
      fail(std::to_string(o.layerFractions.size()) + " layer fractions given for " + std::to_string(o.layerCount) +
           " layers");
    double sum = 0.0;
    for (std::size_t k = 0; k < o.layerFractions.size(); ++k)
    {
      const double f = o.layerFractions[k];
      if (!std::isfinite(f) || f <= 0.0)
        fail("layer " + std::to_string(k) + " has thickness fraction " + std::to_string(f) + "; it must be positive");
      sum += f;
    }
    if (std::abs(sum - 1.0) > 1e-9)
      fail("the layer fractions sum to " + std::to_string(sum) + ", not 1");
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
std::vector<double> levelFractionsOf(const ContinuumMeshOptions& o)
{
  std::vector<double> levels(std::size_t(o.layerCount) + 1, 0.0);
  for (int k = 0; k < o.layerCount; ++k)
    levels[std::size_t(k) + 1] =
      levels[std::size_t(k)] + (o.layerFractions.empty() ? 1.0 / o.layerCount : o.layerFractions[std::size_t(k)]);
  levels.back() = 1.0;
  return levels;
}

/// Union-find over nodes, to merge suture groups (three points closing
/// together, or a chain of edge pairs through one vertex).
struct NodeGroups
{
  std::map<int, int> parent;
  int find(int n)
  {
    auto it = parent.find(n);
    if (it == parent.end())
    {
      parent[n] = n;
      return n;
    }
    if (it->second == n)
      return n;
    const int root = find(it->second);
    parent[n] = root;
    return root;
  }
  /// The root of b's group becomes the root of a's, so a lone pair keeps the
  /// thesis direction: a0 onto b0.
  void join(int a, int b)
  {
    const int ra = find(a), rb = find(b);
    if (ra != rb)
      parent[ra] = rb;
  }
};

/// effectiveTissueDepth(), with the place it is asked for named only when
/// that is needed for a message (@a where() gives the name): the mesher's
/// node optimisation asks for tens of thousands of points of the bone.
template <class Where> double depthOrFail(double rawDepth, const ContinuumMeshOptions& options, const Where& where)
{
  double depth = 0.0;
  if (std::isnan(rawDepth))
  {
    if (!options.noBoneDepth)
      fail("no bone under " + where() +
           " and no default depth for missing bone is set (ContinuumMeshOptions::noBoneDepth)");
    depth = *options.noBoneDepth;
  }
  else if (!std::isfinite(rawDepth))
  {
    fail("the tissue depth at " + where() + " is infinite");
  }
  else
  {
    depth = std::clamp(rawDepth, options.minDepth, options.maxDepth);
  }
  if (depth <= 0.0)
    fail("the tissue depth at " + where() + " is " + std::to_string(depth) +
         " mm; the bone must lie below the skin (set a positive minimum depth to clamp it)");
  return depth;
}

} // namespace

double effectiveTissueDepth(double rawDepth, const ContinuumMeshOptions& options, const char* where)
{
  return depthOrFail(rawDepth, options, [where] { return std::string(where); });
}

std::vector<char> underminingBand(const SurfaceMesh& surface, const std::vector<SutureEdgePair>& sutures, double width)
{
  if (!std::isfinite(width) || width < 0.0)
    fail("the undermining width must be 0 or a positive number of mm (got " + std::to_string(width) + ")");
  const int vertexCount = int(surface.vertices.size());
  std::vector<char> band(std::size_t(vertexCount), 0);
  if (width == 0.0)
    return band;
  std::vector<std::array<int, 2>> edges;
  for (const SutureEdgePair& pair : sutures)
    for (const auto& e : {pair.a, pair.b})
    {
      for (int v : e)
        if (v < 0 || v >= vertexCount)
          fail("a sutured edge refers to vertex " + std::to_string(v) + " of a mesh with " +
               std::to_string(vertexCount) + " vertices");
      edges.push_back(edgeKey(e[0], e[1]));
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  for (int v = 0; v < vertexCount; ++v)
  {
    const ChartPoint& p = surface.vertices[std::size_t(v)];
    for (const auto& [a, b] : edges)
    {
      const ChartPoint& pa = surface.vertices[std::size_t(a)];
      const ChartPoint d = surface.vertices[std::size_t(b)] - pa;
      const double length2 = d.squaredNorm();
      const double t = length2 > 0.0 ? std::clamp((p - pa).dot(d) / length2, 0.0, 1.0) : 0.0;
      if ((p - (pa + t * d)).norm() <= width)
      {
        band[std::size_t(v)] = 1;
        break;
      }
    }
  }
  return band;
}

namespace {

/// (u - u_beneath) . n = 0 for @a sliding, the dependent DOF the normal's
/// largest component.
LinearConstraint slidingEquation(const SlidingNode& sliding)
{
  Eigen::Index dependent = 0;
  sliding.normal.cwiseAbs().maxCoeff(&dependent);
  LinearConstraint onThePlane;
  onThePlane.terms.push_back({sliding.node, int(dependent), sliding.normal[dependent]});
  for (int d = 0; d < 3; ++d)
    if (d != int(dependent) && sliding.normal[d] != 0.0)
      onThePlane.terms.push_back({sliding.node, d, sliding.normal[d]});
  for (int d = 0; sliding.beneath >= 0 && d < 3; ++d)
    if (sliding.normal[d] != 0.0)
      onThePlane.terms.push_back({sliding.beneath, d, -sliding.normal[d]});
  return onThePlane;
}

} // namespace

Constraints ContinuumMesh::constraints() const
{
  Constraints c;
  for (int n : fixedNodes)
    c.fixNode(n);
  for (const Suture& s : sutures)
    c.suture(s.node, s.target);
  for (const SlidingNode& sliding : slidingNodes)
    c.equation(slidingEquation(sliding));
  return c;
}

Constraints ContinuumMesh::openWoundConstraints() const
{
  Constraints c;
  for (int n : fixedNodes)
    c.fixNode(n);
  std::map<int, int> sewnOnto; // sutured node -> its target
  for (const Suture& s : sutures)
    sewnOnto[s.node] = s.target;
  std::map<int, const SlidingNode*> slides;
  for (const SlidingNode& sliding : slidingNodes)
  {
    slides[sliding.node] = &sliding;
    c.equation(slidingEquation(sliding));
  }
  for (const auto& [node, target] : sewnOnto)
  {
    if (!std::binary_search(boneNodes.begin(), boneNodes.end(), node) &&
        !std::binary_search(underminedNodes.begin(), underminedNodes.end(), node))
      continue; // tissue above the deep plane: free once the suture is gone
    if (!std::binary_search(underminedNodes.begin(), underminedNodes.end(), node))
    {
      c.fixNode(node); // the bone holds it
      continue;
    }
    // Undermined: slides as its group's root does (constraints()), if it does.
    int root = target;
    for (int hops = 0; hops < int(sewnOnto.size()) && sewnOnto.count(root); ++hops)
      root = sewnOnto.at(root);
    if (const auto it = slides.find(root); it != slides.end())
    {
      SlidingNode own = *it->second;
      own.node = node;
      c.equation(slidingEquation(own));
    }
  }
  return c;
}

int ContinuumMesh::edgeIndex(int a, int b) const
{
  const auto key = edgeKey(a, b);
  const auto it = std::find(edges.begin(), edges.end(), key);
  return it == edges.end() ? -1 : int(it - edges.begin());
}

namespace {

/// meshContinuum() in its steps (§4.5.2): run() is the table of contents. A
/// cut of partial depth adds four steps: the hole's floor edges, the twins
/// merged below the cut, the undermined plane split at the cut's root, and
/// the nodes no element uses dropped.
class ContinuumMesher
{
public:
  ContinuumMesher(const SurfaceMesh& surface, const std::vector<SutureEdgePair>& sutures,
                  const TissueGeometry& geometry, const ContinuumMeshOptions& options)
    : surface_(surface), sutures_(sutures), geometry_(geometry), options_(options),
      vertexCount_(int(surface.vertices.size())), holeCount_(surface.holeVertexCount), layers_(options.layerCount),
      cut_(options.cutLayers == 0 ? options.layerCount : options.cutLayers), partial_(cut_ < layers_)
  {}

  ContinuumMesh run()
  {
    checkInputs();
    out_.levelFractions = levelFractionsOf(options_);
    collectSurfaceEdges();
    if (partial_)
      addHoleFloorEdges();
    edgeCount_ = int(out_.edges.size());
    placeNodes();
    if (partial_)
    {
      mergeTwinsBelowTheCut();
      splitTheUnderminedPlane();
    }
    makeElements();
    if (partial_)
      dropUnusedNodes();
    if (options_.optimizeInteriorNodes)
      optimizeTheInteriorNodes();
    sew();
    support();
    return std::move(out_);
  }

private:
  struct ColumnGeometry
  {
    Eigen::Vector3d skin, inward;
    double depth = 0.0;
  };

  void checkInputs() const
  {
    validateOptions(options_);
    if (!geometry_.skinPoint || !geometry_.tissueDepth || !geometry_.inwardDirection)
      fail("the tissue geometry needs all three callbacks (skin point, tissue depth, inward direction)");
    if (holeCount_ < 0 || holeCount_ > vertexCount_)
      fail("the hole loop has " + std::to_string(holeCount_) + " vertices but the surface mesh only " +
           std::to_string(vertexCount_));
    if (surface_.polygons.empty())
      fail("the surface mesh has no polygons");
    const auto& undermined = options_.underminedVertices;
    if (!undermined.empty() && int(undermined.size()) != vertexCount_)
      fail(std::to_string(undermined.size()) + " undermining flags given for a surface mesh of " +
           std::to_string(vertexCount_) + " vertices");
  }

  /// 1. Edges of the surface mesh (§4.5.2: each polygon edge, last to first
  ///    included), with the polygons on each side, checking the polygons.
  void collectSurfaceEdges()
  {
    polygonEdges_.resize(surface_.polygons.size());
    for (std::size_t p = 0; p < surface_.polygons.size(); ++p)
    {
      const auto& poly = surface_.polygons[p];
      const std::string name = "surface polygon " + std::to_string(p);
      checkPolygon(poly, name);
      for (std::size_t i = 0; i < poly.size(); ++i)
      {
        const int a = poly[i], b = poly[(i + 1) % poly.size()];
        const auto key = edgeKey(a, b);
        auto [it, added] = edgeOf_.emplace(key, int(out_.edges.size()));
        if (added)
        {
          out_.edges.push_back(key);
          edgeUses_.emplace_back();
        }
        auto& uses = edgeUses_[std::size_t(it->second)];
        const int direction = a < b ? 1 : -1;
        if (uses.size() == 2 || (uses.size() == 1 && uses[0] == direction))
          fail("surface edge (" + std::to_string(a) + ", " + std::to_string(b) + ") of " + name +
               (uses.size() == 2
                  ? " is shared by more than two polygons"
                  : " is used twice in the same direction (polygons overlap or are not all counter-clockwise)"));
        uses.push_back(direction);
        polygonEdges_[p].push_back(it->second);
      }
    }
  }

  /// A triangle or quadrilateral of distinct vertices of the mesh,
  /// counter-clockwise in the chart = seen from outside the head, so the
  /// skin face is the top face (t = +1) of a positive-Jacobian element.
  void checkPolygon(const std::vector<int>& poly, const std::string& name) const
  {
    if (poly.size() != 3 && poly.size() != 4)
      fail(name + " has " + std::to_string(poly.size()) +
           " vertices; only triangles (wedges) and quadrilaterals (bricks) can be extruded (§4.5.2)");
    for (std::size_t i = 0; i < poly.size(); ++i)
    {
      if (poly[i] < 0 || poly[i] >= vertexCount_)
        fail(name + " refers to vertex " + std::to_string(poly[i]) + " of a mesh with " + std::to_string(vertexCount_) +
             " vertices");
      for (std::size_t j = 0; j < i; ++j)
        if (poly[i] == poly[j])
          fail(name + " repeats vertex " + std::to_string(poly[i]));
    }
    double twiceArea = 0.0;
    for (std::size_t i = 0; i < poly.size(); ++i)
    {
      const ChartPoint& a = surface_.vertices[std::size_t(poly[i])];
      const ChartPoint& b = surface_.vertices[std::size_t(poly[(i + 1) % poly.size()])];
      twiceArea += a.x() * b.y() - a.y() * b.x();
    }
    if (!(twiceArea > 0.0))
      fail(name + " is not counter-clockwise in the chart (signed area " + std::to_string(0.5 * twiceArea) +
           " mm^2); polygons must be seen from outside the head");
  }

  /// 1b. A cut of partial depth: the hole's floor is meshed below the cut,
  ///     its new edges (diagonals, edges between merged twins) after the
  ///     surface's.
  void addHoleFloorEdges()
  {
    floor_ = holeFloor(surface_);
    for (const auto& triangle : floor_.triangles)
    {
      std::array<int, 3> edgesOfTriangle{};
      for (std::size_t i = 0; i < 3; ++i)
      {
        auto [it, added] = edgeOf_.emplace(edgeKey(triangle[i], triangle[(i + 1) % 3]), int(out_.edges.size()));
        if (added)
        {
          out_.edges.push_back(it->first);
          edgeUses_.emplace_back(); // no surface polygon uses it: neither hole border nor rim
        }
        edgesOfTriangle[i] = it->second;
      }
      floorEdges_.push_back(edgesOfTriangle);
    }
  }

  /// The skin point, the unit inward direction and the tissue depth at @a c;
  /// @a where() names the point, called only for a message.
  template <class Where> ColumnGeometry columnAt(const ChartPoint& c, const Where& where) const
  {
    ColumnGeometry g;
    g.skin = geometry_.skinPoint(c);
    if (!g.skin.allFinite())
      fail("the skin point at " + where() + " is not finite");
    const Eigen::Vector3d n = geometry_.inwardDirection(c);
    const double len = n.norm();
    if (!std::isfinite(len) || len < 1e-12)
      fail("the inward direction at " + where() + " is zero or not finite");
    g.inward = n / len;
    g.depth = depthOrFail(geometry_.tissueDepth(c), options_, where);
    return g;
  }

  /// 2. Node positions, layer by layer as in the thesis: the skin level,
  ///    then for each layer its vertical mid-edge nodes and its lower
  ///    boundary. Mid-edge columns stand on the skin point of the chart
  ///    midpoint, so the top mid-edge nodes lie on the skin (§4.5.2:
  ///    midpoints offset to the skin).
  void placeNodes()
  {
    std::vector<ColumnGeometry> vertexGeometry(static_cast<std::size_t>(vertexCount_));
    out_.vertexDepths.resize(std::size_t(vertexCount_));
    for (int v = 0; v < vertexCount_; ++v)
    {
      const ChartPoint& c = surface_.vertices[std::size_t(v)];
      vertexGeometry[std::size_t(v)] = columnAt(c, [&] { return "vertex " + std::to_string(v) + " " + chartText(c); });
      out_.vertexDepths[std::size_t(v)] = vertexGeometry[std::size_t(v)].depth;
    }
    std::vector<ColumnGeometry> edgeGeometry(static_cast<std::size_t>(edgeCount_));
    out_.edgeDepths.resize(std::size_t(edgeCount_));
    for (int e = 0; e < edgeCount_; ++e)
    {
      const auto& [a, b] = out_.edges[std::size_t(e)];
      const ChartPoint c = 0.5 * (surface_.vertices[std::size_t(a)] + surface_.vertices[std::size_t(b)]);
      edgeGeometry[std::size_t(e)] = columnAt(c, [&] {
        return "the midpoint of edge (" + std::to_string(a) + ", " + std::to_string(b) + ") " + chartText(c);
      });
      out_.edgeDepths[std::size_t(e)] = edgeGeometry[std::size_t(e)].depth;
    }

    nodeTotal_ = Eigen::Index(layers_) * (2 * vertexCount_ + edgeCount_) + vertexCount_ + edgeCount_;
    out_.mesh.nodes.resize(3, nodeTotal_);
    out_.vertexColumns.assign(std::size_t(vertexCount_), std::vector<int>(std::size_t(2 * layers_ + 1), -1));
    out_.edgeColumns.assign(std::size_t(edgeCount_), std::vector<int>(std::size_t(layers_ + 1), -1));
    int next = 0;
    auto place = [&](const ColumnGeometry& g, double fraction) {
      out_.mesh.nodes.col(next) = g.skin + fraction * g.depth * g.inward;
      return next++;
    };
    for (int level = 0; level <= layers_; ++level)
    {
      const double f = out_.levelFractions[std::size_t(level)];
      if (level > 0)
      {
        // Vertical mid-edge nodes (Bathe 16-19, wedge 12-14) at half the layer.
        const double mid = 0.5 * (out_.levelFractions[std::size_t(level) - 1] + f);
        for (int v = 0; v < vertexCount_; ++v)
          out_.vertexColumns[std::size_t(v)][std::size_t(2 * level - 1)] = place(vertexGeometry[std::size_t(v)], mid);
      }
      for (int v = 0; v < vertexCount_; ++v)
        out_.vertexColumns[std::size_t(v)][std::size_t(2 * level)] = place(vertexGeometry[std::size_t(v)], f);
      for (int e = 0; e < edgeCount_; ++e)
        out_.edgeColumns[std::size_t(e)][std::size_t(level)] = place(edgeGeometry[std::size_t(e)], f);
    }
    // The thesis's count (§4.5.2); holds for wedges too (corner, mid-edge and
    // vertical mid-edge nodes only).
    if (next != nodeTotal_)
      throw std::logic_error("continuum mesher: node count differs from N_l(2N_v + N_e) + N_v + N_e");
  }

  /// 2b. Below a cut of partial depth the two sides are one tissue: twins
  ///     that touch, and the edges between them, share the nodes from the
  ///     cut's root down (the copies are dropped by dropUnusedNodes()).
  void mergeTwinsBelowTheCut()
  {
    auto representativeOf = [&](int v) { return v < holeCount_ ? floor_.representative[std::size_t(v)] : v; };
    for (int v = 0; v < holeCount_; ++v)
    {
      const int r = representativeOf(v);
      for (int i = 2 * cut_; r != v && i <= 2 * layers_; ++i)
        out_.vertexColumns[std::size_t(v)][std::size_t(i)] = out_.vertexColumns[std::size_t(r)][std::size_t(i)];
    }
    std::map<std::array<int, 2>, int> edgeOfRepresentatives;
    for (int e = 0; e < edgeCount_; ++e)
    {
      const auto& [a, b] = out_.edges[std::size_t(e)];
      const auto [it, added] = edgeOfRepresentatives.emplace(edgeKey(representativeOf(a), representativeOf(b)), e);
      for (int level = cut_; !added && level <= layers_; ++level)
        out_.edgeColumns[std::size_t(e)][std::size_t(level)] =
          out_.edgeColumns[std::size_t(it->second)][std::size_t(level)];
    }
  }

  /// 2c. Under a cut of partial depth the surgeon raises the tissue the cut
  ///     goes through in the plane at its root (thesis §3.2.2, §3.2.4 item
  ///     2): every undermined vertex, and every edge between two, gets a
  ///     second node on that plane, which the layer above uses; the layer
  ///     below keeps the first and stays whole and held. Twins merged below
  ///     the cut get one each, so the wound's two sides part there too.
  void splitTheUnderminedPlane()
  {
    upperOfVertex_.assign(std::size_t(vertexCount_), -1);
    upperOfEdge_.assign(std::size_t(edgeCount_), -1);
    const auto& undermined = options_.underminedVertices;
    if (undermined.empty())
      return;
    std::vector<int> copied;
    auto copyOf = [&](int node) {
      copied.push_back(node);
      return int(nodeTotal_) + int(copied.size()) - 1;
    };
    for (int v = 0; v < vertexCount_; ++v)
      if (undermined[std::size_t(v)])
        upperOfVertex_[std::size_t(v)] = copyOf(out_.vertexColumns[std::size_t(v)][std::size_t(2 * cut_)]);
    for (int e = 0; e < edgeCount_; ++e)
    {
      const auto& [a, b] = out_.edges[std::size_t(e)];
      if (undermined[std::size_t(a)] && undermined[std::size_t(b)])
        upperOfEdge_[std::size_t(e)] = copyOf(out_.edgeColumns[std::size_t(e)][std::size_t(cut_)]);
    }
    out_.mesh.nodes.conservativeResize(3, nodeTotal_ + Eigen::Index(copied.size()));
    for (std::size_t i = 0; i < copied.size(); ++i)
      out_.mesh.nodes.col(nodeTotal_ + Eigen::Index(i)) = out_.mesh.nodes.col(copied[i]);
    nodeTotal_ += Eigen::Index(copied.size());
  }

  /// The node of vertex @a v's column on the undermined plane that the layer
  /// above it uses, and the one of edge @a e.
  int upperPlaneNodeOfVertex(int v) const
  {
    const int upper = upperOfVertex_.empty() ? -1 : upperOfVertex_[std::size_t(v)];
    return upper >= 0 ? upper : out_.vertexColumns[std::size_t(v)][std::size_t(2 * cut_)];
  }
  int upperPlaneNodeOfEdge(int e) const
  {
    const int upper = upperOfEdge_.empty() ? -1 : upperOfEdge_[std::size_t(e)];
    return upper >= 0 ? upper : out_.edgeColumns[std::size_t(e)][std::size_t(cut_)];
  }

  /// The element of layer @a k over a polygon of @a n corners, its node
  /// slots read from the corners' and the edges' columns. Bathe: corners 0-3
  /// top, 4-7 bottom, 8-11 / 12-15 top / bottom mid-edges i-(i+1), 16-19
  /// vertical. Wedge: 0-2, 3-5, 6-8, 9-11, 12-14.
  template <class Corners, class Edges>
  Element elementOf(const Corners& corners, const Edges& edges, int n, int k, int region) const
  {
    Element el;
    el.nodes.fill(-1);
    el.region = region;
    el.kind = n == 4 ? ElementKind::Hex20 : ElementKind::Wedge15;
    for (int i = 0; i < n; ++i)
    {
      const auto& column = out_.vertexColumns[std::size_t(corners[std::size_t(i)])];
      const auto& edgeColumn = out_.edgeColumns[std::size_t(edges[std::size_t(i)])];
      el.nodes[std::size_t(i)] = column[std::size_t(2 * k)];
      el.nodes[std::size_t(n + i)] = column[std::size_t(2 * k + 2)];
      el.nodes[std::size_t(2 * n + i)] = edgeColumn[std::size_t(k)];
      el.nodes[std::size_t(3 * n + i)] = edgeColumn[std::size_t(k + 1)];
      el.nodes[std::size_t(4 * n + i)] = column[std::size_t(2 * k + 1)];
      if (partial_ && k == cut_ - 1) // its bottom face is on the undermined plane
      {
        el.nodes[std::size_t(n + i)] = upperPlaneNodeOfVertex(corners[std::size_t(i)]);
        el.nodes[std::size_t(3 * n + i)] = upperPlaneNodeOfEdge(edges[std::size_t(i)]);
      }
    }
    return el;
  }

  /// 3. Elements: one per polygon per layer, and under a cut of partial
  ///    depth the hole's floor: wedges, top triangle counter-clockwise like
  ///    the skin's.
  void makeElements()
  {
    out_.mesh.elements.reserve(surface_.polygons.size() * std::size_t(layers_));
    for (int k = 0; k < layers_; ++k)
    {
      const int region = options_.layerRegions.empty() ? k : options_.layerRegions[std::size_t(k)];
      for (std::size_t p = 0; p < surface_.polygons.size(); ++p)
      {
        const auto& poly = surface_.polygons[p];
        out_.mesh.elements.push_back(elementOf(poly, polygonEdges_[p], int(poly.size()), k, region));
        out_.elementPolygon.push_back(int(p));
        out_.elementLayer.push_back(k);
      }
      for (std::size_t t = 0; k >= cut_ && t < floor_.triangles.size(); ++t)
      {
        out_.mesh.elements.push_back(elementOf(floor_.triangles[t], floorEdges_[t], 3, k, region));
        out_.elementPolygon.push_back(int(surface_.polygons.size() + t));
        out_.elementLayer.push_back(k);
      }
    }
  }

  /// 3b. Nodes no element uses (merged twins' copies, floor edges above the
  ///     cut) are dropped; the rest keep their order.
  void dropUnusedNodes()
  {
    std::vector<int> renumbered(std::size_t(nodeTotal_), -1);
    for (const Element& el : out_.mesh.elements)
      for (int node : el.nodes)
        if (node >= 0)
          renumbered[std::size_t(node)] = 0;
    int kept = 0;
    for (int& index : renumbered)
      if (index == 0)
        index = kept++;
    Eigen::Matrix3Xd nodes(3, kept);
    for (int node = 0; node < nodeTotal_; ++node)
      if (renumbered[std::size_t(node)] >= 0)
        nodes.col(renumbered[std::size_t(node)]) = out_.mesh.nodes.col(node);
    out_.mesh.nodes = std::move(nodes);
    for (Element& el : out_.mesh.elements)
      for (int& node : el.nodes)
        if (node >= 0)
          node = renumbered[std::size_t(node)];
    for (auto* columns : {&out_.vertexColumns, &out_.edgeColumns})
      for (auto& column : *columns)
        for (int& node : column)
          if (node >= 0)
            node = renumbered[std::size_t(node)];
    for (auto* upper : {&upperOfVertex_, &upperOfEdge_}) // a copy no element uses is no copy
      for (int& node : *upper)
        if (node >= 0)
          node = renumbered[std::size_t(node)];
  }

  /// 3c. The nodes inside the tissue, and the bone's along the bone, moved
  ///     so the elements stand upright (InteriorNodeOptimization.h), before
  ///     anything is made from the positions.
  void optimizeTheInteriorNodes()
  {
    DeepSurface bone;
    bone.pointUnder = [this](const ChartPoint& c) {
      const ColumnGeometry g = columnAt(c, [&] { return "a point of the bone " + chartText(c); });
      return Eigen::Vector3d(g.skin + g.depth * g.inward);
    };
    bone.vertexCharts = surface_.vertices;
    out_.nodeOptimization = optimizeInteriorNodes(out_, borderVertices(), &bone);
  }

  /// Vertices on the border of the surface (the rim, the wound's edges):
  ///     their columns are the body's boundary and stay where they are.
  std::vector<char> borderVertices() const
  {
    std::vector<char> border(std::size_t(vertexCount_), 0);
    for (int e = 0; e < edgeCount_; ++e)
      if (edgeUses_[std::size_t(e)].size() == 1)
        for (int v : out_.edges[std::size_t(e)])
          border[std::size_t(v)] = 1;
    return border;
  }

  /// The index of edge (a, b) when it is a border edge of the hole loop, else -1.
  int holeBorderEdge(int a, int b) const
  {
    if (a < 0 || b < 0 || a >= holeCount_ || b >= holeCount_ || a == b)
      return -1;
    const auto it = edgeOf_.find(edgeKey(a, b));
    if (it == edgeOf_.end() || edgeUses_[std::size_t(it->second)].size() != 1)
      return -1;
    return it->second;
  }

  /// 4. Sutures (§4.4.5): edge a onto edge b through every layer (only the
  ///    layers the cut goes through: the nodes at its root and below are
  ///    held by the tissue under it; raised over an undermined plane, the
  ///    wall's foot lies on the plane and slides there), vertex columns
  ///    a0 -> b0, a1 -> b1 (not at a corner being closed) and the mid-edge
  ///    columns.
  void sew()
  {
    NodeGroups groups;
    std::vector<int> joinOrder; // nodes in order of first suture, for a stable output
    auto sewColumns = [&](const std::vector<int>& from, const std::vector<int>& onto, std::size_t sewn) {
      for (std::size_t i = 0; i < sewn; ++i)
      {
        for (int node : {from[i], onto[i]})
          if (groups.parent.find(node) == groups.parent.end())
            joinOrder.push_back(node);
        groups.join(from[i], onto[i]);
      }
    };
    auto edgeName = [](const std::array<int, 2>& e) {
      std::ostringstream text;
      text << "(" << e[0] << ", " << e[1] << ")";
      return text.str();
    };
    for (std::size_t s = 0; s < sutures_.size(); ++s)
    {
      const auto& edgePair = sutures_[s];
      const int ea = holeBorderEdge(edgePair.a[0], edgePair.a[1]);
      const int eb = holeBorderEdge(edgePair.b[0], edgePair.b[1]);
      for (const auto& [index, e] : {std::pair{ea, edgePair.a}, std::pair{eb, edgePair.b}})
        if (index < 0)
          fail("suture pair " + std::to_string(s) + " refers to edge " + edgeName(e) +
               ", which is not a border edge of the hole loop (loop vertices 0.." + std::to_string(holeCount_ - 1) +
               ")");
      if (ea == eb)
        fail("suture pair " + std::to_string(s) + " sews edge " + edgeName(edgePair.a) + " onto itself");
      for (int i = 0; i < 2; ++i)
        if (edgePair.a[std::size_t(i)] != edgePair.b[std::size_t(i)]) // corner rule
          sewColumns(out_.vertexColumns[std::size_t(edgePair.a[std::size_t(i)])],
                     out_.vertexColumns[std::size_t(edgePair.b[std::size_t(i)])],
                     std::size_t(partial_ ? 2 * cut_ : 2 * layers_ + 1));
      sewColumns(out_.edgeColumns[std::size_t(ea)], out_.edgeColumns[std::size_t(eb)],
                 std::size_t(partial_ ? cut_ : layers_ + 1));
    }
    sutured_.assign(std::size_t(out_.mesh.nodes.cols()), 0);
    for (int node : joinOrder)
    {
      sutured_[std::size_t(node)] = 1;
      const int root = groups.find(node);
      if (root != node)
        out_.sutures.push_back({node, root});
    }
  }

  /// 5. Supports: the bone layer (§4.5) less the undermined region (§3.2.4
  ///    item 2: the skin freed from what lies beneath slides over it) and,
  ///    if asked, the rim columns. Under a cut of partial depth the freed
  ///    nodes are the raised tissue's own on the plane at the cut's root
  ///    (splitTheUnderminedPlane()) and the bone holds its whole layer.
  void support()
  {
    const auto& undermined = options_.underminedVertices;
    auto isUndermined = [&](int v) { return !undermined.empty() && undermined[std::size_t(v)] != 0; };
    for (int v = 0; v < vertexCount_; ++v)
    {
      const int node = out_.vertexColumns[std::size_t(v)].back();
      out_.boneNodes.push_back(node);
      if (partial_ && upperOfVertex_[std::size_t(v)] >= 0)
        out_.underminedNodes.push_back(upperOfVertex_[std::size_t(v)]);
      else if (!partial_ && isUndermined(v))
        out_.underminedNodes.push_back(node);
    }
    for (int e = 0; e < edgeCount_; ++e)
    {
      const int node = out_.edgeColumns[std::size_t(e)].back();
      out_.boneNodes.push_back(node);
      if (partial_ && upperOfEdge_[std::size_t(e)] >= 0)
        out_.underminedNodes.push_back(upperOfEdge_[std::size_t(e)]);
      else if (!partial_ && isUndermined(out_.edges[std::size_t(e)][0]) && isUndermined(out_.edges[std::size_t(e)][1]))
        out_.underminedNodes.push_back(node);
    }
    // Merged twins share a bone node: keep each once.
    for (auto* nodes : {&out_.boneNodes, &out_.underminedNodes})
    {
      std::sort(nodes->begin(), nodes->end());
      nodes->erase(std::unique(nodes->begin(), nodes->end()), nodes->end());
    }
    findTheRim();
    const int nodeCount = int(out_.mesh.nodes.cols());
    std::vector<char> fixed(std::size_t(nodeCount), 0);
    for (int node : out_.boneNodes)
      fixed[std::size_t(node)] = 1;
    for (int node : out_.underminedNodes)
      fixed[std::size_t(node)] = 0;
    if (options_.rim == RimCondition::Clamped)
      for (int node : out_.rimNodes)
        fixed[std::size_t(node)] = 1;
    for (int node = 0; node < nodeCount; ++node)
      if (fixed[std::size_t(node)] && !sutured_[std::size_t(node)])
        out_.fixedNodes.push_back(node);
    if (options_.underminedBase == UnderminedBase::Sliding)
      slideOnTheDeepPlane(fixed);
  }

  /// 5b. Undermined tissue glides on the deep plane it was freed from: the
  ///     bone (a full-thickness cut) or the tissue below the cut's root (a
  ///     cut of partial depth), with the plane's normal at each freed node
  ///     from the vector areas of the plane's faces around it (the surface
  ///     polygons' and the hole floor's). Sutured nodes move as one with
  ///     their suture group's root, so a group slides once, on the mean of
  ///     its members' planes: a wound closed onto its mirror image slides on
  ///     the mirror-symmetric plane.
  void slideOnTheDeepPlane(const std::vector<char>& fixed)
  {
    const int nodeCount = int(out_.mesh.nodes.cols());
    const std::size_t vertexLevel = std::size_t(partial_ ? 2 * cut_ : 2 * layers_);
    const std::size_t edgeLevel = std::size_t(partial_ ? cut_ : layers_);
    std::vector<Eigen::Vector3d> vertexNormal(std::size_t(vertexCount_), Eigen::Vector3d::Zero());
    std::vector<Eigen::Vector3d> edgeNormal(std::size_t(edgeCount_), Eigen::Vector3d::Zero());
    auto addFace = [&](const auto& vertices, const auto& edges) {
      const std::size_t n = vertices.size();
      auto at = [&](std::size_t i) {
        return Eigen::Vector3d(out_.mesh.nodes.col(out_.vertexColumns[std::size_t(vertices[i % n])][vertexLevel]));
      };
      Eigen::Vector3d area = Eigen::Vector3d::Zero();
      for (std::size_t i = 0; i < n; ++i)
        area += at(i).cross(at(i + 1));
      for (std::size_t i = 0; i < n; ++i)
      {
        vertexNormal[std::size_t(vertices[i])] += area;
        edgeNormal[std::size_t(edges[i])] += area;
      }
    };
    for (std::size_t p = 0; p < surface_.polygons.size(); ++p)
      addFace(surface_.polygons[p], polygonEdges_[p]);
    if (partial_)
      for (std::size_t t = 0; t < floor_.triangles.size(); ++t)
        addFace(floor_.triangles[t], floorEdges_[t]);

    // The freed nodes, each with its plane's normal and the node beneath it
    // (-1: the bone, which does not move).
    std::vector<Eigen::Vector3d> normal(std::size_t(nodeCount), Eigen::Vector3d::Zero());
    std::vector<int> beneath(std::size_t(nodeCount), -1);
    std::vector<char> freed(std::size_t(nodeCount), 0);
    auto free = [&](int node, const Eigen::Vector3d& n, int below) {
      freed[std::size_t(node)] = 1;
      normal[std::size_t(node)] += n;
      beneath[std::size_t(node)] = below;
    };
    const auto& undermined = options_.underminedVertices;
    for (int v = 0; v < vertexCount_; ++v)
      if (partial_ ? upperOfVertex_[std::size_t(v)] >= 0 : !undermined.empty() && undermined[std::size_t(v)] != 0)
        free(partial_ ? upperOfVertex_[std::size_t(v)] : out_.vertexColumns[std::size_t(v)].back(),
             vertexNormal[std::size_t(v)], partial_ ? out_.vertexColumns[std::size_t(v)][vertexLevel] : -1);
    for (int e = 0; e < edgeCount_; ++e)
    {
      const auto& [a, b] = out_.edges[std::size_t(e)];
      const bool both = !undermined.empty() && undermined[std::size_t(a)] && undermined[std::size_t(b)];
      const int node = partial_ ? upperOfEdge_[std::size_t(e)] : both ? out_.edgeColumns[std::size_t(e)].back() : -1;
      if (node >= 0 && !freed[std::size_t(node)]) // merged twins share their nodes
        free(node, edgeNormal[std::size_t(e)], partial_ ? out_.edgeColumns[std::size_t(e)][edgeLevel] : -1);
    }

    std::vector<int> groupRoot(static_cast<std::size_t>(nodeCount));
    std::iota(groupRoot.begin(), groupRoot.end(), 0);
    for (const Suture& s : out_.sutures) // sutures point at their group's root (sew())
      groupRoot[std::size_t(s.node)] = s.target;
    std::vector<Eigen::Vector3d> groupNormal(std::size_t(nodeCount), Eigen::Vector3d::Zero());
    std::vector<char> slides(std::size_t(nodeCount), 0);
    for (int node = 0; node < nodeCount; ++node)
    {
      // A node the clamped rim holds (and is sutured to nothing) stays held.
      if (!freed[std::size_t(node)] || (fixed[std::size_t(node)] && !sutured_[std::size_t(node)]))
        continue;
      const std::size_t root = std::size_t(groupRoot[std::size_t(node)]);
      groupNormal[root] += normal[std::size_t(node)];
      slides[root] = freed[root]; // a group held by a member that is not freed does not slide
    }
    for (int node = 0; node < nodeCount; ++node)
      if (slides[std::size_t(node)] && groupNormal[std::size_t(node)].norm() > 0.0)
        out_.slidingNodes.push_back({node, groupNormal[std::size_t(node)].normalized(), beneath[std::size_t(node)]});
  }

  /// The rim: the columns of every border edge that is not an edge of the
  /// hole loop.
  void findTheRim()
  {
    const int nodeCount = int(out_.mesh.nodes.cols());
    std::vector<char> onRim(std::size_t(nodeCount), 0);
    for (int e = 0; e < edgeCount_; ++e)
    {
      if (edgeUses_[std::size_t(e)].size() != 1)
        continue;
      const auto& [a, b] = out_.edges[std::size_t(e)];
      const bool holeEdge = a < holeCount_ && b < holeCount_ && (b == a + 1 || (a == 0 && b == holeCount_ - 1));
      if (holeEdge)
        continue;
      for (int node : out_.edgeColumns[std::size_t(e)])
        onRim[std::size_t(node)] = 1;
      for (int v : {a, b})
        for (int node : out_.vertexColumns[std::size_t(v)])
          onRim[std::size_t(node)] = 1;
      if (partial_) // and the raised tissue's nodes on the undermined plane
        for (int node : {upperPlaneNodeOfEdge(e), upperPlaneNodeOfVertex(a), upperPlaneNodeOfVertex(b)})
          onRim[std::size_t(node)] = 1;
    }
    for (int node = 0; node < nodeCount; ++node)
      if (onRim[std::size_t(node)])
        out_.rimNodes.push_back(node);
  }

  const SurfaceMesh& surface_;
  const std::vector<SutureEdgePair>& sutures_;
  const TissueGeometry& geometry_;
  const ContinuumMeshOptions& options_;
  const int vertexCount_, holeCount_, layers_, cut_;
  const bool partial_;
  int edgeCount_ = 0;
  Eigen::Index nodeTotal_ = 0;
  ContinuumMesh out_;
  std::map<std::array<int, 2>, int> edgeOf_;
  std::vector<std::vector<int>> edgeUses_; // per edge: +1 for a use a->b with a < b, -1 reversed
  std::vector<std::vector<int>> polygonEdges_;
  HoleFloor floor_;
  std::vector<std::array<int, 3>> floorEdges_;
  std::vector<char> sutured_;
  /// Per vertex and per edge, the node the layer above the undermined plane
  /// uses there when it is not the column's own (splitTheUnderminedPlane()),
  /// else -1; empty for a full-thickness cut.
  std::vector<int> upperOfVertex_, upperOfEdge_;
};

} // namespace

ContinuumMesh meshContinuum(const SurfaceMesh& surface, const std::vector<SutureEdgePair>& sutures,
                            const TissueGeometry& geometry, const ContinuumMeshOptions& options)
{
  return ContinuumMesher(surface, sutures, geometry, options).run();
}

ContinuumMesh meshExcisedTissue(const SurfaceMesh& surface, const TissueGeometry& geometry,
                                const ContinuumMeshOptions& options)
{
  validateOptions(options);
  if (!geometry.skinPoint || !geometry.tissueDepth || !geometry.inwardDirection)
    fail("the tissue geometry needs all three callbacks (skin point, tissue depth, inward direction)");
  const HoleFloor floor = holeFloor(surface);
  if (floor.triangles.empty())
    return {};
  // The floor as a surface of its own, meshed down to the cut's root: the
  // layers above the cut with their fractions, over the depth they span.
  SurfaceMesh floorSurface;
  floorSurface.vertices.assign(surface.vertices.begin(), surface.vertices.begin() + surface.holeVertexCount);
  for (const auto& t : floor.triangles)
    floorSurface.polygons.push_back({t[0], t[1], t[2]});
  const int cut = options.cutLayers == 0 ? options.layerCount : options.cutLayers;
  const std::vector<double> levels = levelFractionsOf(options);
  const double rootFraction = levels[std::size_t(cut)];
  ContinuumMeshOptions removed;
  removed.layerCount = cut;
  for (int k = 0; k < cut; ++k)
  {
    removed.layerFractions.push_back((levels[std::size_t(k) + 1] - levels[std::size_t(k)]) / rootFraction);
    removed.layerRegions.push_back(options.layerRegions.empty() ? k : options.layerRegions[std::size_t(k)]);
  }
  double sum = 0.0;
  for (double f : removed.layerFractions)
    sum += f;
  removed.layerFractions.back() += 1.0 - sum; // exactly 1 for the check
  TissueGeometry toRoot = geometry;
  toRoot.tissueDepth = [&](const ChartPoint& c) {
    return rootFraction * effectiveTissueDepth(geometry.tissueDepth(c), options, "a point of the excised tissue");
  };
  ContinuumMesh out = meshContinuum(floorSurface, {}, toRoot, removed);
  out.fixedNodes.clear(); // nothing holds what is cut out
  out.slidingNodes.clear();
  return out;
}

double meshVolume(const Mesh& mesh)
{
  double volume = 0.0;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Element& el = mesh.elements[e];
    volume += elementVolume(ElementShape::fromConnectivity(el.kind, el.nodes), mesh.elementCoordinates(e),
                            integrationRule(el.kind, 3), int(e));
  }
  return volume;
}

} // namespace caps::fem
