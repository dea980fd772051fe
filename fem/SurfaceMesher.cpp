#include "fem/SurfaceMesher.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <unordered_set>

namespace caps::fem {
namespace {

using P = Eigen::Vector2d;
constexpr double kPi = std::numbers::pi;

double cross2(const P& a, const P& b)
{
  return a.x() * b.y() - a.y() * b.x();
}
double degrees(double radians)
{
  return radians * 180.0 / kPi;
}

/// Unit normal on the left of direction @a d: outward into the skin, since the
/// skin lies left of every border edge (§4.5.1 footnote 5).
P leftNormal(const P& d)
{
  return P(-d.y(), d.x()).normalized();
}

/// Signed turn of the border at b going a -> b -> c, left (concave for the
/// meshed region) positive, in (-pi, pi]. A full reversal is the end of a
/// cut, where the zero-width hole has a 0° angle and the skin 360° (Fig.
/// 4.11): a convex turn of -pi.
double turnAngle(const P& a, const P& b, const P& c)
{
  const P d1 = b - a, d2 = c - b;
  const double cr = cross2(d1, d2), dt = d1.dot(d2);
  if (std::abs(cr) <= 1e-12 * d1.norm() * d2.norm() && dt < 0)
    return -kPi;
  return std::atan2(cr, dt);
}

std::string mm(double value)
{
  char text[32];
  std::snprintf(text, sizeof text, value < 10 ? "%.1f" : "%.0f", value);
  return text;
}
std::string deg(double radians)
{
  char text[32];
  std::snprintf(text, sizeof text, "%.0f°", degrees(radians));
  return text;
}
std::string at(const P& p)
{
  return "(u " + mm(p.x()) + ", v " + mm(p.y()) + ")";
}

double signedArea(const std::vector<P>& points)
{
  double twice = 0;
  for (std::size_t i = 0; i < points.size(); ++i)
    twice += cross2(points[i], points[(i + 1) % points.size()]);
  return 0.5 * twice;
}

struct Shape
{
  double area = 0, minAngle = 0, maxAngle = 0, aspect = 0;
  bool convexCcw = false;
};

/// Corner angles, area, aspect ratio and convexity of a polygon.
Shape polygonShape(const std::vector<P>& pts)
{
  Shape s;
  const std::size_t k = pts.size();
  s.area = signedArea(pts);
  s.minAngle = 2 * kPi;
  double sum = 0, longest = 0;
  for (std::size_t i = 0; i < k; ++i)
  {
    const P next = pts[(i + 1) % k] - pts[i], prev = pts[(i + k - 1) % k] - pts[i];
    double angle = std::atan2(cross2(next, prev), next.dot(prev));
    if (angle < 0)
      angle += 2 * kPi;
    s.minAngle = std::min(s.minAngle, angle);
    s.maxAngle = std::max(s.maxAngle, angle);
    sum += angle;
    longest = std::max(longest, next.norm());
  }
  // A simple convex CCW polygon has every angle below pi and angles summing to
  // (k - 2) pi; a clockwise or bow-tie one does not.
  s.convexCcw = s.area > 0 && s.maxAngle < kPi && std::abs(sum - (double(k) - 2) * kPi) < 1e-6;
  s.aspect = s.area > 0 ? longest * longest / s.area * (k == 3 ? std::sqrt(3.0) / 4 : 1.0)
                        : std::numeric_limits<double>::infinity();
  return s;
}

bool shapeWithin(const Shape& s, const MeshQualityLimits& limits)
{
  return s.convexCcw && s.minAngle >= limits.minAngle && s.maxAngle <= limits.maxAngle &&
         s.aspect <= limits.maxAspectRatio;
}

/// True when two convex polygons share interior (separating axis theorem on
/// the edge normals of both; touching along an edge or at a corner is fine).
bool convexOverlap(const std::vector<P>& a, const std::vector<P>& b, double tolerance)
{
  for (const auto* poly : {&a, &b})
  {
    for (std::size_t i = 0; i < poly->size(); ++i)
    {
      const P edge = (*poly)[(i + 1) % poly->size()] - (*poly)[i];
      if (edge.norm() == 0)
        continue;
      const P axis = leftNormal(edge);
      double minA = 1e300, maxA = -1e300, minB = 1e300, maxB = -1e300;
      for (const P& p : a)
        minA = std::min(minA, axis.dot(p)), maxA = std::max(maxA, axis.dot(p));
      for (const P& p : b)
        minB = std::min(minB, axis.dot(p)), maxB = std::max(maxB, axis.dot(p));
      if (maxA <= minB + tolerance || maxB <= minA + tolerance)
        return false;
    }
  }
  return true;
}

/// Uniform grid of polygon bounding boxes, for overlap queries.
class PolygonGrid
{
public:
  explicit PolygonGrid(double cellSize) : cell_(cellSize) {}

