#include "fem/InteriorNodeOptimization.h"

#include "fem/ContinuumMesher.h"
#include "fem/ElementQuality.h"
#include "fem/ElementShape.h"
#include "fem/Quadrature.h"

#include <nlopt.h>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace caps::fem {

namespace {

/// Regularisation of the scaled Jacobian (Escobar et al. 2003): small
/// against the limit of 0.2, large enough to keep the objective finite and
/// smooth through an inverted corner.
constexpr double kDelta = 1e-2;

/// A mid-edge node that is put at the middle of its edge once an end moves.
using RecentredMids = std::map<int, std::pair<int, int>>;

/// One row of a Jacobian as a sum of weighted node positions.
struct Term
{
  int node = -1;
  double weight = 0.0;
};

/// The Jacobian of an element at one point (a node, or a point of the
/// 2 x 2 x 2 rule), from its own (quadratic) shape functions, with the
/// mid-edge nodes that will be recentred written as the middles of their
/// edges: row k is dx/d(r, s, t)_k.
struct JacobianSample
{
  std::array<std::vector<Term>, 3> rows;
  ElementKind kind = ElementKind::Hex20;
  int element = -1;
};

/// The scaled Jacobian of the map with Jacobian @a j, as ElementQuality.h
/// defines it.
double scaledJacobian(const Eigen::Matrix3d& j, ElementKind kind)
{
  const double det = j.determinant();
  if (kind == ElementKind::Wedge15)
  {
    const Eigen::Vector3d a = j.row(0), b = j.row(1), c = b - a;
    const double widest = std::max({a.norm() * b.norm(), a.norm() * c.norm(), b.norm() * c.norm()});
    const double scale = widest * j.row(2).norm();
    return scale > 0.0 ? 2.0 / std::sqrt(3.0) * det / scale : 0.0;
  }
  const double scale = j.row(0).norm() * j.row(1).norm() * j.row(2).norm();
  return scale > 0.0 ? det / scale : 0.0;
}

double scaledJacobian(const JacobianSample& f, const Eigen::Matrix3Xd& x)
{
  Eigen::Matrix3d j = Eigen::Matrix3d::Zero();
  for (int k = 0; k < 3; ++k)
    for (const Term& t : f.rows[std::size_t(k)])
      j.row(k) += t.weight * x.col(t.node).transpose();
  return scaledJacobian(j, f.kind);
}

double sampleCost(double sigma)
{
  const double h = 0.5 * (sigma + std::sqrt(sigma * sigma + 4.0 * kDelta * kDelta));
  return 1.0 / (h * h);
}

/// The Jacobians of every element at its nodes and the points of the
/// 2 x 2 x 2 rule, on the nodes' representatives; nodes where a degenerate
/// brick collapses (a node shared by two slots) are left out.
std::vector<JacobianSample> jacobianSamples(const Mesh& mesh, const std::vector<int>& representative,
                                            const RecentredMids& recentred)
{
  std::vector<JacobianSample> frames;
  ShapeVector h;
  ShapeDerivatives dh;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Element& el = mesh.elements[e];
    const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
    std::vector<Eigen::Vector3d> points;
    for (int slot = 0; slot < kHex20NodeCount; ++slot)
      if (shape.hasNode(slot) && std::count(el.nodes.begin(), el.nodes.end(), el.nodes[std::size_t(slot)]) == 1)
        points.push_back(shape.naturalCoordinates(slot));
    for (const Eigen::Vector3d& rst : integrationRule(el.kind, 2).points)
      points.push_back(rst);
    for (const Eigen::Vector3d& rst : points)
    {
      shape.evaluate(rst, h, dh);
      JacobianSample f;
      f.kind = el.kind;
      f.element = int(e);
      for (int k = 0; k < 3; ++k)
      {
        std::map<int, double> weights;
        for (int s = 0; s < kHex20NodeCount; ++s)
        {
          const int node = el.nodes[std::size_t(s)];
          if (node < 0 || dh(s, k) == 0.0)
            continue;
          const auto mid = recentred.find(representative[std::size_t(node)]);
          if (mid == recentred.end())
            weights[representative[std::size_t(node)]] += dh(s, k);
          else
          {
            weights[mid->second.first] += 0.5 * dh(s, k);
            weights[mid->second.second] += 0.5 * dh(s, k);
          }
        }
        for (const auto& [node, weight] : weights)
          if (std::abs(weight) > 1e-12)
            f.rows[std::size_t(k)].push_back({node, weight});
      }
      frames.push_back(std::move(f));
    }
  }
  return frames;
}

