// The whole thickness-review chain on a head CT with a face (FacePhantom.h):
// segmentation, range maps on the fitted axis, automatic landmark placement,
// and each landmark's depth measured in the CT by its published convention,
// against the analytic surfaces: every landmark within 2 mm of its true place
// and every depth within 0.3 mm (issue 22's targets).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include <gtest/gtest.h>
#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include "FacePhantom.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"
#include "segmentation/LandmarkDepth.h"
#include "segmentation/LandmarkPlacement.h"

namespace {

using caps::test::FacePhantom;
using Head = caps::test::FacePhantom::Head;
namespace st = caps::seg::test;

constexpr double kFront = -st::kPi / 2;

double profile(double z)
{
  return FacePhantom::skinRadius(kFront, z);
}

/// The z in [lo, hi] where sign · profile is largest (0.01 mm steps).
double profileExtremum(double lo, double hi, double sign)
{
  double best = lo;
  for (double z = lo; z <= hi; z += 0.01)
    if (sign * profile(z) > sign * profile(best))
      best = z;
  return best;
}

/// θ and z of the largest lateral extent r·|cos θ| of the bone for z in
/// [zLow, zHigh] and θ fromFront..toFront from the front on @a side.
std::pair<double, double> widestBone(double zLow, double zHigh, double fromFront, double toFront, int side)
{
  double best = -1, bestTheta = 0, bestZ = 0;
  for (double a = fromFront; a <= toFront; a += 0.05 * st::kDeg)
    for (double z = zLow; z <= zHigh; z += 0.05)
    {
      const double theta = kFront + side * a;
      const double w = FacePhantom::boneRadius(theta, z) * std::abs(std::cos(theta));
      if (w > best)
        best = w, bestTheta = theta, bestZ = z;
    }
  return {bestTheta, bestZ};
}

/// θ where the skin at height z is @a offset mm beside the midsagittal plane.
double besideTheMidline(double z, double offset, int side)
{
  double a = 0.0;
  while (FacePhantom::skinRadius(kFront + side * a, z) * std::abs(std::cos(kFront + side * a)) < offset)
    a += 1e-5;
  return kFront + side * a;
}

/// The z of the orbit's rim on the bone's column @a theta, above (@a
/// direction +1) or below the orbit, by LandmarkPlacement.h's rule on the
/// analytic bone: walking out from the orbit's middle, where the bone first
/// comes within 1 mm of the highest bone in the next 15 mm.
double orbitRim(double theta, int direction)
{
  const auto r = [theta](double z) { return FacePhantom::boneRadius(theta, z); };
  for (double z = Head::zOrbit;; z += direction * 0.001)
  {
    double highest = r(z);
    for (double d = 0.0; d <= 15.0; d += 0.05)
      highest = std::max(highest, r(z + direction * d));
    if (r(z) >= highest - 1.0)
      return z;
  }
}

/// Each standard landmark's true (θ, z) on the phantom, by the definition
/// LandmarkPlacement.h gives it, applied to the analytic profile.
std::map<std::string, std::pair<double, double>> trueLandmarks()
{
  std::map<std::string, std::pair<double, double>> truth;
  const double prn = profileExtremum(-5, 5, +1);
  const double nasion = profileExtremum(prn + 10, prn + 50, -1);
  const double glabella = profileExtremum(nasion + 0.01, nasion + 25, +1);
  const double subnasale = profileExtremum(prn - 22, prn - 10, -1);
  const double ls = profileExtremum(Head::zLabraleSuperius - 5, Head::zLabraleSuperius + 5, +1);
  const double li = profileExtremum(Head::zLabraleInferius - 5, Head::zLabraleInferius + 5, +1);
  const double pogonion = profileExtremum(Head::zPogonion - 6, Head::zPogonion + 6, +1);
  // Menton: the half-way crossing from the pogonion down to the jaw's
  // underside (the first z below the tip where the profile is under 60 %
  // of the tip's).
  double jaw = prn;
  while (profile(jaw) >= 0.6 * profile(prn))
    jaw -= 0.001;
  double menton = pogonion;
  while (profile(menton) >= 0.5 * (profile(pogonion) + profile(jaw)))
    menton -= 0.001;
  const double supraglabella = profileExtremum(glabella + 0.01, glabella + 25, -1);
  const double sublabiale = profileExtremum(pogonion + 0.01, li - 0.01, -1);
  for (const char* name :
       {"supraglabella", "glabella", "nasion", "mid_nasal", "rhinion", "pronasale", "subnasale", "mid_philtrum",
        "labrale_superius", "labrale_inferius", "sublabiale", "pogonion", "menton", "forehead"})
    truth[name].first = kFront;
  truth["supraglabella"].second = supraglabella;
  truth["rhinion"].second = Head::zRhinion;
  truth["mid_nasal"].second = 0.5 * (nasion + Head::zRhinion);
  truth["sublabiale"].second = sublabiale;
  truth["glabella"].second = glabella;
  truth["nasion"].second = nasion;
  truth["pronasale"].second = prn;
  truth["subnasale"].second = subnasale;
  truth["mid_philtrum"].second = 0.5 * (subnasale + ls);
  truth["labrale_superius"].second = ls;
  truth["labrale_inferius"].second = li;
  truth["pogonion"].second = pogonion;
  truth["menton"].second = menton;
  truth["forehead"].second = prn + 75.0;
  for (int side : {+1, -1})
  {
    const std::string suffix = side > 0 ? "_left" : "_right";
    truth["zygion" + suffix] = widestBone(prn, nasion, 25 * st::kDeg, 80 * st::kDeg, side);
    truth["gonion" + suffix] = widestBone(menton, subnasale, 30 * st::kDeg, 95 * st::kDeg, side);
    truth["mid_cheek" + suffix] = {besideTheMidline(prn, 32.0, side), prn};
    const double pupil = besideTheMidline(nasion - 5.0, 32.0, side);
    truth["supraorbital" + suffix] = {pupil, orbitRim(pupil, +1)};
    truth["infraorbital" + suffix] = {pupil, orbitRim(pupil, -1)};
  }
  return truth;
}

/// The Range maps module's run on @a ct in @a scene, at the phantom's
/// mid-level thresholds; the axis fitted, not given.
caps::RangeMapOutput runTheMaps(caps::Scene& scene, caps::RangeMapLogic& logic, vtkImageData* ct,
                                caps::VolumeNode*& volume)
{
  volume = scene.add<caps::VolumeNode>();
  volume->setImage(ct);
  caps::RangeMapLogic::Parameters parameters;
  parameters.skinThresholdHu = st::skinMidHu;
  parameters.boneThresholdHu = st::boneMidHu;
  caps::RangeMapOutput maps;
  logic.run(*volume, parameters, {}, &maps);
  return maps;
}

TEST(FaceLandmarks, EachIsPlacedWithin2MmOfItsPlaceAndItsDepthInTheCtIsWithin0p3Mm)
{
  const FacePhantom& phantom = FacePhantom::instance();
  caps::Scene scene;
  caps::RangeMapLogic logic(scene);
  caps::VolumeNode* volume = nullptr;
  const caps::RangeMapOutput maps = runTheMaps(scene, logic, phantom.images.ct, volume);

  const caps::seg::LandmarkPlacement placed = caps::seg::placeLandmarks(maps.skin, maps.bone);
  for (const std::string& warning : placed.warnings)
    ADD_FAILURE() << warning;
  ASSERT_EQ(placed.landmarks.size(), caps::seg::standardLandmarks().size());
  auto rows = caps::seg::landmarkThickness(placed.landmarks, maps.skin, maps.thickness, maps.thicknessNormal);
  ASSERT_TRUE(logic.measureLandmarkDepths(*volume, rows));

  const auto truth = trueLandmarks();
  double worstPlace = 0.0, worstDepth = 0.0;
  for (const caps::seg::LandmarkThickness& row : rows)
  {
    const std::string& name = row.landmark.name;
    ASSERT_TRUE(truth.count(name)) << name;
    const auto [theta, z] = truth.at(name);
    const double placeError = (row.position - phantom.skinPoint(theta, z)).norm();
    worstPlace = std::max(worstPlace, placeError);
    EXPECT_LT(placeError, 2.0) << name;

    // The analytic depth from the landmark's own skin point, by its convention.
    const auto [t, h] = phantom.nearestSkin(row.position);
    const Eigen::Vector3d onSkin = phantom.skinPoint(t, h);
    const caps::seg::DepthConvention convention = caps::seg::depthConventionOf(name);
    double expected = std::nan("");
    if (convention == caps::seg::DepthConvention::SkinNormal)
      expected = phantom.toBoneAlong(onSkin, -phantom.skinNormal(t, h));
    else if (convention == caps::seg::DepthConvention::NearestBone)
      expected = phantom.toNearestBone(onSkin);
    std::printf("[ face     ] %-17s %5.2f mm from its place; depth %6.2f mm, analytic %6.2f (%s)\n", name.c_str(),
                placeError, row.depth, expected, row.convention.c_str());
    if (convention == caps::seg::DepthConvention::NotADepth)
      continue;
    ASSERT_TRUE(std::isfinite(expected)) << name;
    EXPECT_EQ(row.convention, caps::seg::conventionName(convention)) << name;
    const double depthError = std::abs(row.depth - expected);
    // The rhinion is the nasal bones' end, a sharp edge here, which the CT's
    // point spread (0.6 mm) and 1.25 mm slices round off: the CT's bone there
    // lies up to about half a millimetre behind the edge. Everywhere else the
    // bone is smooth on the CT's scale.
    const double tolerance = name == "rhinion" ? 0.6 : 0.3;
    if (name != "rhinion")
      worstDepth = std::max(worstDepth, depthError);
    EXPECT_LT(depthError, tolerance) << name;
  }
  std::printf("[ face     ] worst: %.2f mm from a landmark's place, %.3f mm in a depth but the rhinion's (1 x 1 x "
              "1.25 mm voxels)\n",
              worstPlace, worstDepth);
}

// A cranium-only CT: the same head cut 25 mm above the nose tip (between the
// nasion and the glabella). No nose, lip or chin landmark is placed; each is
// listed as not in the scan, with why.
TEST(FaceLandmarks, ACtCutAboveTheNosePlacesNoFaceLandmark)
{
  const FacePhantom& phantom = FacePhantom::instance();
  vtkImageData* full = phantom.images.ct;
  int dims[3];
  full->GetDimensions(dims);
  double origin[3], spacing[3];
  full->GetOrigin(origin);
  full->GetSpacing(spacing);
  const int firstSlice = static_cast<int>(std::ceil((phantom.axis.z() + 25.0 - origin[2]) / spacing[2]));
  auto cranium = vtkSmartPointer<vtkImageData>::New();
  cranium->SetDimensions(dims[0], dims[1], dims[2] - firstSlice);
  cranium->SetSpacing(spacing);
  cranium->SetOrigin(origin[0], origin[1], origin[2] + firstSlice * spacing[2]);
  cranium->AllocateScalars(VTK_SHORT, 1);
  const std::size_t slice = static_cast<std::size_t>(dims[0]) * dims[1];
  std::copy_n(static_cast<short*>(full->GetScalarPointer()) + firstSlice * slice, (dims[2] - firstSlice) * slice,
              static_cast<short*>(cranium->GetScalarPointer()));

  caps::Scene scene;
  caps::RangeMapLogic logic(scene);
  caps::VolumeNode* volume = nullptr;
  const caps::RangeMapOutput maps = runTheMaps(scene, logic, cranium, volume);
  const caps::seg::LandmarkPlacement placed = caps::seg::placeLandmarks(maps.skin, maps.bone);
  std::printf("[ face     ] cut above the nose: %s\n", placed.features.noseMissing.c_str());
  for (const char* name : {"pronasale", "subnasale", "mid_philtrum", "labrale_superius", "labrale_inferius", "pogonion",
                           "menton", "gonion_left", "gonion_right", "mid_cheek_left", "mid_cheek_right"})
  {
    EXPECT_EQ(placed.find(name), nullptr) << name;
    for (const caps::seg::LandmarkStatus& status : placed.status)
      if (status.name == name)
      {
        EXPECT_EQ(status.state, caps::seg::LandmarkState::NotInScan) << name;
        EXPECT_FALSE(status.reason.empty()) << name;
      }
  }
  EXPECT_EQ(placed.status.size(), caps::seg::standardLandmarks().size());
}

} // namespace
