#pragma once
/// @file HeadAxis.h
/// @brief Fitting the cylinder axis to the head from the body mask.

#include <vector>

#include <Eigen/Core>

#include "segmentation/CylindricalFrame.h"

class vtkImageData;

namespace caps::seg {

struct HeadAxisOptions
{
  /// Walking down from the top of the scan, the first slice whose area
  /// exceeds this times the head's reference area (the median slice area of
  /// the upper half of the body) is taken as the shoulders: it and every
  /// slice below are left out of the fit.
  double shoulderAreaRatio = 1.5;
  /// The shoulders also begin, walking down, where a slice's area exceeds
  /// this times the smallest area seen since the widest head slice (the
  /// neck), provided that neck is narrower than neckRatio times the head.
  double shoulderGrowth = 1.3;
  double neckRatio = 0.9;
  /// Slices smaller than this times the reference area (stray voxels, the
  /// very top of the skull) are left out.
  double minimumAreaRatio = 0.05;
  /// Iterations of Tukey-biweight reweighting of the slice centroids.
  int reweightIterations = 5;
  /// The residual scale never drops below this (mm), so clean data keep all slices.
  double minimumResidualScale = 0.5;
  /// Grid of the returned frame.
  int nTheta = 512;
  int nZ = 256;
};

/// The fitted axis and what it was fitted to.
struct HeadAxisFit
{
  /// Axis through the fitted line, pointing superior, origin at the
  /// weighted mean slice; z range covering the whole body mask.
  CylindricalFrame frame;
  /// Per mask slice, inferior to superior (empty slices omitted): centroid (LPS mm),
  /// area (mm²) and final weight in the fit (0 for slices left out).
  std::vector<Eigen::Vector3d> centroids;
  std::vector<double> areas;
  std::vector<double> weights;
  /// Weighted RMS distance of the used centroids from the axis, mm.
  double rmsResidual = 0.0;
  int slicesUsed = 0;
  /// The user set the axis (axisThroughBody): nothing was fitted.
  bool userDefined = false;
};

/// Fits the head axis to the centroids of the body mask slice by slice.
///
/// Slices are taken across the image axis closest to patient superior (the
/// axial slices of an axial series, whatever the direction matrix). Each
/// slice's centroid c_k at slice position s_k is fitted by weighted least
/// squares as the line c(s) = p + s b (errors in the slice plane, where the
/// centroids scatter; s along the slice normal is exact), weights = slice
/// area (big slices have steadier centroids) times a Tukey biweight of the
/// distance from the previous fit. The shoulders are excluded first by area
/// (HeadAxisOptions::shoulderAreaRatio and shoulderGrowth: below the neck
/// the area grows again): they are wide, lie behind the head in a supine
/// patient, and by area alone would outweigh it.
///
/// @param bodyMask unsigned char, non-zero inside the body, with the CT's geometry.
/// @throws std::invalid_argument if the mask is missing, not unsigned char, or
/// has fewer than two usable slices.
HeadAxisFit fitHeadAxis(vtkImageData* bodyMask, const HeadAxisOptions& options = {});

/// The axis the user sets (when the fitted one is not wanted), through
/// @a point along @a direction (LPS mm; flipped to point superior), with the z
/// range covering the whole body mask like fitHeadAxis and its grid
/// (options.nTheta × options.nZ). The result has userDefined set and no centroids.
/// @throws std::invalid_argument if the mask is missing or empty, or the point
/// or direction is not finite or the direction is zero.
HeadAxisFit axisThroughBody(vtkImageData* bodyMask, const Eigen::Vector3d& point, const Eigen::Vector3d& direction,
                            const HeadAxisOptions& options = {});

} // namespace caps::seg
