#pragma once
// A synthetic head CT for the module tests: an ellipsoid of soft tissue (the
// head) around an ellipsoidal shell of bone (the skull) around soft tissue
// (the brain), with partial volume, a Gaussian blur and noise. Built with the
// range map tests' phantom tools (tests/segmentation/rangemaps).

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <Eigen/Core>
#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include "segmentation/rangemaps/RangeMapPhantom.h"

namespace caps::test {

/// Solid between two concentric, axis-aligned ellipsoids.
struct EllipsoidShell : seg::test::Shape
{
  seg::test::Ellipsoid outer, inner;
  EllipsoidShell(const Eigen::Vector3d& centre, const Eigen::Vector3d& outerAxes, const Eigen::Vector3d& innerAxes)
    : outer(centre, outerAxes), inner(centre, innerAxes)
  {}
  double implicit(const Eigen::Vector3d& p) const override
  {
    // < 1 inside the shell: inside the outer and outside the inner ellipsoid.
    return outer.inside(p) && !inner.inside(p) ? 0.0 : 2.0;
  }
  double outermostHit(const Eigen::Vector3d& base, const Eigen::Vector3d& dir) const override
  {
    return outer.outermostHit(base, dir);
  }
};

struct HeadPhantom
{
  // Semi-axes (mm) along patient x (left), y (posterior), z (superior).
  static constexpr double skinA = 70, skinB = 85, skinC = 100;
  static constexpr double boneA = 62, boneB = 77, boneC = 92;    // 8 mm of tissue on the axes
  static constexpr double innerA = 56, innerB = 71, innerC = 86; // 6 mm of skull
  static constexpr double spacing = 2.0;                         // mm, isotropic voxels

  Eigen::Vector3d centre{3.0, -2.0, 40.0};
  seg::test::Ellipsoid skin{centre, {skinA, skinB, skinC}};
  seg::test::Ellipsoid bone{centre, {boneA, boneB, boneC}};
  EllipsoidShell skull{centre, {boneA, boneB, boneC}, {innerA, innerB, innerC}};
  seg::test::Phantom images;

  HeadPhantom()
  {
    // 10 mm of air around the head on every side.
    const Eigen::Vector3i dims(static_cast<int>(2 * (skinA + 10) / spacing),
                               static_cast<int>(2 * (skinB + 10) / spacing),
                               static_cast<int>(2 * (skinC + 10) / spacing));
    const auto geometry =
      seg::test::centredGeometry(dims, Eigen::Vector3d::Constant(spacing), Eigen::Matrix3d::Identity(), centre);
    // 0.6 mm point spread and 15 HU noise: a sharp head CT.
    images = seg::test::makePhantom(geometry, skin, skull, {}, 0.6, 15.0, VTK_SHORT);
  }

  /// One phantom per test process (building it takes about a second).
  static const HeadPhantom& instance()
  {
    static const HeadPhantom phantom;
    return phantom;
  }

  /// Thresholds in the middle of the air/tissue and tissue/bone steps: the
  /// blurred edges cross them at the true surfaces (RangeMapPhantom.h).
  static constexpr double skinThreshold = seg::test::skinMidHu;
  static constexpr double boneThreshold = seg::test::boneMidHu;

  /// Radial thickness along the ray from @a base in direction @a dir (unit).
  double radialThickness(const Eigen::Vector3d& base, const Eigen::Vector3d& dir) const
  {
    return skin.outermostHit(base, dir) - bone.outermostHit(base, dir);
  }

  /// Thickness along the inward normal of the skin at the skin point @a p:
  /// the distance to where the line p − t n first meets the bone ellipsoid.
  double normalThickness(const Eigen::Vector3d& p) const
  {
    const Eigen::Vector3d q = p - centre;
    const Eigen::Vector3d n =
      Eigen::Vector3d(q.x() / (skinA * skinA), q.y() / (skinB * skinB), q.z() / (skinC * skinC)).normalized();
    // |(q − t n) / axes|² = 1 for the bone: a t² + b t + c = 0, smallest root.
    const Eigen::Vector3d axes(boneA, boneB, boneC);
    const Eigen::Vector3d qa = q.cwiseQuotient(axes), na = n.cwiseQuotient(axes);
    const double a = na.squaredNorm(), b = -2 * qa.dot(na), c = qa.squaredNorm() - 1;
    const double disc = b * b - 4 * a * c;
    if (disc < 0)
      return std::numeric_limits<double>::quiet_NaN();
    return (-b - std::sqrt(disc)) / (2 * a);
  }

  /// A copy of the CT with a filling: 2 x 2 x 2 voxels of 3071 HU (metal at
  /// the top of a 12-bit scanner's scale) at the voxel cell holding @a at.
  vtkSmartPointer<vtkImageData> withFilling(const Eigen::Vector3d& at) const
  {
    auto ct = vtkSmartPointer<vtkImageData>::New();
    ct->DeepCopy(images.ct);
    int ijk[3];
    double pcoords[3];
    Eigen::Vector3d point = at;
    if (!ct->ComputeStructuredCoordinates(point.data(), ijk, pcoords))
      throw std::invalid_argument("withFilling: the point is outside the phantom's CT");
    for (int dk = 0; dk <= 1; ++dk)
      for (int dj = 0; dj <= 1; ++dj)
        for (int di = 0; di <= 1; ++di)
          ct->SetScalarComponentFromDouble(ijk[0] + di, ijk[1] + dj, ijk[2] + dk, 0, 3071.0);
    return ct;
  }

  static double ellipsoidVolume(double a, double b, double c) { return 4.0 / 3.0 * std::numbers::pi * a * b * c; }
  /// Knud Thomsen's approximation of an ellipsoid's area (within 1.1 %).
  static double ellipsoidArea(double a, double b, double c)
  {
    const double p = 1.6075;
    return 4 * std::numbers::pi * std::pow((std::pow(a * b, p) + std::pow(a * c, p) + std::pow(b * c, p)) / 3, 1 / p);
  }
};

} // namespace caps::test
