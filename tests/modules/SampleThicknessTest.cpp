// The sample head CT, headless, through the module logic a user drives: read,
// segment, range maps. Soft-tissue thickness over the forehead, the cheeks and
// the chin must lie in anatomically plausible ranges. One TEST: reading and
// segmenting the sample takes ~10 s, and each test runs in its own process.
//
// Where those places are is found from the maps themselves (the sample has
// no landmarks) by the library's automatic landmark placement
// (segmentation/LandmarkPlacement.h, which documents the rules), on the
// midline profile r_skin(z) at θ = -π/2 (the front of the face; median of the
// 7 columns around it):
// - nose tip (pronasale): the largest r of the profile in the upper two
//   thirds of the scan (below lie the neck and the shoulders);
// - forehead: 75 mm above the nose tip: above the nasion (34 mm above the
//   nose tip on the sample) and the glabella, below the hairline;
// - underside of the jaw: walking down from the nose tip, the first sample
//   whose r is below 60 % of the nose tip's;
// - chin (pogonion): the most anterior point (largest r) 5 to 25 mm above
//   the underside of the jaw (on the sample the lips and the chin are within
//   3 mm of the same r, so "the local maximum below the lips" is not stable);
// - cheeks: θ = -π/2 ± 50° (left and right) at the height of the nose tip:
//   over the maxilla below the zygoma. (Lower, at the height of the mouth,
//   the normal through the cheek meets no bone in the bone map on the sample:
//   the teeth and the thin maxillary wall leave holes there.)
// Thickness there is the median of the map over a small patch (±5° in θ,
// ±5 mm in z), radial (r_skin − r_bone along the ray from the axis) and
// along the inward skin normal.
//
// Expected ranges, generous around published means: De Greef et al. 2006,
// "Large-scale in-vivo Caucasian facial soft tissue thickness database for
// craniofacial reconstruction", Forensic Sci Int 159S:S126-S146 (ultrasound,
// 967 adults): glabella/mid-forehead ~5-6 mm, pogonion (chin) ~10-12 mm,
// mid-cheek and zygomatic region ~7-20 mm (larger at the mid-cheek). The CT's
// radial measure runs obliquely through the tissue where the surface is not
// perpendicular to the ray (the cheeks), so the radial ranges are wider:
//   forehead 3-10 mm, chin 6-18 mm, cheeks 5-30 mm (radial);
//   forehead 3-10 mm, chin 6-18 mm, cheeks 4-25 mm (normal).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "modules/rangemap/RangeMapLogic.h"
#include "modules/rangemap/RangeMapPreview.h"
#include "modules/segment/SegmentLogic.h"
#include "modules/volumes/VolumesLogic.h"
#include "segmentation/LandmarkPlacement.h"
#include "segmentation/Landmarks.h"
#include "scene/LabelMapNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"
#include "TestPaths.h"

namespace {

constexpr double kPi = std::numbers::pi;

double degrees(double radians)
{
  return radians * 180.0 / kPi;
}

// Row (θ sample) of the node nearest θ.
Eigen::Index rowOf(const caps::RangeMapNode& node, double theta)
{
  const Eigen::Index n = node.values().rows();
  const auto i = static_cast<Eigen::Index>(std::lround((theta + kPi) / (2 * kPi) * n));
  return ((i % n) + n) % n;
}

// Column (z sample) of the node nearest z, clamped.
Eigen::Index columnOf(const caps::RangeMapNode& node, double z)
{
  const Eigen::Index n = node.values().cols();
  const double u = (z - node.zMin()) / (node.zMax() - node.zMin()) * (n - 1);
  return std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::lround(u)), 0, n - 1);
}

