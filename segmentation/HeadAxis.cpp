#include "segmentation/HeadAxis.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <vtkImageData.h>
#include <vtkType.h>

#include "segmentation/RangeMapImageGeometry.h"

namespace caps::seg {

namespace {

struct SliceSums
{
  long long count = 0;
  Eigen::Vector3d indexSum = Eigen::Vector3d::Zero();
  Eigen::Vector3i lo = Eigen::Vector3i::Constant(std::numeric_limits<int>::max());
  Eigen::Vector3i hi = Eigen::Vector3i::Constant(std::numeric_limits<int>::min());
};

struct Line
{
  Eigen::Vector3d p = Eigen::Vector3d::Zero(); ///< point at s = 0
  Eigen::Vector3d b = Eigen::Vector3d::Zero(); ///< change per unit s
  double meanS = 0.0;
};

/// Weighted least squares of c(s) = p + s b; false if fewer than two distinct positions carry weight.
bool fitLine(const std::vector<Eigen::Vector3d>& c, const std::vector<double>& s, const std::vector<double>& w,
             Line& line)
{
  double sw = 0.0, ss = 0.0;
  Eigen::Vector3d sc = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < c.size(); ++k)
  {
    sw += w[k];
    ss += w[k] * s[k];
    sc += w[k] * c[k];
  }
  if (!(sw > 0.0))
    return false;
  const double meanS = ss / sw;
  const Eigen::Vector3d meanC = sc / sw;
  double sxx = 0.0;
  Eigen::Vector3d sxc = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < c.size(); ++k)
  {
    sxx += w[k] * (s[k] - meanS) * (s[k] - meanS);
    sxc += w[k] * (s[k] - meanS) * (c[k] - meanC);
  }
  if (!(sxx > 1e-9 * sw))
    return false;
  line.b = sxc / sxx;
  line.p = meanC - meanS * line.b;
  line.meanS = meanS;
  return true;
}

double median(std::vector<double> v)
{
  if (v.empty())
    return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

/// The body mask cut into slices across the index axis that points most
/// nearly superior: each slice's voxel count, index sum and bounding box.
struct SlicedMask
{
  ImageGeometry g;
  int sliceAxis = 0;
  int inPlane[2] = {1, 2};
  Eigen::Vector3d sliceNormal = Eigen::Vector3d::UnitZ(); ///< pointing superior
  std::vector<SliceSums> sums;                            ///< per index along sliceAxis

  /// The world position of index @a idx.
  Eigen::Vector3d world(const Eigen::Vector3d& idx) const
  {
    return g.indexToWorld(Eigen::Vector3d(g.extent[0], g.extent[2], g.extent[4]) + idx);
  }
};

SlicedMask sliceTheMask(vtkImageData* bodyMask)
{
  SlicedMask m;
  m.g = ImageGeometry::of(bodyMask);
  const ImageGeometry& g = m.g;
  const auto dims = g.dimensions();
  const auto* mask = static_cast<const unsigned char*>(bodyMask->GetScalarPointer());
  if (!mask)
    throw std::invalid_argument("The body mask has no voxels.");
  for (int a = 1; a < 3; ++a)
    if (std::abs(g.direction(2, a)) > std::abs(g.direction(2, m.sliceAxis)))
      m.sliceAxis = a;
  m.sliceNormal = g.direction.col(m.sliceAxis).normalized() * (g.direction(2, m.sliceAxis) < 0 ? -1.0 : 1.0);
  m.inPlane[0] = (m.sliceAxis + 1) % 3;
  m.inPlane[1] = (m.sliceAxis + 2) % 3;
  m.sums.resize(static_cast<std::size_t>(dims[m.sliceAxis]));
  std::size_t offset = 0;
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i, ++offset)
      {
        if (!mask[offset])
          continue;
        const Eigen::Vector3i idx(i, j, k);
        SliceSums& s = m.sums[static_cast<std::size_t>(idx[m.sliceAxis])];
        ++s.count;
        s.indexSum += idx.cast<double>();
        s.lo = s.lo.cwiseMin(idx);
        s.hi = s.hi.cwiseMax(idx);
      }
  return m;
}

/// A slice of the body: its centroid, area, position along the superior
/// direction and index.
struct Slice
{
  Eigen::Vector3d centroid;
  double area;
  double s;
  std::size_t index;
};

