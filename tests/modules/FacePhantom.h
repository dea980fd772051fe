#pragma once
// A synthetic head CT with a face: the stylised head of the landmark tests
// (LandmarkPhantoms.h: a nose, a nasion, a brow, lips, a chin, the chin's
// underside over a neck) as skin, over a skull with cheekbones, jaw angles,
// nasal bones, orbits, a chin and a rounded lower end, sampled with partial volume, blurred and
// noisy like HeadPhantom. Every landmark's true place and depth follow from
// the two analytic surfaces r(θ, z) about a vertical axis, so the whole chain
// (segmentation, range maps, placement, depth in the CT) can be checked
// against them.

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "segmentation/landmarks/LandmarkPhantoms.h"
#include "segmentation/rangemaps/RangeMapPhantom.h"

namespace caps::test {

/// The solid inside r(θ, z) about the vertical axis through @a axisPoint (θ
/// as CylindricalFrame: 0 patient left, -π/2 the front); nothing where r is
/// NaN.
struct RadialSolid : seg::test::Shape
{
  Eigen::Vector3d axisPoint;
  double (*radius)(double theta, double z);

  RadialSolid(const Eigen::Vector3d& p, double (*r)(double, double)) : axisPoint(p), radius(r) {}
  double implicit(const Eigen::Vector3d& p) const override
  {
    const Eigen::Vector3d q = p - axisPoint;
    const double r = radius(std::atan2(q.y(), q.x()), q.z());
    if (!(r > 0.0))
      return 2.0;
    return (q.x() * q.x() + q.y() * q.y()) / (r * r);
  }
  double outermostHit(const Eigen::Vector3d& base, const Eigen::Vector3d& dir) const override
  {
    // The last inside-to-outside change walking out 300 mm, then bisection.
    double last = std::numeric_limits<double>::quiet_NaN();
    for (double t = 0.0; t < 300.0; t += 0.25)
      if (inside(base + t * dir) && !inside(base + (t + 0.25) * dir))
        last = t;
    if (!std::isfinite(last))
      return last;
    double lo = last, hi = last + 0.25;
    for (int k = 0; k < 50; ++k)
      (inside(base + 0.5 * (lo + hi) * dir) ? lo : hi) = 0.5 * (lo + hi);
    return 0.5 * (lo + hi);
  }
};

struct FacePhantom
{
  using Head = seg::test::StylisedHead;
  static constexpr double spacing = 1.0, sliceSpacing = 1.25; // mm
  /// The skull's lower end: r shrinks as a quarter ellipse from zCap down to zCap − capHeight.
  static constexpr double zCap = -58, capHeight = 12;
  /// The chin's bone: +7 mm at the pogonion's height, 15° wide.
  static constexpr double chinBone = 7;

  /// The axis point at the nose tip's height.
  Eigen::Vector3d axis{4.0, -3.0, 20.0};
  RadialSolid skin{axis, &skinRadius};
  RadialSolid bone{axis, &boneRadius};
  seg::test::Phantom images;

  /// The stylised head's skin with its profile bent no tighter than a real
  /// face's: the stylised head's Gaussians bend it with radii of 1.5-2.7 mm
  /// at the lips, the subnasale and the nasion, folds that a CT's 0.6 mm
  /// point spread and 1.25 mm slices round off (the CT's skin there is not
  /// the analytic one) and where no probe can be held perpendicular to the
  /// skin. Here each feature is wide enough to bend it with a radius of 4 mm
  /// or more (the width σ of a Gaussian of height A gives σ²/A).
  static double skinRadius(double theta, double z)
  {
    using seg::test::gauss;
    const double base = 50.0 + 30.0 / (1.0 + std::exp(-(z - Head::zMenton) / 2.5));
    const double w = gauss(seg::test::angleFrom(theta, -seg::test::kPi / 2), 0.0, 12 * seg::test::kDeg);
    const double face = 22 * gauss(z, 0, 6) - 6 * gauss(z, Head::zNasion, 5.5) + 4 * gauss(z, Head::zGlabella, 5) -
                        2 * gauss(z, Head::zSupraglabella, 5) - 4 * gauss(z, Head::zSubnasale, 4.5) +
                        6 * gauss(z, Head::zLabraleSuperius, 5) - 3 * gauss(z, -32, 3.5) +
                        5 * gauss(z, Head::zLabraleInferius, 5) + 8 * gauss(z, Head::zPogonion, 6);
    return base + w * face;
  }
  static double boneRadius(double theta, double z)
  {
    if (z < zCap - capHeight)
      return std::numeric_limits<double>::quiet_NaN();
    // The stylised head's skull without its flat cut, a chin, then the end.
    const double w = seg::test::gauss(seg::test::angleFrom(theta, -seg::test::kPi / 2), 0.0, 15 * seg::test::kDeg);
    const double r = Head::bone(theta, std::max(z, -60.0)) + chinBone * w * seg::test::gauss(z, Head::zPogonion, 5);
    if (z >= zCap)
      return r;
    const double u = (zCap - z) / capHeight;
    return r * std::sqrt(std::max(0.0, 1.0 - u * u));
  }

