#include "segmentation/RangeMapFromPoints.h"

#include <cmath>

namespace caps::seg {

RangeMap rangeMapFromPoints(const CylindricalFrame& frame, const std::vector<Eigen::Vector3d>& points)
{
  RangeMap map(frame);
  const int nt = frame.nTheta();
  const int nz = frame.nZ();
  for (const Eigen::Vector3d& p : points)
  {
    if (!p.allFinite())
      continue;
    const CylindricalPoint c = frame.toCylindrical(p);
    int i = static_cast<int>(std::floor(frame.thetaToIndex(c.theta) + 0.5));
    if (i >= nt)
      i -= nt;
    const double v = std::floor(frame.zToIndex(c.z) + 0.5);
    if (!(v >= 0.0 && v <= nz - 1))
      continue;
    float& r = map.at(i, static_cast<int>(v));
    if (!(r >= c.r)) // NaN or smaller
      r = static_cast<float>(c.r);
  }
  return map;
}

} // namespace caps::seg