/// The non-empty slices, from the feet up.
std::vector<Slice> slicesFromBelow(const SlicedMask& m)
{
  const double voxelArea = m.g.spacing[m.inPlane[0]] * m.g.spacing[m.inPlane[1]];
  std::vector<Slice> slices;
  for (std::size_t k = 0; k < m.sums.size(); ++k)
    if (m.sums[k].count > 0)
    {
      const Eigen::Vector3d c = m.world(m.sums[k].indexSum / m.sums[k].count);
      slices.push_back({c, m.sums[k].count * voxelArea, c.dot(m.sliceNormal), k});
    }
  std::sort(slices.begin(), slices.end(), [](const Slice& a, const Slice& b) { return a.s < b.s; });
  if (slices.size() < 2)
    throw std::invalid_argument("The body mask covers fewer than two slices: no head axis can be fitted.");
  return slices;
}

/// 1 for the head's slices, 0 for the others: from the top down until the
/// shoulders (an area well above the head's, or growing again past a neck),
/// leaving out slices too small to be the head (the vertex). The head's area
/// is the median over the upper half of the body's extent.
std::vector<double> headSlices(const std::vector<Slice>& slices, const HeadAxisOptions& options)
{
  const double sMid = 0.5 * (slices.front().s + slices.back().s);
  std::vector<double> upper;
  for (const Slice& s : slices)
    if (s.s >= sMid)
      upper.push_back(s.area);
  const double referenceArea = median(upper);
  const std::size_t n = slices.size();
  std::vector<double> use(n, 0.0);
  double widest = 0.0;
  double narrowest = std::numeric_limits<double>::max(); // since the widest
  for (std::size_t k = n; k-- > 0;)
  {
    const double area = slices[k].area;
    if (area > widest)
      narrowest = widest = area;
    else
      narrowest = std::min(narrowest, area);
    const bool pastNeck = area > options.shoulderGrowth * narrowest && narrowest < options.neckRatio * widest;
    if (area > options.shoulderAreaRatio * referenceArea || pastNeck)
      break; // the shoulders: this slice and all below are out
    if (area >= options.minimumAreaRatio * referenceArea)
      use[k] = 1.0;
  }
  return use;
}

/// The line through the head slices' centroids, weighted by area, then
/// reweighted by Tukey's biweight on the distance from the line. @a w
/// receives the final weights.
Line robustAxisLine(const std::vector<Eigen::Vector3d>& c, const std::vector<double>& s,
                    const std::vector<double>& area, const std::vector<double>& use, const HeadAxisOptions& options,
                    std::vector<double>& w)
{
  const std::size_t n = c.size();
  w.assign(n, 0.0);
  for (std::size_t k = 0; k < n; ++k)
    w[k] = use[k] * area[k];
  Line line;
  if (!fitLine(c, s, w, line))
    throw std::invalid_argument(
      "The body mask has fewer than two head slices (below the shoulders' area) to fit the head axis.");
  for (int iteration = 0; iteration < options.reweightIterations; ++iteration)
  {
    std::vector<double> d(n), used;
    for (std::size_t k = 0; k < n; ++k)
    {
      d[k] = (c[k] - (line.p + s[k] * line.b)).norm();
      if (use[k] > 0.0)
        used.push_back(d[k]);
    }
    const double scale = std::max(1.4826 * median(used), options.minimumResidualScale);
    const double cutoff = 4.685 * scale;
    std::vector<double> trial(n);
    for (std::size_t k = 0; k < n; ++k)
    {
      const double u = d[k] / cutoff;
      trial[k] = use[k] * area[k] * (u < 1.0 ? (1 - u * u) * (1 - u * u) : 0.0);
    }
    Line next;
    if (!fitLine(c, s, trial, next))
      break;
    line = next;
    w = trial;
  }
  return line;
}

/// The z range on the axis: every mask slice's bounding rectangle projected on it.
std::pair<double, double> zRangeOnAxis(const SlicedMask& m, const std::vector<Slice>& slices,
                                       const Eigen::Vector3d& origin, const Eigen::Vector3d& direction)
{
  double zMin = std::numeric_limits<double>::max();
  double zMax = std::numeric_limits<double>::lowest();
  for (const Slice& sl : slices)
  {
    const SliceSums& sum = m.sums[sl.index];
    for (int corner = 0; corner < 4; ++corner)
    {
      Eigen::Vector3i idx = sum.lo;
      idx[m.inPlane[0]] = corner & 1 ? sum.hi[m.inPlane[0]] : sum.lo[m.inPlane[0]];
      idx[m.inPlane[1]] = corner & 2 ? sum.hi[m.inPlane[1]] : sum.lo[m.inPlane[1]];
      const double z = (m.world(idx.cast<double>()) - origin).dot(direction);
      zMin = std::min(zMin, z);
      zMax = std::max(zMax, z);
    }
  }
  return {zMin, zMax};
}

} // namespace

