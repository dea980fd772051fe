#include "segmentation/SkinShade.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <vtkDataArray.h>
#include <vtkPointData.h>

namespace caps::seg {
namespace {

/// Trilinear CT value at a world point (LPS mm), NaN outside the voxel grid.
class CtSampler
{
public:
  explicit CtSampler(vtkImageData* ct) : ct_(ct), scalars_(ct->GetPointData()->GetScalars())
  {
    ct->GetExtent(extent_);
    ct->GetDimensions(dims_);
  }

  double operator()(const Eigen::Vector3d& world) const
  {
    double ijk[3];
    double p[3] = {world.x(), world.y(), world.z()};
    ct_->TransformPhysicalPointToContinuousIndex(p, ijk);
    int i0[3];
    double f[3];
    for (int a = 0; a < 3; ++a)
    {
      const double lo = extent_[2 * a], hi = extent_[2 * a + 1];
      if (!(ijk[a] >= lo - 1e-9 && ijk[a] <= hi + 1e-9))
        return std::numeric_limits<double>::quiet_NaN();
      if (hi == lo)
      {
        i0[a] = int(lo);
        f[a] = 0.0;
        continue;
      }
      i0[a] = std::clamp(int(std::floor(ijk[a])), int(lo), int(hi) - 1);
      f[a] = std::clamp(ijk[a] - i0[a], 0.0, 1.0);
    }
    double value = 0.0;
    for (int c = 0; c < 8; ++c)
    {
      const int d[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
      double w = 1.0;
      vtkIdType id = 0, stride = 1;
      for (int a = 0; a < 3; ++a)
      {
        w *= d[a] ? f[a] : 1.0 - f[a];
        const int index = std::min(i0[a] + d[a], extent_[2 * a + 1]) - extent_[2 * a];
        id += index * stride;
        stride *= dims_[a];
      }
      if (w != 0.0)
        value += w * scalars_->GetComponent(id, 0);
    }
    return value;
  }

private:
  vtkImageData* ct_;
  vtkDataArray* scalars_;
  int extent_[6] = {0, 0, 0, 0, 0, 0};
  int dims_[3] = {0, 0, 0};
};

Rgb8 ramp(const SkinShadeOptions& o, double hu)
{
  const double t = std::clamp((hu - o.darkHu) / (o.lightHu - o.darkHu), 0.0, 1.0);
  Rgb8 c;
  for (int k = 0; k < 3; ++k)
    c[k] = std::uint8_t(std::lround((1.0 - t) * o.dark[k] + t * o.light[k]));
  return c;
}

} // namespace

ColourMap skinShadeFromCt(vtkImageData* ct, const RangeMap& skin, const SkinShadeOptions& options)
{
  if (!ct || !ct->GetPointData()->GetScalars() || ct->GetNumberOfPoints() == 0)
    throw std::invalid_argument("the skin shade needs the CT's voxels: none were given");
  if (skin.empty())
    throw std::invalid_argument("the skin shade needs the skin range map: build it from the CT first");
  if (!(options.depthBegin >= 0.0) || !(options.depthEnd >= options.depthBegin) || !std::isfinite(options.depthEnd) ||
      options.samples < 1 || !(options.lightHu > options.darkHu) || !std::isfinite(options.lightHu) ||
      !std::isfinite(options.darkHu))
    throw std::invalid_argument("skin shade options: need 0 <= depthBegin <= depthEnd, at least one sample and "
                                "darkHu < lightHu");
  const CylindricalFrame& frame = skin.frame();
  const CtSampler sample(ct);
  ColourMap out(frame, kNoSourceColour);
  for (int j = 0; j < frame.nZ(); ++j)
    for (int i = 0; i < frame.nTheta(); ++i)
    {
      const double r = skin.at(i, j);
      if (!std::isfinite(r))
        continue;
      const double theta = frame.indexToTheta(i), z = frame.indexToZ(j);
      double sum = 0.0;
      int count = 0;
      for (int k = 0; k < options.samples; ++k)
      {
        const double depth = options.samples == 1 ? 0.5 * (options.depthBegin + options.depthEnd)
                                                  : options.depthBegin + (options.depthEnd - options.depthBegin) * k /
                                                                           (options.samples - 1);
        const double hu = sample(frame.toWorld(r - depth, theta, z));
        if (std::isfinite(hu))
        {
          sum += hu;
          ++count;
        }
      }
      if (count > 0)
        out.at(i, j) = ramp(options, sum / count);
    }
  return out;
}

Rgb8 sampleColour(const ColourMap& map, double theta, double z)
{
  if (map.empty())
    return kNoSourceColour;
  const CylindricalFrame& frame = map.frame();
  const double v = frame.zToIndex(z);
  double u = frame.thetaToIndex(theta);
  if (!(v >= 0.0 && v <= frame.nZ() - 1) || !std::isfinite(u))
    return kNoSourceColour;
  const int nt = frame.nTheta();
  u = std::fmod(u, double(nt));
  if (u < 0.0)
    u += nt;
  const int i0 = std::min(int(std::floor(u)), nt - 1), i1 = i0 + 1 == nt ? 0 : i0 + 1;
  const int j0 = std::min(int(std::floor(v)), frame.nZ() - 2), j1 = j0 + 1;
  const double fu = u - i0, fv = v - j0;
  Rgb8 c;
  for (int k = 0; k < 3; ++k)
  {
    const double value = ((1 - fu) * map.at(i0, j0)[k] + fu * map.at(i1, j0)[k]) * (1 - fv) +
                         ((1 - fu) * map.at(i0, j1)[k] + fu * map.at(i1, j1)[k]) * fv;
    c[k] = std::uint8_t(std::clamp(std::lround(value), 0L, 255L));
  }
  return c;
}

} // namespace caps::seg
