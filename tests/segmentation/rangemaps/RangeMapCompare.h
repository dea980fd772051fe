#pragma once
// Comparing a range map with an analytic r(θ, z).

#include <cmath>
#include <cstdio>
#include <functional>

#include "segmentation/RangeMap.h"

namespace caps::seg::test {

struct MapError
{
  double rms = 0.0;
  double maxAbs = 0.0;
  std::size_t compared = 0; ///< samples where both are finite
  std::size_t missing = 0;  ///< analytic finite, map NaN
  std::size_t extra = 0;    ///< analytic NaN, map finite
};

inline MapError compare(const RangeMap& map, const std::function<double(double theta, double z)>& analytic)
{
  MapError e;
  double sum = 0.0;
  for (int j = 0; j < map.nZ(); ++j)
    for (int i = 0; i < map.nTheta(); ++i)
    {
      const double expected = analytic(map.frame().indexToTheta(i), map.frame().indexToZ(j));
      const double got = map.at(i, j);
      if (std::isfinite(expected) && std::isfinite(got))
      {
        const double d = got - expected;
        sum += d * d;
        e.maxAbs = std::max(e.maxAbs, std::abs(d));
        ++e.compared;
      }
      else if (std::isfinite(expected))
        ++e.missing;
      else if (std::isfinite(got))
        ++e.extra;
    }
  e.rms = e.compared ? std::sqrt(sum / static_cast<double>(e.compared)) : 0.0;
  return e;
}

inline void print(const char* what, const MapError& e)
{
  std::printf("%-44s RMS %.4f mm, max %.4f mm over %zu samples (%zu missing, %zu extra)\n", what, e.rms, e.maxAbs,
              e.compared, e.missing, e.extra);
}

} // namespace caps::seg::test
