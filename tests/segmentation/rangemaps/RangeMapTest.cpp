// RangeMap: bilinear sampling (eq. 4.9) across the θ seam, NaN rules, box
// smoothing (eq. 4.2), surface normals, and the point-list input (§3.2.7).

#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "segmentation/RangeMap.h"
#include "segmentation/RangeMapFromPoints.h"

using namespace caps::seg;
constexpr double pi = std::numbers::pi;

namespace {
CylindricalFrame smallFrame()
{
  return CylindricalFrame(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::UnitZ(), 0, 90, 64, 10);
}
} // namespace

TEST(RangeMap, BilinearAcrossTheThetaSeam)
{
  const CylindricalFrame frame = smallFrame();
  RangeMap map(frame);
  // A field that is not periodic-smooth at the seam, so wrapping errors show.
  for (int j = 0; j < map.nZ(); ++j)
    for (int i = 0; i < map.nTheta(); ++i)
      map.at(i, j) = static_cast<float>(50.0 + 0.5 * i + 2.0 * j);
  const int last = map.nTheta() - 1;
  for (double f : {0.0, 0.25, 0.5, 0.9})
    for (double g : {0.0, 0.3, 1.0})
    {
      const int j = 4;
      const double expected = (1 - g) * ((1 - f) * map.at(last, j) + f * map.at(0, j)) +
                              g * ((1 - f) * map.at(last, j + 1) + f * map.at(0, j + 1));
      EXPECT_NEAR(map.sampleIndex(last + f, j + g), expected, 1e-4) << f << " " << g;
      const double theta = frame.indexToTheta(last) + f * frame.thetaStep(); // passes π
      const double z = frame.indexToZ(j + g);
      EXPECT_NEAR(map.sample(theta, z), expected, 1e-4);
      EXPECT_NEAR(map.sample(theta - 2 * pi, z), expected, 1e-4);
      EXPECT_NEAR(map.sample(theta + 4 * pi, z), expected, 1e-4);
    }
  // Negative u wraps too; the last row is reachable, beyond it is NaN.
  EXPECT_NEAR(map.sampleIndex(-0.5, 2), map.sampleIndex(last + 0.5, 2), 1e-5);
  EXPECT_NEAR(map.sampleIndex(3, map.nZ() - 1), map.at(3, map.nZ() - 1), 1e-5);
  EXPECT_TRUE(std::isnan(map.sampleIndex(3, map.nZ() - 0.99)));
  EXPECT_TRUE(std::isnan(map.sample(0.0, -0.01)));
}

TEST(RangeMap, NextToANaN)
{
  RangeMap map(smallFrame(), 10.0f);
  map.at(5, 5) = RangeMap::quietNaN();
  map.at(6, 5) = 20.0f;
  EXPECT_TRUE(std::isnan(map.sampleIndex(5, 5)));    // on the hole
  EXPECT_NEAR(map.sampleIndex(6, 5), 20.0, 1e-6);    // on a sample next to it
  EXPECT_NEAR(map.sampleIndex(5.75, 5), 20.0, 1e-6); // only 6 carries weight there
  EXPECT_NEAR(map.sampleIndex(5.5, 5), 20.0, 1e-6);  // half the weight is enough
  EXPECT_TRUE(std::isnan(map.sampleIndex(5.25, 5))); // the hole dominates
  EXPECT_NEAR(map.sampleIndex(5.5, 5.5), (20.0 * 0.25 + 10.0 * 0.5) / 0.75, 1e-5);
  EXPECT_EQ(map.validCount(), map.values().size() - 1);
}

