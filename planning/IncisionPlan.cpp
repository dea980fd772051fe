#include "planning/IncisionPlan.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include <Eigen/Geometry>

#include "planning/Undermining.h"

namespace caps::planning {
namespace {

constexpr double pi = 3.14159265358979323846;

std::string edgeText(const std::array<int, 2>& e)
{
  return "(" + std::to_string(e[0]) + "," + std::to_string(e[1]) + ")";
}

std::string sutureText(int k, const SutureEdges& s)
{
  return "suture " + std::to_string(k + 1) + " (" + edgeText(s.a) + "," + edgeText(s.b) + ")";
}

/// Union-find over loop vertices.
struct Classes
{
  std::vector<int> parent;
  explicit Classes(int n) : parent(std::max(n, 0)) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int v)
  {
    while (parent[v] != v)
      v = parent[v] = parent[parent[v]];
    return v;
  }
  void join(int a, int b) { parent[find(a)] = find(b); }
};

/// Loop-order start of border edge (x, y), or -1 when x and y are not neighbours on the loop.
int edgeStart(int loopSize, const std::array<int, 2>& e)
{
  const int x = e[0], y = e[1];
  if (x < 0 || y < 0 || x >= loopSize || y >= loopSize || x == y)
    return -1;
  if ((x + 1) % loopSize == y)
    return x;
  if ((y + 1) % loopSize == x)
    return y;
  return -1;
}

double cross2(const ChartPoint& a, const ChartPoint& b)
{
  return a.x() * b.y() - a.y() * b.x();
}

/// Whether segments pq and rs cross at a point inside both (touching or overlapping does not count).
bool segmentsCross(const ChartPoint& p, const ChartPoint& q, const ChartPoint& r, const ChartPoint& s)
{
  const double scale = std::max({(q - p).norm(), (s - r).norm(), 1e-12});
  const double eps = 1e-9 * scale * scale;
  const double d1 = cross2(q - p, r - p), d2 = cross2(q - p, s - p);
  const double d3 = cross2(s - r, p - r), d4 = cross2(s - r, q - r);
  return ((d1 > eps && d2 < -eps) || (d1 < -eps && d2 > eps)) && ((d3 > eps && d4 < -eps) || (d3 < -eps && d4 > eps));
}

/// A length for a message: "0.2", "100" (std::to_string gives "0.200000").
std::string mmText(double mm)
{
  std::ostringstream o;
  o.precision(3);
  o << mm;
  return o.str();
}

std::string whereText(const SkinPoint& s)
{
  std::ostringstream o;
  o.precision(4);
  o << "θ = " << s.theta * 180.0 / pi << "°, z = " << s.z << " mm";
  return o.str();
}

} // namespace

int holeLoopSize(int pathPoints)
{
  return pathPoints < 2 ? 0 : 2 * (pathPoints - 1);
}

int rightSideVertex(int pathIndex, int pathPoints)
{
  if (pathIndex <= 0 || pathIndex >= pathPoints - 1)
    return pathIndex;
  return 2 * (pathPoints - 1) - pathIndex;
}

int pathIndexOfVertex(int loopVertex, int pathPoints)
{
  return loopVertex < pathPoints ? loopVertex : 2 * (pathPoints - 1) - loopVertex;
}

fem::HoleLoop makeHoleLoop(const std::vector<ChartPoint>& path, const std::vector<ChartPoint>& offsets)
{
  const int n = int(path.size());
  if (n < 2)
    throw std::invalid_argument("a cut needs at least two points");
  const int loopSize = holeLoopSize(n);
  if (!offsets.empty() && int(offsets.size()) != loopSize)
    throw std::invalid_argument("makeHoleLoop: " + std::to_string(offsets.size()) + " offsets for a hole of " +
                                std::to_string(loopSize) + " border points");
  fem::HoleLoop loop;
  loop.points.resize(loopSize);
  loop.pathIndex.resize(loopSize);
  for (int v = 0; v < loopSize; ++v)
  {
    const int i = pathIndexOfVertex(v, n);
    loop.pathIndex[v] = i;
    loop.points[v] = path[i] + (offsets.empty() ? ChartPoint::Zero() : offsets[v]);
  }
  return loop;
}

