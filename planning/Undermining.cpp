#include "planning/Undermining.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace caps::planning {
namespace {

constexpr double pi = 3.14159265358979323846;
/// Chart points closer than this (mm) are one point; borders closer than this touch.
constexpr double kSamePlace = 1e-6;

double cross2(const ChartPoint& a, const ChartPoint& b)
{
  return a.x() * b.y() - a.y() * b.x();
}

double distanceToSegment(const ChartPoint& p, const ChartPoint& a, const ChartPoint& b)
{
  const ChartPoint d = b - a;
  const double length2 = d.squaredNorm();
  const double t = length2 > 0.0 ? std::clamp((p - a).dot(d) / length2, 0.0, 1.0) : 0.0;
  return (p - (a + t * d)).norm();
}

/// Whether segments pq and rs cross or come within kSamePlace of each other.
bool segmentsMeet(const ChartPoint& p, const ChartPoint& q, const ChartPoint& r, const ChartPoint& s)
{
  const double d1 = cross2(q - p, r - p), d2 = cross2(q - p, s - p);
  const double d3 = cross2(s - r, p - r), d4 = cross2(s - r, q - r);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)))
    return true;
  return std::min({distanceToSegment(p, r, s), distanceToSegment(q, r, s), distanceToSegment(r, p, q),
                   distanceToSegment(s, p, q)}) < kSamePlace;
}

std::string whereText(const SkinPoint& s)
{
  std::ostringstream o;
  o.precision(4);
  o << "θ = " << s.theta * 180.0 / pi << "°, z = " << s.z << " mm";
  return o.str();
}

std::string mmText(double mm)
{
  std::ostringstream o;
  o.precision(4);
  o << mm;
  return o.str();
}

std::string pointText(int k)
{
  return "point " + std::to_string(k);
}

std::string edgeText(int k, int n)
{
  return "edge " + std::to_string(k) + " (points " + std::to_string(k) + "–" + std::to_string((k + 1) % n) + ")";
}

} // namespace

std::vector<ChartPoint> regionInChart(const UnderminedRegion& region, const SkinChart& chart)
{
  const seg::CylindricalFrame& frame = chart.skin().frame();
  std::vector<ChartPoint> out;
  out.reserve(region.size());
  SkinPoint previous;
  for (std::size_t k = 0; k < region.size(); ++k)
  {
    const SkinPoint s = skinPointFromNormalized(frame, region[k]);
    if (k == 0)
      out.push_back(chart.toChart(s));
    else
      out.emplace_back(out.back().x() + chart.radius() * seg::CylindricalFrame::wrapTheta(s.theta - previous.theta),
                       s.z - chart.centreZ());
    previous = s;
  }
  return out;
}

bool insidePolygon(const std::vector<ChartPoint>& polygon, const ChartPoint& p)
{
  bool inside = false;
  const std::size_t n = polygon.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++)
  {
    const ChartPoint& a = polygon[i];
    const ChartPoint& b = polygon[j];
    // Edge (b, a) straddles the horizontal line through p (half-open in v),
    // and meets it to the right of p.
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < a.x() + (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()))
      inside = !inside;
  }
  return inside;
}

bool insideRegion(const std::vector<ChartPoint>& region, const ChartPoint& p, double period)
{
  if (region.size() < 3)
    return false;
  for (const double shift : {0.0, period, -period})
    if (insidePolygon(region, p + ChartPoint(shift, 0.0)))
      return true;
  return false;
}

