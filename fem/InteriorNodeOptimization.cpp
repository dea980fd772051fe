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
  double reach = 0.0;        ///< bound of the move in u and v (mm)
  double shortestEdge = 0.0; ///< mm
  std::vector<int> frames;       ///< the frames it moves, grouped by element
  std::vector<int> frameElement; ///< for each of frames, its element's local index
  int elementCount = 0;
};

/// The movable nodes of @a c: the inner layer boundaries' corner nodes
/// (by representative) of the columns under vertices not @a held.
std::vector<MovableNode> movableNodes(const ContinuumMesh& c, const std::vector<char>& held,
                                      const std::vector<int>& representative)
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
  }
  return movable;
}

/// The mid-edge nodes (by representative) on an edge with an end in
/// @a moving, each with its edge's ends: the vertical edges of the columns
/// and the edges of the inner layer boundaries.
RecentredMids recentredMids(const ContinuumMesh& c, const std::vector<int>& representative,
                            const std::set<int>& moving)
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
      if (2 * level < columnA.size() && 2 * level < columnB.size())
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
  std::vector<double> floors; ///< by MovableNode::frameElement
  mutable std::vector<double> worst;

  void place(const double* uv) const { x->col(node->node) = node->origin + uv[0] * node->u + uv[1] * node->v; }
  /// The smoothing cost, and a steep penalty for any element pushed below
  /// its floor (so the worst element of the mesh never gets worse); fills
  /// worst.
  double cost() const
  {
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
  const auto* problem = static_cast<const LocalProblem*>(data);
  problem->place(uv);
  return problem->cost();
}

/// Best place for one node (BOBYQA in the plane across its column); how
/// far it moved (mm), 0 if the move was not kept.
double relaxNode(const MovableNode& m, Eigen::Matrix3Xd& x, const std::vector<JacobianSample>& frames,
                 const InteriorNodeOptions& options)
{
  LocalProblem problem{&x, &frames, &m, {}, {}};
  const Eigen::Vector3d start = x.col(m.node);
  const double oldCost = problem.cost();
  for (double w : problem.worst)
    problem.floors.push_back(std::min(w, options.acceptableScaledJacobian));
  double uv[2] = {(start - m.origin).dot(m.u), (start - m.origin).dot(m.v)};
  const double startUv[2] = {uv[0], uv[1]};
  nlopt_opt opt = nlopt_create(NLOPT_LN_BOBYQA, 2);
  const double lower[2] = {-m.reach, -m.reach}, upper[2] = {m.reach, m.reach};
  nlopt_set_lower_bounds(opt, lower);
  nlopt_set_upper_bounds(opt, upper);
  nlopt_set_min_objective(opt, localCost, &problem);
  nlopt_set_xtol_abs1(opt, 1e-3 * m.shortestEdge);
  nlopt_set_maxeval(opt, 100);
  const double step[2] = {0.1 * m.shortestEdge, 0.1 * m.shortestEdge};
  nlopt_set_initial_step(opt, step);
  double best = 0.0;
  const nlopt_result result = nlopt_optimize(opt, uv, &best);
  nlopt_destroy(opt);
  problem.place(uv);
  const bool better = result > 0 && best < oldCost && problem.withinFloors();
  if (!better)
  {
    x.col(m.node) = start;
    return 0.0;
  }
  return std::hypot(uv[0] - startUv[0], uv[1] - startUv[1]);
}

/// Gauss-Seidel sweeps of relaxNode() until the nodes settle.
void relaxAll(const std::vector<MovableNode>& movable, Eigen::Matrix3Xd& x, const std::vector<JacobianSample>& frames,
              const InteriorNodeOptions& options, InteriorNodeOptimization& report)
{
  for (int sweep = 0; sweep < options.maxSweeps; ++sweep)
  {
    ++report.sweeps;
    bool settled = true;
    for (const MovableNode& m : movable)
      if (relaxNode(m, x, frames, options) > options.settledMove * m.shortestEdge)
        settled = false;
    if (settled)
      break;
  }
}

