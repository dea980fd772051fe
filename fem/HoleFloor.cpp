#include "fem/HoleFloor.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

namespace caps::fem {
namespace {

double cross(const ChartPoint& a, const ChartPoint& b, const ChartPoint& c)
{
  return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
}

/// Twice the signed area of a cycle (positive: counter-clockwise).
double twiceArea(const std::vector<ChartPoint>& p, const std::vector<int>& cycle)
{
  double sum = 0.0;
  for (std::size_t i = 0; i < cycle.size(); ++i)
  {
    const ChartPoint& a = p[std::size_t(cycle[i])];
    const ChartPoint& b = p[std::size_t(cycle[(i + 1) % cycle.size()])];
    sum += a.x() * b.y() - a.y() * b.x();
  }
  return sum;
}

/// Whether q lies inside or on triangle (a, b, c) (counter-clockwise).
bool inTriangle(const ChartPoint& q, const ChartPoint& a, const ChartPoint& b, const ChartPoint& c, double eps)
{
  return cross(a, b, q) >= -eps && cross(b, c, q) >= -eps && cross(c, a, q) >= -eps;
}

/// Whether two non-adjacent edges of the cycle cross or touch.
bool crossesItself(const std::vector<ChartPoint>& p, const std::vector<int>& cycle, double eps)
{
  const std::size_t n = cycle.size();
  auto point = [&](std::size_t i) -> const ChartPoint& { return p[std::size_t(cycle[i % n])]; };
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 2; j < n; ++j)
    {
      if (i == 0 && j == n - 1)
        continue; // adjacent through the closing edge
      const ChartPoint &a = point(i), &b = point(i + 1), &c = point(j), &d = point(j + 1);
      const double abc = cross(a, b, c), abd = cross(a, b, d), cda = cross(c, d, a), cdb = cross(c, d, b);
      if (((abc > eps && abd < -eps) || (abc < -eps && abd > eps)) &&
          ((cda > eps && cdb < -eps) || (cda < -eps && cdb > eps)))
        return true;
    }
  return false;
}

/// Ear clipping of a simple counter-clockwise cycle.
void clipEars(const std::vector<ChartPoint>& p, std::vector<int> polygon, double eps,
              std::vector<std::array<int, 3>>& out)
{
  std::size_t start = 0;
  while (polygon.size() > 3)
  {
    const std::size_t n = polygon.size();
    bool clipped = false;
    for (std::size_t step = 0; step < n && !clipped; ++step)
    {
      const std::size_t i = (start + step) % n;
      const int a = polygon[(i + n - 1) % n], b = polygon[i], c = polygon[(i + 1) % n];
      const ChartPoint &pa = p[std::size_t(a)], &pb = p[std::size_t(b)], &pc = p[std::size_t(c)];
      if (cross(pa, pb, pc) <= eps)
        continue; // reflex or straight: not an ear
      bool blocked = false;
      for (int v : polygon)
        if (v != a && v != b && v != c && inTriangle(p[std::size_t(v)], pa, pb, pc, eps))
        {
          blocked = true;
          break;
        }
      if (blocked)
        continue;
      out.push_back({a, b, c});
      polygon.erase(polygon.begin() + std::ptrdiff_t(i));
      start = i % polygon.size();
      clipped = true;
    }
    if (!clipped)
      throw std::invalid_argument(
        "hole floor: part of the hole loop cannot be triangulated (it crosses itself or folds back); "
        "check the excision offsets");
  }
  if (cross(p[std::size_t(polygon[0])], p[std::size_t(polygon[1])], p[std::size_t(polygon[2])]) <= eps)
    throw std::invalid_argument("hole floor: the last triangle of part of the hole has no area");
  out.push_back({polygon[0], polygon[1], polygon[2]});
}

/// Positive when d lies inside the circumcircle of counter-clockwise (a, b, c).
double inCircle(const ChartPoint& a, const ChartPoint& b, const ChartPoint& c, const ChartPoint& d)
{
  const ChartPoint ad = a - d, bd = b - d, cd = c - d;
  return ad.squaredNorm() * (bd.x() * cd.y() - bd.y() * cd.x()) -
         bd.squaredNorm() * (ad.x() * cd.y() - ad.y() * cd.x()) +
         cd.squaredNorm() * (ad.x() * bd.y() - ad.y() * bd.x());
}

/// Lawson's flips until every interior edge is locally Delaunay. Border
/// edges (one triangle) never move.
void makeDelaunay(const std::vector<ChartPoint>& p, std::vector<std::array<int, 3>>& triangles, double eps)
{
  const std::size_t limit = 10 * triangles.size() * triangles.size() + 10;
  for (std::size_t pass = 0; pass < limit; ++pass)
  {
    std::map<std::pair<int, int>, std::pair<int, int>> edgeOwner; // directed edge -> (triangle, corner opposite)
    for (std::size_t t = 0; t < triangles.size(); ++t)
      for (int k = 0; k < 3; ++k)
        edgeOwner[{triangles[t][std::size_t(k)], triangles[t][std::size_t((k + 1) % 3)]}] = {int(t), (k + 2) % 3};
    bool flipped = false;
    for (const auto& [edge, owner] : edgeOwner)
    {
      const auto other = edgeOwner.find({edge.second, edge.first});
      if (other == edgeOwner.end() || edge.first > edge.second)
        continue;
      const int a = edge.first, b = edge.second;
      const int c = triangles[std::size_t(owner.first)][std::size_t(owner.second)];
      const int d = triangles[std::size_t(other->second.first)][std::size_t(other->second.second)];
      const ChartPoint &pa = p[std::size_t(a)], &pb = p[std::size_t(b)], &pc = p[std::size_t(c)],
                       &pd = p[std::size_t(d)];
      // (a, b, c) and (b, a, d) become (c, a, d) and (d, b, c) when d is
      // inside the circle through a, b, c and the quad a d b c is convex.
      const double scale = (pa - pb).squaredNorm() + (pc - pd).squaredNorm();
      if (inCircle(pa, pb, pc, pd) <= eps * scale * scale)
        continue;
      if (cross(pc, pa, pd) <= eps || cross(pd, pb, pc) <= eps)
        continue;
      triangles[std::size_t(owner.first)] = {c, a, d};
      triangles[std::size_t(other->second.first)] = {d, b, c};
      flipped = true;
      break; // the edge map is stale
    }
    if (!flipped)
      return;
  }
}

} // namespace