/// Nodes at the same place are one point of the body split for a reason
/// (the two sides of an undermined plane): they move as one. Each node's
/// representative is the smallest index at its position.
std::vector<int> coincidentRepresentatives(const Eigen::Matrix3Xd& x)
{
  std::map<std::array<double, 3>, int> first;
  std::vector<int> representative(std::size_t(x.cols()));
  for (Eigen::Index n = 0; n < x.cols(); ++n)
    representative[std::size_t(n)] = first.try_emplace({x(0, n), x(1, n), x(2, n)}, int(n)).first->second;
  return representative;
}

/// One movable node: the plane it moves in and the frames around it.
struct MovableNode
{
  int node = -1; ///< a representative
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d u = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero(); ///< across the column
  double reach = 0.0;                                                       ///< bound of the move in u and v (mm)
  double shortestEdge = 0.0;                                                ///< mm
  std::vector<int> frames;                                                  ///< the frames it moves, grouped by element
  std::vector<int> frameElement; ///< for each of frames, its element's local index
  int elementCount = 0;
  /// On the deep surface: it moves by its chart point (u, v the chart's
  /// axes), and so do the mid-edge nodes of its deep edges.
  bool deep = false;
  int vertex = -1;
  ChartPoint chartOrigin = ChartPoint::Zero();
  std::vector<int> deepEdges;
};

/// A mid-edge node of the deep surface (by representative) and its edge's
/// two vertices.
struct DeepEdge
{
  int mid = -1;
  int a = -1, b = -1;
};

/// Where the deep surface's vertices are in the chart as they slide.
struct DeepState
{
  const DeepSurface* surface = nullptr;
  std::vector<ChartPoint> chart; ///< by vertex
  std::vector<DeepEdge> edges;
};

/// The deepest node of vertex @a v's column, @a n, as a node that slides on
/// the deep surface, unless held or taken.
void addDeepNode(const ContinuumMesh& c, std::size_t v, int n, const DeepState& deep, const std::vector<int>& edgesOfV,
                 const std::set<int>& heldPoints, std::set<int>& taken, std::vector<MovableNode>& movable)
{
  if (heldPoints.count(n) || !taken.insert(n).second)
    return;
  MovableNode m;
  m.node = n;
  m.origin = c.mesh.nodes.col(n);
  m.deep = true;
  m.vertex = int(v);
  m.chartOrigin = deep.chart[v];
  m.u = Eigen::Vector3d::UnitX();
  m.v = Eigen::Vector3d::UnitY();
  double shortestChart = std::numeric_limits<double>::infinity();
  m.shortestEdge = std::numeric_limits<double>::infinity();
  for (int e : edgesOfV)
  {
    const auto& edge = c.edges[std::size_t(e)];
    const int other = edge[0] == int(v) ? edge[1] : edge[0];
    shortestChart = std::min(shortestChart, (deep.chart[v] - deep.chart[std::size_t(other)]).norm());
    m.shortestEdge =
      std::min(m.shortestEdge, (m.origin - c.mesh.nodes.col(c.vertexColumns[std::size_t(other)].back())).norm());
  }
  for (std::size_t k = 0; k < deep.edges.size(); ++k)
    if (deep.edges[k].a == int(v) || deep.edges[k].b == int(v))
      m.deepEdges.push_back(int(k));
  if (!std::isfinite(shortestChart) || shortestChart <= 0.0 || !(m.shortestEdge > 0.0))
    return;
  m.reach = 0.5 * shortestChart;
  movable.push_back(std::move(m));
}

