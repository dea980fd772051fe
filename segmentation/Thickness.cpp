#include "segmentation/Thickness.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "segmentation/RangeMapParallel.h"

namespace caps::seg {

namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

void checkSameFrame(const RangeMap& skin, const RangeMap& bone)
{
  if (skin.frame() != bone.frame() || skin.values().size() != bone.values().size())
    throw std::invalid_argument("The skin and bone range maps are on different cylinders or grids.");
}

std::vector<double> finiteSorted(const RangeMap& map)
{
  std::vector<double> v;
  v.reserve(map.values().size());
  for (float x : map.values())
    if (std::isfinite(x))
      v.push_back(x);
  std::sort(v.begin(), v.end());
  return v;
}

double percentileOfSorted(const std::vector<double>& v, double p)
{
  if (v.empty())
    return nan;
  const double h = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (h - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

/// Gap between the point and the bone surface along its ray from the axis.
double gap(const RangeMap& bone, const Eigen::Vector3d& point)
{
  const CylindricalPoint c = bone.frame().toCylindrical(point);
  return c.r - bone.sample(c.theta, c.z);
}

} // namespace

RangeMap radialThickness(const RangeMap& skin, const RangeMap& bone)
{
  checkSameFrame(skin, bone);
  RangeMap out(skin.frame());
  for (std::size_t k = 0; k < out.values().size(); ++k)
    out.values()[k] = skin.values()[k] - bone.values()[k]; // NaN propagates
  return out;
}

RangeMap normalThickness(const RangeMap& skin, const RangeMap& bone, const NormalThicknessOptions& options)
{
  checkSameFrame(skin, bone);
  RangeMap out(skin.frame());
  const double minRadius = 0.5 * options.minStep;
  internal::parallelRows(
    skin.nZ(), options.threads,
    [&](int j) {
      for (int i = 0; i < skin.nTheta(); ++i)
      {
        const Eigen::Vector3d p = skin.surfacePoint(i, j);
        const Eigen::Vector3d n = skin.outwardNormal(i, j);
        if (!p.allFinite() || !n.allFinite())
          continue;
        double f = gap(bone, p);
        if (std::isnan(f))
          continue;
        if (f <= 0.0)
        {
          out.at(i, j) = 0.0f;
          continue;
        }
        double t = 0.0;
        double fPrev = f;
        while (t < options.maxDistance)
        {
          const double step = std::clamp(0.5 * fPrev, options.minStep, options.maxStep);
          const double tNext = t + step;
          const Eigen::Vector3d q = p - tNext * n;
          const CylindricalPoint c = skin.frame().toCylindrical(q);
          if (c.r < minRadius)
            break;
          const double fNext = c.r - bone.sample(c.theta, c.z);
          if (std::isnan(fNext))
            break;
          if (fNext <= 0.0)
          {
            double tOut = t, tIn = tNext;
            bool ok = true;
            for (int it = 0; it < 30 && tIn - tOut > 1e-4; ++it)
            {
              const double mid = 0.5 * (tOut + tIn);
              const double fm = gap(bone, p - mid * n);
              if (std::isnan(fm))
              {
                ok = false;
                break;
              }
              (fm > 0.0 ? tOut : tIn) = mid;
            }
            if (ok)
            {
              out.at(i, j) = static_cast<float>(0.5 * (tOut + tIn));
            }
            break;
          }
          t = tNext;
          fPrev = fNext;
        }
      }
    },
    options.progress, "Tissue thickness along the normal", 0.0, 1.0);
  return out;
}

ThicknessStatistics thicknessStatistics(const RangeMap& map)
{
  const std::vector<double> v = finiteSorted(map);
  ThicknessStatistics s;
  if (v.empty())
    return s;
  s.count = v.size();
  s.min = v.front();
  s.max = v.back();
  double sum = 0.0;
  for (double x : v)
    sum += x;
  s.mean = sum / static_cast<double>(v.size());
  double ss = 0.0;
  for (double x : v)
    ss += (x - s.mean) * (x - s.mean);
  s.standardDeviation = v.size() > 1 ? std::sqrt(ss / static_cast<double>(v.size() - 1)) : 0.0;
  s.p5 = percentileOfSorted(v, 5);
  s.p25 = percentileOfSorted(v, 25);
  s.median = percentileOfSorted(v, 50);
  s.p75 = percentileOfSorted(v, 75);
  s.p95 = percentileOfSorted(v, 95);
  return s;
}

double thicknessPercentile(const RangeMap& map, double p)
{
  return percentileOfSorted(finiteSorted(map), p);
}

} // namespace caps::seg