  FacePhantom()
  {
    // The face reaches 102 mm in front of the axis; 8 mm of air around.
    const Eigen::Vector3d lo(-92, -112, -100), hi(92, 92, 110);
    const Eigen::Vector3d step(spacing, spacing, sliceSpacing);
    const Eigen::Vector3i dims = ((hi - lo).cwiseQuotient(step)).cast<int>() + Eigen::Vector3i::Ones();
    const auto geometry = seg::test::centredGeometry(dims, step, Eigen::Matrix3d::Identity(), axis + 0.5 * (lo + hi));
    images = seg::test::makePhantom(geometry, skin, bone, {}, 0.6, 15.0, VTK_SHORT);
  }

  static const FacePhantom& instance()
  {
    static const FacePhantom phantom;
    return phantom;
  }

  Eigen::Vector3d toWorld(double r, double theta, double z) const
  {
    return axis + Eigen::Vector3d(r * std::cos(theta), r * std::sin(theta), z);
  }
  /// θ and z of a world point about the phantom's axis.
  std::pair<double, double> cylindrical(const Eigen::Vector3d& p) const
  {
    const Eigen::Vector3d q = p - axis;
    return {std::atan2(q.y(), q.x()), q.z()};
  }
  Eigen::Vector3d skinPoint(double theta, double z) const { return toWorld(skinRadius(theta, z), theta, z); }

  /// The skin's outward unit normal at (θ, z): the gradient of ρ − R(θ, z).
  Eigen::Vector3d skinNormal(double theta, double z) const
  {
    const double h = 1e-4, r = skinRadius(theta, z);
    const double dTheta = (skinRadius(theta + h, z) - skinRadius(theta - h, z)) / (2 * h);
    const double dZ = (skinRadius(theta, z + h) - skinRadius(theta, z - h)) / (2 * h);
    const Eigen::Vector3d radial(std::cos(theta), std::sin(theta), 0.0),
      tangent(-std::sin(theta), std::cos(theta), 0.0);
    return (radial - dTheta / r * tangent - dZ * Eigen::Vector3d::UnitZ()).normalized();
  }

  /// θ and z of the skin point nearest @a p (within 5° and 10 mm of the
  /// radial projection): a grid search refined four times.
  std::pair<double, double> nearestSkin(const Eigen::Vector3d& p) const
  {
    auto [bestTheta, bestZ] = cylindrical(p);
    double best = (skinPoint(bestTheta, bestZ) - p).norm();
    double dTheta = 0.5 * seg::test::kDeg, dZ = 1.0;
    for (int level = 0; level < 6; ++level)
    {
      const double theta0 = bestTheta, z0 = bestZ;
      for (int a = -10; a <= 10; ++a)
        for (int b = -10; b <= 10; ++b)
        {
          const double theta = theta0 + a * dTheta, z = z0 + b * dZ;
          const double d = (skinPoint(theta, z) - p).norm();
          if (d < best)
            best = d, bestTheta = theta, bestZ = z;
        }
      dTheta /= 5, dZ /= 5;
    }
    return {bestTheta, bestZ};
  }

  bool inBone(const Eigen::Vector3d& p) const { return bone.inside(p); }

  /// From @a p along the unit @a direction to where the line first enters
  /// bone (mm); NaN within 100 mm none.
  double toBoneAlong(const Eigen::Vector3d& p, const Eigen::Vector3d& direction) const
  {
    constexpr double step = 0.02;
    for (double t = 0.0; t < 100.0; t += step)
      if (inBone(p + (t + step) * direction))
      {
        double lo = t, hi = t + step;
        for (int k = 0; k < 40; ++k)
          (inBone(p + 0.5 * (lo + hi) * direction) ? hi : lo) = 0.5 * (lo + hi);
        return 0.5 * (lo + hi);
      }
    return std::numeric_limits<double>::quiet_NaN();
  }

  /// The shortest distance from @a p to the bone surface: a search over the
  /// surface's (θ, z), refined four times around the best sample.
  double toNearestBone(const Eigen::Vector3d& p) const
  {
    double best = std::numeric_limits<double>::infinity(), bestTheta = 0.0, bestZ = 0.0;
    auto tryPoint = [&](double theta, double z) {
      const double r = boneRadius(theta, z);
      if (!std::isfinite(r))
        return;
      const double d = (toWorld(r, theta, z) - p).norm();
      if (d < best)
        best = d, bestTheta = theta, bestZ = z;
    };
    const double zLow = zCap - capHeight, zHigh = 110.0;
    for (double theta = -seg::test::kPi; theta < seg::test::kPi; theta += seg::test::kDeg)
      for (double z = zLow; z <= zHigh; z += 0.5)
        tryPoint(theta, z);
    double dTheta = seg::test::kDeg, dZ = 0.5;
    for (int level = 0; level < 5; ++level)
    {
      const double theta0 = bestTheta, z0 = bestZ;
      for (int a = -20; a <= 20; ++a)
        for (int b = -20; b <= 20; ++b)
          tryPoint(theta0 + a * dTheta / 10, std::clamp(z0 + b * dZ / 10, zLow, zHigh));
      dTheta /= 10, dZ /= 10;
    }
    return best;
  }
};

} // namespace caps::test
