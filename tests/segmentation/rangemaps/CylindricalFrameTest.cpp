// The cylindrical frame: conventions of DESIGN.md and round trips between
// world, cylindrical, normalised cylindrical, sample indices and image indices.

#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <vtkImageData.h>
#include <vtkNew.h>

#include "segmentation/CylindricalFrame.h"
#include "segmentation/RangeMapImageGeometry.h"

using namespace caps::seg;
constexpr double pi = std::numbers::pi;

TEST(CylindricalFrame, ConventionsOfTheDesign)
{
  const CylindricalFrame frame(Eigen::Vector3d(10, -20, 600), Eigen::Vector3d(0, 0, 2), -50, 150);
  EXPECT_EQ(frame.nTheta(), 512);
  EXPECT_EQ(frame.nZ(), 256);
  EXPECT_TRUE(frame.direction().isApprox(Eigen::Vector3d::UnitZ()));
  // Anterior (-y) is θ = -π/2, patient left (+x) θ = 0, posterior π/2, right -π.
  const Eigen::Vector3d o = frame.origin();
  EXPECT_NEAR(frame.toCylindrical(o + Eigen::Vector3d(0, -80, 0)).theta, -pi / 2, 1e-12);
  EXPECT_NEAR(frame.toCylindrical(o + Eigen::Vector3d(80, 0, 0)).theta, 0.0, 1e-12);
  EXPECT_NEAR(frame.toCylindrical(o + Eigen::Vector3d(0, 80, 0)).theta, pi / 2, 1e-12);
  EXPECT_NEAR(frame.toCylindrical(o + Eigen::Vector3d(-80, 0, 0)).theta, -pi, 1e-12); // [-π, π)
  const CylindricalPoint c = frame.toCylindrical(o + Eigen::Vector3d(3, 4, 12));
  EXPECT_NEAR(c.r, 5.0, 1e-12);
  EXPECT_NEAR(c.z, 12.0, 1e-12);
  // eq. 4.11 in the axis frame.
  EXPECT_TRUE(frame.toWorld(2.0, pi / 3, 7.0).isApprox(o + Eigen::Vector3d(1.0, std::sqrt(3.0), 7.0)));
  // Grid: column 0 at -π, front of the face at column nθ/4; rows from zMin to zMax.
  EXPECT_NEAR(frame.indexToTheta(0), -pi, 1e-12);
  EXPECT_NEAR(frame.thetaToIndex(-pi / 2), 128.0, 1e-9);
  EXPECT_NEAR(frame.indexToZ(0), -50.0, 1e-12);
  EXPECT_NEAR(frame.indexToZ(255), 150.0, 1e-9);
  const double justBeforeSeam = frame.thetaToIndex(pi - 1e-14);
  EXPECT_LT(justBeforeSeam, 512.0); // never nθ
  EXPECT_LT(std::min(justBeforeSeam, 512.0 - justBeforeSeam), 1e-6);
  EXPECT_EQ(frame.thetaToIndex(pi), 0.0);
  EXPECT_NEAR(CylindricalFrame::wrapTheta(pi), -pi, 0);
  EXPECT_NEAR(CylindricalFrame::wrapTheta(3 * pi + 0.25), -pi + 0.25, 1e-12);
  EXPECT_NEAR(CylindricalFrame::wrapTheta(-5 * pi / 2), -pi / 2, 1e-12);
  EXPECT_THROW(CylindricalFrame(o, Eigen::Vector3d::Zero(), 0, 1), std::invalid_argument);
  EXPECT_THROW(CylindricalFrame(o, Eigen::Vector3d::UnitZ(), 1, 1), std::invalid_argument);
}

TEST(CylindricalFrame, TiltedAxisIsRightHandedAndFrontStaysAnterior)
{
  const Eigen::Vector3d axis = Eigen::Vector3d(0.1, -0.25, 1.0).normalized();
  const CylindricalFrame frame(Eigen::Vector3d(1, 2, 3), axis, -10, 10, 360, 50);
  EXPECT_NEAR(frame.xAxis().dot(frame.yAxis()), 0.0, 1e-12);
  EXPECT_NEAR(frame.xAxis().dot(axis), 0.0, 1e-12);
  EXPECT_TRUE(frame.xAxis().cross(frame.yAxis()).isApprox(axis, 1e-12));
  EXPECT_GT(frame.xAxis().x(), 0.9);                   // still patient left
  EXPECT_GT(frame.yAxis().y(), 0.9);                   // still posterior
  EXPECT_LT(frame.radialDirection(-pi / 2).y(), -0.9); // θ = -π/2 is the face
}

