#include "planning/SkinTensionLines.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>

#include <vtkCellArray.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>

#include "planning/IncisionPlan.h"
#include "planning/PlanLines.h"

namespace caps::planning {

namespace {

constexpr double kPi = std::numbers::pi;

// 0 up to a, 1 from b on, smooth (C1) in between; a > b gives the reverse.
double smooth(double t, double a, double b)
{
  double u = (t - a) / (b - a);
  u = std::clamp(u, 0.0, 1.0);
  return u * u * (3.0 - 2.0 * u);
}

// Lines have no sign: directions add on the doubled angle.
struct AxialSum
{
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  void add(double weight, double angle)
  {
    if (weight > 0.0)
      sum += weight * Eigen::Vector2d(std::cos(2.0 * angle), std::sin(2.0 * angle));
  }
  double angle() const { return 0.5 * std::atan2(sum.y(), sum.x()); }
};

// a + t (b - a) for line angles, the short way round (mod π).
double lerpAxial(double a, double b, double t)
{
  double d = std::remainder(b - a, kPi);
  return a + t * d;
}

const seg::Landmark* findLandmark(const std::vector<seg::Landmark>& landmarks, const std::string& name)
{
  for (const auto& l : landmarks)
    if (l.name == name && std::isfinite(l.z))
      return &l;
  return nullptr;
}

} // namespace

FaceLayout FaceLayout::fromLandmarks(const std::vector<seg::Landmark>& landmarks, const seg::RangeMap& skin)
{
  std::string missing;
  auto z = [&](const char* name) {
    const seg::Landmark* l = findLandmark(landmarks, name);
    if (!l)
    {
      missing += missing.empty() ? "" : ", ";
      missing += name;
      return 0.0;
    }
    return l->z;
  };
  FaceLayout f;
  f.zGlabella = z("glabella");
  f.zNasion = z("nasion");
  f.zPronasale = z("pronasale");
  f.zSubnasale = z("subnasale");
  const double upperLip = z("labrale_superius");
  f.zLabraleInferius = z("labrale_inferius");
  if (const seg::Landmark* menton = findLandmark(landmarks, "menton"))
    f.zMenton = menton->z;
  else if (const seg::Landmark* pogonion = findLandmark(landmarks, "pogonion"))
    f.zMenton = pogonion->z - 12.0;
  else
    missing += missing.empty() ? "menton (or pogonion)" : ", menton (or pogonion)";
  if (!missing.empty())
    throw std::invalid_argument("The skin tension lines are placed by the facial landmarks, and these are missing: " +
                                missing + ". Place them in the Range maps module (or run it again to find them).");
  f.zStomion = 0.5 * (upperLip + f.zLabraleInferius);
  if (!(f.zGlabella > f.zNasion - 5.0 && f.zNasion > f.zPronasale && f.zPronasale > f.zSubnasale &&
        f.zSubnasale > upperLip && upperLip > f.zLabraleInferius && f.zLabraleInferius > f.zMenton))
    throw std::invalid_argument(
      "The facial landmarks are not in anatomical order from the glabella down to the menton; "
      "check them in the Range maps module before showing the skin tension lines.");
  const seg::Landmark* nasion = findLandmark(landmarks, "nasion");
  f.frontTheta = nasion->theta;
  const double r = skin.sample(nasion->theta, nasion->z);
  f.scale = std::isfinite(r) && r > 20.0 ? r : 90.0;
  // Average adult proportions (Farkas 1994), scaled by this face's height.
  const double size = (f.zNasion - f.zSubnasale) / 53.0;
  f.eyeOffset = 32.0 * size;
  f.eyeZ = f.zNasion - 0.15 * (f.zNasion - f.zSubnasale);
  f.mouthHalfWidth = 25.0 * size;
  return f;
}

SkinTensionLines::SkinTensionLines(const seg::RangeMap& skin, FaceLayout layout) : skin_(&skin), layout_(layout) {}

double SkinTensionLines::planeAngle(double x, double y) const
{
  const FaceLayout& f = layout_;
  const double h = std::max(f.zNasion - f.zSubnasale, 20.0); // the unit of the face's heights
  const double w = f.eyeOffset;                              // and of its widths
  const double s = x >= 0.0 ? 1.0 : -1.0;
  const double ax = std::abs(x);
  AxialSum field;

  // Cheek: parallel to the nasolabial fold (ala down and out past the mouth
  // corner), turning vertical in front of the ear; faintly everywhere, so
  // that the other regions decide where they are.
  const Eigen::Vector2d ala(s * 0.55 * w, f.zSubnasale + 0.1 * h);
  const Eigen::Vector2d pastCorner(s * (f.mouthHalfWidth + 0.3 * w), f.zStomion - 0.35 * h);
  const Eigen::Vector2d fold = pastCorner - ala;
  const double cheek = smooth(ax, 0.35 * w, 0.6 * w) * (1.0 - smooth(y, f.eyeZ - 0.3 * h, f.eyeZ - 0.1 * h)) *
                       smooth(y, f.zMenton - 0.05 * h, f.zMenton + 0.15 * h);
  field.add(0.02 + 2.0 * cheek, lerpAxial(std::atan2(fold.y(), fold.x()), kPi / 2.0, smooth(ax, 1.4 * w, 2.6 * w)));

  // Forehead: arcs about a centre far below, horizontal on the midline.
  {
    const Eigen::Vector2d p(x, y - (f.zGlabella - 4.0 * h));
    field.add(3.0 * smooth(y, f.zGlabella - 0.15 * h, f.zGlabella + 0.15 * h), std::atan2(-p.x(), p.y()));
  }
  // Glabella: vertical between the brows.
  field.add(6.0 * (1.0 - smooth(ax, 0.3 * w, 0.5 * w)) * smooth(y, f.zNasion - 0.05 * h, f.zNasion + 0.15 * h) *
              (1.0 - smooth(y, f.zGlabella + 0.25 * h, f.zGlabella + 0.5 * h)),
            kPi / 2.0);
  // Eyes: flat arcs along the lids, radiating from the lateral canthus.
  for (const double side : {1.0, -1.0})
  {
    const Eigen::Vector2d d = Eigen::Vector2d(x, y) - Eigen::Vector2d(side * w, f.eyeZ);
    const double rho = d.norm();
    const double zone = 4.0 * (1.0 - smooth(std::hypot(d.x() / 1.4, d.y()), 0.35 * h, 0.55 * h));
    if (rho > 1e-9 && zone > 0.0)
    {
      const double lateral = smooth(side * d.x() / rho, 0.55, 0.8);
      field.add(zone * (1.0 - lateral), std::atan2(d.x(), -3.24 * d.y())); // ellipse 1.8 : 1 tangent
      field.add(zone * lateral, std::atan2(d.y(), d.x()));
    }
  }
  // Nasal dorsum: across the nose.
  field.add(5.0 * (1.0 - smooth(ax, 0.3 * w, 0.5 * w)) * smooth(y, f.zPronasale - 0.05 * h, f.zPronasale + 0.1 * h) *
              (1.0 - smooth(y, f.zNasion - 0.15 * h, f.zNasion)),
            0.0);
  // Lips: radial to the mouth, up to the nose and down to the chin.
  {
    const Eigen::Vector2d d(x, y - f.zStomion);
    const double up = std::max(f.zSubnasale - f.zStomion, 5.0);
    const double down = std::max(f.zStomion - f.zLabraleInferius, 3.0) + 0.1 * h;
    const double rho = std::hypot(d.x() / (f.mouthHalfWidth + 0.25 * h), d.y() / (d.y() > 0.0 ? up : down));
    if (d.norm() > 1e-9)
      field.add(5.0 * (1.0 - smooth(rho, 0.85, 1.15)), std::atan2(d.y(), d.x()));
  }
  // Chin: arcs rising a little to the sides.
  {
    const Eigen::Vector2d p(x, y - (f.zMenton + 3.0 * h));
    field.add(6.0 * (1.0 - smooth(y, f.zLabraleInferius - 0.25 * h, f.zLabraleInferius - 0.1 * h)) *
                (1.0 - smooth(ax, 0.9 * w, 1.3 * w)),
              std::atan2(p.x(), -p.y()));
  }
  // Neck: horizontal.
  field.add(6.0 * (1.0 - smooth(y, f.zMenton - 0.15 * h, f.zMenton + 0.05 * h)), 0.0);
  return field.angle();
}

Eigen::Vector2d SkinTensionLines::directionAt(double theta, double z) const
{
  const double x = layout_.scale * std::remainder(theta - layout_.frontTheta, 2.0 * kPi);
  const double phi = planeAngle(x, z);
  double r = skin_->sample(theta, z);
  if (!std::isfinite(r) || r <= 0.0)
    r = layout_.scale;
  // d/dx = (1/scale) d/dθ: a plane step (cos φ, sin φ) is r/scale·cos φ mm around the head.
  return Eigen::Vector2d(r / layout_.scale * std::cos(phi), std::sin(phi)).normalized();
}

double SkinTensionLines::angleTo(double theta, double z, const Eigen::Vector2d& direction) const
{
  if (direction.norm() == 0.0)
    throw std::invalid_argument("a direction of zero length has no angle to the skin tension lines");
  const double c = std::abs(directionAt(theta, z).dot(direction.normalized()));
  return std::acos(std::min(1.0, c)) * 180.0 / kPi;
}

bool SkinTensionLines::covers(double theta, double z) const
{
  const FaceLayout& f = layout_;
  const double h = std::max(f.zNasion - f.zSubnasale, 20.0);
  const double x = f.scale * std::remainder(theta - f.frontTheta, 2.0 * kPi);
  if (std::abs(x) > 2.9 * f.eyeOffset || z < f.zMenton - 0.7 * h || z > f.zGlabella + 1.3 * h)
    return false;
  // Not across the mouth or the eyes (where the radial and the lid lines meet).
  if (std::hypot(x / f.mouthHalfWidth, (z - f.zStomion) / (0.6 * (f.zStomion - f.zLabraleInferius))) < 1.0)
    return false;
  if (std::hypot((std::abs(x) - f.eyeOffset) / (0.45 * f.eyeOffset), (z - f.eyeZ) / (0.1 * h)) < 1.0)
    return false;
  return std::isfinite(skin_->sample(theta, z));
}

std::vector<std::vector<SkinPoint>> SkinTensionLines::traceLines(double spacing) const
{
  if (!(spacing >= 2.0))
    throw std::invalid_argument("the skin tension lines need a spacing of at least 2 mm");
  const FaceLayout& f = layout_;
  const double h = std::max(f.zNasion - f.zSubnasale, 20.0);
  const double xMax = 2.9 * f.eyeOffset, yMin = f.zMenton - 0.7 * h, yMax = f.zGlabella + 1.3 * h;
  const double step = std::min(0.5, spacing / 6.0);
  auto thetaOf = [&f](double x) { return f.frontTheta + x / f.scale; };
  auto inside = [&](const Eigen::Vector2d& p) { return covers(thetaOf(p.x()), p.y()); };
  auto direction = [&](const Eigen::Vector2d& p) {
    const double phi = planeAngle(p.x(), p.y());
    return Eigen::Vector2d(std::cos(phi), std::sin(phi));
  };

  // Points of the lines kept so far, bucketed by cells of the spacing, so a
  // new line stops where it comes within half a spacing of another.
  std::map<std::pair<int, int>, std::vector<Eigen::Vector2d>> cells;
  auto cellOf = [spacing](const Eigen::Vector2d& p) {
    return std::make_pair(int(std::floor(p.x() / spacing)), int(std::floor(p.y() / spacing)));
  };
  auto nearest = [&](const Eigen::Vector2d& p) {
    double best = std::numeric_limits<double>::infinity();
    const auto [cx, cy] = cellOf(p);
    for (int i = cx - 1; i <= cx + 1; ++i)
      for (int j = cy - 1; j <= cy + 1; ++j)
        if (auto it = cells.find({i, j}); it != cells.end())
          for (const auto& q : it->second)
            best = std::min(best, (q - p).norm());
    return best;
  };

  std::vector<std::vector<SkinPoint>> lines;
  for (double y0 = yMin + 0.5 * spacing; y0 < yMax; y0 += spacing)
    for (double x0 = -xMax + 0.5 * spacing; x0 < xMax; x0 += spacing)
    {
      const Eigen::Vector2d seed(x0, y0);
      if (!inside(seed) || nearest(seed) < 0.9 * spacing)
        continue;
      // Both ways from the seed (midpoint rule, the direction kept
      // consistent along the line), stopping at the edge of the guide, near
      // another line, at a sharp turn (a meeting point of regions) or after
      // 150 mm.
      std::vector<Eigen::Vector2d> halves[2];
      for (int side = 0; side < 2; ++side)
      {
        Eigen::Vector2d p = seed, heading = direction(seed) * (side == 0 ? 1.0 : -1.0);
        for (double length = 0.0; length < 150.0; length += step)
        {
          Eigen::Vector2d d = direction(p);
          if (d.dot(heading) < 0.0)
            d = -d;
          const Eigen::Vector2d mid = p + 0.5 * step * d;
          Eigen::Vector2d dm = direction(mid);
          if (dm.dot(d) < 0.0)
            dm = -dm;
          if (dm.dot(heading) < std::cos(10.0 * kPi / 180.0))
            break;
          const Eigen::Vector2d next = p + step * dm;
          if (!inside(next) || nearest(next) < 0.5 * spacing)
            break;
          halves[side].push_back(next);
          heading = dm;
          p = next;
        }
      }
      std::vector<Eigen::Vector2d> line(halves[1].rbegin(), halves[1].rend());
      line.push_back(seed);
      line.insert(line.end(), halves[0].begin(), halves[0].end());
      if (double(line.size() - 1) * step < 2.0 * spacing)
        continue;
      std::vector<SkinPoint> points;
      for (const auto& p : line)
      {
        cells[cellOf(p)].push_back(p);
        points.push_back({std::remainder(thetaOf(p.x()), 2.0 * kPi), p.y()});
      }
      lines.push_back(std::move(points));
    }
  return lines;
}

vtkSmartPointer<vtkPolyData> skinTensionLinesPolyData(const SkinTensionLines& lines, double spacing)
{
  const seg::RangeMap& skin = lines.skin();
  auto points = vtkSmartPointer<vtkPoints>::New();
  auto cells = vtkSmartPointer<vtkCellArray>::New();
  for (const auto& line : lines.traceLines(spacing))
  {
    std::vector<vtkIdType> ids;
    for (const auto& p : line)
    {
      // Lifted off the skin as the plan's lines are, so the surface does not hide them.
      const Eigen::Vector3d x = skin.frame().toWorld(skin.sample(p.theta, p.z) + kIncisionLineLift, p.theta, p.z);
      if (x.allFinite())
        ids.push_back(points->InsertNextPoint(x.data()));
    }
    if (ids.size() >= 2)
      cells->InsertNextCell(vtkIdType(ids.size()), ids.data());
  }
  auto data = vtkSmartPointer<vtkPolyData>::New();
  data->SetPoints(points);
  data->SetLines(cells);
  return data;
}

AxisToTensionLines axisToTensionLines(const IncisionPlan& plan, const SkinTensionLines& lines)
{
  if (plan.pointCount() < 2)
    throw std::invalid_argument("the plan has no cut to compare with the skin tension lines");
  const bool z = (plan.generator() == "z" || plan.generator() == "multiple-z") && plan.pointCount() >= 4;
  const int a = z ? 1 : 0;
  const int b = z ? 2 : plan.pointCount() - 1;
  const SkinChart chart = plan.chart(lines.skin());
  const std::vector<ChartPoint> path = plan.chartPath(chart);
  const ChartPoint middle = 0.5 * (path[std::size_t(a)] + path[std::size_t(b)]);
  const SkinPoint at = chart.fromChart(middle);
  if (!lines.covers(at.theta, at.z))
    throw std::invalid_argument("the cut is outside the part of the face the skin tension lines cover");
  // The chart's u is r0·dθ; the lines' metric is r·dθ at the point itself.
  const double r = lines.skin().sample(at.theta, at.z);
  Eigen::Vector2d d = path[std::size_t(b)] - path[std::size_t(a)];
  d.x() *= r / chart.radius();
  AxisToTensionLines result;
  char axis[32];
  std::snprintf(axis, sizeof axis, "p%d–p%d", a, b);
  result.axis = axis;
  result.degrees = lines.angleTo(at.theta, at.z, d);
  return result;
}

} // namespace caps::planning