std::vector<fem::SutureEdgePair> resolveSutures(int loopSize, const std::vector<SutureEdges>& written)
{
  std::vector<fem::SutureEdgePair> resolved;
  std::map<int, int> sewnBy; // edge start → suture index
  Classes classes(loopSize);
  for (int k = 0; k < int(written.size()); ++k)
  {
    const SutureEdges& s = written[k];
    const int startA = edgeStart(loopSize, s.a), startB = edgeStart(loopSize, s.b);
    for (const auto& [start, edge] : {std::pair{startA, s.a}, std::pair{startB, s.b}})
      if (start < 0)
        throw SutureError(k, sutureText(k, s) + ": " + edgeText(edge) +
                               " is not a border edge of the hole; border edges join neighbouring "
                               "border points 0.." +
                               std::to_string(loopSize - 1) + " (and " + std::to_string(loopSize - 1) + " back to 0)");
    if (startA == startB)
      throw SutureError(k, sutureText(k, s) + ": an edge cannot be sewn to itself");
    for (int start : {startA, startB})
      if (auto it = sewnBy.find(start); it != sewnBy.end())
        throw SutureError(k, sutureText(k, s) + ": border edge (" + std::to_string(start) + "," +
                               std::to_string((start + 1) % loopSize) + ") is already sewn by " +
                               sutureText(it->second, written[it->second]) + "; each border edge can be sewn once");
    sewnBy[startA] = k;
    sewnBy[startB] = k;
    // Face to face: the loop-order start of one edge meets the end of the other.
    fem::SutureEdgePair pair;
    pair.a = s.a;
    const int endB = (startB + 1) % loopSize;
    const bool aFromStart = s.a[0] == startA;
    pair.b = aFromStart ? std::array<int, 2>{endB, startB} : std::array<int, 2>{startB, endB};
    classes.join(pair.a[0], pair.b[0]);
    classes.join(pair.a[1], pair.b[1]);
    for (int v = 0; v < loopSize; ++v)
      if (classes.find(v) == classes.find((v + 1) % loopSize))
        throw SutureError(k, sutureText(k, s) +
                               ": together with the sutures before it, it pulls both "
                               "ends of border edge (" +
                               std::to_string(v) + "," + std::to_string((v + 1) % loopSize) +
                               ") onto one point; check which points each suture brings together");
    resolved.push_back(pair);
  }
  return resolved;
}

std::vector<std::vector<int>> sutureClasses(int loopSize, const std::vector<fem::SutureEdgePair>& sutures)
{
  Classes classes(loopSize);
  for (const auto& s : sutures)
  {
    classes.join(s.a[0], s.b[0]);
    classes.join(s.a[1], s.b[1]);
  }
  std::map<int, std::vector<int>> groups;
  for (int v = 0; v < loopSize; ++v)
    groups[classes.find(v)].push_back(v);
  std::vector<std::vector<int>> result;
  for (auto& [root, members] : groups)
    result.push_back(std::move(members));
  return result;
}

IncisionPlan::IncisionPlan(std::vector<Eigen::Vector2d> cutPath, SkinPoint centre)
  : cutPath_(std::move(cutPath)), centre_(centre)
{}

void IncisionPlan::moveCutPoint(int i, const Eigen::Vector2d& thetaZN)
{
  if (i < 0 || i >= pointCount())
    throw std::out_of_range("cut point " + std::to_string(i) + " does not exist: the cut has " +
                            std::to_string(pointCount()) + " points");
  cutPath_[i] = thetaZN;
}

void IncisionPlan::offsetBorderPoint(int loopVertex, const ChartPoint& d)
{
  const int n = pointCount(), loopSize = holeLoopSize(n);
  if (loopVertex < 0 || loopVertex >= loopSize)
    throw std::out_of_range("border point " + std::to_string(loopVertex) + " does not exist: the hole has " +
                            std::to_string(loopSize) + " border points");
  if (loopVertex == 0 || loopVertex == n - 1)
    throw std::invalid_argument("border point " + std::to_string(loopVertex) +
                                " is an end of the cut and has no twin to move away from; move the cut "
                                "point instead");
  if (d.isZero())
    offsets_.erase(loopVertex);
  else
    offsets_[loopVertex] = d;
}

std::vector<ChartPoint> IncisionPlan::borderOffsets() const
{
  std::vector<ChartPoint> result(holeLoopSize(pointCount()), ChartPoint::Zero());
  for (const auto& [v, d] : offsets_)
    if (v < int(result.size()))
      result[v] = d;
  return result;
}