/// The movable nodes of @a c: the inner layer boundaries' corner nodes
/// (by representative) of the columns under vertices not @a held.
std::vector<MovableNode> movableNodes(const ContinuumMesh& c, const std::vector<char>& held,
                                      const std::vector<int>& representative, const DeepState& deep)
{
  std::set<int> heldPoints; // anything of a held column stays, with whatever coincides with it
  for (std::size_t v = 0; v < c.vertexColumns.size(); ++v)
    if (held[v])
      for (int n : c.vertexColumns[v])
        heldPoints.insert(representative[std::size_t(n)]);
  std::vector<std::vector<int>> edgesOfVertex(c.vertexColumns.size());
  for (std::size_t e = 0; e < c.edges.size(); ++e)
    for (int v : c.edges[e])
      edgesOfVertex[std::size_t(v)].push_back(int(e));
  const Eigen::Matrix3Xd& x = c.mesh.nodes;
  std::vector<MovableNode> movable;
  std::set<int> taken;
  for (std::size_t v = 0; v < c.vertexColumns.size(); ++v)
  {
    const std::vector<int>& column = c.vertexColumns[v];
    const int layers = int(column.size() - 1) / 2;
    const Eigen::Vector3d along = x.col(column.front()) - x.col(column.back());
    if (held[v] || along.norm() <= 0.0)
      continue;
    const Eigen::Vector3d w = along.normalized();
    const Eigen::Vector3d u =
      (std::abs(w.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(w).normalized();
    for (int level = 1; level < layers; ++level)
    {
      const int n = representative[std::size_t(column[std::size_t(2 * level)])];
      if (heldPoints.count(n) || !taken.insert(n).second)
        continue;
      double shortest = std::numeric_limits<double>::infinity();
      for (int e : edgesOfVertex[v])
      {
        const auto& edge = c.edges[std::size_t(e)];
        const auto& other = c.vertexColumns[std::size_t(edge[0] == int(v) ? edge[1] : edge[0])];
        if (other.size() > std::size_t(2 * level))
          shortest = std::min(shortest, (x.col(n) - x.col(other[std::size_t(2 * level)])).norm());
      }
      if (!std::isfinite(shortest) || shortest <= 0.0)
        continue;
      MovableNode m;
      m.node = n;
      m.origin = x.col(n);
      m.u = u;
      m.v = w.cross(u);
      m.shortestEdge = shortest;
      m.reach = std::max(shortest, along.norm());
      movable.push_back(std::move(m));
    }
    if (deep.surface)
      addDeepNode(c, v, representative[std::size_t(column.back())], deep, edgesOfVertex[v], heldPoints, taken, movable);
  }
  return movable;
}

/// The mid-edge nodes (by representative) on an edge with an end in
/// @a moving, each with its edge's ends: the vertical edges of the columns
/// and the edges of the inner layer boundaries (and of the deepest level
/// unless it is curved on the deep surface).
RecentredMids recentredMids(const ContinuumMesh& c, const std::vector<int>& representative, const std::set<int>& moving,
                            bool deepSurfaceCurved)
{
  RecentredMids mids;
  const auto add = [&](int mid, int a, int b) {
    if (mid < 0 || a < 0 || b < 0)
      return;
    const int ra = representative[std::size_t(a)], rb = representative[std::size_t(b)];
    if (moving.count(ra) || moving.count(rb))
      mids[representative[std::size_t(mid)]] = {ra, rb};
  };
  for (const auto& column : c.vertexColumns)
    for (std::size_t i = 1; i + 1 < column.size(); i += 2)
      add(column[i], column[i - 1], column[i + 1]);
  for (std::size_t e = 0; e < c.edges.size() && e < c.edgeColumns.size(); ++e)
  {
    const auto& columnA = c.vertexColumns[std::size_t(c.edges[e][0])];
    const auto& columnB = c.vertexColumns[std::size_t(c.edges[e][1])];
    const auto& mid = c.edgeColumns[e];
    for (std::size_t level = 0; level < mid.size(); ++level)
      if (2 * level < columnA.size() && 2 * level < columnB.size() &&
          !(deepSurfaceCurved && level + 1 == mid.size())) // those follow the deep surface
        add(mid[level], columnA[2 * level], columnB[2 * level]);
  }
  return mids;
}

/// One node's problem: the frames around it, grouped by element, each
/// element with the floor its worst point must stay above (its own worst
/// before, or the acceptable value if that is lower).
struct LocalProblem
{
  Eigen::Matrix3Xd* x = nullptr;
  const std::vector<JacobianSample>* frames = nullptr;
  const MovableNode* node = nullptr;
  DeepState* deep = nullptr;
  std::vector<double> floors; ///< by MovableNode::frameElement
  mutable std::vector<double> worst;
  bool offTheSurface = false; ///< the deep surface has no point there

  void place(const double* uv)
  {
    if (!node->deep)
    {
      x->col(node->node) = node->origin + uv[0] * node->u + uv[1] * node->v;
      return;
    }
    const ChartPoint c = node->chartOrigin + ChartPoint(uv[0], uv[1]);
    try
    {
      const Eigen::Vector3d p = deep->surface->pointUnder(c);
      std::vector<std::pair<int, Eigen::Vector3d>> mids;
      for (int k : node->deepEdges)
      {
        const DeepEdge& e = deep->edges[std::size_t(k)];
        const int other = e.a == node->vertex ? e.b : e.a;
        mids.emplace_back(e.mid, deep->surface->pointUnder(0.5 * (c + deep->chart[std::size_t(other)])));
      }
      offTheSurface = !p.allFinite();
      for (const auto& [mid, q] : mids)
        offTheSurface = offTheSurface || !q.allFinite();
      if (offTheSurface)
        return;
      x->col(node->node) = p;
      for (const auto& [mid, q] : mids)
        x->col(mid) = q;
      deep->chart[std::size_t(node->vertex)] = c;
    }
    catch (const std::exception&)
    {
      offTheSurface = true;
    }
  }
  /// The smoothing cost, and a steep penalty for any element pushed below
  /// its floor (so the worst element of the mesh never gets worse); fills
  /// worst.
  double cost() const
  {
    if (offTheSurface)
      return 1e12;
    worst.assign(std::size_t(node->elementCount), std::numeric_limits<double>::infinity());
    double sum = 0.0;
    for (std::size_t i = 0; i < node->frames.size(); ++i)
    {
      const double sigma = scaledJacobian((*frames)[std::size_t(node->frames[i])], *x);
      sum += sampleCost(sigma);
      double& w = worst[std::size_t(node->frameElement[i])];
      w = std::min(w, sigma);
    }
    for (std::size_t k = 0; k < floors.size(); ++k)
      if (worst[k] < floors[k])
        sum += 1e6 * (1.0 + floors[k] - worst[k]);
    return sum;
  }
  bool withinFloors() const
  {
    if (offTheSurface)
      return false;
    cost();
    for (std::size_t k = 0; k < floors.size(); ++k)
      if (worst[k] < floors[k])
        return false;
    return true;
  }
};

double localCost(unsigned n, const double* uv, double* gradient, void* data)
{
  (void)n;
  (void)gradient; // BOBYQA is derivative-free
  auto* problem = static_cast<LocalProblem*>(data);
  problem->place(uv);
  return problem->cost();
}

/// Best place for one node (BOBYQA in the plane across its column); how
/// far it moved (mm), 0 if the move was not kept.
double relaxNode(const MovableNode& m, Eigen::Matrix3Xd& x, const std::vector<JacobianSample>& frames, DeepState& deep,
                 const InteriorNodeOptions& options)
{
  LocalProblem problem{&x, &frames, &m, &deep, {}, {}};
  const double oldCost = problem.cost();
  for (double w : problem.worst)
    problem.floors.push_back(std::min(w, options.acceptableScaledJacobian));
  const Eigen::Vector3d start = x.col(m.node);
  double uv[2] = {(start - m.origin).dot(m.u), (start - m.origin).dot(m.v)};
  if (m.deep)
  {
    const ChartPoint moved = deep.chart[std::size_t(m.vertex)] - m.chartOrigin;
    uv[0] = moved.x();
    uv[1] = moved.y();
  }
  const double startUv[2] = {uv[0], uv[1]};
  nlopt_opt opt = nlopt_create(NLOPT_LN_BOBYQA, 2);
  const double lower[2] = {-m.reach, -m.reach}, upper[2] = {m.reach, m.reach};
  nlopt_set_lower_bounds(opt, lower);
  nlopt_set_upper_bounds(opt, upper);
  nlopt_set_min_objective(opt, localCost, &problem);
  nlopt_set_xtol_abs1(opt, 1e-3 * m.shortestEdge);
  nlopt_set_maxeval(opt, 100);
  const double first = std::min(0.1 * m.shortestEdge, 0.2 * m.reach);
  const double step[2] = {first, first};
  nlopt_set_initial_step(opt, step);
  double best = 0.0;
  const nlopt_result result = nlopt_optimize(opt, uv, &best);
  nlopt_destroy(opt);
  problem.place(uv);
  const bool better = result > 0 && best < oldCost && problem.withinFloors();
  if (!better)
  {
    problem.place(startUv);
    return 0.0;
  }
  return std::hypot(uv[0] - startUv[0], uv[1] - startUv[1]);
}

/// Gauss-Seidel sweeps of relaxNode() until the nodes settle.
void relaxAll(const std::vector<MovableNode>& movable, Eigen::Matrix3Xd& x, const std::vector<JacobianSample>& frames,
              DeepState& deep, const InteriorNodeOptions& options, InteriorNodeOptimization& report)
{
  for (int sweep = 0; sweep < options.maxSweeps; ++sweep)
  {
    ++report.sweeps;
    bool settled = true;
    for (const MovableNode& m : movable)
      if (relaxNode(m, x, frames, deep, options) > options.settledMove * m.shortestEdge)
        settled = false;
    if (settled)
      break;
  }
}

/// Puts the mesh's nodes where the optimisation left them, the nodes of
/// @a reverted (representatives) back where the mesher put them.
class FinalPlacement
{
public:
  FinalPlacement(Mesh& mesh, const std::vector<MovableNode>& movable, const Eigen::Matrix3Xd& optimized,
                 const std::vector<int>& representative, const RecentredMids& mids, const DeepState& deep)
    : mesh_(mesh), movable_(movable), optimized_(optimized), representative_(representative), mids_(mids), deep_(deep),
      original_(mesh.nodes)
  {
    for (Eigen::Index n = 0; n < mesh.nodes.cols(); ++n)
      membersOf_[representative[std::size_t(n)]].push_back(int(n));
  }

  /// Every node at the place of its representative; the deep surface's
  /// mid-edge nodes under the chart middles of their edges; the recentred
  /// mid-edge nodes with a moved end at the middle of their edges.
  /// Returns the representatives that moved.
  std::set<int> place(const std::set<int>& reverted)
  {
    Eigen::Matrix3Xd& nodes = mesh_.nodes;
    nodes = original_;
    std::set<int> moved;
    std::vector<ChartPoint> chart = deep_.surface ? deep_.surface->vertexCharts : std::vector<ChartPoint>();
    std::vector<char> chartMoved(chart.size(), 0);
    for (const MovableNode& m : movable_)
      if (!reverted.count(m.node) && optimized_.col(m.node) != m.origin)
      {
        moved.insert(m.node);
        setGroup(m.node, optimized_.col(m.node));
        if (m.deep)
        {
          chart[std::size_t(m.vertex)] = deep_.chart[std::size_t(m.vertex)];
          chartMoved[std::size_t(m.vertex)] = 1;
        }
      }
    for (const DeepEdge& e : deep_.edges)
      if (chartMoved[std::size_t(e.a)] || chartMoved[std::size_t(e.b)])
        setDeepMid(e, chart);
    for (Eigen::Index n = 0; n < nodes.cols(); ++n)
    {
      const auto mid = mids_.find(representative_[std::size_t(n)]);
      if (mid != mids_.end() && (moved.count(mid->second.first) || moved.count(mid->second.second)))
        nodes.col(n) = 0.5 * (nodes.col(mid->second.first) + nodes.col(mid->second.second));
    }
    return moved;
  }

private:
  void setGroup(int rep, const Eigen::Vector3d& p)
  {
    for (int member : membersOf_[rep])
      mesh_.nodes.col(member) = p;
  }
  /// Under the chart middle of its edge; where the surface has no point
  /// there (not met while optimising), the straight middle.
  void setDeepMid(const DeepEdge& e, const std::vector<ChartPoint>& chart)
  {
    Eigen::Vector3d p =
      0.5 * (mesh_.nodes.col(representative_[std::size_t(e.a)]) + mesh_.nodes.col(representative_[std::size_t(e.b)]));
    try
    {
      const Eigen::Vector3d q = deep_.surface->pointUnder(0.5 * (chart[std::size_t(e.a)] + chart[std::size_t(e.b)]));
      if (q.allFinite())
        p = q;
    }
    catch (const std::exception&)
    {}
    setGroup(e.mid, p);
  }

  Mesh& mesh_;
  const std::vector<MovableNode>& movable_;
  const Eigen::Matrix3Xd& optimized_;
  const std::vector<int>& representative_;
  const RecentredMids& mids_;
  const DeepState& deep_;
  const Eigen::Matrix3Xd original_;
  std::map<int, std::vector<int>> membersOf_;
};

/// The samples see the elements at fewer points than the checks. So the
/// result is measured as the checks measure it (elementQuality(), at the
/// nodes and 3 x 3 x 3 points), and the moved nodes of any element that
/// came out worse than it was (and below the acceptable value) go back
/// where the mesher put them, until none does. Leaves the mesh's nodes in
/// their final places.
void keepNoElementWorse(Mesh& mesh, const std::vector<MovableNode>& movable, FinalPlacement& placement,
                        const std::vector<int>& representative, const InteriorNodeOptions& options)
{
  std::vector<std::vector<int>> elementsOf(std::size_t(mesh.nodeCount()));
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
    for (int n : mesh.elements[e].nodes)
      if (n >= 0)
        elementsOf[std::size_t(representative[std::size_t(n)])].push_back(int(e));
  std::set<int> touched;
  for (const MovableNode& m : movable)
    touched.insert(elementsOf[std::size_t(m.node)].begin(), elementsOf[std::size_t(m.node)].end());
  std::map<int, double> before;
  for (int e : touched)
    before[e] = elementQuality(mesh, e).scaledJacobian;
  std::set<int> reverted;
  for (std::size_t round = 0; round <= movable.size(); ++round)
  {
    const std::set<int> moved = placement.place(reverted);
    std::set<int> worse;
    for (int e : touched)
      if (elementQuality(mesh, e).scaledJacobian < std::min(before[e], options.acceptableScaledJacobian))
        for (int n : mesh.elements[std::size_t(e)].nodes)
          if (n >= 0 && moved.count(representative[std::size_t(n)]))
            worse.insert(representative[std::size_t(n)]);
    if (worse.empty())
      return;
    reverted.insert(worse.begin(), worse.end());
  }
}

/// Of @a movable, the nodes of elements whose worst point is below
/// @a acceptable: a good mesh, or the good part of one, is left as the
/// mesher made it (and a symmetric mesh stays symmetric).
std::vector<MovableNode> nearPoorElements(std::vector<MovableNode> movable, const Mesh& mesh,
                                          const std::vector<int>& representative, double acceptable)
{
  std::set<int> nearPoor;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
    if (elementQuality(mesh, int(e)).scaledJacobian < acceptable)
      for (int n : mesh.elements[e].nodes)
        if (n >= 0)
          nearPoor.insert(representative[std::size_t(n)]);
  std::erase_if(movable, [&](const MovableNode& m) { return !nearPoor.count(m.node); });
  return movable;
}

/// The deep surface's vertices and mid-edge nodes, for @a surface.
DeepState deepStateOf(const ContinuumMesh& c, const std::vector<int>& representative, const DeepSurface* surface)
{
  DeepState deep;
  if (!surface || !surface->pointUnder)
    return deep;
  if (surface->vertexCharts.size() != c.vertexColumns.size())
    throw std::invalid_argument("interior node optimisation: one chart point per vertex column is needed (" +
                                std::to_string(surface->vertexCharts.size()) + " for " +
                                std::to_string(c.vertexColumns.size()) + " columns)");
  deep.surface = surface;
  deep.chart = surface->vertexCharts;
  for (std::size_t e = 0; e < c.edges.size() && e < c.edgeColumns.size(); ++e)
    if (!c.edgeColumns[e].empty() && c.edgeColumns[e].back() >= 0)
      deep.edges.push_back({representative[std::size_t(c.edgeColumns[e].back())], c.edges[e][0], c.edges[e][1]});
  return deep;
}

/// The samples each movable node changes (its own, and for a deep node its
/// mid-edge nodes'), grouped by element.
void assignSamples(std::vector<MovableNode>& movable, const std::vector<JacobianSample>& frames, const DeepState& deep)
{
  std::map<int, std::vector<int>> framesOf;
  for (std::size_t f = 0; f < frames.size(); ++f)
  {
    std::set<int> nodes;
    for (const auto& row : frames[f].rows)
      for (const Term& t : row)
        nodes.insert(t.node);
    for (int n : nodes)
      framesOf[n].push_back(int(f));
  }
  for (MovableNode& m : movable)
  {
    std::set<int> own(framesOf[m.node].begin(), framesOf[m.node].end());
    for (int k : m.deepEdges)
      own.insert(framesOf[deep.edges[std::size_t(k)].mid].begin(), framesOf[deep.edges[std::size_t(k)].mid].end());
    m.frames.assign(own.begin(), own.end()); // ascending: in element order, as jacobianSamples() made them
    int last = -1;
    for (int f : m.frames)
    {
      if (frames[std::size_t(f)].element != last)
      {
        last = frames[std::size_t(f)].element;
        ++m.elementCount;
      }
      m.frameElement.push_back(m.elementCount - 1);
    }
  }
}

} // namespace

InteriorNodeOptimization optimizeInteriorNodes(ContinuumMesh& continuum, const std::vector<char>& heldVertices,
                                               const DeepSurface* deepSurface, const InteriorNodeOptions& options)
{
  if (options.maxSweeps < 0 || !(options.settledMove > 0.0))
    throw std::invalid_argument("interior node options: sweeps must be >= 0 and the settled move positive");
  if (heldVertices.size() != continuum.vertexColumns.size())
    throw std::invalid_argument("interior node optimisation: one held flag per vertex column is needed (" +
                                std::to_string(heldVertices.size()) + " for " +
                                std::to_string(continuum.vertexColumns.size()) + " columns)");
  const std::vector<int> representative = coincidentRepresentatives(continuum.mesh.nodes);
  DeepState deep = deepStateOf(continuum, representative, deepSurface);
  std::vector<MovableNode> movable = nearPoorElements(movableNodes(continuum, heldVertices, representative, deep),
                                                      continuum.mesh, representative, options.acceptableScaledJacobian);
  std::set<int> moving;
  for (const MovableNode& m : movable)
    moving.insert(m.node);
  const RecentredMids mids = recentredMids(continuum, representative, moving, deep.surface != nullptr);
  const std::vector<JacobianSample> frames = jacobianSamples(continuum.mesh, representative, mids);
  assignSamples(movable, frames, deep);

  InteriorNodeOptimization report;
  report.movableNodes = int(movable.size());
  report.movableDeepNodes = int(std::count_if(movable.begin(), movable.end(), [](const auto& m) { return m.deep; }));
  const MeshQualityCheck before = checkMeshQuality(continuum.mesh);
  report.minScaledJacobianBefore = before.minScaledJacobian;
  report.poorElementsBefore = before.poorJacobian;
  Eigen::Matrix3Xd x = continuum.mesh.nodes; // the representatives move here
  relaxAll(movable, x, frames, deep, options, report);
  FinalPlacement placement(continuum.mesh, movable, x, representative, mids, deep);
  keepNoElementWorse(continuum.mesh, movable, placement, representative, options);
  for (const MovableNode& m : movable)
  {
    const double move = (continuum.mesh.nodes.col(m.node) - m.origin).norm();
    if (move > 1e-3)
      ++report.movedNodes;
    report.largestMove = std::max(report.largestMove, move);
  }
  return report;
}

} // namespace caps::fem
