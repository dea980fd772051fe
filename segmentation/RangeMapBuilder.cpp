#include "segmentation/RangeMapBuilder.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/LU>
#include <vtkImageData.h>
#include <vtkType.h>

#include "segmentation/RangeMapImageGeometry.h"
#include "segmentation/RangeMapParallel.h"

namespace caps::seg {

namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();
constexpr float outsideValue = -1.0e6f; // "air" outside the volume

struct Grid
{
  int nx, ny, nz;
  std::ptrdiff_t sy, sz;
};

template <typename T> struct Volume
{
  const T* data;
  Grid g;

  /// Trilinear value at a 0-based continuous index; outsideValue off the grid.
  float operator()(const Eigen::Vector3d& p) const
  {
    const double x = p.x(), y = p.y(), z = p.z();
    if (!(x >= 0.0 && y >= 0.0 && z >= 0.0 && x <= g.nx - 1 && y <= g.ny - 1 && z <= g.nz - 1))
      return outsideValue;
    const int i = std::min(static_cast<int>(x), g.nx - 2);
    const int j = std::min(static_cast<int>(y), g.ny - 2);
    const int k = std::min(static_cast<int>(z), g.nz - 2);
    const float fx = static_cast<float>(x - i), fy = static_cast<float>(y - j), fz = static_cast<float>(z - k);
    const T* c = data + i + j * g.sy + k * g.sz;
    const float c00 = c[0] + fx * (float(c[1]) - float(c[0]));
    const float c10 = c[g.sy] + fx * (float(c[g.sy + 1]) - float(c[g.sy]));
    const float c01 = c[g.sz] + fx * (float(c[g.sz + 1]) - float(c[g.sz]));
    const float c11 = c[g.sy + g.sz] + fx * (float(c[g.sy + g.sz + 1]) - float(c[g.sy + g.sz]));
    const float c0 = c00 + fy * (c10 - c00);
    const float c1 = c01 + fy * (c11 - c01);
    return c0 + fz * (c1 - c0);
  }
};

struct Mask
{
  const unsigned char* data;
  Grid g;

  bool nearest(const Eigen::Vector3d& p) const
  {
    const long i = std::lround(p.x()), j = std::lround(p.y()), k = std::lround(p.z());
    if (i < 0 || j < 0 || k < 0 || i >= g.nx || j >= g.ny || k >= g.nz)
      return false;
    return data[i + j * g.sy + k * g.sz] != 0;
  }

