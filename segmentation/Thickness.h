#pragma once
/// @file Thickness.h
/// @brief Soft-tissue thickness from the skin and bone range maps.

#include <cstddef>

#include "segmentation/Progress.h"
#include "segmentation/RangeMap.h"

namespace caps::seg {

/// r_skin − r_bone at every sample: the thickness along the ray from the
/// axis. NaN where either map is.
/// @throws std::invalid_argument if the maps are on different frames.
RangeMap radialThickness(const RangeMap& skin, const RangeMap& bone);

struct NormalThicknessOptions
{
  /// Beyond this distance along the normal (mm) the bone counts as not found.
  double maxDistance = 80.0;
  /// Smallest and largest march step (mm); the step is half the current
  /// radial gap between the marching point and the bone, within these bounds.
  double minStep = 0.05;
  double maxStep = 2.0;
  int threads = 2;
  ProgressCallback progress;
};

/// Thickness along the inward skin normal: the distance from each skin sample
/// to where the line along its inward normal meets the bone surface.
///
/// The normal comes from the skin map's derivatives (RangeMap::outwardNormal):
/// it is the normal of the very surface the map describes, costs nothing
/// extra, and needs neither the CT nor a 3D distance transform (which would
/// give the distance to the nearest bone, a different and smaller quantity,
/// and take longer than the whole range map). The bone surface is the bone
/// range map: along q(t) = p − t n the gap f(t) = r(q) − r_bone(θ(q), z(q))
/// is followed (f(0) is the radial thickness) until it changes sign, and the
/// root is refined by bisection. 0 where the skin is on or inside the bone;
/// NaN where the skin or its normal is NaN, or the line reaches a hole of the
/// bone map, the ends of the z range, the axis or maxDistance first.
/// @throws std::invalid_argument if the maps are on different frames; Cancelled.
RangeMap normalThickness(const RangeMap& skin, const RangeMap& bone, const NormalThicknessOptions& options = {});

/// Summary of a thickness (or any range) map, over its finite samples only.
struct ThicknessStatistics
{
  std::size_t count = 0; ///< finite samples
  double min = 0.0;
  double max = 0.0;
  double mean = 0.0;
  double standardDeviation = 0.0;
  double p5 = 0.0;
  double p25 = 0.0;
  double median = 0.0;
  double p75 = 0.0;
  double p95 = 0.0;
};

/// Statistics of the finite samples (each sample counts once; samples are
/// not weighted by the area they cover). All zero when no sample is finite.
/// Percentiles interpolate linearly between order statistics (type 7, as
/// NumPy's default).
ThicknessStatistics thicknessStatistics(const RangeMap& map);

/// The p-th percentile (p in [0, 100]) of the finite samples, as in
/// thicknessStatistics; NaN when none is finite.
double thicknessPercentile(const RangeMap& map, double p);

} // namespace caps::seg
