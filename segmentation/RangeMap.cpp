#include "segmentation/RangeMap.h"

#include <cmath>
#include <limits>

namespace caps::seg {

float RangeMap::quietNaN()
{
  return std::numeric_limits<float>::quiet_NaN();
}

RangeMap::RangeMap() : frame_() {}

RangeMap::RangeMap(const CylindricalFrame& frame, float value)
  : frame_(frame), values_(static_cast<std::size_t>(frame.nTheta()) * static_cast<std::size_t>(frame.nZ()), value)
{}

std::size_t RangeMap::validCount() const
{
  std::size_t n = 0;
  for (float v : values_)
    n += std::isfinite(v) ? 1 : 0;
  return n;
}

double RangeMap::sampleIndex(double u, double v) const
{
  const int nt = nTheta();
  const int nz = nZ();
  if (values_.empty() || !(v >= 0.0 && v <= nz - 1) || !std::isfinite(u))
    return std::numeric_limits<double>::quiet_NaN();
  // eq. 4.4–4.7, u wrapped into [0, nθ).
  u = std::fmod(u, static_cast<double>(nt));
  if (u < 0.0)
    u += nt;
  int i0 = static_cast<int>(std::floor(u));
  if (i0 >= nt)
    i0 = nt - 1;
  int j0 = static_cast<int>(std::floor(v));
  if (j0 >= nz - 1)
    j0 = nz - 2;
  const double fu = u - i0;
  const double fv = v - j0;
  const int i1 = i0 + 1 == nt ? 0 : i0 + 1;
  const int j1 = j0 + 1;
  const double w[4] = {(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv};
  const float r[4] = {at(i0, j0), at(i1, j0), at(i0, j1), at(i1, j1)};
  if (std::isfinite(r[0]) && std::isfinite(r[1]) && std::isfinite(r[2]) && std::isfinite(r[3]))
    // eq. 4.9
    return ((1 - fu) * r[0] + fu * r[1]) * (1 - fv) + ((1 - fu) * r[2] + fu * r[3]) * fv;
  double sum = 0.0;
  double weight = 0.0;
  for (int c = 0; c < 4; ++c)
    if (std::isfinite(r[c]) && w[c] > 0.0)
    {
      sum += w[c] * r[c];
      weight += w[c];
    }
  if (weight < 0.5)
    return std::numeric_limits<double>::quiet_NaN();
  return sum / weight;
}

double RangeMap::sample(double theta, double z) const
{
  return sampleIndex(frame_.thetaToIndex(theta), frame_.zToIndex(z));
}

Eigen::Vector3d RangeMap::surfacePoint(int i, int j) const
{
  const float r = at(i, j);
  if (!std::isfinite(r))
    return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  return frame_.toWorld(r, frame_.indexToTheta(i), frame_.indexToZ(j));
}

Eigen::Vector3d RangeMap::outwardNormal(int i, int j) const
{
  const Eigen::Vector3d nan = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  const double r = at(i, j);
  if (!std::isfinite(r))
    return nan;
  const int nt = nTheta();
  const int nz = nZ();
  // Derivative from the finite neighbours: central if both, one-sided if one.
  auto derivative = [r](double before, double after, double step) {
    const bool b = std::isfinite(before);
    const bool a = std::isfinite(after);
    if (a && b)
      return (after - before) / (2.0 * step);
    if (a)
      return (after - r) / step;
    if (b)
      return (r - before) / step;
    return std::numeric_limits<double>::quiet_NaN();
  };
  const float left = at(i == 0 ? nt - 1 : i - 1, j);
  const float right = at(i == nt - 1 ? 0 : i + 1, j);
  const float below = j > 0 ? at(i, j - 1) : quietNaN();
  const float above = j < nz - 1 ? at(i, j + 1) : quietNaN();
  const double drdTheta = derivative(left, right, frame_.thetaStep());
  const double drdZ = derivative(below, above, frame_.zStep());
  if (!std::isfinite(drdTheta) || !std::isfinite(drdZ))
    return nan;
  const double theta = frame_.indexToTheta(i);
  const Eigen::Vector3d er = frame_.radialDirection(theta);
  const Eigen::Vector3d et = -std::sin(theta) * frame_.xAxis() + std::cos(theta) * frame_.yAxis();
  // S(θ,z) = o + z â + r ê_r: S_θ × S_z = r ê_r − r_θ ê_θ − r r_z â (outward).
  const Eigen::Vector3d n = r * er - drdTheta * et - r * drdZ * frame_.direction();
  const double length = n.norm();
  return length > 0.0 ? Eigen::Vector3d(n / length) : nan;
}

RangeMap boxSmooth(const RangeMap& map)
{
  RangeMap out(map.frame());
  const int nt = map.nTheta();
  const int nz = map.nZ();
  for (int j = 0; j < nz; ++j)
    for (int i = 0; i < nt; ++i)
    {
      if (!std::isfinite(map.at(i, j)))
        continue;
      double sum = 0.0;
      int count = 0;
      for (int dj = -1; dj <= 1; ++dj)
      {
        const int jj = j + dj;
        if (jj < 0 || jj >= nz)
          continue;
        for (int di = -1; di <= 1; ++di)
        {
          const int ii = (i + di + nt) % nt;
          const float v = map.at(ii, jj);
          if (std::isfinite(v))
          {
            sum += v;
            ++count;
          }
        }
      }
      out.at(i, j) = static_cast<float>(sum / count);
    }
  return out;
}

} // namespace caps::seg