HeadAxisFit fitHeadAxis(vtkImageData* bodyMask, const HeadAxisOptions& options)
{
  if (!bodyMask || bodyMask->GetScalarType() != VTK_UNSIGNED_CHAR || bodyMask->GetNumberOfScalarComponents() != 1)
    throw std::invalid_argument("The head axis needs a body mask of one unsigned char component.");
  const SlicedMask sliced = sliceTheMask(bodyMask);
  const std::vector<Slice> slices = slicesFromBelow(sliced);
  const std::vector<double> use = headSlices(slices, options);

  const std::size_t n = slices.size();
  std::vector<Eigen::Vector3d> c(n);
  std::vector<double> s(n), area(n), w;
  for (std::size_t k = 0; k < n; ++k)
  {
    c[k] = slices[k].centroid;
    s[k] = slices[k].s;
    area[k] = slices[k].area;
  }
  const Line line = robustAxisLine(c, s, area, use, options, w);
  Eigen::Vector3d direction = line.b.normalized();
  if (direction.z() < 0.0)
    direction = -direction;
  const Eigen::Vector3d origin = line.p + line.meanS * line.b;
  const auto [zMin, zMax] = zRangeOnAxis(sliced, slices, origin, direction);

  HeadAxisFit fit;
  fit.frame = CylindricalFrame(origin, direction, zMin, zMax, options.nTheta, options.nZ);
  double sw = 0.0, sd = 0.0;
  for (std::size_t k = 0; k < n; ++k)
  {
    fit.centroids.push_back(c[k]);
    fit.areas.push_back(area[k]);
    fit.weights.push_back(w[k]);
    if (w[k] > 0.0)
    {
      ++fit.slicesUsed;
      sw += w[k];
      sd += w[k] * (c[k] - (line.p + s[k] * line.b)).squaredNorm();
    }
  }
  fit.rmsResidual = sw > 0.0 ? std::sqrt(sd / sw) : 0.0;
  return fit;
}

HeadAxisFit axisThroughBody(vtkImageData* bodyMask, const Eigen::Vector3d& point, const Eigen::Vector3d& direction,
                            const HeadAxisOptions& options)
{
  if (!bodyMask || bodyMask->GetScalarType() != VTK_UNSIGNED_CHAR || bodyMask->GetNumberOfScalarComponents() != 1 ||
      !bodyMask->GetScalarPointer())
    throw std::invalid_argument("The head axis needs a body mask of one unsigned char component.");
  if (!point.allFinite() || !direction.allFinite() || direction.norm() < 1e-9)
    throw std::invalid_argument("The axis needs a finite point and a non-zero direction (e.g. 0,0,0 and 0,0,1).");
  Eigen::Vector3d d = direction.normalized();
  if (d.z() < 0.0)
    d = -d;
  const ImageGeometry g = ImageGeometry::of(bodyMask);
  const auto dims = g.dimensions();
  const auto* mask = static_cast<const unsigned char*>(bodyMask->GetScalarPointer());
  const Eigen::Vector3d extentStart(g.extent[0], g.extent[2], g.extent[4]);

  // z along the axis is linear in the voxel index, so along each row of the
  // mask its extremes are at the row's first and last body voxels.
  double zMin = std::numeric_limits<double>::max();
  double zMax = std::numeric_limits<double>::lowest();
  std::size_t offset = 0;
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j, offset += static_cast<std::size_t>(dims[0]))
    {
      const unsigned char* row = mask + offset;
      int first = 0, last = dims[0] - 1;
      while (first < dims[0] && !row[first])
        ++first;
      if (first == dims[0])
        continue;
      while (!row[last])
        --last;
      for (int i : {first, last})
      {
        const double z = (g.indexToWorld(extentStart + Eigen::Vector3d(i, j, k)) - point).dot(d);
        zMin = std::min(zMin, z);
        zMax = std::max(zMax, z);
      }
    }
  if (zMin > zMax)
    throw std::invalid_argument("The body mask is empty: there is no head to put the axis in.");
  if (zMax - zMin < 1e-6)
    zMax = zMin + 1.0; // one slice thick: give the frame a range
  HeadAxisFit fit;
  fit.frame = CylindricalFrame(point, d, zMin, zMax, options.nTheta, options.nZ);
  fit.userDefined = true;
  return fit;
}

} // namespace caps::seg
