#include "segmentation/Calibration.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <Eigen/Dense>

namespace caps::seg {

double ModelDistance::length() const
{
  return std::hypot(horizontalMm, verticalMm);
}

double CalibrationMeasurement::ratio() const
{
  return measuredMm / model.length();
}

ModelDistance modelDistance(const RangeMap& map, const MapLandmark& from, const MapLandmark& to)
{
  auto inPlane = [&map](const MapLandmark& l) {
    const double r = map.sample(l.theta, l.z);
    if (!std::isfinite(r))
      throw std::runtime_error("a calibration landmark at θ = " + std::to_string(l.theta * 180.0 / std::numbers::pi) +
                               "°, z = " + std::to_string(l.z) +
                               " mm falls on a hole of the range map: place it on the surface");
    return Eigen::Vector2d(r * std::cos(l.theta), r * std::sin(l.theta));
  };
  return {(inPlane(from) - inPlane(to)).norm(), std::abs(from.z - to.z)};
}

CalibrationMeasurement measureOnMap(const RangeMap& map, const LandmarkDistance& distance)
{
  return {distance.name, distance.direction, modelDistance(map, distance.from, distance.to), distance.measuredMm};
}

CalibrationResult fitCalibration(const std::vector<CalibrationMeasurement>& measurements)
{
  CalibrationResult result;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  double sumH = 0.0, sumV = 0.0;
  int nH = 0, nV = 0;
  for (const CalibrationMeasurement& m : measurements)
  {
    if (!(m.measuredMm > 0.0) || !(m.model.length() > 0.0))
      throw std::invalid_argument("the calibration distance '" + m.name +
                                  "' is zero or negative (on the patient or on the map)");
    if (m.direction == CalibrationDirection::Horizontal)
      sumH += m.ratio(), ++nH;
    else
      sumV += m.ratio(), ++nV;
  }
  result.thesisHorizontalScale = nH ? sumH / nH : nan;
  result.thesisVerticalScale = nV ? sumV / nV : nan;

  // Linear start: D² ≈ a h² + b v² with a = sh², b = sv², relative weights 1/D².
  Eigen::Matrix2d ata = Eigen::Matrix2d::Zero();
  Eigen::Vector2d atb = Eigen::Vector2d::Zero();
  for (const CalibrationMeasurement& m : measurements)
  {
    const double w = 1.0 / (m.measuredMm * m.measuredMm);
    const Eigen::Vector2d row(m.model.horizontalMm * m.model.horizontalMm * w,
                              m.model.verticalMm * m.model.verticalMm * w);
    ata += row * row.transpose();
    atb += row * (m.measuredMm * m.measuredMm * w);
  }
  // Conditioning: both columns must carry weight, independently.
  const double det = ata.determinant();
  if (!(det > 1e-8 * ata(0, 0) * ata(1, 1)))
    throw std::invalid_argument(
      "the calibration distances do not determine both scale factors: give at least one mainly horizontal "
      "distance (e.g. zygion–zygion) and one mainly vertical distance (e.g. nasion–subnasale)");
  const Eigen::Vector2d ab = ata.ldlt().solve(atb);
  Eigen::Vector2d s(ab(0) > 0.0 ? std::sqrt(ab(0)) : (nH ? result.thesisHorizontalScale : 1.0),
                    ab(1) > 0.0 ? std::sqrt(ab(1)) : (nV ? result.thesisVerticalScale : 1.0));

  // Gauss–Newton on Σ (L_k(s) − D_k)², L_k = sqrt(sh² h² + sv² v²).
  for (int iteration = 0; iteration < 50; ++iteration)
  {
    Eigen::Matrix2d jtj = Eigen::Matrix2d::Zero();
    Eigen::Vector2d jtr = Eigen::Vector2d::Zero();
    for (const CalibrationMeasurement& m : measurements)
    {
      const double h2 = m.model.horizontalMm * m.model.horizontalMm, v2 = m.model.verticalMm * m.model.verticalMm;
      const double l = std::sqrt(s(0) * s(0) * h2 + s(1) * s(1) * v2);
      const Eigen::Vector2d j(s(0) * h2 / l, s(1) * v2 / l);
      jtj += j * j.transpose();
      jtr += j * (l - m.measuredMm);
    }
    const Eigen::Vector2d step = jtj.ldlt().solve(jtr);
    s -= step;
    if (step.norm() < 1e-13 * s.norm())
      break;
  }
  result.horizontalScale = s(0);
  result.verticalScale = s(1);
  double sum2 = 0.0;
  for (const CalibrationMeasurement& m : measurements)
  {
    const double l = std::hypot(s(0) * m.model.horizontalMm, s(1) * m.model.verticalMm);
    result.residualsMm.push_back(l - m.measuredMm);
    sum2 += (l - m.measuredMm) * (l - m.measuredMm);
  }
  result.rmsResidualMm = measurements.empty() ? 0.0 : std::sqrt(sum2 / static_cast<double>(measurements.size()));
  return result;
}

CalibrationResult calibrate(const RangeMap& map, const std::vector<LandmarkDistance>& distances)
{
  std::vector<CalibrationMeasurement> measurements;
  measurements.reserve(distances.size());
  for (const LandmarkDistance& d : distances)
    measurements.push_back(measureOnMap(map, d));
  return fitCalibration(measurements);
}

CylindricalFrame calibratedFrame(const CylindricalFrame& frame, double verticalScale)
{
  if (!(verticalScale > 0.0))
    throw std::invalid_argument("the vertical calibration scale must be positive");
  return frame.withRange(verticalScale * frame.zMin(), verticalScale * frame.zMax());
}

RangeMap applyCalibration(const RangeMap& map, const CalibrationResult& calibration)
{
  if (!(calibration.horizontalScale > 0.0))
    throw std::invalid_argument("the horizontal calibration scale must be positive");
  RangeMap out(calibratedFrame(map.frame(), calibration.verticalScale));
  for (std::size_t k = 0; k < map.values().size(); ++k)
    out.values()[k] = static_cast<float>(map.values()[k] * calibration.horizontalScale);
  return out;
}

ColourMap applyCalibration(const ColourMap& map, const CalibrationResult& calibration)
{
  ColourMap out = map;
  out.setFrame(calibratedFrame(map.frame(), calibration.verticalScale));
  return out;
}

} // namespace caps::seg