/// The mesh's nodes after the representatives @a moved took their places in
/// @a x: every node at the place of its representative, and the mid-edge
/// nodes of @a mids with an end moved at the middle of their edges, with
/// whatever coincides with them.
void placeNodes(Mesh& mesh, const Eigen::Matrix3Xd& x, const std::vector<int>& representative,
                const RecentredMids& mids, const std::set<int>& moved)
{
  Eigen::Matrix3Xd& nodes = mesh.nodes;
  for (Eigen::Index n = 0; n < nodes.cols(); ++n)
    if (moved.count(representative[std::size_t(n)]))
      nodes.col(n) = x.col(representative[std::size_t(n)]);
  for (Eigen::Index n = 0; n < nodes.cols(); ++n)
  {
    const auto mid = mids.find(representative[std::size_t(n)]);
    if (mid != mids.end() && (moved.count(mid->second.first) || moved.count(mid->second.second)))
      nodes.col(n) = 0.5 * (nodes.col(mid->second.first) + nodes.col(mid->second.second));
  }
}

/// The samples see the elements at fewer points than the checks. So the result
/// is measured as the checks measure it (elementQuality(), at the nodes and
/// integration points), and the moved nodes of any element that came out
/// worse than it was (and below the acceptable value) go back where the
/// mesher put them, until none does. Leaves the mesh's nodes in their final
/// places.
void keepNoElementWorse(Mesh& mesh, const std::vector<MovableNode>& movable, const Eigen::Matrix3Xd& optimized,
                        const std::vector<int>& representative, const RecentredMids& mids,
                        const InteriorNodeOptions& options)
{
  const Eigen::Matrix3Xd original = mesh.nodes;
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
    mesh.nodes = original;
    std::set<int> moved;
    for (const MovableNode& m : movable)
      if (!reverted.count(m.node) && optimized.col(m.node) != m.origin)
        moved.insert(m.node);
    placeNodes(mesh, optimized, representative, mids, moved);
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

} // namespace

InteriorNodeOptimization optimizeInteriorNodes(ContinuumMesh& continuum, const std::vector<char>& heldVertices,
                                               const InteriorNodeOptions& options)
{
  if (options.maxSweeps < 0 || !(options.settledMove > 0.0))
    throw std::invalid_argument("interior node options: sweeps must be >= 0 and the settled move positive");
  if (heldVertices.size() != continuum.vertexColumns.size())
    throw std::invalid_argument("interior node optimisation: one held flag per vertex column is needed (" +
                                std::to_string(heldVertices.size()) + " for " +
                                std::to_string(continuum.vertexColumns.size()) + " columns)");
  const std::vector<int> representative = coincidentRepresentatives(continuum.mesh.nodes);
  std::vector<MovableNode> movable = movableNodes(continuum, heldVertices, representative);
  std::set<int> moving;
  for (const MovableNode& m : movable)
    moving.insert(m.node);
  const RecentredMids mids = recentredMids(continuum, representative, moving);
  const std::vector<JacobianSample> frames = jacobianSamples(continuum.mesh, representative, mids);
  std::map<int, std::vector<int>> framesOf;
  for (std::size_t f = 0; f < frames.size(); ++f)
  {
    std::set<int> nodes;
    for (const auto& row : frames[f].rows)
      for (const Term& t : row)
        nodes.insert(t.node);
    for (int n : nodes)
      if (moving.count(n))
        framesOf[n].push_back(int(f));
  }
  for (MovableNode& m : movable)
  {
    m.frames = framesOf[m.node]; // in element order, as jacobianSamples() made them
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

  InteriorNodeOptimization report;
  report.movableNodes = int(movable.size());
  const MeshQualityCheck before = checkMeshQuality(continuum.mesh);
  report.minScaledJacobianBefore = before.minScaledJacobian;
  report.poorElementsBefore = before.poorJacobian;
  Eigen::Matrix3Xd x = continuum.mesh.nodes; // the representatives move here
  relaxAll(movable, x, frames, options, report);
  keepNoElementWorse(continuum.mesh, movable, x, representative, mids, options);
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
