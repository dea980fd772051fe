#include "planning/SkinMeasurements.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

namespace caps::planning {
namespace {

constexpr double pi = 3.14159265358979323846;
constexpr double degree = pi / 180.0;

Eigen::Vector3d liftOrThrow(const SkinChart& chart, const ChartPoint& p, const char* what)
{
  const Eigen::Vector3d x = chart.lift(p);
  if (!std::isfinite(x.x()))
  {
    const SkinPoint s = chart.fromChart(p);
    std::ostringstream message;
    message.precision(4);
    message << "cannot measure " << what << ": the skin map has no surface at θ = " << s.theta / degree
            << "°, z = " << s.z << " mm";
    throw std::invalid_argument(message.str());
  }
  return x;
}

double cross2(const ChartPoint& a, const ChartPoint& b)
{
  return a.x() * b.y() - a.y() * b.x();
}

/// Unit 3D tangent of the lifted chart segment corner→towards where it leaves the corner.
Eigen::Vector3d tangent(const SkinChart& chart, const ChartPoint& corner, const ChartPoint& towards)
{
  const ChartPoint d = towards - corner;
  const double length = d.norm();
  if (length <= 0.0)
    throw std::invalid_argument("cannot measure an angle: a limb has zero length");
  // Second-order one-sided difference over a thousandth of a millimetre:
  // inside the first range map cell, far above rounding.
  const double h = std::min(1e-3, 0.25 * length);
  const ChartPoint step = d * (h / length);
  const Eigen::Vector3d t = 4.0 * liftOrThrow(chart, corner + step, "an angle") -
                            3.0 * liftOrThrow(chart, corner, "an angle") -
                            liftOrThrow(chart, corner + 2.0 * step, "an angle");
  return t.normalized();
}

} // namespace

double skinLength(const SkinChart& chart, const ChartPoint& a, const ChartPoint& b, double step)
{
  const int samples = std::max(1, int(std::ceil((b - a).norm() / step)));
  double length = 0.0;
  Eigen::Vector3d previous = liftOrThrow(chart, a, "a limb length");
  for (int k = 1; k <= samples; ++k)
  {
    const Eigen::Vector3d x = liftOrThrow(chart, a + (b - a) * (double(k) / samples), "a limb length");
    length += (x - previous).norm();
    previous = x;
  }
  return length;
}

double skinAngle(const SkinChart& chart, const ChartPoint& corner, const ChartPoint& a, const ChartPoint& b)
{
  const double c = tangent(chart, corner, a).dot(tangent(chart, corner, b));
  return std::acos(std::clamp(c, -1.0, 1.0));
}

double skinArea(const SkinChart& chart, const std::vector<ChartPoint>& polygon, double step)
{
  const int n = int(polygon.size());
  if (n < 3)
    return 0.0;
  ChartPoint centre = ChartPoint::Zero();
  for (const auto& p : polygon)
    centre += p;
  centre /= n;
  // Signed fan: every chart point is covered (winding number) times, so the
  // sum is the polygon's area even when it is not star-shaped about centre.
  double area = 0.0;
  std::vector<Eigen::Vector3d> row, next;
  for (int e = 0; e < n; ++e)
  {
    const ChartPoint p = polygon[e], q = polygon[(e + 1) % n];
    const double orientation = cross2(p - centre, q - centre);
    if (std::abs(orientation) < 1e-14)
      continue; // degenerate: a slit or a point on the fan's ray
    const double sign = orientation > 0 ? 1.0 : -1.0;
    const double longest = std::max({(p - centre).norm(), (q - centre).norm(), (q - p).norm()});
    const int m = std::clamp(int(std::ceil(longest / step)), 1, 400);
    // Grid points centre + i/m (p − centre) + j/m (q − centre), i + j ≤ m.
    auto at = [&](int i, int j) {
      return liftOrThrow(chart, centre + (p - centre) * (double(i) / m) + (q - centre) * (double(j) / m),
                         "the excised area");
    };
    row.clear();
    for (int j = 0; j <= m; ++j)
      row.push_back(at(0, j));
    double triangleArea = 0.0;
    for (int i = 0; i < m; ++i)
    {
      next.clear();
      for (int j = 0; j <= m - i - 1; ++j)
        next.push_back(at(i + 1, j));
      for (int j = 0; j < m - i; ++j)
      {
        triangleArea += 0.5 * (row[j + 1] - row[j]).cross(next[j] - row[j]).norm();
        if (j + 1 < m - i)
          triangleArea += 0.5 * (row[j + 1] - next[j]).cross(next[j + 1] - next[j]).norm();
      }
      row.swap(next);
    }
    area += sign * triangleArea;
  }
  return std::abs(area);
}

double excisedArea(const IncisionPlan& plan, const seg::RangeMap& skin)
{
  if (!plan.isExcision())
    return 0.0;
  const SkinChart chart = plan.chart(skin);
  return skinArea(chart, plan.holeLoop(chart).points);
}

double tissueVolume(const SkinChart& chart, const seg::RangeMap& bone, const std::vector<ChartPoint>& polygon,
                    double noBoneDepth, double step)
{
  if (!(noBoneDepth > 0.0) || !std::isfinite(noBoneDepth))
    throw std::invalid_argument("the depth used where there is no bone must be a positive number of mm");
  const seg::RangeMap& skin = chart.skin();
  const bool haveBone = !bone.empty();
  if (haveBone && ((bone.frame().origin() - skin.frame().origin()).norm() > 1e-6 ||
                   (bone.frame().direction() - skin.frame().direction()).norm() > 1e-9))
    throw std::invalid_argument("the bone range map is on another cylinder axis than the skin map: "
                                "build both on the same frame");
  const int n = int(polygon.size());
  if (n < 3)
    return 0.0;
  // (r_skin² − r_bone²) / (2 r0): volume per chart mm² under chart point c.
  auto density = [&](const ChartPoint& c) {
    const SkinPoint s = chart.fromChart(c);
    auto refuse = [&](const char* why) {
      std::ostringstream message;
      message.precision(4);
      message << "cannot measure the excised volume: " << why << " at θ = " << s.theta / degree << "°, z = " << s.z
              << " mm";
      throw std::invalid_argument(message.str());
    };
    const double rSkin = skin.sample(s.theta, s.z);
    if (!std::isfinite(rSkin))
      refuse("the skin map has no surface");
    double rBone = haveBone ? bone.sample(s.theta, s.z) : std::nan("");
    if (!std::isfinite(rBone))
      rBone = rSkin - noBoneDepth;
    if (rBone > rSkin)
      refuse("the bone lies above the skin");
    return (rSkin * rSkin - rBone * rBone) / (2.0 * chart.radius());
  };
  ChartPoint centre = ChartPoint::Zero();
  for (const auto& p : polygon)
    centre += p;
  centre /= n;
  // Signed fan as in skinArea(): points outside a non-star-shaped polygon
  // are covered once each way and cancel.
  double volume = 0.0;
  for (int e = 0; e < n; ++e)
  {
    const ChartPoint a = polygon[e] - centre, b = polygon[(e + 1) % n] - centre;
    const double twiceArea = cross2(a, b);
    if (std::abs(twiceArea) < 1e-14)
      continue;
    const double longest = std::max({a.norm(), b.norm(), (b - a).norm()});
    const int m = std::clamp(int(std::ceil(longest / step)), 1, 400);
    // m² sub-triangles of equal area: the upright ones (i, j), (i+1, j),
    // (i, j+1) and the inverted ones (i+1, j), (i+1, j+1), (i, j+1).
    double sum = 0.0;
    auto at = [&](double i, double j) { return ChartPoint(centre + a * (i / m) + b * (j / m)); };
    for (int i = 0; i < m; ++i)
      for (int j = 0; i + j < m; ++j)
      {
        sum += density(at(i + 1.0 / 3.0, j + 1.0 / 3.0));
        if (i + j + 1 < m)
          sum += density(at(i + 2.0 / 3.0, j + 2.0 / 3.0));
      }
    volume += 0.5 * twiceArea * sum / (double(m) * m);
  }
  return std::abs(volume);
}

double excisedVolume(const IncisionPlan& plan, const seg::RangeMap& skin, const seg::RangeMap& bone, double noBoneDepth)
{
  if (!plan.isExcision())
    return 0.0;
  const SkinChart chart = plan.chart(skin);
  return tissueVolume(chart, bone, plan.holeLoop(chart).points, noBoneDepth);
}

PlanMeasurements measurePlan(const IncisionPlan& plan, const seg::RangeMap& skin)
{
  const SkinChart chart = plan.chart(skin);
  const auto path = plan.chartPath(chart);
  const fem::HoleLoop loop = plan.holeLoop(chart);
  PlanMeasurements m;
  const int n = int(path.size());
  for (int i = 0; i + 1 < n; ++i)
    m.limbs.push_back({i, i + 1, (path[i + 1] - path[i]).norm(), skinLength(chart, path[i], path[i + 1])});
  for (int i = 1; i + 1 < n; ++i)
  {
    const ChartPoint a = path[i - 1] - path[i], b = path[i + 1] - path[i];
    const double chartAngle = std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
    m.limbAngles.push_back({i, chartAngle, skinAngle(chart, path[i], path[i - 1], path[i + 1])});
  }
  const int loopSize = int(loop.points.size());
  for (int v = 0; v < loopSize; ++v)
  {
    const ChartPoint p = loop.points[v], q = loop.points[(v + 1) % loopSize];
    m.borderEdges.push_back({v, (v + 1) % loopSize, (q - p).norm(), skinLength(chart, p, q)});
  }
  for (int v = 0; v < loopSize; ++v)
  {
    const ChartPoint prev = loop.points[(v + loopSize - 1) % loopSize], here = loop.points[v],
                     next = loop.points[(v + 1) % loopSize];
    if ((prev - here).norm() < 1e-9 || (next - here).norm() < 1e-9)
      continue; // two border points on one spot: no corner to measure
    const double between = skinAngle(chart, here, prev, next);
    // Skin is to the left of the border: the angle turns counter-clockwise
    // from the next edge to the previous one (chart orientation = seen from outside).
    const double turn = cross2(next - here, prev - here);
    const bool slit =
      std::abs(turn) < 1e-12 * (prev - here).norm() * (next - here).norm() && (prev - here).dot(next - here) > 0.0;
    double angle = turn >= 0.0 ? between : 2.0 * pi - between;
    if (slit)
      angle = 2.0 * pi - between;
    m.borderAngles.push_back({v, angle});
  }
  m.excisedArea = plan.isExcision() ? skinArea(chart, loop.points) : 0.0;
  return m;
}

double zPlastyTheoreticalGain(double limbAngle)
{
  // Fig. 2.2 (McCarthy, Plastic Surgery [27]): angles of the Z and the
  // theoretical gain in length of the central limb.
  static const double angles[] = {30.0, 45.0, 60.0, 75.0, 90.0};
  static const double gains[] = {0.25, 0.50, 0.75, 1.00, 1.20};
  const double a = limbAngle / degree;
  if (!(a >= 30.0 - 1e-9 && a <= 90.0 + 1e-9))
  {
    std::ostringstream message;
    message << "the Z-plasty gain table (thesis Fig. 2.2) covers limb angles from 30° to 90°, not " << a << "°";
    throw std::invalid_argument(message.str());
  }
  for (int k = 0; k < 4; ++k)
    if (a <= angles[k + 1] + 1e-9)
    {
      const double t = std::clamp((a - angles[k]) / (angles[k + 1] - angles[k]), 0.0, 1.0);
      return gains[k] + t * (gains[k + 1] - gains[k]);
    }
  return gains[4];
}

double zPlastyGeometricGain(double limbAngle)
{
  return std::sqrt(5.0 - 4.0 * std::cos(limbAngle)) - 1.0;
}

ZPlastyGain zPlastyPredictedGain(const std::array<Eigen::Vector3d, 2>& tipsBefore,
                                 const std::array<Eigen::Vector3d, 2>& tipsAfter, const Eigen::Vector3d& axis)
{
  const Eigen::Vector3d a = axis.normalized();
  ZPlastyGain g;
  g.before = std::abs((tipsBefore[1] - tipsBefore[0]).dot(a));
  g.after = std::abs((tipsAfter[1] - tipsAfter[0]).dot(a));
  g.gain = g.after - g.before;
  if (g.before <= 0.0)
    throw std::invalid_argument("the flap tips are not apart along the central axis: cannot express the gain as a "
                                "fraction of the central limb");
  g.fraction = g.gain / g.before;
  return g;
}

std::array<int, 2> zPlastyFlapTips(const IncisionPlan& plan)
{
  if (plan.generator() == "z" && plan.pointCount() == 4)
    return {1, 2};
  if (plan.generator() == "multiple-z" && plan.pointCount() == 7)
    return {2, 4};
  throw std::invalid_argument("the plan '" + plan.procedure() + "' is not a Z-plasty: it has no flap tips");
}

Eigen::Vector3d centralAxis(const IncisionPlan& plan, const seg::RangeMap& skin)
{
  const auto tips = zPlastyFlapTips(plan);
  const SkinChart chart = plan.chart(skin);
  const auto path = plan.chartPath(chart);
  return (liftOrThrow(chart, path[tips[1]], "the central axis") - liftOrThrow(chart, path[tips[0]], "the central axis"))
    .normalized();
}

} // namespace caps::planning