TEST(CylindricalFrame, RoundTripsBetweenSpaces)
{
  const CylindricalFrame frame(Eigen::Vector3d(-5, 12, 700), Eigen::Vector3d(0.05, -0.2, 1), -80, 120, 512, 256);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> u(-150, 150);
  double worst = 0, worstIndex = 0, worstNorm = 0;
  for (int n = 0; n < 2000; ++n)
  {
    const Eigen::Vector3d p = frame.origin() + Eigen::Vector3d(u(random), u(random), u(random));
    const CylindricalPoint c = frame.toCylindrical(p);
    EXPECT_GE(c.theta, -pi);
    EXPECT_LT(c.theta, pi);
    worst = std::max(worst, (frame.toWorld(c) - p).norm());
    // normalised cylindrical
    const NormalizedCylindricalPoint nc = frame.toNormalized(c);
    const CylindricalPoint back = frame.fromNormalized(nc);
    worstNorm = std::max({worstNorm, std::abs(back.r - c.r), std::abs(back.theta - c.theta), std::abs(back.z - c.z)});
    // sample indices
    const double uu = frame.thetaToIndex(c.theta), vv = frame.zToIndex(c.z);
    EXPECT_GE(uu, 0.0);
    EXPECT_LT(uu, 512.0);
    worstIndex = std::max({worstIndex, std::abs(frame.indexToZ(vv) - c.z),
                           std::abs(CylindricalFrame::wrapTheta(frame.indexToTheta(uu) - c.theta))});
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_LT(worstNorm, 1e-9);
  EXPECT_LT(worstIndex, 1e-9); // θ compared on the circle
  // The ends of the normalised range.
  EXPECT_NEAR(frame.toNormalized({1, 0, -80}).zN, -1.0, 1e-12);
  EXPECT_NEAR(frame.toNormalized({1, 0, 120}).zN, 1.0, 1e-12);
  EXPECT_NEAR(frame.toNormalized({1, -pi, 0}).thetaN, -1.0, 1e-12);
  EXPECT_NEAR(frame.toNormalized({1, -pi / 2, 0}).thetaN, -0.5, 1e-12);
}

TEST(ImageGeometry, IndexToWorldAgreesWithVtkForAnObliqueDirection)
{
  vtkNew<vtkImageData> image;
  image->SetExtent(2, 40, -3, 30, 0, 20);
  image->SetOrigin(-120.5, 33.0, 510.25);
  image->SetSpacing(0.54, 0.61, 1.25);
  const Eigen::Matrix3d d = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix() *
                            Eigen::Vector3d(1, -1, 1).asDiagonal();
  image->SetDirectionMatrix(d(0, 0), d(0, 1), d(0, 2), d(1, 0), d(1, 1), d(1, 2), d(2, 0), d(2, 1), d(2, 2));
  const ImageGeometry g = ImageGeometry::of(image);
  EXPECT_EQ(g.dimensions()[0], 39);
  for (const Eigen::Vector3d& ijk : {Eigen::Vector3d(2, -3, 0), Eigen::Vector3d(17.25, 4.5, 19.75)})
  {
    double xyz[3];
    image->TransformContinuousIndexToPhysicalPoint(ijk.data(), xyz);
    EXPECT_LT((g.indexToWorld(ijk) - Eigen::Vector3d(xyz[0], xyz[1], xyz[2])).norm(), 1e-9);
    EXPECT_LT((g.worldToIndex(g.indexToWorld(ijk)) - ijk).norm(), 1e-9);
  }
  vtkNew<vtkImageData> copy;
  g.applyTo(copy);
  EXPECT_TRUE(ImageGeometry::of(copy).sameGrid(g, 1e-9));
  ImageGeometry shifted = g;
  shifted.origin.x() += 0.1;
  EXPECT_FALSE(shifted.sameGrid(g));
}
