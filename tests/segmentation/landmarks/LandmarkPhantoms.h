#pragma once
// Synthetic heads for the landmark tests: range maps filled directly from
// analytic r(θ, z), no CT.

#include <cmath>
#include <functional>
#include <numbers>

#include "segmentation/RangeMap.h"

namespace caps::seg::test {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

inline double gauss(double x, double centre, double sigma)
{
  const double d = (x - centre) / sigma;
  return std::exp(-0.5 * d * d);
}

/// θ − θ0 wrapped into [-π, π).
inline double angleFrom(double theta, double theta0)
{
  return CylindricalFrame::wrapTheta(theta - theta0);
}

inline RangeMap fillMap(const CylindricalFrame& frame, const std::function<double(double, double)>& r)
{
  RangeMap map(frame);
  for (int j = 0; j < frame.nZ(); ++j)
    for (int i = 0; i < frame.nTheta(); ++i)
      map.at(i, j) = static_cast<float>(r(frame.indexToTheta(i), frame.indexToZ(j)));
  return map;
}

/// A stylised head, the nose tip at z = 0 (mm), built so that each midline
/// landmark is a feature of its own at a known height:
/// head r = 80, neck r = 50 below a sharp step at z = -72 (the underside of
/// the chin: menton); on the front (weight falling off with σ = 12° from
/// θ = -90°) Gaussian bumps and dips: nose tip +22 at z = 0, nasion -6 at 30,
/// glabella +4 at 42, a concavity -2 above it at 56 (supraglabella),
/// subnasale -4 at -16, upper lip +6 at -24, stomion -3 at -32, lower lip +5
/// at -40, chin +8 at -62.
struct StylisedHead
{
  static constexpr double zNasion = 30, zGlabella = 42, zSupraglabella = 56, zSubnasale = -16, zLabraleSuperius = -24,
                          zLabraleInferius = -40, zPogonion = -62, zMenton = -72;
  /// The nasal bones: a ridge on the front of the skull from the nasion's
  /// height down to their end (the rhinion), standing out more the lower.
  static constexpr double zRhinion = 12, nasalBone = 8;
  /// Bone: an ellipse (60 mm lateral, 70 mm front-back) with zygomatic arches
  /// (+10 mm at 65° from the front, z = 15), mandible angles (+10 mm at 75°
  /// from the front, z = -55), the nasal bones (up to +8 mm on the front,
  /// ending at z = 12) and the orbits (below), none below z = -68 (the neck).
  static constexpr double zygionFromFront = 65 * kDeg, zZygion = 15;
  static constexpr double gonionFromFront = 75 * kDeg, zGonion = -55;
  /// The orbits: flat-bottomed pits 20 mm deep in the skull, centred 29°
  /// either side of the front and 4 mm below the nasion, 26° wide and 28 mm
  /// high, with steep walls; their rims raised 2 mm (σ 3 mm) 3 mm above and
  /// below them: the brow ridge at the glabella's height and the
  /// infraorbital margin.
  static constexpr double orbitFromFront = 29 * kDeg, orbitHalfWidth = 13 * kDeg;
  static constexpr double zOrbit = zNasion - 4, orbitHalfHeight = 14, orbitDepth = 20;

  static double skin(double theta, double z)
  {
    const double base = 50.0 + 30.0 / (1.0 + std::exp(-(z - zMenton) / 1.0));
    const double w = gauss(angleFrom(theta, -kPi / 2), 0.0, 12 * kDeg);
    const double face = 22 * gauss(z, 0, 6) - 6 * gauss(z, zNasion, 4) + 4 * gauss(z, zGlabella, 5) -
                        2 * gauss(z, zSupraglabella, 5) - 4 * gauss(z, zSubnasale, 3) +
                        6 * gauss(z, zLabraleSuperius, 3) - 3 * gauss(z, -32, 2) + 5 * gauss(z, zLabraleInferius, 3) +
                        8 * gauss(z, zPogonion, 5);
    return base + w * face;
  }

  static double bone(double theta, double z)
  {
    if (z < -68.0)
      return std::nan("");
    const double c = std::cos(theta), s = std::sin(theta);
    double r = 1.0 / std::sqrt(c * c / (60.0 * 60.0) + s * s / (70.0 * 70.0));
    if (z >= zRhinion && z <= zNasion)
      r += nasalBone * gauss(angleFrom(theta, -kPi / 2), 0, 8 * kDeg) * (zNasion - z) / (zNasion - zRhinion);
    for (int side : {-1, 1})
    {
      r += 10 * gauss(angleFrom(theta, -kPi / 2 + side * zygionFromFront), 0, 8 * kDeg) * gauss(z, zZygion, 5);
      r += 10 * gauss(angleFrom(theta, -kPi / 2 + side * gonionFromFront), 0, 8 * kDeg) * gauss(z, zGonion, 5);
      const double a = angleFrom(theta, -kPi / 2 + side * orbitFromFront) / orbitHalfWidth;
      const double b = (z - zOrbit) / orbitHalfHeight, rho2 = a * a + b * b;
      const double rims = gauss(z, zOrbit + orbitHalfHeight + 3, 3) + gauss(z, zOrbit - orbitHalfHeight - 3, 3);
      r += 2.0 * std::exp(-a * a / 4) * rims - orbitDepth * std::exp(-rho2 * rho2 * rho2 * rho2);
    }
    return r;
  }

  static CylindricalFrame frame()
  {
    return CylindricalFrame(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), -120.0, 110.0, 512, 256);
  }
};

/// Concentric spheres about the origin: skin R = 90, bone 80. Radial
/// thickness sqrt(90² − z²) − sqrt(80² − z²); along the normal 10 everywhere.
struct ConcentricSpheres
{
  static constexpr double skinRadius = 90, boneRadius = 80;
  static double skin(double, double z) { return std::sqrt(skinRadius * skinRadius - z * z); }
  static double bone(double, double z)
  {
    return std::abs(z) <= boneRadius ? std::sqrt(boneRadius * boneRadius - z * z) : std::nan("");
  }
  static double radial(double z) { return skin(0, z) - bone(0, z); }
  static CylindricalFrame frame()
  {
    return CylindricalFrame(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), -85.0, 85.0, 256, 128);
  }
};

} // namespace caps::seg::test