void checkUnderminedRegion(const UnderminedRegion& region, const SkinChart& chart)
{
  const int n = int(region.size());
  if (n < 3)
    throw std::invalid_argument("an undermined region is a closed polygon of at least 3 points on the skin; this one "
                                "has " +
                                std::to_string(n) + ": add points round the skin to undermine");
  const seg::RangeMap& skin = chart.skin();
  const seg::CylindricalFrame& frame = skin.frame();
  for (int k = 0; k < n; ++k)
  {
    const Eigen::Vector2d& p = region[std::size_t(k)];
    if (!p.allFinite())
      throw std::invalid_argument(pointText(k) + " of the region is not a number");
    const SkinPoint s = skinPointFromNormalized(frame, p);
    if (std::abs(p.y()) > 1.0)
      throw std::invalid_argument(pointText(k) + " of the region (" + whereText(s) +
                                  ") is outside the scanned region (z from " + mmText(frame.zMin()) + " to " +
                                  mmText(frame.zMax()) + " mm): move it onto the skin map");
    if (!std::isfinite(skin.sample(s.theta, s.z)))
      throw std::invalid_argument("the skin map has no surface under " + pointText(k) + " of the region (" +
                                  whereText(s) + "): move it onto measured skin");
  }
  const std::vector<ChartPoint> poly = regionInChart(region, chart);
  for (int k = 0; k < n; ++k)
    if ((poly[std::size_t((k + 1) % n)] - poly[std::size_t(k)]).norm() < kSamePlace)
      throw std::invalid_argument("points " + std::to_string(k) + " and " + std::to_string((k + 1) % n) +
                                  " of the region are at the same place: delete one of them");
  // Round the head: the closing edge, taken the short way, does not come
  // back to the first point.
  {
    const double closingStep =
      chart.radius() * seg::CylindricalFrame::wrapTheta(skinPointFromNormalized(frame, region.front()).theta -
                                                        skinPointFromNormalized(frame, region.back()).theta);
    if (std::abs(poly.back().x() + closingStep - poly.front().x()) > pi * chart.radius())
      throw std::invalid_argument("the region goes all the way round the head: draw it as a loop on one side of the "
                                  "head (two regions for a ring)");
  }
  for (int i = 0; i < n; ++i)
    for (int j = i + 2; j < n; ++j)
    {
      if (i == 0 && j == n - 1)
        continue; // neighbours through point 0
      if (segmentsMeet(poly[std::size_t(i)], poly[std::size_t(i + 1)], poly[std::size_t(j)],
                       poly[std::size_t((j + 1) % n)]))
        throw std::invalid_argument(edgeText(i, n) + " and " + edgeText(j, n) +
                                    " of the region cross or touch: a region's border may not cross itself; "
                                    "draw it as one loop, or as two regions");
    }
  double twiceArea = 0.0, perimeter = 0.0;
  for (int k = 0; k < n; ++k)
  {
    const ChartPoint& a = poly[std::size_t(k)];
    const ChartPoint& b = poly[std::size_t((k + 1) % n)];
    twiceArea += cross2(a, b);
    perimeter += (b - a).norm();
  }
  if (std::abs(0.5 * twiceArea) <= 1e-6 * perimeter * perimeter)
    throw std::invalid_argument("the region has no area (its points lie on one line): draw a loop round the skin to "
                                "undermine");
  // A border folding back along itself touches an edge that is not its
  // neighbour (above) or, with 3 points, encloses no area: both refused.
}

std::vector<char> underminedRegionVertices(const fem::SurfaceMesh& surface, const IncisionPlan& plan,
                                           const SkinChart& chart)
{
  std::vector<char> flags(surface.vertices.size(), 0);
  addUnderminedRegions(surface, plan, chart, flags);
  return flags;
}

void addUnderminedRegions(const fem::SurfaceMesh& surface, const IncisionPlan& plan, const SkinChart& chart,
                          std::vector<char>& flags)
{
  if (flags.size() != surface.vertices.size())
    throw std::invalid_argument("addUnderminedRegions: " + std::to_string(flags.size()) +
                                " undermining flags for a surface mesh of " + std::to_string(surface.vertices.size()) +
                                " vertices");
  const double period = 2.0 * pi * chart.radius();
  for (const UnderminedRegion& region : plan.underminedRegions())
  {
    const std::vector<ChartPoint> polygon = regionInChart(region, chart);
    for (std::size_t v = 0; v < surface.vertices.size(); ++v)
      if (!flags[v] && insideRegion(polygon, surface.vertices[v], period))
        flags[v] = 1;
  }
}

} // namespace caps::planning