  /// Any of the 8 voxels of the trilinear cell around p is in the mask.
  bool cellTouches(const Eigen::Vector3d& p) const
  {
    const int i0 = static_cast<int>(std::floor(p.x())), j0 = static_cast<int>(std::floor(p.y())),
              k0 = static_cast<int>(std::floor(p.z()));
    for (int k = k0; k <= k0 + 1; ++k)
      for (int j = j0; j <= j0 + 1; ++j)
        for (int i = i0; i <= i0 + 1; ++i)
          if (i >= 0 && j >= 0 && k >= 0 && i < g.nx && j < g.ny && k < g.nz && data[i + j * g.sy + k * g.sz])
            return true;
    return false;
  }
};

/// A ray from the axis: index(r) = base + r · step (0-based continuous indices, r in mm).
struct Ray
{
  Eigen::Vector3d base;
  Eigen::Vector3d step;
  Eigen::Vector3d at(double r) const { return base + r * step; }
};

struct Steps
{
  double mask;     ///< mm
  double crossing; ///< mm
  double window;   ///< mm searched either side of the mask edge
};

/// Where the nearest-voxel mask switches between rOut (outside) and rIn (inside).
double maskEdge(const Mask& mask, const Ray& ray, double rOut, double rIn)
{
  for (int it = 0; it < 12; ++it)
  {
    const double mid = 0.5 * (rOut + rIn);
    (mask.nearest(ray.at(mid)) ? rIn : rOut) = mid;
  }
  return 0.5 * (rOut + rIn);
}

/// The first rise through threshold, going inward from rOuter to rInner, whose
/// cell touches the mask; NaN if none.
template <typename T>
double findCrossing(const Volume<T>& volume, const Mask& mask, const Ray& ray, float threshold, double rOuter,
                    double rInner, double step)
{
  double rPrev = rOuter;
  float vPrev = volume(ray.at(rPrev));
  for (double r = rOuter - step; r >= rInner; r -= step)
  {
    const float v = volume(ray.at(r));
    if (vPrev < threshold && v >= threshold)
    {
      double out = rPrev, in = r;
      for (int it = 0; it < 10; ++it)
      {
        const double mid = 0.5 * (out + in);
        (volume(ray.at(mid)) >= threshold ? in : out) = mid;
      }
      const double rc = 0.5 * (out + in);
      if (mask.cellTouches(ray.at(rc - 0.25 * step)))
        return rc;
    }
    rPrev = r;
    vPrev = v;
  }
  return nan;
}

/// Outermost crossing inward from rStart (mask march, then HU search); sets
/// fromEdge when the mask edge had to be used.
template <typename T>
double outermostCrossing(const Volume<T>& volume, const Mask& mask, const Ray& ray, float threshold, double rStart,
                         const Steps& steps, bool& fromEdge)
{
  fromEdge = false;
  double r = rStart;
  while (r >= 0.0 && !mask.nearest(ray.at(r)))
    r -= steps.mask;
  if (r < 0.0)
    return nan;
  const double rOuter = std::min(r + steps.window, rStart);
  const double rInner = std::max(r - steps.window, 0.0);
  const double rc = findCrossing(volume, mask, ray, threshold, rOuter, rInner, steps.crossing);
  if (std::isfinite(rc))
    return rc;
  fromEdge = true;
  return maskEdge(mask, ray, std::min(r + steps.mask, rStart), r);
}

/// Largest r (mm) at which the ray is still inside the box [lo, hi] (0-based
/// indices), or -1 if it never is for r >= 0.
double exitRadius(const Ray& ray, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi)
{
  double t0 = 0.0, t1 = std::numeric_limits<double>::max();
  for (int a = 0; a < 3; ++a)
  {
    const double b = ray.base[a], d = ray.step[a];
    if (std::abs(d) < 1e-15)
    {
      if (b < lo[a] || b > hi[a])
        return -1.0;
      continue;
    }
    double ta = (lo[a] - b) / d, tb = (hi[a] - b) / d;
    if (ta > tb)
      std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t1 >= t0 ? t1 : -1.0;
}

void checkMask(vtkImageData* mask, const ImageGeometry& ctGeometry, const char* what)
{
  if (!mask)
    throw std::invalid_argument(std::string("The range maps need the ") + what + " mask.");
  if (mask->GetScalarType() != VTK_UNSIGNED_CHAR || mask->GetNumberOfScalarComponents() != 1)
    throw std::invalid_argument(std::string("The ") + what + " mask must hold one unsigned char component per voxel.");
  if (!ImageGeometry::of(mask).sameGrid(ctGeometry))
    throw std::invalid_argument(std::string("The ") + what +
                                " mask does not lie on the CT's voxel grid (origin, spacing, "
                                "direction or size differ); segment this CT again.");
}

template <typename T>
SkinBoneRangeMaps build(const T* ctData, vtkImageData* bodyMask, vtkImageData* boneMask, const ImageGeometry& geometry,
                        const CylindricalFrame& frame, const RangeMapBuildOptions& options)
{
  const auto dims = geometry.dimensions();
  const Grid grid{dims[0], dims[1], dims[2], dims[0], static_cast<std::ptrdiff_t>(dims[0]) * dims[1]};
  const Volume<T> volume{ctData, grid};
  const Mask body{static_cast<const unsigned char*>(bodyMask->GetScalarPointer()), grid};
  const Mask bone{static_cast<const unsigned char*>(boneMask->GetScalarPointer()), grid};

  // Bounding box of the body mask (0-based indices), one voxel of margin.
  Eigen::Vector3i lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max());
  Eigen::Vector3i hi = Eigen::Vector3i::Constant(-1);
  {
    std::size_t offset = 0;
    for (int k = 0; k < dims[2]; ++k)
      for (int j = 0; j < dims[1]; ++j)
      {
        const unsigned char* row = body.data + offset;
        const unsigned char* first = std::find_if(row, row + dims[0], [](unsigned char v) { return v; });
        if (first != row + dims[0])
        {
          const unsigned char* last = row + dims[0] - 1;
          while (!*last)
            --last;
          lo = lo.cwiseMin(Eigen::Vector3i(static_cast<int>(first - row), j, k));
          hi = hi.cwiseMax(Eigen::Vector3i(static_cast<int>(last - row), j, k));
        }
        offset += static_cast<std::size_t>(dims[0]);
      }
  }

  SkinBoneRangeMaps maps{RangeMap(frame), RangeMap(frame), 0, 0};
  if (hi.x() < 0)
    return maps; // empty body mask: all NaN
  const Eigen::Vector3d boxLo = (lo.cast<double>().array() - 1.0).max(0.0);
  const Eigen::Vector3d boxHi =
    (hi.cast<double>().array() + 1.0).min(Eigen::Vector3d(dims[0] - 1, dims[1] - 1, dims[2] - 1).array());

  const Eigen::Vector3d volumeLo = Eigen::Vector3d::Zero();
  const Eigen::Vector3d volumeHi(dims[0] - 1, dims[1] - 1, dims[2] - 1);
  const double minSpacing = geometry.spacing.minCoeff();
  const double maxSpacing = geometry.spacing.maxCoeff();
  const Steps steps{options.maskStep * minSpacing, options.crossingStep * minSpacing,
                    2.0 * maxSpacing + options.maskStep * minSpacing};
  const Eigen::Matrix3d toIndex = geometry.indexToWorldMatrix().inverse();
  const Eigen::Vector3d extentStart(geometry.extent[0], geometry.extent[2], geometry.extent[4]);
  const float skinThreshold = static_cast<float>(options.skinThreshold);
  const float boneThreshold = static_cast<float>(options.boneThreshold);

  std::vector<std::size_t> skinEdges(static_cast<std::size_t>(frame.nZ()), 0);
  std::vector<std::size_t> boneEdges(static_cast<std::size_t>(frame.nZ()), 0);
  internal::parallelRows(
    frame.nZ(), options.threads,
    [&](int j) {
      const double z = frame.indexToZ(j);
      const Eigen::Vector3d base = toIndex * (frame.axisPoint(z) - geometry.origin) - extentStart;
      for (int i = 0; i < frame.nTheta(); ++i)
      {
        const Ray ray{base, toIndex * frame.radialDirection(frame.indexToTheta(i))};
        const double rStart = exitRadius(ray, boxLo, boxHi);
        if (rStart < 0.0)
          continue;
        // The body goes on past the edge of the scan along this ray: its skin is not in the CT.
        if (body.nearest(ray.at(exitRadius(ray, volumeLo, volumeHi))))
          continue;
        bool edge = false;
        const double rSkin = outermostCrossing(volume, body, ray, skinThreshold, rStart, steps, edge);
        if (!std::isfinite(rSkin))
          continue;
        maps.skin.at(i, j) = static_cast<float>(rSkin);
        skinEdges[static_cast<std::size_t>(j)] += edge;
        const double rBone = outermostCrossing(volume, bone, ray, boneThreshold, rSkin, steps, edge);
        if (!std::isfinite(rBone))
          continue;
        maps.bone.at(i, j) = static_cast<float>(rBone);
        boneEdges[static_cast<std::size_t>(j)] += edge;
      }
    },
    options.progress, "Range maps", 0.0, 1.0);
  for (std::size_t j = 0; j < skinEdges.size(); ++j)
  {
    maps.skinFromMaskEdge += skinEdges[j];
    maps.boneFromMaskEdge += boneEdges[j];
  }
  return maps;
}

} // namespace

SkinBoneRangeMaps buildRangeMaps(vtkImageData* ct, vtkImageData* bodyMask, vtkImageData* boneMask,
                                 const CylindricalFrame& frame, const RangeMapBuildOptions& options)
{
  if (!ct || ct->GetNumberOfScalarComponents() != 1 || !ct->GetScalarPointer())
    throw std::invalid_argument("The range maps need a CT with one value per voxel.");
  const ImageGeometry geometry = ImageGeometry::of(ct);
  const auto dims = geometry.dimensions();
  if (dims[0] < 2 || dims[1] < 2 || dims[2] < 2)
    throw std::invalid_argument("The CT must have at least two voxels along each axis.");
  checkMask(bodyMask, geometry, "body");
  checkMask(boneMask, geometry, "bone");
  if (!(options.maskStep > 0.0 && options.crossingStep > 0.0))
    throw std::invalid_argument("The range map march steps must be positive.");

  switch (ct->GetScalarType())
  {
    vtkTemplateMacro(
      return build(static_cast<const VTK_TT*>(ct->GetScalarPointer()), bodyMask, boneMask, geometry, frame, options));
  default:
    throw std::invalid_argument("The CT's voxel type is not supported for range maps.");
  }
}

} // namespace caps::seg
