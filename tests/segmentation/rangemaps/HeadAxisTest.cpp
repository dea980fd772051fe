// fitHeadAxis: a tilted head on wide, off-centre shoulders; the axis comes
// back within a fraction of a degree whatever the direction matrix.

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "RangeMapPhantom.h"
#include "segmentation/HeadAxis.h"

using namespace caps::seg;
using namespace caps::seg::test;

namespace {

struct TiltedHead
{
  Eigen::Vector3d axisPoint = Eigen::Vector3d(12, -8, 40);
  Eigen::Vector3d axis = (Eigen::AngleAxisd(0.15, Eigen::Vector3d::UnitX()) *
                          Eigen::AngleAxisd(-0.08, Eigen::Vector3d::UnitY()) * Eigen::Vector3d::UnitZ());
  double angleDegrees(const Eigen::Vector3d& d) const
  {
    return std::acos(std::min(1.0, std::abs(d.normalized().dot(axis)))) * 180.0 / std::numbers::pi;
  }
  double distanceFromAxis(const Eigen::Vector3d& p) const
  {
    const Eigen::Vector3d w = p - axisPoint;
    return (w - w.dot(axis) * axis).norm();
  }
};

/// Mask of an elliptic head (semi-axes 70 × 90 mm around the tilted axis,
/// top closed by an ellipsoid) from z = -60 up, and shoulders: a box 360 mm
/// wide, 40 mm posterior of the axis, below z = -40.
vtkSmartPointer<vtkImageData> headMask(const TiltedHead& head, const Eigen::Matrix3d& direction)
{
  const ImageGeometry g =
    centredGeometry(Eigen::Vector3i(200, 160, 150), Eigen::Vector3d(2, 2, 2), direction, Eigen::Vector3d(0, 0, 50));
  auto mask = makeImage(g, VTK_UNSIGNED_CHAR);
  auto* m = static_cast<unsigned char*>(mask->GetScalarPointer());
  const Eigen::Vector3d x =
    (Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitX().dot(head.axis) * head.axis).normalized();
  const Eigen::Vector3d y = head.axis.cross(x);
  const auto dims = g.dimensions();
  std::size_t o = 0;
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i, ++o)
      {
        const Eigen::Vector3d p = g.indexToWorld(Eigen::Vector3d(i, j, k));
        const Eigen::Vector3d w = p - head.axisPoint;
        const double a = w.dot(x) / 70.0, b = w.dot(y) / 90.0, h = w.dot(head.axis);
        const bool inHead =
          h > -100 && (h < 80 ? a * a + b * b < 1.0 : a * a + b * b + (h - 80) * (h - 80) / (50.0 * 50.0) < 1.0);
        const bool inShoulders = p.z() < -40 && std::abs(p.x()) < 180 && std::abs(p.y() - 40) < 60;
        m[o] = inHead || inShoulders;
      }
  return mask;
}

} // namespace

TEST(HeadAxis, RecoversATiltedAxisAboveShoulders)
{
  const TiltedHead head;
  for (const Eigen::Matrix3d& direction :
       {Eigen::Matrix3d(Eigen::Matrix3d::Identity()),
        Eigen::Matrix3d(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 0.3, 1).normalized()).matrix())})
  {
    const auto mask = headMask(head, direction);
    const HeadAxisFit fit = fitHeadAxis(mask);
    const double angle = head.angleDegrees(fit.frame.direction());
    const double offset = head.distanceFromAxis(fit.frame.origin());
    std::printf("tilted head axis: %.3f deg, origin %.3f mm off the axis, %d slices, rms %.3f mm\n", angle, offset,
                fit.slicesUsed, fit.rmsResidual);
    EXPECT_LT(angle, 0.5);
    EXPECT_LT(offset, 1.0);
    EXPECT_GT(fit.frame.direction().z(), 0.9); // superior
    EXPECT_GT(fit.frame.xAxis().x(), 0.9);
    // The frame spans the mask along the axis.
    EXPECT_LT(fit.frame.zMin(), -100 + 30);
    EXPECT_GT(fit.frame.zMax() - fit.frame.zMin(), 200);

    // Without the shoulder cut the shoulders drag the axis away: the test can fail.
    HeadAxisOptions naive;
    naive.shoulderAreaRatio = 1e9;
    naive.reweightIterations = 0;
    const HeadAxisFit bad = fitHeadAxis(mask, naive);
    std::printf("  same fit without the shoulder cut or reweighting: %.3f deg\n",
                head.angleDegrees(bad.frame.direction()));
    EXPECT_GT(head.angleDegrees(bad.frame.direction()), 2.0);
  }
}

