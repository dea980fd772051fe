#include "planning/WoundTension.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>

namespace caps::planning {
namespace {

/// The refined loop vertices along plan edge @a e, from its first vertex to
/// its second (the walk refineHole() sews along).
std::vector<int> refinedWalk(const PlanPrediction& p, int planLoop, const std::array<int, 2>& e)
{
  const int loop = int(p.hole.points.size());
  const int step = e[1] == (e[0] + 1) % planLoop ? 1 : -1;
  std::vector<int> walk{p.refinedVertexOf.at(std::size_t(e[0]))};
  const int end = p.refinedVertexOf.at(std::size_t(e[1]));
  while (walk.back() != end && int(walk.size()) <= loop)
    walk.push_back((walk.back() + step + loop) % loop);
  return walk;
}

/// The force across one sutured piece of wound and its closed length.
struct PairTension
{
  double across = 0.0; ///< N
  double length = 0.0; ///< mm
};

class TensionOfPairs
{
public:
  TensionOfPairs(const PlanPrediction& prediction, const IncisionPlan& plan) : p_(prediction), plan_(plan)
  {
    sewn_.assign(std::size_t(p_.continuum.mesh.nodeCount()), 0);
    for (const fem::Suture& s : p_.continuum.sutures)
      sewn_[std::size_t(s.node)] = sewn_[std::size_t(s.target)] = 1;
    // A column where two sewn pieces meet (a cut point along a line, a
    // corner between lines) counts half in each, so the line's sum is each
    // node's force once.
    sharedBy_.assign(sewn_.size(), 0);
    for (int e = 0; e < int(plan_.sutures().size()); ++e)
      for (int node : firstSideNodes(e))
        ++sharedBy_[std::size_t(node)];
  }

  /// Pair @a e: the sum of the internal forces at its first side's sewn
  /// nodes, across the closed line in the skin's tangent plane.
  PairTension of(int e) const
  {
    const std::vector<int> walk = walkOf(e);
    Eigen::Vector3d force = Eigen::Vector3d::Zero();
    for (int node : firstSideNodes(e))
      force += p_.nodalForces.segment<3>(3 * Eigen::Index(node)) / double(sharedBy_[std::size_t(node)]);
    PairTension t;
    for (std::size_t k = 0; k + 1 < walk.size(); ++k)
      t.length += (skinAfter(walk[k + 1]) - skinAfter(walk[k])).norm();
    const Eigen::Vector3d along = skinAfter(walk.back()) - skinAfter(walk.front());
    const Eigen::Vector3d outward = outwardAt(walk[walk.size() / 2]);
    const Eigen::Vector3d across = along.cross(outward);
    if (across.norm() > 0.0)
      t.across = std::abs(force.dot(across.normalized()));
    return t;
  }

private:
  std::vector<int> walkOf(int e) const
  {
    return refinedWalk(p_, holeLoopSize(plan_.pointCount()), plan_.sutures()[std::size_t(e)].a);
  }

  /// The sewn nodes of pair @a e's first side: its vertex and mid-edge
  /// columns through the layers sewn.
  std::vector<int> firstSideNodes(int e) const
  {
    const std::vector<int> walk = walkOf(e);
    std::vector<int> nodes;
    const auto add = [&](const std::vector<int>& column) {
      for (int node : column)
        if (sewn_[std::size_t(node)])
          nodes.push_back(node);
    };
    for (std::size_t k = 0; k < walk.size(); ++k)
    {
      add(p_.continuum.vertexColumns[std::size_t(walk[k])]);
      if (k + 1 < walk.size())
        if (const int edge = p_.continuum.edgeIndex(walk[k], walk[k + 1]); edge >= 0)
          add(p_.continuum.edgeColumns[std::size_t(edge)]);
    }
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    return nodes;
  }

  Eigen::Vector3d skinAfter(int vertex) const
  {
    return p_.displacedNode(p_.continuum.vertexColumns[std::size_t(vertex)].front());
  }
  /// Up the vertex's column, from its deepest node to the skin, after the closure.
  Eigen::Vector3d outwardAt(int vertex) const
  {
    const auto& column = p_.continuum.vertexColumns[std::size_t(vertex)];
    return (p_.displacedNode(column.front()) - p_.displacedNode(column.back())).normalized();
  }

  const PlanPrediction& p_;
  const IncisionPlan& plan_;
  std::vector<char> sewn_;
  std::vector<int> sharedBy_; ///< per node, the sewn pieces whose first side it is on
};

void checkInputs(const PlanPrediction& prediction, const IncisionPlan& plan, double stitchSpacing)
{
  if (!(stitchSpacing > 0.0) || !std::isfinite(stitchSpacing))
    throw std::invalid_argument("the stitch spacing must be a positive number of mm, not " +
                                std::to_string(stitchSpacing));
  if (prediction.closure.edges.size() != plan.sutures().size() ||
      prediction.refinedVertexOf.size() != std::size_t(holeLoopSize(plan.pointCount())) ||
      prediction.nodalForces.size() != 3 * prediction.continuum.mesh.nodeCount())
    throw std::invalid_argument("the wound tension needs the prediction of this plan, solved: its sutures or "
                                "hole do not match the plan's");
}

} // namespace

WoundTension woundTension(const PlanPrediction& prediction, const IncisionPlan& plan, double stitchSpacing)
{
  checkInputs(prediction, plan, stitchSpacing);
  WoundTension out;
  out.stitchSpacing = stitchSpacing;
  const TensionOfPairs pairs(prediction, plan);
  const int n = plan.pointCount();
  for (int e = 0; e < int(plan.sutures().size()); ++e)
  {
    const std::string name = woundLineName(plan, e);
    auto line = std::find_if(out.lines.begin(), out.lines.end(), [&](const auto& l) { return l.name == name; });
    if (line == out.lines.end())
    {
      line = out.lines.insert(out.lines.end(), WoundLineTension{});
      line->name = name;
    }
    const PairTension t = pairs.of(e);
    line->sutures.push_back(e);
    line->length += t.length;
    line->acrossForce += t.across;
    const double perCm = t.length > 0.0 ? 10.0 * t.across / t.length : 0.0;
    line->piecePerCentimetre.push_back(perCm);
    if (line->peakBetween.empty() || perCm > line->peakPerCentimetre)
    {
      const auto& a = plan.sutures()[std::size_t(e)].a;
      line->peakPerCentimetre = perCm;
      line->peakBetween = cutPointName(a[0], n) + " and " + cutPointName(a[1], n);
    }
  }
  for (WoundLineTension& line : out.lines)
  {
    line.perCentimetre = line.length > 0.0 ? 10.0 * line.acrossForce / line.length : 0.0;
    line.stitches = std::max(1, int(std::lround(line.length / stitchSpacing)));
    line.perStitch = line.perCentimetre * stitchSpacing / 10.0;
    line.peakPerStitch = line.peakPerCentimetre * stitchSpacing / 10.0;
    if (line.peakPerCentimetre > out.peakPerCentimetre)
    {
      out.peakPerCentimetre = line.peakPerCentimetre;
      out.peakPerStitch = line.peakPerStitch;
      out.peakLine = line.name;
    }
  }
  return out;
}

} // namespace caps::planning