HoleFloor holeFloor(const SurfaceMesh& surface, double tolerance)
{
  const int h = surface.holeVertexCount;
  if (h < 0 || h > int(surface.vertices.size()))
    throw std::invalid_argument("hole floor: the hole loop has " + std::to_string(h) + " vertices but the mesh " +
                                std::to_string(surface.vertices.size()));
  const std::vector<ChartPoint>& p = surface.vertices;
  HoleFloor floor;
  floor.representative.resize(std::size_t(h));
  for (int v = 0; v < h; ++v)
  {
    floor.representative[std::size_t(v)] = v;
    for (int u = 0; u < v; ++u)
      if ((p[std::size_t(u)] - p[std::size_t(v)]).norm() <= tolerance)
      {
        floor.representative[std::size_t(v)] = floor.representative[std::size_t(u)];
        break;
      }
  }
  // The loop with twins merged, without repeats in a row.
  std::vector<int> sequence;
  for (int v = 0; v < h; ++v)
  {
    const int r = floor.representative[std::size_t(v)];
    if (sequence.empty() || sequence.back() != r)
      sequence.push_back(r);
  }
  while (sequence.size() > 1 && sequence.front() == sequence.back())
    sequence.pop_back();

  // Simple cycles: where a vertex comes back, the stretch since its last
  // visit closes a cycle.
  std::vector<std::vector<int>> cycles;
  std::vector<int> stack, positionOf(std::size_t(std::max(h, 1)), -1);
  for (int r : sequence)
  {
    const int k = positionOf[std::size_t(r)];
    if (k >= 0)
    {
      cycles.emplace_back(stack.begin() + k, stack.end());
      for (std::size_t i = std::size_t(k) + 1; i < stack.size(); ++i)
        positionOf[std::size_t(stack[i])] = -1;
      stack.resize(std::size_t(k) + 1);
    }
    else
    {
      positionOf[std::size_t(r)] = int(stack.size());
      stack.push_back(r);
    }
  }
  cycles.push_back(stack);

  for (auto& cycle : cycles)
  {
    if (cycle.size() < 3)
      continue;
    double extent = 0.0;
    for (int v : cycle)
      extent = std::max(extent, (p[std::size_t(v)] - p[std::size_t(cycle[0])]).norm());
    const double eps = 1e-12 * extent * extent;
    const double area2 = twiceArea(p, cycle);
    if (std::abs(area2) <= 1e-9 * extent * extent)
      continue; // a slit folded on itself
    if (crossesItself(p, cycle, eps))
      throw std::invalid_argument(
        "hole floor: the hole loop crosses itself, so the excised region has no inside; check the excision "
        "offsets and the cut path");
    if (area2 < 0.0)
      std::reverse(cycle.begin(), cycle.end());
    std::vector<std::array<int, 3>> triangles;
    clipEars(p, cycle, eps, triangles);
    makeDelaunay(p, triangles, 1e-12);
    floor.triangles.insert(floor.triangles.end(), triangles.begin(), triangles.end());
  }
  return floor;
}

} // namespace caps::fem
