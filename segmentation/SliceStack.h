#pragma once
/// @file SliceStack.h
/// @brief The geometry of a DICOM slice stack as the slices state it, its
/// problems (missing slices, uneven spacing, gantry tilt), and resampling of
/// an irregular stack onto a regular grid.
///
/// ITK stacks the slices of a series and takes one spacing for all; a
/// missing slice or a tilted gantry then silently distorts every distance
/// along the head. Here the positions of all slices are checked first.

#include <array>
#include <string>
#include <vector>

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

namespace caps::seg {

/// Where each slice of a stack lies (DICOM Image Position / Orientation).
/// Plain arrays: this header is included next to ITK, whose bundled Eigen
/// must not meet the system one.
struct SliceStackGeometry
{
  using Vector = std::array<double, 3>;
  Vector row{1, 0, 0};             ///< direction of increasing column index (first IOP triplet)
  Vector column{0, 1, 0};          ///< direction of increasing row index (second IOP triplet)
  double pixelSpacing[2] = {1, 1}; ///< along row, along column (mm)
  std::vector<Vector> positions;   ///< top-left voxel of each slice, in stack order
};

/// What is wrong with a stack, if anything.
struct SliceStackReport
{
  double spacing = 0;     ///< median distance between neighbouring slices (mm)
  double largestGap = 0;  ///< mm
  int missingSlices = 0;  ///< estimated from gaps of about whole multiples of the spacing
  double tiltDegrees = 0; ///< angle between the stacking direction and the slice normal
  bool uneven = false;    ///< some gap differs from the spacing by more than 5 %
  bool needsResampling = false;
  /// Set when the stack cannot be made regular honestly (duplicate
  /// positions, a gap too large to interpolate); the text says where.
  std::string refusal;
  /// One sentence per problem, naming where it is (z in mm along the normal).
  std::vector<std::string> problems;
};

/// Gaps larger than this many times the spacing are refused, not interpolated.
inline constexpr double kLargestInterpolatedGap = 5.0;

SliceStackReport analyseSliceStack(const SliceStackGeometry& geometry);

/// Resamples a stack of slices (the voxels of slice k at stack[k * nx * ny],
/// x fastest) onto a regular grid: origin at the first slice, axes row,
/// column, normal, spacing (pixel spacing, report.spacing). Each output voxel
/// is interpolated bilinearly in the two slices around it (shifted in plane
/// by the tilt) and linearly between them; outside a slice it is @a padding.
/// Returns an image of the same scalar type (short or float).
vtkSmartPointer<vtkImageData> resampleSliceStack(vtkImageData* stack, const SliceStackGeometry& geometry,
                                                 const SliceStackReport& report, double padding);

} // namespace caps::seg