TEST(HeadAxis, RefusesAnEmptyMask)
{
  const ImageGeometry g = centredGeometry(Eigen::Vector3i(10, 10, 10), Eigen::Vector3d(1, 1, 1),
                                          Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  auto mask = makeImage(g, VTK_UNSIGNED_CHAR);
  std::fill_n(static_cast<unsigned char*>(mask->GetScalarPointer()), 1000, 0);
  EXPECT_THROW(fitHeadAxis(mask), std::invalid_argument);
  EXPECT_THROW(fitHeadAxis(nullptr), std::invalid_argument);
}

// The axis set by the user: kept as given (pointing superior), its z range
// covering every body voxel, compared with projecting each voxel centre.
TEST(HeadAxis, TakesTheUsersAxisAndSpansTheBody)
{
  const TiltedHead head;
  const Eigen::Matrix3d direction = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 0.3, 1).normalized()).matrix();
  const auto mask = headMask(head, direction);
  const Eigen::Vector3d point(5, -3, 20);
  const Eigen::Vector3d along = -Eigen::Vector3d(0.1, -0.2, 1.0).normalized(); // given pointing down
  HeadAxisOptions options;
  options.nTheta = 90;
  options.nZ = 40;
  const HeadAxisFit fit = axisThroughBody(mask, point, along, options);
  EXPECT_TRUE(fit.userDefined);
  EXPECT_TRUE(fit.centroids.empty());
  EXPECT_NEAR((fit.frame.direction() + along).norm(), 0.0, 1e-12); // flipped to superior
  EXPECT_NEAR((fit.frame.origin() - point).norm(), 0.0, 1e-12);
  EXPECT_EQ(fit.frame.nTheta(), 90);
  EXPECT_EQ(fit.frame.nZ(), 40);

  const ImageGeometry g = ImageGeometry::of(mask);
  const auto dims = g.dimensions();
  const auto* m = static_cast<const unsigned char*>(mask->GetScalarPointer());
  double lo = 1e300, hi = -1e300;
  std::size_t o = 0;
  for (int k = 0; k < dims[2]; ++k)
    for (int j = 0; j < dims[1]; ++j)
      for (int i = 0; i < dims[0]; ++i, ++o)
        if (m[o])
        {
          const double z = (g.indexToWorld(Eigen::Vector3d(i, j, k)) - point).dot(-along);
          lo = std::min(lo, z);
          hi = std::max(hi, z);
        }
  EXPECT_NEAR(fit.frame.zMin(), lo, 1e-9);
  EXPECT_NEAR(fit.frame.zMax(), hi, 1e-9);

  EXPECT_THROW(axisThroughBody(mask, point, Eigen::Vector3d::Zero()), std::invalid_argument);
  EXPECT_THROW(axisThroughBody(mask, Eigen::Vector3d(0, std::nan(""), 0), along), std::invalid_argument);
  EXPECT_THROW(axisThroughBody(nullptr, point, along), std::invalid_argument);
  std::fill_n(static_cast<unsigned char*>(mask->GetScalarPointer()), mask->GetNumberOfPoints(), 0);
  EXPECT_THROW(axisThroughBody(mask, point, along), std::invalid_argument);
}
