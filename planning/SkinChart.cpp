#include "planning/SkinChart.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>

namespace caps::planning {
namespace {

constexpr double pi = 3.14159265358979323846;
constexpr double degrees = 180.0 / pi;

} // namespace

SkinChart::SkinChart(const seg::RangeMap& skin, double centreTheta, double centreZ)
  : skin_(&skin), centreTheta_(seg::CylindricalFrame::wrapTheta(centreTheta)), centreZ_(centreZ),
    radius_(skin.empty() ? std::nan("") : skin.sample(centreTheta, centreZ))
{
  if (!std::isfinite(radius_) || radius_ <= 0.0)
  {
    std::ostringstream message;
    message << "the skin map has no surface at θ = " << centreTheta_ * degrees << "°, z = " << centreZ
            << " mm (scanned z range " << skin.frame().zMin() << " to " << skin.frame().zMax()
            << " mm): place the plan on the measured skin";
    throw std::invalid_argument(message.str());
  }
}

ChartPoint SkinChart::toChart(const SkinPoint& p) const
{
  // Unwrap θ about θc so the chart is one piece across θ = ±π.
  const double dTheta = seg::CylindricalFrame::wrapTheta(p.theta - centreTheta_);
  return {radius_ * dTheta, p.z - centreZ_};
}

SkinPoint SkinChart::fromChart(const ChartPoint& p) const
{
  return {seg::CylindricalFrame::wrapTheta(centreTheta_ + p.x() / radius_), centreZ_ + p.y()};
}

ChartPoint SkinChart::fromNormalized(const Eigen::Vector2d& thetaZN) const
{
  return toChart(skinPointFromNormalized(skin_->frame(), thetaZN));
}

Eigen::Vector2d SkinChart::toNormalized(const ChartPoint& p) const
{
  return normalizedFromSkinPoint(skin_->frame(), fromChart(p));
}

Eigen::Vector3d SkinChart::lift(const ChartPoint& p) const
{
  const SkinPoint s = fromChart(p);
  const double r = skin_->sample(s.theta, s.z);
  if (!std::isfinite(r))
    return Eigen::Vector3d::Constant(std::nan(""));
  return skin_->frame().toWorld(r, s.theta, s.z);
}

double chartDistortion(const SkinChart& chart, const ChartPoint& p, double step)
{
  const Eigen::Vector2d du(step, 0.0), dv(0.0, step);
  Eigen::Matrix<double, 3, 2> jacobian;
  jacobian.col(0) = (chart.lift(p + du) - chart.lift(p - du)) / (2.0 * step);
  jacobian.col(1) = (chart.lift(p + dv) - chart.lift(p - dv)) / (2.0 * step);
  if (!jacobian.allFinite())
    return std::nan("");
  // σ² are the eigenvalues of the 2 × 2 metric JᵀJ.
  const Eigen::Vector2d sigmaSquared =
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(jacobian.transpose() * jacobian, Eigen::EigenvaluesOnly)
      .eigenvalues();
  const double smallest = std::sqrt(std::max(0.0, sigmaSquared(0))), largest = std::sqrt(sigmaSquared(1));
  return smallest > 0.0 ? std::max(largest, 1.0 / smallest) : std::numeric_limits<double>::infinity();
}

SkinPoint skinPointFromNormalized(const seg::CylindricalFrame& frame, const Eigen::Vector2d& thetaZN)
{
  const seg::CylindricalPoint c = frame.fromNormalized({0.0, thetaZN.x(), thetaZN.y()});
  return {c.theta, c.z};
}

Eigen::Vector2d normalizedFromSkinPoint(const seg::CylindricalFrame& frame, const SkinPoint& p)
{
  const seg::NormalizedCylindricalPoint n = frame.toNormalized({0.0, p.theta, p.z});
  return {n.thetaN, n.zN};
}

} // namespace caps::planning
