#include "segmentation/CylindricalFrame.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

namespace caps::seg {

namespace {
constexpr double pi = std::numbers::pi;
}

CylindricalFrame::CylindricalFrame()
  : CylindricalFrame(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), -100.0, 100.0)
{}

CylindricalFrame::CylindricalFrame(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double zMin,
                                   double zMax, int nTheta, int nZ)
  : origin_(origin), zMin_(zMin), zMax_(zMax), nTheta_(nTheta), nZ_(nZ)
{
  const double length = direction.norm();
  if (!(length > 1e-12) || !std::isfinite(length))
    throw std::invalid_argument("The cylinder axis needs a non-zero direction.");
  if (!(zMax > zMin))
    throw std::invalid_argument("The cylinder's z range is empty (zMin " + std::to_string(zMin) + " mm, zMax " +
                                std::to_string(zMax) + " mm).");
  if (nTheta < 4 || nZ < 2)
    throw std::invalid_argument("A range map needs at least 4 samples around and 2 along the axis.");
  axis_ = direction / length;
  // x: patient left made orthogonal to the axis; for an axis along left-right
  // (never a head), fall back to posterior for y.
  const Eigen::Vector3d left = Eigen::Vector3d::UnitX();
  Eigen::Vector3d x = left - left.dot(axis_) * axis_;
  if (x.norm() > 1e-6)
  {
    xAxis_ = x.normalized();
    yAxis_ = axis_.cross(xAxis_);
  }
  else
  {
    const Eigen::Vector3d posterior = Eigen::Vector3d::UnitY();
    yAxis_ = (posterior - posterior.dot(axis_) * axis_).normalized();
    xAxis_ = yAxis_.cross(axis_);
  }
}

double CylindricalFrame::thetaStep() const
{
  return 2.0 * pi / nTheta_;
}
double CylindricalFrame::zStep() const
{
  return (zMax_ - zMin_) / (nZ_ - 1);
}

CylindricalFrame CylindricalFrame::withRange(double zMin, double zMax) const
{
  return CylindricalFrame(origin_, axis_, zMin, zMax, nTheta_, nZ_);
}

CylindricalFrame CylindricalFrame::withGrid(int nTheta, int nZ) const
{
  return CylindricalFrame(origin_, axis_, zMin_, zMax_, nTheta, nZ);
}

CylindricalPoint CylindricalFrame::toCylindrical(const Eigen::Vector3d& world) const
{
  const Eigen::Vector3d d = world - origin_;
  const double x = d.dot(xAxis_);
  const double y = d.dot(yAxis_);
  return {std::hypot(x, y), wrapTheta(std::atan2(y, x)), d.dot(axis_)};
}

Eigen::Vector3d CylindricalFrame::toWorld(const CylindricalPoint& p) const
{
  return toWorld(p.r, p.theta, p.z);
}

Eigen::Vector3d CylindricalFrame::toWorld(double r, double theta, double z) const
{
  return axisPoint(z) + r * radialDirection(theta);
}

Eigen::Vector3d CylindricalFrame::radialDirection(double theta) const
{
  return std::cos(theta) * xAxis_ + std::sin(theta) * yAxis_;
}

Eigen::Vector3d CylindricalFrame::axisPoint(double z) const
{
  return origin_ + z * axis_;
}

NormalizedCylindricalPoint CylindricalFrame::toNormalized(const CylindricalPoint& p) const
{
  return {p.r, wrapTheta(p.theta) / pi, 2.0 * (p.z - zMin_) / (zMax_ - zMin_) - 1.0};
}

CylindricalPoint CylindricalFrame::fromNormalized(const NormalizedCylindricalPoint& p) const
{
  return {p.r, wrapTheta(p.thetaN * pi), zMin_ + 0.5 * (p.zN + 1.0) * (zMax_ - zMin_)};
}

double CylindricalFrame::thetaToIndex(double theta) const
{
  double u = (wrapTheta(theta) + pi) / (2.0 * pi) * nTheta_;
  return u >= nTheta_ ? u - nTheta_ : u; // rounding at θ just below π
}

double CylindricalFrame::zToIndex(double z) const
{
  return (z - zMin_) / zStep();
}
double CylindricalFrame::indexToTheta(double u) const
{
  return wrapTheta(-pi + u * thetaStep());
}
double CylindricalFrame::indexToZ(double v) const
{
  return zMin_ + v * zStep();
}

double CylindricalFrame::wrapTheta(double theta)
{
  if (theta >= -pi && theta < pi)
    return theta;
  double t = std::fmod(theta + pi, 2.0 * pi);
  if (t < 0.0)
    t += 2.0 * pi;
  t -= pi;
  return t >= pi ? -pi : t;
}

bool CylindricalFrame::operator==(const CylindricalFrame& o) const
{
  return origin_ == o.origin_ && axis_ == o.axis_ && zMin_ == o.zMin_ && zMax_ == o.zMax_ && nTheta_ == o.nTheta_ &&
         nZ_ == o.nZ_;
}

} // namespace caps::seg
