// The thickness review's readings (ThicknessReview) on maps whose values are
// known in closed form: a skin cylinder that widens linearly up the axis
// around a bone cylinder, so the radial thickness is 10 + 0.1 z mm and
// bilinear reading (eq. 4.9) is exact.

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include <gtest/gtest.h>
#include <vtkDoubleArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>

#include "modules/rangemap/ThicknessReview.h"
#include "segmentation/CylindricalFrame.h"

namespace {

constexpr double kPi = std::numbers::pi;

double skinRadius(double z)
{
  return 80.0 + 0.1 * z;
}
constexpr double kBoneRadius = 70.0;

caps::ThicknessReview makeReview(caps::seg::CylindricalFrame& frame)
{
  // A tilted axis, so nothing depends on the axis being the world's z.
  frame = caps::seg::CylindricalFrame(Eigen::Vector3d(3, -4, 20), Eigen::Vector3d(0.1, 0.2, 1.0), -50, 50, 128, 51);
  caps::seg::RangeMap skin(frame), bone(frame), thickness(frame), normal(frame);
  for (int j = 0; j < frame.nZ(); ++j)
    for (int i = 0; i < frame.nTheta(); ++i)
    {
      const double z = frame.indexToZ(j);
      skin.at(i, j) = float(skinRadius(z));
      bone.at(i, j) = float(kBoneRadius);
      thickness.at(i, j) = float(skinRadius(z) - kBoneRadius);
      normal.at(i, j) = float(0.99 * (skinRadius(z) - kBoneRadius));
    }
  return caps::ThicknessReview(skin, bone, thickness, normal);
}

TEST(ThicknessReview, ProbeReadsTheMapsAndFindsTheSkinPoint)
{
  caps::seg::CylindricalFrame frame;
  const caps::ThicknessReview review = makeReview(frame);
  for (double theta : {-kPi / 2, -2.0, 0.3, 3.0})
    for (double z : {-47.3, 0.0, 12.6})
    {
      const caps::ThicknessProbe p = review.probe(theta, z);
      EXPECT_NEAR(p.skinRadius, skinRadius(z), 1e-4);
      EXPECT_NEAR(p.boneRadius, kBoneRadius, 1e-4);
      EXPECT_NEAR(p.thickness, skinRadius(z) - kBoneRadius, 1e-4);
      EXPECT_NEAR(p.thicknessNormal, 0.99 * (skinRadius(z) - kBoneRadius), 1e-4);
      const Eigen::Vector3d expected = frame.toWorld(skinRadius(z), theta, z);
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(p.skinPoint[size_t(k)], expected[k], 1e-3);
      // And back: the chart point of that skin point.
      const auto chart = review.chartOf(p.skinPoint);
      EXPECT_NEAR(std::remainder(chart[0] - theta, 2 * kPi), 0.0, 1e-9);
      EXPECT_NEAR(chart[1], z, 1e-9);
    }
  // Off the maps (beyond zMax) there is nothing to read.
  const caps::ThicknessProbe off = review.probe(0.0, 80.0);
  EXPECT_TRUE(std::isnan(off.thickness));
  EXPECT_TRUE(std::isnan(off.skinPoint[0]));
}

TEST(ThicknessReview, PaintedSkinCarriesTheThicknessUnderEachVertex)
{
  caps::seg::CylindricalFrame frame;
  const caps::ThicknessReview review = makeReview(frame);
  auto points = vtkSmartPointer<vtkPoints>::New();
  std::vector<double> expected;
  for (double theta = -3.0; theta < 3.1; theta += 0.37)
    for (double z = -45.0; z <= 45.0; z += 7.5)
    {
      const Eigen::Vector3d p = frame.toWorld(skinRadius(z), theta, z);
      points->InsertNextPoint(p.data());
      expected.push_back(skinRadius(z) - kBoneRadius);
    }
  const Eigen::Vector3d above = frame.toWorld(80.0, 0.0, 70.0); // off the maps
  points->InsertNextPoint(above.data());
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  surface->SetPoints(points);
  const auto painted = review.paintThickness(surface);
  auto* values = vtkDoubleArray::SafeDownCast(painted->GetPointData()->GetArray("thickness_mm"));
  ASSERT_NE(values, nullptr);
  ASSERT_EQ(values->GetNumberOfTuples(), points->GetNumberOfPoints());
  for (std::size_t k = 0; k < expected.size(); ++k)
    EXPECT_NEAR(values->GetValue(vtkIdType(k)), expected[k], 1e-4) << k;
  EXPECT_TRUE(std::isnan(values->GetValue(vtkIdType(expected.size()))));
  // The source surface is left as it was.
  EXPECT_EQ(surface->GetPointData()->GetArray("thickness_mm"), nullptr);
}

TEST(ThicknessReview, FaceHistogramCountsTheFaceByTheMeasureShown)
{
  caps::seg::CylindricalFrame frame;
  caps::ThicknessReview review = makeReview(frame);
  // Thickness 10 + 0.1 z (normal: 0.99 times it): rows z_j = -50 + 2 j; the
  // face's columns lie within 75° of the front (θ = -90°), not the ears.
  int faceColumns = 0;
  for (int i = 0; i < frame.nTheta(); ++i)
    faceColumns += std::abs(std::remainder(frame.indexToTheta(i) + kPi / 2, 2 * kPi)) <= 75.0 * kPi / 180.0;
  ASSERT_GT(faceColumns, 0);
  ASSERT_LT(faceColumns, frame.nTheta() / 2);
  auto expected = [&](double scale, double zLow, double zHigh) {
    std::vector<int> counts(12, 0);
    for (int j = 0; j < frame.nZ(); ++j)
    {
      const double z = frame.indexToZ(j);
      if (z < zLow || z > zHigh)
        continue;
      const double t = scale * (10.0 + 0.1 * z);
      counts[std::min<size_t>(size_t(std::floor(float(t) + 1e-6)), counts.size() - 1)] += faceColumns;
    }
    return counts;
  };
  EXPECT_EQ(review.faceHistogram(1.0, 12), expected(1.0, -1e9, 1e9));
  EXPECT_EQ(review.faceHistogram(1.0, 12, caps::ThicknessMeasure::AlongNormal), expected(0.99, -1e9, 1e9));
  // Only the face's rows once they are known (the landmarks' span).
  review.setFaceRows(-20.0, 30.0);
  EXPECT_EQ(review.faceHistogram(1.0, 12), expected(1.0, -20.0, 30.0));
}

// Skin in the slices metal's streaks spoil is no measurement: it is left out
// of the histogram and painted with no thickness, marked as such.
TEST(ThicknessReview, SkinInMetalStreaksIsLeftOutOfTheHistogramAndThePaint)
{
  caps::seg::CylindricalFrame frame;
  caps::ThicknessReview review = makeReview(frame);
  const std::vector<int> whole = review.faceHistogram(1.0, 12);
  // Spoiled: the skin from z = 10 to 20 along the axis (rows 30 to 35).
  review.setSpoiled([&frame](const Eigen::Vector3d& p) {
    const double z = frame.toCylindrical(p).z;
    return z >= 9.999 && z <= 20.001;
  });
  const std::vector<int> sound = review.faceHistogram(1.0, 12);
  // Thickness 10 + 0.1 z: rows z = 10 .. 20 hold 11 to 12 mm (bins 11 and 12's).
  int faceColumns = 0;
  for (int i = 0; i < frame.nTheta(); ++i)
    faceColumns += std::abs(std::remainder(frame.indexToTheta(i) + kPi / 2, 2 * kPi)) <= 75.0 * kPi / 180.0;
  std::vector<int> expected = whole;
  for (double z = 10.0; z <= 20.0; z += 2.0)
    expected[std::min<size_t>(size_t(std::floor(float(10.0 + 0.1 * z) + 1e-6)), expected.size() - 1)] -= faceColumns;
  EXPECT_EQ(sound, expected);
  // The map's samples in the band: 6 rows all round (the map view hatches them).
  const std::vector<unsigned char> spoiled = review.spoiledSamples();
  ASSERT_EQ(spoiled.size(), std::size_t(frame.nTheta() * frame.nZ()));
  EXPECT_EQ(std::count(spoiled.begin(), spoiled.end(), 1), 6 * frame.nTheta());
  for (int i = 0; i < frame.nTheta(); ++i)
    EXPECT_EQ(spoiled[std::size_t(i + frame.nTheta() * 30)], 1);

  auto points = vtkSmartPointer<vtkPoints>::New();
  for (double z : {0.0, 15.0, 30.0})
    points->InsertNextPoint(frame.toWorld(skinRadius(z), -kPi / 2, z).data());
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  surface->SetPoints(points);
  const auto painted = review.paintThickness(surface);
  auto* values = vtkDoubleArray::SafeDownCast(painted->GetPointData()->GetArray("thickness_mm"));
  auto* streaks = painted->GetPointData()->GetArray("unreliable_skin");
  ASSERT_TRUE(values && streaks);
  EXPECT_NEAR(values->GetValue(0), skinRadius(0.0) - kBoneRadius, 1e-4);
  EXPECT_TRUE(std::isnan(values->GetValue(1)));
  EXPECT_NEAR(values->GetValue(2), skinRadius(30.0) - kBoneRadius, 1e-4);
  EXPECT_EQ(streaks->GetTuple1(0), 0.0);
  EXPECT_EQ(streaks->GetTuple1(1), 1.0);
  EXPECT_EQ(streaks->GetTuple1(2), 0.0);
}

// The test made from a CT's metal: true in the slices a piece's streaks
// spoil (5 mm either side of its own), false elsewhere; none without metal.
TEST(ThicknessReview, SpoiledByTheMetalOfACt)
{
  auto ct = vtkSmartPointer<vtkImageData>::New();
  ct->SetDimensions(20, 20, 60);
  ct->SetSpacing(1.0, 1.0, 1.0);
  ct->SetOrigin(0.0, 0.0, 0.0);
  ct->AllocateScalars(VTK_SHORT, 1);
  auto* v = static_cast<short*>(ct->GetScalarPointer());
  for (int k = 0; k < 60; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i)
        v[i + 20 * (j + 20 * k)] =
          (std::abs(i - 10) <= 1 && std::abs(j - 10) <= 1 && std::abs(k - 30) <= 1) ? 3071 : 40;
  const auto metal = caps::seg::findMetal(ct);
  ASSERT_EQ(metal.size(), 1u);
  const auto spoiled = caps::ThicknessReview::spoiledBy(metal, ct);
  ASSERT_TRUE(bool(spoiled));
  EXPECT_TRUE(spoiled(Eigen::Vector3d(2.0, 3.0, 30.0)));
  EXPECT_TRUE(spoiled(Eigen::Vector3d(2.0, 3.0, 34.0)));
  EXPECT_FALSE(spoiled(Eigen::Vector3d(2.0, 3.0, 40.0)));
  EXPECT_FALSE(spoiled(Eigen::Vector3d(2.0, 3.0, 10.0)));
  EXPECT_FALSE(bool(caps::ThicknessReview::spoiledBy({}, ct)));

  // Joined with another test (skin against the head holder): either marks.
  const auto below = [](const Eigen::Vector3d& p) { return p.z() < 5.0; };
  const auto either = caps::ThicknessReview::eitherOf(spoiled, below);
  EXPECT_TRUE(either(Eigen::Vector3d(2.0, 3.0, 30.0)));
  EXPECT_TRUE(either(Eigen::Vector3d(2.0, 3.0, 2.0)));
  EXPECT_FALSE(either(Eigen::Vector3d(2.0, 3.0, 10.0)));
  EXPECT_TRUE(caps::ThicknessReview::eitherOf({}, below)(Eigen::Vector3d(0.0, 0.0, 0.0)));
  EXPECT_FALSE(bool(caps::ThicknessReview::eitherOf({}, {})));
}

TEST(ThicknessReview, TheSkinIsPaintedWithTheMeasureShown)
{
  caps::seg::CylindricalFrame frame;
  const caps::ThicknessReview review = makeReview(frame);
  auto points = vtkSmartPointer<vtkPoints>::New();
  const Eigen::Vector3d p = frame.toWorld(skinRadius(12.0), -1.0, 12.0);
  points->InsertNextPoint(p.data());
  auto surface = vtkSmartPointer<vtkPolyData>::New();
  surface->SetPoints(points);
  for (const auto measure : {caps::ThicknessMeasure::Radial, caps::ThicknessMeasure::AlongNormal})
  {
    const auto painted = review.paintThickness(surface, measure);
    auto* values = vtkDoubleArray::SafeDownCast(painted->GetPointData()->GetArray("thickness_mm"));
    ASSERT_NE(values, nullptr);
    const double radial = skinRadius(12.0) - kBoneRadius;
    EXPECT_NEAR(values->GetValue(0), measure == caps::ThicknessMeasure::Radial ? radial : 0.99 * radial, 1e-4);
  }
  // Without a normal map the normal measure falls back on the radial one.
  const caps::ThicknessReview radialOnly(review.skin(), review.bone(), review.thickness(), caps::seg::RangeMap());
  EXPECT_EQ(&radialOnly.thicknessMap(caps::ThicknessMeasure::AlongNormal), &radialOnly.thickness());
}

TEST(ThicknessReview, LandmarksCsvHasOneRowPerLandmarkWithItsThickness)
{
  caps::seg::CylindricalFrame frame;
  const caps::ThicknessReview review = makeReview(frame);
  const Eigen::Vector3d nasion = frame.toWorld(skinRadius(30.0), -kPi / 2, 30.0);
  std::vector<caps::LandmarksNode::Landmark> landmarks{{"nasion", {nasion.x(), nasion.y(), nasion.z()}},
                                                       {"far, \"away\"", {0.0, 0.0, 500.0}}};
  std::istringstream csv(review.landmarksCsv(landmarks));
  std::string header, first, second;
  std::getline(csv, header);
  std::getline(csv, first);
  std::getline(csv, second);
  EXPECT_EQ(header.rfind("name,x_mm,y_mm,z_mm,theta_deg,axis_z_mm", 0), 0u) << header;
  // nasion,x,y,z,-90.00,30.00,83.00,70.00,13.00,12.87
  EXPECT_NE(first.find("nasion,"), std::string::npos);
  EXPECT_NE(first.find(",-90.00,30.00,83.00,70.00,13.00,12.87"), std::string::npos) << first;
  // A name with a comma and quotes is quoted; off the maps the readings are empty.
  EXPECT_EQ(second.rfind("\"far, \"\"away\"\"\",", 0), 0u) << second;
  EXPECT_EQ(second.substr(second.size() - 4), ",,,,") << second;

  // With the depths measured in the CT: the depth, how, and what spoils it.
  std::istringstream measured(review.landmarksCsv(
    landmarks, {{12.345, "perpendicular to the skin", ""}, {std::nan(""), "", "in the streaks, check it"}}));
  std::getline(measured, header);
  std::getline(measured, first);
  std::getline(measured, second);
  EXPECT_NE(header.find(",depth_mm,convention,note"), std::string::npos) << header;
  EXPECT_NE(first.find(",12.87,12.35,perpendicular to the skin,"), std::string::npos) << first;
  EXPECT_EQ(second.substr(second.size() - 29), ",,,\"in the streaks, check it\"") << second; // quoted: a comma
  EXPECT_THROW(review.landmarksCsv(landmarks, {{}}), std::invalid_argument);
}

// The ruler's distances: both ends and the length (a 3-4-12 box's diagonal is 13).
TEST(ThicknessReview, DistancesCsvHasBothEndsAndTheLength)
{
  std::istringstream csv(caps::ThicknessReview::distancesCsv({{"Ruler 1", {1, 2, 3}, {4, 6, 15}}}));
  std::string header, row;
  std::getline(csv, header);
  std::getline(csv, row);
  EXPECT_EQ(header, "name,from_x_mm,from_y_mm,from_z_mm,to_x_mm,to_y_mm,to_z_mm,length_mm");
  EXPECT_EQ(row, "Ruler 1,1.00,2.00,3.00,4.00,6.00,15.00,13.00");
}

// The profile along a line on the skin, against the cylinder's closed form:
// up the axis the skin is a straight line of slope 0.1 (r = 80 + 0.1 z), so
// its length is dz·√1.01 and the thickness grows by 0.1 mm per mm of z;
// round the axis it is an arc r·dθ of constant thickness.
TEST(ThicknessReview, ProfileAlongALineOnTheSkinFollowsTheClosedForm)
{
  caps::seg::CylindricalFrame frame;
  const caps::ThicknessReview review = makeReview(frame);
  const auto up = review.profile({0.4, -30.0}, {0.4, 40.0}, caps::ThicknessMeasure::Radial, 0.5);
  ASSERT_GE(up.along.size(), 140u); // a sample every half millimetre of skin or finer
  EXPECT_NEAR(up.along.back(), 70.0 * std::sqrt(1.01), 1e-3);
  for (std::size_t k = 0; k < up.along.size(); ++k)
  {
    const double z = up.chart[k][1];
    EXPECT_NEAR(up.thickness[k], skinRadius(z) - kBoneRadius, 1e-4);
    EXPECT_NEAR(up.along[k], (z + 30.0) * std::sqrt(1.01), 1e-3);
    const Eigen::Vector3d skin = frame.toWorld(skinRadius(z), 0.4, z);
    EXPECT_NEAR(up.skin[k][0], skin.x(), 1e-3);
  }
  // Along the normal: the normal map's values (0.99 of the radial here).
  const auto normal = review.profile({0.4, -30.0}, {0.4, 40.0}, caps::ThicknessMeasure::AlongNormal, 0.5);
  EXPECT_NEAR(normal.thickness.back(), 0.99 * (skinRadius(40.0) - kBoneRadius), 1e-4);

  // Round the axis, the shorter way: from θ = 3 to θ = −3 crosses the seam
  // (0.283 rad), not the face (6 rad).
  const double dTheta = 2 * kPi - 6.0;
  const auto round = review.profile({3.0, 10.0}, {-3.0, 10.0}, caps::ThicknessMeasure::Radial, 0.5);
  EXPECT_NEAR(round.along.back(), skinRadius(10.0) * dTheta, 1e-3 * skinRadius(10.0) * dTheta);
  for (double t : round.thickness)
    EXPECT_NEAR(t, 11.0, 1e-4);

  // A line that leaves the maps (z above 50) has no thickness there, and
  // its length counts only the skin it crosses.
  const auto off = review.profile({0.0, 30.0}, {0.0, 70.0}, caps::ThicknessMeasure::Radial, 0.5);
  EXPECT_TRUE(std::isnan(off.thickness.back()));
  EXPECT_NEAR(off.along.back(), 20.0 * std::sqrt(1.01), 0.5);
  EXPECT_THROW(review.profile({0.0, 60.0}, {1.0, 80.0}, caps::ThicknessMeasure::Radial), std::invalid_argument);
}

} // namespace
