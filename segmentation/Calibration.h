#pragma once
/// @file Calibration.h
/// @brief Calibration of surface scan range maps by anthropometric landmark
/// distances (§4.3, Tables 4.2–4.3): a horizontal scale for r (x, y) and a
/// vertical scale for z.

#include <string>
#include <vector>

#include "segmentation/RangeMap.h"
#include "segmentation/SurfaceScanColourMap.h"

namespace caps::seg {

/// The thesis's two classes of measurements.
enum class CalibrationDirection
{
  Horizontal, ///< Table 4.2: inter-ocular, outer-canthal, nasal width, mouth width, zygomatic width.
  Vertical,   ///< Table 4.3: upper and lower facial height, upper lip height.
};

/// A landmark located on the map (θ in radians, z in mm along the axis).
struct MapLandmark
{
  double theta = 0.0;
  double z = 0.0;
};

/// A pair of landmarks and the distance measured between them on the patient.
struct LandmarkDistance
{
  std::string name; ///< e.g. "mouth width (cheilion–cheilion)".
  CalibrationDirection direction = CalibrationDirection::Horizontal;
  MapLandmark from;
  MapLandmark to;
  double measuredMm = 0.0;
};

/// The distance between two landmarks on the uncalibrated map, split into
/// its part across the axis (in the x-y plane, scaled by the horizontal
/// factor) and its part along the axis (|Δz|, scaled by the vertical factor).
struct ModelDistance
{
  double horizontalMm = 0.0;
  double verticalMm = 0.0;
  double length() const;
};

/// One row of Table 4.2 or 4.3: the model distance and the measured one.
struct CalibrationMeasurement
{
  std::string name;
  CalibrationDirection direction = CalibrationDirection::Horizontal;
  ModelDistance model;
  double measuredMm = 0.0;
  /// measuredMm / model.length(): the thesis's "scale factor" column.
  double ratio() const;
};

/// Scale factors and how well they fit.
struct CalibrationResult
{
  /// Least-squares factors (r and x, y are multiplied by horizontalScale, z by
  /// verticalScale): they minimise Σ (|S d_k| − D_k)² over all measurements,
  /// S = diag(h, h, v), using each distance's horizontal and vertical parts, so
  /// a "vertical" distance with some depth (nasion–subnasale) is not biased.
  double horizontalScale = 1.0;
  double verticalScale = 1.0;
  /// The thesis's estimate: mean of the ratios of each class (NaN if the class is empty).
  double thesisHorizontalScale = 0.0;
  double thesisVerticalScale = 0.0;
  /// |S d_k| − D_k in mm after the least-squares fit, per measurement, and their RMS.
  std::vector<double> residualsMm;
  double rmsResidualMm = 0.0;
};

/// Distance between two landmarks on the map: r is map.sample(θ, z).
/// @throws std::runtime_error if a landmark falls on a hole (NaN) of the map.
ModelDistance modelDistance(const RangeMap& map, const MapLandmark& from, const MapLandmark& to);

/// The measurement of one landmark pair on the map.
CalibrationMeasurement measureOnMap(const RangeMap& map, const LandmarkDistance& distance);

/// Fit the horizontal and vertical factors (Gauss–Newton from a linear fit of squared distances).
/// @throws std::invalid_argument if a measured distance is not positive, or the
/// measurements do not constrain both factors (e.g. no vertical distance).
CalibrationResult fitCalibration(const std::vector<CalibrationMeasurement>& measurements);

/// measureOnMap on each pair, then fitCalibration.
CalibrationResult calibrate(const RangeMap& map, const std::vector<LandmarkDistance>& distances);

/// The frame with z scaled about its origin: [v · zMin, v · zMax], same grid.
CylindricalFrame calibratedFrame(const CylindricalFrame& frame, double verticalScale);

/// The calibrated map: r · horizontalScale on calibratedFrame (sample (i, j) stays
/// sample (i, j); the landmark (θ, z) moves to (θ, v · z)).
RangeMap applyCalibration(const RangeMap& map, const CalibrationResult& calibration);
/// The colour map on the calibrated frame (colours unchanged).
ColourMap applyCalibration(const ColourMap& map, const CalibrationResult& calibration);

} // namespace caps::seg