// Median of the finite samples within θ0 ± dTheta, z0 ± dz; NaN if none.
double patchMedian(const caps::RangeMapNode& node, double theta0, double dTheta, double z0, double dz)
{
  std::vector<float> v;
  const Eigen::Index n = node.values().rows();
  const auto half = static_cast<Eigen::Index>(std::ceil(dTheta / (2 * kPi) * n));
  const Eigen::Index centre = rowOf(node, theta0);
  for (Eigen::Index j = columnOf(node, z0 - dz); j <= columnOf(node, z0 + dz); ++j)
    for (Eigen::Index d = -half; d <= half; ++d)
    {
      const float x = node.values()(((centre + d) % n + n) % n, j);
      if (std::isfinite(x))
        v.push_back(x);
    }
  if (v.empty())
    return std::nan("");
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

struct Place
{
  const char* name;
  double theta, z;
  double radialMin, radialMax, normalMin, normalMax;
};

} // namespace

TEST(SampleThickness, ForeheadCheeksAndChinArePlausible)
{
  caps::Scene scene;
  const auto t0 = std::chrono::steady_clock::now();
  auto seconds = [&t0]() { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  caps::VolumesLogic volumes(scene);
  std::vector<std::string> warnings;
  caps::VolumeNode* volume = volumes.load(caps::test::sampleCt(), {}, warnings);
  ASSERT_NE(volume, nullptr);
  std::printf("[ timing   ] read: %.1f s\n", seconds());

  caps::SegmentLogic segment(scene);
  const caps::SegmentationResult labels = segment.segment(*volume, {});
  std::printf("[ timing   ] segment (with display surfaces): %.1f s\n", seconds());
  for (const auto* id : {&labels.skinSurfaceId, &labels.boneSurfaceId})
  {
    auto* surface = scene.nodeAs<caps::SurfaceNode>(*id);
    ASSERT_NE(surface, nullptr);
    std::printf("[ surface  ] %s: %lld display triangles\n", surface->name().c_str(),
                static_cast<long long>(surface->polyData()->GetNumberOfPolys()));
    EXPECT_GT(surface->polyData()->GetNumberOfPolys(), 100000);
  }
  // Plausible volumes for a head and neck (litres): the sample's body is ~8.7 L.
  vtkImageData* labelImage = scene.nodeAs<caps::LabelMapNode>(labels.labelMapId)->image();
  EXPECT_GT(caps::SegmentLogic::volumeMm3(labelImage, 1), 4.0e6);
  EXPECT_LT(caps::SegmentLogic::volumeMm3(labelImage, 1), 14.0e6);
  EXPECT_GT(caps::SegmentLogic::volumeMm3(labelImage, 2), 0.3e6);

  caps::RangeMapLogic rangeMaps(scene);
  caps::RangeMapOutput output;
  const caps::RangeMapResult maps = rangeMaps.run(*volume, {}, {}, &output);
  std::printf("[ timing   ] range maps, radial and normal thickness: %.1f s\n", seconds());
  EXPECT_FALSE(maps.segmented);
  std::printf("%s", caps::RangeMapLogic::describeAxis(output.axis).c_str());
  // The axis is near patient superior (a head CT lies straight within ~15°).
  EXPECT_GT(output.axis.frame.direction().z(), std::cos(15.0 * kPi / 180.0));

  const auto& skin = *scene.nodeAs<caps::RangeMapNode>(maps.skinId);
  const auto& radial = *scene.nodeAs<caps::RangeMapNode>(maps.thicknessId);
  const auto& normal = *scene.nodeAs<caps::RangeMapNode>(maps.thicknessNormalId);
  ASSERT_EQ(skin.values().rows(), 512);
  ASSERT_EQ(skin.values().cols(), 256);

  // The landmarks, placed automatically from the skin and bone maps.
  const caps::seg::RangeMap skinMap = caps::RangeMapLogic::toRangeMap(skin);
  const caps::seg::RangeMap boneMap = caps::RangeMapLogic::toRangeMap(*scene.nodeAs<caps::RangeMapNode>(maps.boneId));
  const caps::seg::LandmarkPlacement placed = caps::seg::placeLandmarks(skinMap, boneMap);
  for (const auto& warning : placed.warnings)
    std::printf("[ landmark ] %s\n", warning.c_str());
  const caps::seg::ProfileFeatures& features = placed.features;
  const std::vector<double>& profile = features.profile;
  const double front = -kPi / 2;
  const Eigen::Index nose = features.pronasale;
  const Eigen::Index jaw = features.jawUnderside;
  const Eigen::Index chin = features.pogonion;
  ASSERT_GE(nose, 0);
  const double zNose = skin.zAt(nose);
  ASSERT_GE(jaw, 0) << "no underside of the jaw below the nose tip";
  // Print the profile from the chin to the forehead, for a person to check.
  const Eigen::Index first = columnOf(skin, zNose - 100);
  for (Eigen::Index j = first; j <= columnOf(skin, zNose + 90); ++j)
    if ((j - first) % 3 == 0 || j == nose || j == chin || j == jaw)
      std::printf("[ profile  ] z %7.1f mm  r %6.1f mm%s%s%s\n", skin.zAt(j), profile[j],
                  j == nose ? "  <- nose tip" : "", j == chin ? "  <- chin" : "", j == jaw ? "  <- under the jaw" : "");
  ASSERT_GE(chin, 0) << "no chin found below the nose tip";
  // How clearly the nose tip is a nose (seg::placeLandmarks refuses one that
  // stands less than 8 mm in front of the skin 20° beside it).
  const double beside = std::min(caps::seg::midlineProfile(skinMap, front - 20.0 * kPi / 180.0, 1)[nose],
                                 caps::seg::midlineProfile(skinMap, front + 20.0 * kPi / 180.0, 1)[nose]);
  std::printf("[ nose     ] the tip stands %.1f mm in front of the skin 20 deg beside it\n", profile[nose] - beside);
  EXPECT_GT(profile[nose] - beside, 8.0);
  const double zChin = skin.zAt(chin);
  // The nose tip lies in front of the chin, and the chin 30-110 mm under it.
  EXPECT_GT(profile[nose], profile[chin] + 5.0);
  EXPECT_GT(zNose - zChin, 30.0);
  EXPECT_LT(zNose - zChin, 110.0);

  // The same head scanned only from 15 mm above the nose tip up (a cranium
  // CT, orbits to vertex): no landmark of the nose, the lips, the chin or the
  // cheeks is placed, each is listed as not in the scan.
  {
    const caps::seg::CylindricalFrame& frame = skinMap.frame();
    const int cut = static_cast<int>(columnOf(skin, zNose + 15.0));
    const caps::seg::CylindricalFrame upper(frame.origin(), frame.direction(), frame.indexToZ(cut), frame.zMax(),
                                            frame.nTheta(), frame.nZ() - cut);
    auto crop = [&](const caps::seg::RangeMap& map) {
      caps::seg::RangeMap part(upper);
      for (int j = 0; j < upper.nZ(); ++j)
        for (int i = 0; i < upper.nTheta(); ++i)
          part.at(i, j) = map.at(i, j + cut);
      return part;
    };
    const caps::seg::LandmarkPlacement cranium = caps::seg::placeLandmarks(crop(skinMap), crop(boneMap));
    std::printf("[ cranium  ] scan from z %.1f mm: %s\n", upper.zMin(), cranium.features.noseMissing.c_str());
    for (const auto& status : cranium.status)
      if (status.name != "glabella" && status.name != "nasion" && status.name != "forehead")
      {
        EXPECT_EQ(cranium.find(status.name), nullptr) << status.name;
        EXPECT_EQ(status.state, caps::seg::LandmarkState::NotInScan) << status.name;
      }
  }

  const caps::seg::Landmark* forehead = placed.find("forehead");
  const caps::seg::Landmark* rightCheek = placed.find("mid_cheek_right");
  const caps::seg::Landmark* leftCheek = placed.find("mid_cheek_left");
  ASSERT_TRUE(forehead && rightCheek && leftCheek);
  const Place places[] = {
    {"forehead", forehead->theta, forehead->z, 3.0, 10.0, 3.0, 10.0},
    {"chin", front, zChin, 6.0, 18.0, 6.0, 18.0},
    {"right cheek", rightCheek->theta, rightCheek->z, 5.0, 30.0, 4.0, 25.0},
    {"left cheek", leftCheek->theta, leftCheek->z, 5.0, 30.0, 4.0, 25.0},
  };
  const double dTheta = 5.0 * kPi / 180.0, dz = 5.0;
  for (const Place& p : places)
  {
    const double r = patchMedian(radial, p.theta, dTheta, p.z, dz);
    const double n = patchMedian(normal, p.theta, dTheta, p.z, dz);
    std::printf("[ thickness] %-11s theta %6.1f deg, z %6.1f mm: radial %5.1f mm, normal %5.1f mm\n", p.name,
                degrees(p.theta), p.z, r, n);
    EXPECT_GE(r, p.radialMin) << p.name;
    EXPECT_LE(r, p.radialMax) << p.name;
    EXPECT_GE(n, p.normalMin) << p.name;
    EXPECT_LE(n, p.normalMax) << p.name;
  }

  // Pictures and the landmark table for a person: the thickness maps as the
  // command writes them, and every landmark placed with its thickness.
  const auto folder = caps::test::artifacts() / "modules";
  std::filesystem::create_directories(folder);
  auto table = caps::seg::landmarkThickness(placed.landmarks, skinMap, caps::RangeMapLogic::toRangeMap(radial),
                                            caps::RangeMapLogic::toRangeMap(normal));
  ASSERT_TRUE(rangeMaps.measureLandmarkDepths(*volume, table));
  int compared = 0;
  for (const auto& row : table)
  {
    std::printf("[ landmark ] %-17s theta %6.1f deg, z %6.1f mm: radial %5.1f mm, normal %5.1f mm; in the CT: "
                "normal %5.1f mm, nearest bone %5.1f mm, depth %5.1f mm %s\n",
                row.landmark.name.c_str(), degrees(row.landmark.theta), row.landmark.z, row.radial, row.normal,
                row.ctSkinNormal, row.ctNearestBone, row.depth, row.convention.c_str());
    // Every landmark but the nose tip (cartilage, no bone under it) has a
    // depth, and the nearest bone is never farther than the bone along the normal.
    if (row.landmark.name != "pronasale")
    {
      EXPECT_TRUE(std::isfinite(row.depth)) << row.landmark.name;
    }
    if (std::isfinite(row.ctSkinNormal))
    {
      EXPECT_LE(row.ctNearestBone, row.ctSkinNormal + 1e-9) << row.landmark.name;
    }
    // Two independent measures of the same thing: the normal thickness map
    // marches the map's normal to the bone map; the CT's marches the skin's
    // own normal through the CT. Over thick bone under thin tissue (forehead,
    // nasion, chin, zygia) they agree to 1 mm; deeper, over the maxilla's
    // thin oblique wall beside the nose, the two normals part by a few
    // degrees and the depths by up to 4 mm (there the map's normal depth
    // changes by 1 mm when the point moves 0.2 mm up: the map's normal is
    // the map's gradient on a 0.8 mm grid; the CT's depth stays within 0.2 mm).
    // Not over the nasal bones, a voxel or two thick: the bone map has holes
    // there, which the map's normal marches through (4.0 mm at the mid-nasal
    // point, where the CT's normal and nearest bone agree on 2.2 mm).
    const bool overNasalBones = row.landmark.name == "mid_nasal" || row.landmark.name == "rhinion";
    if (std::isfinite(row.normal) && std::isfinite(row.ctSkinNormal) && row.ctSkinNormal < 25.0 && !overNasalBones)
    {
      EXPECT_NEAR(row.ctSkinNormal, row.normal, row.ctSkinNormal < 12.0 ? 1.0 : 4.0) << row.landmark.name;
      compared += row.ctSkinNormal < 12.0;
    }
  }
  EXPECT_GE(compared, 6);
  caps::seg::writeLandmarkCsv(folder / "sample-landmarks.csv", table);
  caps::PreviewStyle style;
  style.title = "Sample CT: radial soft-tissue thickness";
  caps::writeRangeMapPreview(radial.values(), radial.zMin(), radial.zMax(), style, folder / "sample-thickness.png");
  style.title = "Sample CT: soft-tissue thickness along the skin normal";
  caps::writeRangeMapPreview(normal.values(), normal.zMin(), normal.zMax(), style,
                             folder / "sample-thickness-normal.png");
}
