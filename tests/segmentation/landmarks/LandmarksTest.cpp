// Thickness at landmarks on concentric spheres (known radial and normal
// thickness), and the landmark table's CSV round trip.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include <gtest/gtest.h>

#include "LandmarkPhantoms.h"
#include "segmentation/Landmarks.h"
#include "segmentation/Thickness.h"

namespace caps::seg::test {
namespace {

std::filesystem::path scratch(const std::string& name)
{
  const auto dir = std::filesystem::temp_directory_path() / ("caps-landmarks-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir / name;
}

struct SphereMaps
{
  RangeMap skin, bone, radial, normal;
  SphereMaps()
    : skin(fillMap(ConcentricSpheres::frame(), ConcentricSpheres::skin)),
      bone(fillMap(ConcentricSpheres::frame(), ConcentricSpheres::bone)), radial(radialThickness(skin, bone)),
      normal(normalThickness(skin, bone))
  {}
};

const SphereMaps& sphereMaps()
{
  static const SphereMaps maps;
  return maps;
}

std::vector<Landmark> someLandmarks()
{
  return {{"nasion", -kPi / 2, 40.0},    {"pronasale", -kPi / 2, 0.3}, {"zygion_left", -0.4, 12.7},
          {"gonion_right", -2.9, -47.1}, {"seam", -kPi + 1e-4, -20.0}, {"high", 1.0, 60.0},
          {"beyond the scan", 0.0, 88.0}};
}

TEST(LandmarkThickness, MatchesTheAnalyticThicknessOfConcentricSpheres)
{
  const SphereMaps& m = sphereMaps();
  const auto table = landmarkThickness(someLandmarks(), m.skin, m.radial, m.normal);
  ASSERT_EQ(table.size(), someLandmarks().size());
  double worstRadial = 0, worstNormal = 0, worstPosition = 0;
  for (const auto& row : table)
  {
    const double z = row.landmark.z;
    if (std::abs(z) > 85.0)
    {
      EXPECT_TRUE(std::isnan(row.radial));
      EXPECT_TRUE(std::isnan(row.normal));
      EXPECT_TRUE(std::isnan(row.position.x()));
      continue;
    }
    const double radial = ConcentricSpheres::radial(z);
    std::printf("[ thickness] %-13s z %6.1f: radial %.4f (analytic %.4f), normal %.4f (10)\n",
                row.landmark.name.c_str(), z, row.radial, radial, row.normal);
    worstRadial = std::max(worstRadial, std::abs(row.radial - radial));
    worstNormal = std::max(worstNormal, std::abs(row.normal - 10.0));
    // The skin point lies on the skin sphere, at the landmark's θ and z.
    worstPosition = std::max(worstPosition, std::abs(row.position.norm() - 90.0));
    EXPECT_NEAR(row.position.z(), z, 1e-9);
    EXPECT_NEAR(std::atan2(row.position.y(), row.position.x()), row.landmark.theta, 1e-9);
  }
  std::printf("[ thickness] worst error: radial %.2e mm, normal %.2e mm, skin point %.2e mm\n", worstRadial,
              worstNormal, worstPosition);
  // Bilinear reading of a map sampled every 1.34 mm in z: error h²|f''|/8 < 0.005 mm at |z| ≤ 60.
  EXPECT_LT(worstRadial, 0.01);
  EXPECT_LT(worstPosition, 0.01);
  // Normal thickness: the march and bisection against the bilinear bone map.
  EXPECT_LT(worstNormal, 0.05);
}

TEST(LandmarkThickness, EmptyMapsGiveNaNColumnsAndOtherGridsAreRefused)
{
  const SphereMaps& m = sphereMaps();
  const auto table = landmarkThickness(someLandmarks(), m.skin, RangeMap(), RangeMap());
  EXPECT_TRUE(std::isnan(table[0].radial));
  EXPECT_TRUE(std::isnan(table[0].normal));
  EXPECT_NEAR(table[0].position.norm(), 90.0, 0.01);
  const RangeMap other(m.skin.frame().withGrid(128, 64), 1.0f);
  EXPECT_THROW(landmarkThickness(someLandmarks(), m.skin, other, RangeMap()), std::invalid_argument);
}

TEST(LandmarkCsv, RoundTripsExactly)
{
  const SphereMaps& m = sphereMaps();
  auto table = landmarkThickness(someLandmarks(), m.skin, m.radial, m.normal);
  ASSERT_GE(table.size(), 2u);
  table[0].ctSkinNormal = 6.25;
  table[0].ctNearestBone = 5.0 / 3.0;
  table[0].depth = 6.25;
  table[0].convention = "perpendicular to the skin";
  table[0].note = "in the streaks of metal";
  table[1].ctNearestBone = 0.1;
  const auto path = scratch("landmarks.csv");
  writeLandmarkCsv(path, table);
  {
    std::ifstream in(path);
    std::string header;
    std::getline(in, header);
    EXPECT_EQ(header, "name,theta_deg,z_mm,x,y,z,radial_mm,normal_mm,ct_skin_normal_mm,ct_nearest_bone_mm,depth_mm,"
                      "convention,note");
  }
  const auto back = readLandmarkCsv(path);
  ASSERT_EQ(back.size(), table.size());
  auto same = [](double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; };
  for (std::size_t k = 0; k < table.size(); ++k)
  {
    EXPECT_EQ(back[k].landmark.name, table[k].landmark.name);
    // θ goes through degrees: equal to rounding.
    EXPECT_NEAR(back[k].landmark.theta, table[k].landmark.theta, 1e-14);
    EXPECT_EQ(back[k].landmark.z, table[k].landmark.z);
    for (int c = 0; c < 3; ++c)
      EXPECT_TRUE(same(back[k].position[c], table[k].position[c])) << k << " " << c;
    EXPECT_TRUE(same(back[k].radial, table[k].radial)) << k;
    EXPECT_TRUE(same(back[k].normal, table[k].normal)) << k;
    EXPECT_TRUE(same(back[k].ctSkinNormal, table[k].ctSkinNormal)) << k;
    EXPECT_TRUE(same(back[k].ctNearestBone, table[k].ctNearestBone)) << k;
    EXPECT_TRUE(same(back[k].depth, table[k].depth)) << k;
    EXPECT_EQ(back[k].convention, table[k].convention) << k;
    EXPECT_EQ(back[k].note, table[k].note) << k;
  }
  std::filesystem::remove_all(path.parent_path());
}

TEST(LandmarkCsv, ReportsTheLineOfAProblemAndRefusesBadNames)
{
  const auto path = scratch("edited.csv");
  auto writeText = [&path](const std::string& text) { std::ofstream(path) << text; };
  const std::string header = "name,theta_deg,z_mm,x,y,z,radial_mm,normal_mm\n";

  // A person's edit: moved a landmark, blank line, spaces, nan, CRLF.
  writeText(header + "nasion, -90 ,40,,,,nan,\r\n\nchin,-90,-60.5,1,2,3,11.5,10\n");
  const auto rows = readLandmarkCsv(path);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_NEAR(rows[0].landmark.theta, -kPi / 2, 1e-15);
  EXPECT_TRUE(std::isnan(rows[0].radial));
  EXPECT_EQ(rows[1].landmark.z, -60.5);
  EXPECT_EQ(rows[1].radial, 11.5);

  writeText(header + "nasion,-90,40,,,,,\nchin,-90,abc,,,,,\n");
  try
  {
    readLandmarkCsv(path);
    FAIL() << "no exception";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
  }
  writeText("name,theta,z\n");
  EXPECT_THROW(readLandmarkCsv(path), std::runtime_error);
  writeText(header + "chin,-90,,,,,,\n");
  EXPECT_THROW(readLandmarkCsv(path), std::runtime_error);
  writeText(header + "chin,-90,1,2\n");
  EXPECT_THROW(readLandmarkCsv(path), std::runtime_error);
  EXPECT_THROW(readLandmarkCsv(path.parent_path() / "missing.csv"), std::runtime_error);

  LandmarkThickness bad;
  bad.landmark = {"chin, soft tissue", -kPi / 2, 0.0};
  EXPECT_THROW(writeLandmarkCsv(path, {bad}), std::invalid_argument);
  bad.landmark.name = "chin";
  bad.convention = "perpendicular, to the skin";
  EXPECT_THROW(writeLandmarkCsv(path, {bad}), std::invalid_argument);
  // The full header wants its 13 fields on every row.
  writeText("name,theta_deg,z_mm,x,y,z,radial_mm,normal_mm,ct_skin_normal_mm,ct_nearest_bone_mm,depth_mm,convention,"
            "note\nchin,-90,1,,,,,,\n");
  EXPECT_THROW(readLandmarkCsv(path), std::runtime_error);
  std::filesystem::remove_all(path.parent_path());
}

} // namespace
} // namespace caps::seg::test
