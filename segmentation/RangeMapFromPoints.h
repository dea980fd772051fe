#pragma once
/// @file RangeMapFromPoints.h
/// @brief The thesis's point-list input (§3.2.7): surface points bucketed into (θ, z), maximum r.

#include <vector>

#include <Eigen/Core>

#include "segmentation/RangeMap.h"

namespace caps::seg {

/// Range map of a point list (for example skin or bone points from another
/// segmenter) on frame's grid.
///
/// Sample (i, j) is the bucket θ ∈ [θ_i − Δθ/2, θ_i + Δθ/2) (wrapping: points
/// just below θ = π belong to column 0), z ∈ [z_j − Δz/2, z_j + Δz/2); its value
/// is the largest r of the points in it, placed at the bucket centre (θ_i, z_j)
/// as in §3.2.7. Empty buckets and points outside the z range are NaN / ignored.
/// Non-finite points are ignored.
RangeMap rangeMapFromPoints(const CylindricalFrame& frame, const std::vector<Eigen::Vector3d>& points);

} // namespace caps::seg