bool IncisionPlan::isExcision() const
{
  return !offsets_.empty();
}

const char* cutDepthId(CutDepth depth)
{
  return depth == CutDepth::Fascia ? "fascia" : "bone";
}

std::optional<CutDepth> cutDepthFromId(const std::string& id)
{
  for (CutDepth d : {CutDepth::Bone, CutDepth::Fascia})
    if (id == cutDepthId(d))
      return d;
  return std::nullopt;
}

int layersCutTo(CutDepth depth, int layerCount)
{
  return depth == CutDepth::Fascia && layerCount > 1 ? layerCount - 1 : layerCount;
}

void IncisionPlan::setUnderminingBand(double millimetres)
{
  if (!(millimetres >= 0.0) || !std::isfinite(millimetres))
    throw std::invalid_argument("the undermining band must be 0 (none) or a positive number of mm, not " +
                                std::to_string(millimetres));
  underminingBand_ = millimetres;
}

void IncisionPlan::setSutures(std::vector<SutureEdges> written, std::vector<std::string> woundLineNames)
{
  if (!woundLineNames.empty() && woundLineNames.size() != written.size())
    throw std::invalid_argument(
      "a plan's sutures need one wound line name each or none: " + std::to_string(woundLineNames.size()) +
      " names for " + std::to_string(written.size()) + " sutures");
  sutures_ = resolveSutures(holeLoopSize(pointCount()), written);
  written_ = std::move(written);
  woundLineNames_ = std::move(woundLineNames);
}

std::string cutPointName(int loopVertex, int pathPoints)
{
  const int n = pathPoints;
  std::ostringstream name;
  if (loopVertex < n)
    name << "p" << loopVertex;
  else
    name << "p" << 2 * (n - 1) - loopVertex << "'";
  return name.str();
}

std::string woundLineName(const IncisionPlan& plan, int suture)
{
  const auto& names = plan.woundLineNames();
  if (suture >= 0 && suture < int(names.size()) && !names[suture].empty())
    return names[suture];
  const fem::SutureEdgePair& s = plan.sutures().at(std::size_t(suture));
  const int n = plan.pointCount();
  return cutPointName(s.a[0], n) + "-" + cutPointName(s.a[1], n) + " onto " + cutPointName(s.b[0], n) + "-" +
         cutPointName(s.b[1], n);
}

std::vector<ChartPoint> IncisionPlan::chartPath(const SkinChart& chart) const
{
  std::vector<ChartPoint> path;
  path.reserve(cutPath_.size());
  for (const auto& p : cutPath_)
    path.push_back(chart.fromNormalized(p));
  return path;
}

fem::HoleLoop IncisionPlan::holeLoop(const SkinChart& chart) const
{
  return makeHoleLoop(chartPath(chart), borderOffsets());
}

namespace {

/// The plan must lie on skin the map measured, where the chart is true to
/// the skin: every border edge and the inside of an excision has a surface
/// under it, and nowhere does the chart stretch lengths on the skin by more
/// than kMaxChartDistortion (there a plan drawn in the chart is another plan
/// on the skin, and its measurements would not be the plan's).
void checkTheSkinUnderTheHole(const fem::HoleLoop& loop, const SkinChart& chart)
{
  const int loopSize = int(loop.points.size());
  const auto check = [&](const ChartPoint& p, const std::string& what) {
    const double distortion = chartDistortion(chart, p);
    if (!std::isfinite(chart.lift(p).x()) || std::isnan(distortion))
    {
      std::ostringstream o;
      o << "the skin map has no surface under " << what;
      if (std::isfinite(chart.lift(p).x()))
        o << " (within a millimetre)";
      o << " near " << whereText(chart.fromChart(p)) << ": move the cut onto measured skin";
      throw std::invalid_argument(o.str());
    }
    if (!(distortion <= kMaxChartDistortion))
    {
      std::ostringstream o;
      o.precision(3);
      o << "the skin under " << what << " near " << whereText(chart.fromChart(p))
        << " is too oblique to the head's axis for the skin map (the top of the head, under the chin, the side of "
           "the nose): lengths on the skin there are "
        << distortion
        << " times what they are in the plan, so the plan on the skin would not be the plan drawn. Move the plan "
           "where the skin faces away from the head's axis (lengths within "
        << kMaxChartDistortion << " times)";
      throw std::invalid_argument(o.str());
    }
  };
  const double step = 0.5; // mm: finer than a range map cell on the sample CT
  for (int e = 0; e < loopSize; ++e)
  {
    const ChartPoint a = loop.points[e], b = loop.points[(e + 1) % loopSize];
    const int samples = std::max(1, int(std::ceil((b - a).norm() / step)));
    const std::string what = "border edge (" + std::to_string(e) + "," + std::to_string((e + 1) % loopSize) + ")";
    for (int k = 0; k <= samples; ++k)
      check(a + (b - a) * (double(k) / samples), what);
  }
  // The inside of an excision, on a grid of the same step.
  Eigen::AlignedBox2d box;
  for (const ChartPoint& p : loop.points)
    box.extend(p);
  for (double v = box.min().y() + 0.5 * step; v < box.max().y(); v += step)
    for (double u = box.min().x() + 0.5 * step; u < box.max().x(); u += step)
      if (insidePolygon(loop.points, {u, v}))
        check({u, v}, "the excision");
}

} // namespace