  void insert(int id, const std::vector<P>& pts)
  {
    forCells(pts, [&](long long key) { cells_[key].push_back(id); });
  }
  /// Ids of polygons whose boxes share a cell with @a pts's box.
  std::vector<int> candidates(const std::vector<P>& pts) const
  {
    std::vector<int> ids;
    forCells(pts, [&](long long key) {
      const auto it = cells_.find(key);
      if (it != cells_.end())
        ids.insert(ids.end(), it->second.begin(), it->second.end());
    });
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    return ids;
  }

private:
  template <class F> void forCells(const std::vector<P>& pts, F&& f) const
  {
    P lo = pts[0], hi = pts[0];
    for (const P& p : pts)
      lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    const long long i0 = std::floor(lo.x() / cell_), i1 = std::floor(hi.x() / cell_);
    const long long j0 = std::floor(lo.y() / cell_), j1 = std::floor(hi.y() / cell_);
    for (long long i = i0; i <= i1; ++i)
      for (long long j = j0; j <= j1; ++j)
        f(i * 2000003LL + j);
  }
  double cell_;
  std::unordered_map<long long, std::vector<int>> cells_;
};

std::vector<P> corners(const std::vector<P>& vertices, const std::vector<int>& polygon)
{
  std::vector<P> pts;
  for (int id : polygon)
    pts.push_back(vertices[id]);
  return pts;
}

/// Distance from p to segment (a, b).
double segmentDistance(const P& p, const P& a, const P& b)
{
  const P ab = b - a;
  const double t = ab.squaredNorm() > 0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

/// Segments (a, b) and (c, d) cross at a point inside both.
bool properlyCross(const P& a, const P& b, const P& c, const P& d, double tolerance)
{
  const double o1 = cross2(b - a, c - a), o2 = cross2(b - a, d - a);
  const double o3 = cross2(d - c, a - c), o4 = cross2(d - c, b - c);
  const double tb = tolerance * (b - a).norm(), td = tolerance * (d - c).norm();
  return ((o1 > tb && o2 < -tb) || (o1 < -tb && o2 > tb)) && ((o3 > td && o4 < -td) || (o3 < -td && o4 > td));
}

/// The mesh as it grows: vertices, polygons and the current border ("front"),
/// clockwise around hole plus meshed skin, skin on its left.
class Mesher
{
public:
  Mesher(const HoleLoop& hole, const SurfaceMesherOptions& options) : hole_(hole), o_(options) {}

  SurfaceMesherResult run();

private:
  // Input checks (§4.4.3-4.4.4), each with a message the surgeon can act on.
  std::string pointName(int loopIndex) const;
  void checkHole();
  double chooseFirstLayer() const;

  // Stage 1: concavities -> triangles.
  int fillConcavities(double threshold);
  bool earIsClear(int ia, int ib, int ic) const;

  // Stage 2: one layer of quadrilaterals; empty string on success, else why not.
  std::string addLayer(double thickness, double nextThickness);
  /// The layer addLayer() is building: the new vertices of each border
  /// vertex, new vertices merged into others (alias) and split points of
  /// the new border edges (midpoint, per border edge, or -1).
  struct NewLayer
  {
    std::size_t firstPolygon = 0;
    int firstVertex = 0;
    std::vector<std::vector<int>> offspring;
    std::unordered_map<int, int> alias;
    std::vector<int> midpoint;
    /// @a id after its merges.
    int resolve(int id) const;
  };
  std::string offsetFront(double thickness, NewLayer& layer);
  void mergeOrSplitBridges(double thickness, double nextThickness, NewLayer& layer);
  void mergeShortRuns(double nextThickness, NewLayer& layer);
  std::vector<int> joinLayer(const NewLayer& layer);
  void splitBentQuadrilaterals(std::size_t firstPolygon);
  int newVertex(P p, double thickness);
  std::string checkNewPolygons(std::size_t firstNew) const;

  void rebuildGrid();
  SurfaceMesh finish() const;

  const HoleLoop& hole_;
  const SurfaceMesherOptions& o_;
  double scale_ = 1.0; ///< size of the hole, for tolerances
  std::vector<int> firstOccurrence_;
  std::vector<P> vertices_;
  std::vector<char> frozen_; ///< on a chart bound: no longer grows
  std::vector<std::vector<int>> polygons_;
  std::vector<int> front_;
  double gridCell_ = 1.0;
  std::optional<PolygonGrid> grid_;
  std::size_t gridded_ = 0;         ///< polygons_[0, gridded_) are in grid_
  mutable P problemAt_ = P::Zero(); ///< where the last failed layer went wrong
};

std::string Mesher::pointName(int loopIndex) const
{
  const int path = hole_.pathIndex.empty() ? loopIndex : hole_.pathIndex[loopIndex];
  const bool twin = !hole_.pathIndex.empty() && firstOccurrence_[loopIndex] != loopIndex;
  return "point " + std::to_string(path) + (twin ? "'" : "");
}

void Mesher::checkHole()
{
  const auto& pts = hole_.points;
  const int n = int(pts.size());
  if (n < 2)
    throw std::invalid_argument("the incision needs at least 2 points");
  if (!hole_.pathIndex.empty() && int(hole_.pathIndex.size()) != n)
    throw std::invalid_argument("the hole loop has " + std::to_string(n) + " points but " +
                                std::to_string(hole_.pathIndex.size()) + " path indices");
  for (int i = 0; i < n; ++i)
    if (!pts[i].allFinite())
      throw std::invalid_argument(pointName(i) + " of the incision is not a number");
  const MeshQualityLimits& q = o_.quality;
  if (!(o_.layerGrowth >= 1.0 && o_.layerGrowth <= 3.0))
    throw std::invalid_argument("layer growth must be between 1 and 3");
  if (!(o_.triangleFillAngle >= 0 && o_.triangleFillAngle < kPi) ||
      !(o_.cornerExpandAngle > 0 && o_.cornerExpandAngle < kPi))
    throw std::invalid_argument("the fill angle t1 and expand angle t2 must lie between 0° and 180°");

  P lo = pts[0], hi = pts[0];
  for (const P& p : pts)
    lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  scale_ = std::max((hi - lo).norm(), 1e-3);
  const double tolerance = 1e-9 * scale_;
  auto twins = [&](int i, int j) {
    return i == j || (!hole_.pathIndex.empty() && hole_.pathIndex[i] == hole_.pathIndex[j]);
  };

  // Points too close along the cut.
  for (int i = 0; i < n; ++i)
  {
    const int j = (i + 1) % n;
    if (n == 2 && i == 1)
      break;
    const double d = (pts[j] - pts[i]).norm();
    if (d < o_.minPointSpacing)
      throw std::invalid_argument(pointName(i) + " and " + pointName(j) + " are " + mm(d) +
                                  " mm apart: move them apart (at least " + mm(o_.minPointSpacing) + " mm)");
  }
  // Sharp turns: the skin between two limbs at b has angle 180° - turn, and
  // every mesh has an element corner no larger than that there.
  if (n >= 3)
  {
    for (int i = 0; i < n; ++i)
    {
      const double turn = turnAngle(pts[(i + n - 1) % n], pts[i], pts[(i + 1) % n]);
      if (kPi - turn < q.minAngle)
        throw std::invalid_argument("the incision turns back too sharply at " + pointName(i) + " (" + deg(kPi - turn) +
                                    " of skin between its limbs): open the angle to at least " + deg(q.minAngle));
    }
  }
  // Crossing: the loop's edges may run along each other (the two sides of a
  // cut) but never cross.
  for (int i = 0; i < n; ++i)
  {
    const int i1 = (i + 1) % n;
    for (int j = i + 1; j < n; ++j)
    {
      const int j1 = (j + 1) % n;
      if (j == i1 || j1 == i)
        continue;
      if (properlyCross(pts[i], pts[i1], pts[j], pts[j1], tolerance))
      {
        const int k = firstOccurrence_[j];
        throw std::invalid_argument("the incision crosses itself near " + pointName(k) +
                                    ": move the points so the cut does not cross itself");
      }
    }
  }
  // Parts of the border that nearly touch (other than a point and its twin).
  for (int i = 0; i < n; ++i)
  {
    for (int j = 0; j < n; ++j)
    {
      const int j1 = (j + 1) % n;
      if (n == 2 && j == 1)
        break;
      if (twins(i, j) || twins(i, j1))
        continue;
      // Edges next to i's neighbours are covered by the spacing check.
      const double d = segmentDistance(pts[i], pts[j], pts[j1]);
      if (d < o_.minPointSpacing && !(twins(j, (i + 1) % n) && twins(j1, (i + n - 1) % n)) &&
          !(twins(j, (i + n - 1) % n) && twins(j1, (i + 1) % n)) && (pts[i] - pts[j]).norm() > tolerance &&
          (pts[i] - pts[j1]).norm() > tolerance)
      {
        throw std::invalid_argument("the incision passes " + mm(d) + " mm from itself at " +
                                    pointName(firstOccurrence_[i]) + ": keep its parts at least " +
                                    mm(o_.minPointSpacing) + " mm apart");
      }
    }
  }
  const double area = signedArea(pts);
  if (area > 1e-6 * scale_ * scale_)
    throw std::invalid_argument(
      "the hole border runs the wrong way round: excised points must move to the left of the cut direction "
      "and their twins (') to the right");
}

double Mesher::chooseFirstLayer() const
{
  const auto& pts = hole_.points;
  const int n = int(pts.size());
  std::vector<double> lengths;
  for (int i = 0; i < (n == 2 ? 1 : n); ++i)
    lengths.push_back((pts[(i + 1) % n] - pts[i]).norm());
  std::sort(lengths.begin(), lengths.end());
  const double shortest = lengths.front(), longest = lengths.back();
  // Hole edges are element edges; first-layer quads with edges over 4 times
  // their thickness would be long slivers, and edges under a third of it
  // would make the merged triangles too sharp.
  if (longest > 12 * shortest)
    throw std::invalid_argument("the incision's points are unevenly spaced (" + mm(shortest) + " to " + mm(longest) +
                                " mm): add points along the long stretches");
  if (o_.firstLayerThickness > 0)
  {
    if (longest > 4 * o_.firstLayerThickness || shortest < o_.firstLayerThickness / 3)
      throw std::invalid_argument("the incision's points are " + mm(shortest) + " to " + mm(longest) +
                                  " mm apart but the elements at the wound are " + mm(o_.firstLayerThickness) +
                                  " mm: space the points between " + mm(o_.firstLayerThickness / 3) + " and " +
                                  mm(4 * o_.firstLayerThickness) + " mm (add points or change the element size)");
    return o_.firstLayerThickness;
  }
  return std::clamp(lengths[lengths.size() / 2], longest / 4, 3 * shortest);
}

bool Mesher::earIsClear(int ia, int ib, int ic) const
{
  const P &a = vertices_[ia], &b = vertices_[ib], &c = vertices_[ic];
  const double tolerance = 1e-9 * scale_;
  const double area2 = cross2(b - a, c - a);
  for (std::size_t k = 0; k < front_.size(); ++k)
  {
    const int id = front_[k];
    if (id == ia || id == ib || id == ic)
      continue;
    const P& p = vertices_[id];
    // A twin sitting on a corner is allowed (Fig. 4.11: both sides of a cut).
    if ((p - a).norm() <= tolerance || (p - b).norm() <= tolerance || (p - c).norm() <= tolerance)
      continue;
    const double t = tolerance * std::sqrt(area2);
    if (cross2(b - a, p - a) >= -t && cross2(c - b, p - b) >= -t && cross2(a - c, p - c) >= -t)
      return false;
  }
  for (std::size_t k = 0; k < front_.size(); ++k)
  {
    const P &e0 = vertices_[front_[k]], &e1 = vertices_[front_[(k + 1) % front_.size()]];
    if (properlyCross(a, c, e0, e1, 1e-9))
      return false;
  }
  return true;
}

// Stage 1 (§4.5.1): at each border vertex v_i+1 turning concavely by more
// than the threshold, add triangle (v_i, v_i+1, v_i+2) and drop v_i+1 from
// the border; repeat until a full pass adds nothing. Beyond the thesis, a
// triangle that would break the shape limits (a 150° corner from a
// concavity just above 30° between unequal edges) is not added: the
// quadrilateral layer handles that concavity with a mitre instead.
int Mesher::fillConcavities(double threshold)
{
  int added = 0;
  bool changed = true;
  while (changed && front_.size() > 3)
  {
    changed = false;
    for (std::size_t i = 0; i < front_.size() && front_.size() > 3;)
    {
      const std::size_t n = front_.size();
      const int ia = front_[(i + n - 1) % n], ib = front_[i], ic = front_[(i + 1) % n];
      const double turn = turnAngle(vertices_[ia], vertices_[ib], vertices_[ic]);
      if (turn > threshold && shapeWithin(polygonShape({vertices_[ia], vertices_[ib], vertices_[ic]}), o_.quality) &&
          earIsClear(ia, ib, ic))
      {
        polygons_.push_back({ia, ib, ic});
        front_.erase(front_.begin() + std::ptrdiff_t(i));
        ++added;
        changed = true;
      }
      else
      {
        ++i;
      }
    }
  }
  return added;
}

int Mesher::newVertex(P p, double thickness)
{
  // A vertex that would leave the scanned range, or end up thinly short of
  // it, goes onto the bound and grows no further there.
  const double snap = 0.4 * thickness;
  bool onBound = false;
  if (p.y() > o_.vMax - snap)
    p.y() = o_.vMax, onBound = true;
  if (p.y() < o_.vMin + snap)
    p.y() = o_.vMin, onBound = true;
  vertices_.push_back(p);
  frozen_.push_back(onBound);
  return int(vertices_.size()) - 1;
}

// Stage 2 (§4.5.1): the new border from offsets of the current one, joined
// to it by quadrilaterals.
std::string Mesher::addLayer(double l, double lNext)
{
  NewLayer layer;
  layer.firstPolygon = polygons_.size();
  layer.firstVertex = int(vertices_.size());
  auto fail = [&](const std::string& problem) {
    polygons_.resize(layer.firstPolygon);
    vertices_.resize(layer.firstVertex);
    frozen_.resize(layer.firstVertex);
    return problem;
  };
  if (std::string problem = offsetFront(l, layer); !problem.empty())
    return fail(problem);
  mergeOrSplitBridges(l, lNext, layer);
  mergeShortRuns(lNext, layer);
  const std::vector<int> newFront = joinLayer(layer);
  splitBentQuadrilaterals(layer.firstPolygon);
  const std::string problem = checkNewPolygons(layer.firstPolygon);
  if (!problem.empty())
    return fail(problem);
  front_ = newFront;
  return {};
}

int Mesher::NewLayer::resolve(int id) const
{
  for (auto it = alias.find(id); it != alias.end(); it = alias.find(id))
    id = it->second;
  return id;
}

// Substage 1: the new border vertices of each border vertex.
std::string Mesher::offsetFront(double l, NewLayer& layer)
{
  const std::size_t n = front_.size();
  const double expandTurn = kPi - o_.cornerExpandAngle;
  layer.offspring.assign(n, {});
  for (std::size_t i = 0; i < n; ++i)
  {
    const int v = front_[i];
    if (frozen_[v])
    {
      layer.offspring[i] = {v};
      continue;
    }
    // Copies: newVertex() grows vertices_ and would leave references dangling.
    const P a = vertices_[front_[(i + n - 1) % n]], p = vertices_[v], c = vertices_[front_[(i + 1) % n]];
    const P n1 = leftNormal(p - a), n2 = leftNormal(c - p);
    const double turn = turnAngle(a, p, c);
    if (-turn > expandTurn + 1e-9)
    {
      // Expanded vertex: a fan of corner quadrilaterals (kites) from n1 round
      // to n2. The thesis adds one, with vertices p + l n1, p + l(n1 + n2),
      // p + l n2; a turn of 180° (the end of a cut, n1 = -n2) needs two.
      const int sectors = std::max(1, int(std::lround(-turn / (kPi / 2))));
      const double sector = -turn / sectors;
      const double base = std::atan2(n1.y(), n1.x());
      std::vector<int> fan;
      for (int j = 0; j <= 2 * sectors; ++j)
      {
        const double angle = base - j * sector / 2;
        const double r = j % 2 == 0 ? l : l / std::cos(sector / 2);
        fan.push_back(newVertex(p + r * P(std::cos(angle), std::sin(angle)), l));
      }
      for (int s = 0; s < sectors; ++s)
        polygons_.push_back({v, fan[2 * s + 2], fan[2 * s + 1], fan[2 * s]});
      layer.offspring[i] = fan;
    }
    else
    {
      // Mitre: the offset lines of both edges meet at distance l / cos(turn/2).
      const double denominator = 1 + n1.dot(n2);
      if (denominator < 0.1)
        return problemAt_ = p, "the border turns back on itself at " + at(p);
      layer.offspring[i] = {newVertex(p + l * (n1 + n2) / denominator, l)};
    }
  }
  return {};
}

// New border edges between the offspring of neighbours ("bridges"): merge
// the ends of one that has become short or reversed (a concave corner, or
// short edges under a thick layer), split one that has grown long (round a
// convex corner), so the next layer's quadrilaterals keep their shape.
void Mesher::mergeOrSplitBridges(double l, double lNext, NewLayer& layer)
{
  const std::size_t n = front_.size();
  const auto& offspring = layer.offspring;
  std::vector<char> merged(vertices_.size() + n, 0);
  layer.midpoint.assign(n, -1);
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::size_t i1 = (i + 1) % n;
    const int x = offspring[i].back(), y = offspring[i1].front();
    if (x < layer.firstVertex || y < layer.firstVertex || x == y)
      continue;
    const P edge = vertices_[front_[i1]] - vertices_[front_[i]];
    const P bridge = vertices_[y] - vertices_[x];
    const double along = bridge.dot(edge.normalized());
    const bool single = offspring[i].size() == 1 && offspring[i1].size() == 1;
    if (single && along < 0.5 * lNext && !merged[x] && !merged[y])
    {
      P m = 0.5 * (vertices_[x] + vertices_[y]);
      if (frozen_[y] && !frozen_[x])
        m = vertices_[y];
      if (frozen_[x] && !frozen_[y])
        m = vertices_[x];
      vertices_[x] = m;
      frozen_[x] = frozen_[x] || frozen_[y];
      layer.alias[y] = x;
      merged[x] = merged[y] = 1;
    }
    else if (bridge.norm() > 3.0 * lNext && bridge.norm() > 1.3 * edge.norm() && !frozen_[x] && !frozen_[y])
    {
      layer.midpoint[i] = newVertex(0.5 * (vertices_[x] + vertices_[y]), l);
      if (frozen_.back())
      { // a split point must not be pulled off the line
        vertices_.pop_back();
        frozen_.pop_back();
        layer.midpoint[i] = -1;
      }
    }
  }
}

// Merging every other short bridge leaves short edges where several come
// in a row (a concave bend of the border): the next layer would build
// slivers on them. Merge their ends as well, a few passes, each vertex
// once per pass, so edges double until they are long enough. The corner
// fans keep their vertices (their kites are already built).
void Mesher::mergeShortRuns(double lNext, NewLayer& layer)
{
  const std::size_t n = front_.size();
  const auto& offspring = layer.offspring;
  const auto& midpoint = layer.midpoint;
  std::vector<char> single(vertices_.size(), 0);
  for (std::size_t i = 0; i < n; ++i)
  {
    if (offspring[i].size() == 1 && offspring[i][0] >= layer.firstVertex)
      single[std::size_t(offspring[i][0])] = 1;
    if (midpoint[i] >= 0)
      single[std::size_t(midpoint[i])] = 1;
  }
  for (int pass = 0; pass < 4; ++pass)
  {
    std::vector<int> ring;
    for (std::size_t i = 0; i < n; ++i)
    {
      for (int id : offspring[i])
        if (ring.empty() || ring.back() != layer.resolve(id))
          ring.push_back(layer.resolve(id));
      if (midpoint[i] >= 0)
        ring.push_back(layer.resolve(midpoint[i]));
    }
    while (ring.size() > 1 && ring.front() == ring.back())
      ring.pop_back();
    std::vector<char> touched(vertices_.size(), 0);
    bool any = false;
    for (std::size_t k = 0; k < ring.size() && ring.size() > 4; ++k)
    {
      const int x = ring[k], y = ring[(k + 1) % ring.size()];
      if (x == y || !single[std::size_t(x)] || !single[std::size_t(y)] || touched[std::size_t(x)] ||
          touched[std::size_t(y)] || (frozen_[x] && frozen_[y]))
        continue;
      if ((vertices_[x] - vertices_[y]).norm() >= 0.4 * lNext)
        continue;
      vertices_[x] = frozen_[y] ? vertices_[y] : frozen_[x] ? vertices_[x] : P(0.5 * (vertices_[x] + vertices_[y]));
      frozen_[x] = frozen_[x] || frozen_[y];
      layer.alias[y] = x;
      touched[std::size_t(x)] = touched[std::size_t(y)] = 1;
      any = true;
    }
    if (!any)
      break;
  }
}

// Substage 2: a quadrilateral (v_i, v_i+1, new_i+1, new_i) per border edge,
// counter-clockwise; repeated vertices (frozen or merged) make it a triangle.
// Returns the new border.
std::vector<int> Mesher::joinLayer(const NewLayer& layer)
{
  const std::size_t n = front_.size();
  const auto& offspring = layer.offspring;
  const auto& midpoint = layer.midpoint;
  const auto resolve = [&layer](int id) { return layer.resolve(id); };
  std::vector<int> newFront;
  for (std::size_t i = 0; i < n; ++i)
  {
    const std::size_t i1 = (i + 1) % n;
    const int a = front_[i], b = front_[i1];
    const int x = resolve(offspring[i].back()), y = resolve(offspring[i1].front());
    std::vector<std::vector<int>> pieces;
    if (midpoint[i] >= 0)
    {
      const int m = resolve(midpoint[i]);
      pieces.push_back({a, b, m, x});
      pieces.push_back({b, y, m});
    }
    else
    {
      pieces.push_back({a, b, y, x});
    }
    for (auto& piece : pieces)
    {
      std::vector<int> polygon;
      for (int id : piece)
        if (polygon.empty() || polygon.back() != id)
          polygon.push_back(id);
      while (polygon.size() > 1 && polygon.front() == polygon.back())
        polygon.pop_back();
      if (polygon.size() >= 3)
        polygons_.push_back(polygon);
    }
    for (int id : offspring[i])
    {
      id = resolve(id);
      if (newFront.empty() || newFront.back() != id)
        newFront.push_back(id);
    }
    if (midpoint[i] >= 0 && newFront.back() != resolve(midpoint[i]))
      newFront.push_back(resolve(midpoint[i]));
  }
  while (newFront.size() > 1 && newFront.front() == newFront.back())
    newFront.pop_back();
  return newFront;
}

// A quadrilateral bent out of shape where the border bends (a corner near
// 180°, or too long for its width) becomes two good triangles if one of its
// diagonals gives them; checkNewPolygons() judges the rest.
void Mesher::splitBentQuadrilaterals(std::size_t firstPolygon)
{
  for (std::size_t k = firstPolygon, end = polygons_.size(); k < end; ++k)
  {
    const std::vector<int> q = polygons_[k];
    if (q.size() != 4 || shapeWithin(polygonShape(corners(vertices_, q)), o_.quality))
      continue;
    double best = -1;
    std::array<std::vector<int>, 2> split;
    for (const auto& pair : {std::array<std::vector<int>, 2>{{{q[0], q[1], q[2]}, {q[0], q[2], q[3]}}},
                             std::array<std::vector<int>, 2>{{{q[0], q[1], q[3]}, {q[1], q[2], q[3]}}}})
    {
      const Shape s0 = polygonShape(corners(vertices_, pair[0])), s1 = polygonShape(corners(vertices_, pair[1]));
      if (shapeWithin(s0, o_.quality) && shapeWithin(s1, o_.quality) && std::min(s0.minAngle, s1.minAngle) > best)
        best = std::min(s0.minAngle, s1.minAngle), split = pair;
    }
    if (best < 0)
      continue;
    polygons_[k] = split[0];
    polygons_.push_back(split[1]);
  }
}

void Mesher::rebuildGrid()
{
  grid_.emplace(gridCell_);
  for (std::size_t k = 0; k < polygons_.size(); ++k)
    grid_->insert(int(k), corners(vertices_, polygons_[k]));
  gridded_ = polygons_.size();
}

std::string Mesher::checkNewPolygons(std::size_t firstNew) const
{
  const double tolerance = 1e-9 * scale_;
  PolygonGrid local(gridCell_);
  for (std::size_t k = firstNew; k < polygons_.size(); ++k)
  {
    const std::vector<P> pts = corners(vertices_, polygons_[k]);
    P centre = P::Zero();
    for (const P& p : pts)
      centre += p / double(pts.size());
    problemAt_ = centre;
    if (!shapeWithin(polygonShape(pts), o_.quality))
      return "a badly shaped element would appear at " + at(centre);
    for (int other : grid_->candidates(pts))
      if (std::size_t(other) < gridded_ && convexOverlap(pts, corners(vertices_, polygons_[other]), tolerance))
        return "the mesh would overlap itself at " + at(centre);
    for (int other : local.candidates(pts))
      if (convexOverlap(pts, corners(vertices_, polygons_[other]), tolerance))
        return "the mesh would overlap itself at " + at(centre);
    local.insert(int(k), pts);
  }
  return {};
}

SurfaceMesh Mesher::finish() const
{
  // Drop vertices that merging left unused, keeping the hole loop first.
  const int holeCount = int(hole_.points.size());
  std::vector<int> used(vertices_.size(), 0);
  for (int i = 0; i < holeCount; ++i)
    used[i] = 1;
  for (const auto& polygon : polygons_)
    for (int id : polygon)
      used[id] = 1;
  std::vector<int> index(vertices_.size(), -1);
  SurfaceMesh mesh;
  for (std::size_t i = 0; i < vertices_.size(); ++i)
    if (used[i])
      index[i] = int(mesh.vertices.size()), mesh.vertices.push_back(vertices_[i]);
  for (const auto& polygon : polygons_)
  {
    std::vector<int> renumbered;
    for (int id : polygon)
      renumbered.push_back(index[id]);
    mesh.polygons.push_back(renumbered);
  }
  mesh.holeVertexCount = holeCount;
  // The front is clockwise round the meshed region; the rim is its reverse.
  for (auto it = front_.rbegin(); it != front_.rend(); ++it)
    mesh.outerBorder.push_back(index[*it]);
  return mesh;
}

SurfaceMesherResult Mesher::run()
{
  const int n = int(hole_.points.size());
  firstOccurrence_.resize(n);
  {
    std::map<int, int> first;
    for (int i = 0; i < n; ++i)
    {
      const int path =
        hole_.pathIndex.empty() ? i : hole_.pathIndex[std::min<std::size_t>(i, hole_.pathIndex.size() - 1)];
      firstOccurrence_[i] = first.emplace(path, i).first->second;
    }
  }
  checkHole();
  const double l1 = chooseFirstLayer();
  for (int i = 0; i < n; ++i)
  {
    const double v = hole_.points[i].y();
    if (v > o_.vMax - 0.5 * l1 || v < o_.vMin + 0.5 * l1)
    {
      const bool top = v > o_.vMax - 0.5 * l1;
      throw std::invalid_argument("the incision reaches within " + mm(std::max(0.0, top ? o_.vMax - v : v - o_.vMin)) +
                                  " mm of the " + (top ? "top" : "bottom") + " of the scanned range at " +
                                  pointName(firstOccurrence_[i]) + ": keep it at least " + mm(0.5 * l1) + " mm inside");
    }
  }

  // Layer thicknesses l1 g^k; with a region radius, as many as reach it,
  // scaled to reach it exactly.
  std::vector<double> thickness;
  if (o_.regionRadius > 0)
  {
    double sum = 0;
    for (double l = l1; sum < o_.regionRadius - 1e-9 && thickness.size() < 200; l *= o_.layerGrowth)
      thickness.push_back(l), sum += l;
    for (double& l : thickness)
      l *= o_.regionRadius / sum;
  }
  else
  {
    for (int k = 0; k < o_.layerCount; ++k)
      thickness.push_back(l1 * std::pow(o_.layerGrowth, k));
  }

  vertices_ = hole_.points;
  frozen_.assign(n, 0);
  front_.resize(n);
  for (int i = 0; i < n; ++i)
    front_[i] = i;
  gridCell_ = 2 * l1;

  SurfaceMesherResult result;
  result.layersPlanned = int(thickness.size());
  result.stageOneTriangles = fillConcavities(o_.triangleFillAngle);

  for (std::size_t k = 0; k < thickness.size(); ++k)
  {
    if (k > 0)
      fillConcavities(o_.triangleFillAngle);
    rebuildGrid();
    const double l = thickness[k];
    const double lNext = k + 1 < thickness.size() ? thickness[k + 1] : l * o_.layerGrowth;
    std::string problem = addLayer(l, lNext);
    if (!problem.empty())
    {
      // Retry with every concavity filled (a curled cut whose arms would meet),
      // then at half thickness.
      fillConcavities(5.0 * kPi / 180.0);
      rebuildGrid();
      problem = addLayer(l, lNext);
      if (!problem.empty() && addLayer(0.5 * l, lNext).empty())
        problem.clear(), result.reach -= 0.5 * l;
    }
    if (!problem.empty() && k == 0)
    {
      // Not even one layer: the skin between parts of the cut is too narrow.
      int nearest = 0;
      for (int i = 1; i < n; ++i)
        if ((hole_.points[i] - problemAt_).norm() < (hole_.points[nearest] - problemAt_).norm())
          nearest = i;
      throw std::invalid_argument("the incision curls too tightly round itself near " +
                                  pointName(firstOccurrence_[nearest]) +
                                  " to mesh the skin between its turns: open the curve or move the points apart");
    }
    if (!problem.empty())
    {
      result.stoppedEarly = true;
      result.message = "the mesh stops " + mm(result.reach) + " mm from the wound after " + std::to_string(k) + " of " +
                       std::to_string(thickness.size()) + " layers: " + problem;
      break;
    }
    result.reach += l;
    ++result.layersBuilt;
  }
  for (int id : front_)
    result.reachedChartBound = result.reachedChartBound || frozen_[id];
  if (result.reachedChartBound && result.message.empty())
    result.message = "the mesh reaches the edge of the scanned range and stops there";
  result.mesh = finish();
  result.quality = surfaceMeshQuality(result.mesh, o_.quality);
  return result;
}

} // namespace

HoleLoop holeLoopFromCutPath(const std::vector<ChartPoint>& cutPath)
{
  const int n = int(cutPath.size());
  if (n < 2)
    throw std::invalid_argument("the incision needs at least 2 points");
  HoleLoop hole;
  for (int i = 0; i < n; ++i)
    hole.points.push_back(cutPath[i]), hole.pathIndex.push_back(i);
  for (int i = n - 2; i >= 1; --i)
    hole.points.push_back(cutPath[i]), hole.pathIndex.push_back(i);
  return hole;
}

RefinedCutPath refineCutPath(const std::vector<ChartPoint>& cutPath, double maxSpacing)
{
  if (!(maxSpacing > 0))
    throw std::invalid_argument("the point spacing must be positive");
  RefinedCutPath refined;
  for (std::size_t i = 0; i < cutPath.size(); ++i)
  {
    if (i > 0)
    {
      const int parts = std::max(1, int(std::ceil((cutPath[i] - cutPath[i - 1]).norm() / maxSpacing - 1e-9)));
      for (int k = 1; k < parts; ++k)
        refined.points.push_back(cutPath[i - 1] + (cutPath[i] - cutPath[i - 1]) * (double(k) / parts));
    }
    refined.originalIndex.push_back(int(refined.points.size()));
    refined.points.push_back(cutPath[i]);
  }
  return refined;
}

SurfaceMesherResult meshAroundHole(const HoleLoop& hole, const SurfaceMesherOptions& options)
{
  return Mesher(hole, options).run();
}

SurfaceMeshQuality surfaceMeshQuality(const SurfaceMesh& mesh, const MeshQualityLimits& limits)
{
  SurfaceMeshQuality q;
  q.vertexCount = int(mesh.vertices.size());
  q.minAngle = 2 * kPi;
  constexpr int kMaxPerKind = 5;
  std::map<std::string, int> reported;
  auto problem = [&](const std::string& kind, const std::string& text) {
    if (reported[kind]++ < kMaxPerKind)
      q.problems.push_back(text);
  };
  const int vertexCount = int(mesh.vertices.size());
  double longestEdge = 0;
  std::vector<std::vector<P>> shapes;
  for (std::size_t k = 0; k < mesh.polygons.size(); ++k)
  {
    const auto& polygon = mesh.polygons[k];
    const std::string name = "polygon " + std::to_string(k);
    bool indicesOk = polygon.size() == 3 || polygon.size() == 4;
    for (int id : polygon)
      indicesOk = indicesOk && id >= 0 && id < vertexCount;
    if (!indicesOk)
    {
      problem("index", name + " has bad vertex indices or is not a triangle or quadrilateral");
      shapes.emplace_back();
      continue;
    }
    (polygon.size() == 3 ? q.triangleCount : q.quadCount)++;
    const std::vector<P> pts = corners(mesh.vertices, polygon);
    const Shape s = polygonShape(pts);
    q.meshArea += s.area;
    q.minAngle = std::min(q.minAngle, s.minAngle);
    q.maxAngle = std::max(q.maxAngle, s.maxAngle);
    q.maxAspectRatio = std::max(q.maxAspectRatio, s.aspect);
    for (std::size_t i = 0; i < pts.size(); ++i)
      longestEdge = std::max(longestEdge, (pts[(i + 1) % pts.size()] - pts[i]).norm());
    if (!s.convexCcw)
      problem("convex", name + " is not convex and counter-clockwise (area " + std::to_string(s.area) + ")");
    if (s.minAngle < limits.minAngle)
      problem("min", name + " has a " + deg(s.minAngle) + " corner");
    if (s.maxAngle > limits.maxAngle)
      problem("max", name + " has a " + deg(s.maxAngle) + " corner");
    if (s.aspect > limits.maxAspectRatio)
      problem("aspect", name + " has aspect ratio " + std::to_string(s.aspect));
    shapes.push_back(pts);
  }
  if (mesh.polygons.empty())
    q.minAngle = 0;

  // Overlap through a grid sized by the polygons.
  const double scale = std::max(longestEdge, 1e-6);
  PolygonGrid grid(scale);
  for (std::size_t k = 0; k < shapes.size(); ++k)
  {
    if (shapes[k].empty())
      continue;
    for (int other : grid.candidates(shapes[k]))
      if (convexOverlap(shapes[k], shapes[other], 1e-9 * scale))
        problem("overlap", "polygons " + std::to_string(other) + " and " + std::to_string(k) + " overlap");
    grid.insert(int(k), shapes[k]);
  }

  // Conformity: directed edges. Interior edges appear once each way; hole and
  // rim edges once, in loop direction (hole clockwise, rim counter-clockwise,
  // both with the skin on their left, as every CCW polygon edge has).
  auto key = [](int a, int b) { return (long long)a << 32 | (unsigned)b; };
  std::unordered_map<long long, int> uses;
  for (const auto& polygon : mesh.polygons)
    for (std::size_t i = 0; i < polygon.size(); ++i)
      uses[key(polygon[i], polygon[(i + 1) % polygon.size()])]++;
  std::unordered_set<long long> border;
  const int h = mesh.holeVertexCount;
  for (int i = 0; i < h && h >= 2; ++i)
    border.insert(key(i, (i + 1) % h));
  const int r = int(mesh.outerBorder.size());
  for (int i = 0; i < r; ++i)
    border.insert(key(mesh.outerBorder[i], mesh.outerBorder[(i + 1) % r]));
  for (const auto& [edge, count] : uses)
  {
    const int a = int(edge >> 32), b = int(edge & 0xffffffff);
    const std::string name = "edge " + std::to_string(a) + "-" + std::to_string(b);
    if (count > 1)
      problem("edge", name + " is used by " + std::to_string(count) + " polygons the same way");
    else if (!border.count(edge) && !uses.count(key(b, a)))
      problem("edge", name + " has a polygon on one side only (a gap or a hanging vertex)");
  }
  for (long long edge : border)
    if (!uses.count(edge))
      problem("edge", "border edge " + std::to_string(edge >> 32) + "-" + std::to_string(edge & 0xffffffff) +
                        " belongs to no polygon");

  // Coverage: the polygons fill the region between hole and rim.
  std::vector<P> holePts(mesh.vertices.begin(), mesh.vertices.begin() + std::min(h, vertexCount));
  std::vector<P> rimPts;
  for (int id : mesh.outerBorder)
    if (id >= 0 && id < vertexCount)
      rimPts.push_back(mesh.vertices[id]);
  q.holeArea = holePts.size() >= 3 ? -signedArea(holePts) : 0.0;
  q.outerArea = rimPts.size() >= 3 ? signedArea(rimPts) : 0.0;
  const double expected = q.outerArea - q.holeArea;
  if (std::abs(q.meshArea - expected) > 1e-6 * std::max(1.0, q.outerArea))
    problem("area", "the polygons cover " + std::to_string(q.meshArea) +
                      " mm² but the region between hole and rim is " + std::to_string(expected) + " mm²");
  return q;
}

} // namespace caps::fem