TEST(RangeMap, BoxSmoothingOfAConstantIsTheConstantAndWraps)
{
  RangeMap constant(smallFrame(), 42.5f);
  constant.at(0, 0) = constant.at(63, 4) = RangeMap::quietNaN();
  const RangeMap smooth = boxSmooth(constant);
  for (int j = 0; j < smooth.nZ(); ++j)
    for (int i = 0; i < smooth.nTheta(); ++i)
      if (std::isfinite(constant.at(i, j)))
        EXPECT_FLOAT_EQ(smooth.at(i, j), 42.5f);
      else
        EXPECT_TRUE(std::isnan(smooth.at(i, j)));
  // A cosine around θ: the 3-tap mean multiplies it by (1 + 2 cos Δθ)/3,
  // at the seam columns too; a linear function of z is kept in inner rows.
  RangeMap wave(smallFrame());
  const double dt = wave.frame().thetaStep();
  for (int j = 0; j < wave.nZ(); ++j)
    for (int i = 0; i < wave.nTheta(); ++i)
      wave.at(i, j) = static_cast<float>(60.0 + 5.0 * std::cos(wave.frame().indexToTheta(i)) + 0.3 * j);
  const RangeMap s = boxSmooth(wave);
  const double factor = (1 + 2 * std::cos(dt)) / 3;
  for (int i : {0, 1, 31, 62, 63})
    EXPECT_NEAR(s.at(i, 4), 60.0 + 5.0 * factor * std::cos(wave.frame().indexToTheta(i)) + 0.3 * 4, 1e-4) << i;
}

TEST(RangeMap, OutwardNormalOfACone)
{
  // r = 40 + 0.5 z: a cone whose outward normal is (e_r - 0.5 â)/|.|.
  RangeMap cone(CylindricalFrame(Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(0.2, 0.1, 1), 0, 50, 128, 26));
  for (int j = 0; j < cone.nZ(); ++j)
    for (int i = 0; i < cone.nTheta(); ++i)
      cone.at(i, j) = static_cast<float>(40.0 + 0.5 * cone.frame().indexToZ(j));
  for (int i : {0, 32, 127})
    for (int j : {0, 10, 25})
    {
      const Eigen::Vector3d expected =
        (cone.frame().radialDirection(cone.frame().indexToTheta(i)) - 0.5 * cone.frame().direction()).normalized();
      EXPECT_LT((cone.outwardNormal(i, j) - expected).norm(), 1e-5);
    }
}

TEST(RangeMapFromPoints, BucketsKeepTheLargestRadius)
{
  const CylindricalFrame frame = smallFrame(); // Δθ = 2π/64, Δz = 10 mm
  std::vector<Eigen::Vector3d> points;
  points.push_back(frame.toWorld(30, frame.indexToTheta(8) + 0.4 * frame.thetaStep(), 42));
  points.push_back(frame.toWorld(35, frame.indexToTheta(8) - 0.4 * frame.thetaStep(), 38)); // same bucket, larger
  points.push_back(frame.toWorld(20, frame.indexToTheta(8), 40));                           // same bucket, smaller
  points.push_back(frame.toWorld(50, pi - 0.3 * frame.thetaStep(), 0));                     // wraps to column 0
  points.push_back(frame.toWorld(60, 0.0, 95.1));                                           // beyond zMax + Δz/2
  points.push_back(Eigen::Vector3d::Constant(std::nan("")));
  const RangeMap map = rangeMapFromPoints(frame, points);
  EXPECT_FLOAT_EQ(map.at(8, 4), 35.0f);
  EXPECT_FLOAT_EQ(map.at(0, 0), 50.0f);
  EXPECT_EQ(map.validCount(), 2u);

  // Dense points on a cylinder of radius 70 and on an inner one of radius 40:
  // every bucket holds the outer radius (the "outer surface" of §3.2.7).
  std::mt19937 random(11);
  std::uniform_real_distribution<double> t(-pi, pi), z(-5, 95);
  std::vector<Eigen::Vector3d> cloud;
  for (int n = 0; n < 40000; ++n)
  {
    cloud.push_back(frame.toWorld(70, t(random), z(random)));
    cloud.push_back(frame.toWorld(40, t(random), z(random)));
  }
  const RangeMap dense = rangeMapFromPoints(frame, cloud);
  EXPECT_EQ(dense.validCount(), dense.values().size());
  for (float r : dense.values())
    EXPECT_NEAR(r, 70.0, 1e-4);
}