void checkPlan(const IncisionPlan& plan, const seg::RangeMap& skin, double minSpacing)
{
  const int n = plan.pointCount();
  if (n < 2)
    throw std::invalid_argument("a cut needs at least two points; this plan has " + std::to_string(n));
  const auto& frame = skin.frame();
  for (int i = 0; i < n; ++i)
  {
    const SkinPoint s = skinPointFromNormalized(frame, plan.cutPath()[i]);
    if (std::abs(plan.cutPath()[i].y()) > 1.0)
      throw std::invalid_argument("cut point " + std::to_string(i) + " (" + whereText(s) +
                                  ") is outside the scanned region (z from " + mmText(frame.zMin()) + " to " +
                                  mmText(frame.zMax()) + " mm): move it, or the plan, inside the scan");
  }
  const SkinChart chart = plan.chart(skin);
  const auto path = plan.chartPath(chart);
  for (int i = 0; i + 1 < n; ++i)
    if ((path[i + 1] - path[i]).norm() < minSpacing)
      throw std::invalid_argument("cut points " + std::to_string(i) + " and " + std::to_string(i + 1) + " are " +
                                  mmText((path[i + 1] - path[i]).norm()) + " mm apart, closer than " +
                                  mmText(minSpacing) + " mm: move one of them or delete it");
  for (int i = 0; i + 1 < n; ++i)
    for (int j = i + 2; j + 1 < n; ++j)
      if (segmentsCross(path[i], path[i + 1], path[j], path[j + 1]))
        throw std::invalid_argument("limb " + std::to_string(i) + " (cut points " + std::to_string(i) + "–" +
                                    std::to_string(i + 1) + ") crosses limb " + std::to_string(j) + " (cut points " +
                                    std::to_string(j) + "–" + std::to_string(j + 1) + "): a cut may not cross itself");
  const fem::HoleLoop loop = plan.holeLoop(chart);
  const int loopSize = int(loop.points.size());
  for (int e = 0; e < loopSize; ++e)
    for (int f = e + 2; f < loopSize; ++f)
    {
      if ((f + 1) % loopSize == e)
        continue;
      const auto& p = loop.points;
      if (segmentsCross(p[e], p[(e + 1) % loopSize], p[f], p[(f + 1) % loopSize]))
        throw std::invalid_argument("border edges (" + std::to_string(e) + "," + std::to_string((e + 1) % loopSize) +
                                    ") and (" + std::to_string(f) + "," + std::to_string((f + 1) % loopSize) +
                                    ") of the hole cross: an excision point was moved across the cut");
    }
  double twiceArea = 0.0;
  for (int e = 0; e < loopSize; ++e)
    twiceArea += cross2(loop.points[e], loop.points[(e + 1) % loopSize]);
  if (twiceArea > 1e-9)
    throw std::invalid_argument("the excision's sides are swapped: border points 1.." + std::to_string(n - 2) +
                                " open to the left of the cut (walking from its first point), their twins to "
                                "the right: offset each border point away from its twin, to its own side");
  checkTheSkinUnderTheHole(loop, chart);
}

} // namespace caps::planning
