#include "planning/FaceModel.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>

#include "planning/PlanSimulation.h"
#include "planning/SkinChart.h"

namespace caps::expression {
namespace {

constexpr double kPi = std::numbers::pi;

const seg::Landmark* findLandmark(const std::vector<seg::Landmark>& landmarks, const std::string& name)
{
  for (const seg::Landmark& l : landmarks)
    if (l.name == name)
      return &l;
  return nullptr;
}

/// θ wrapped into [θref − π, θref + π), so a region never splits at the seam.
double unwrapAbout(double theta, double reference)
{
  double t = theta;
  while (t < reference - kPi)
    t += 2.0 * kPi;
  while (t >= reference + kPi)
    t -= 2.0 * kPi;
  return t;
}

} // namespace

FaceRegion faceRegion(const std::vector<seg::Landmark>& landmarks, const seg::RangeMap& skin,
                      const FaceModelOptions& options)
{
  if (skin.empty())
    throw std::invalid_argument("the whole-face model needs the skin range map: make the range maps first");
  std::string missing;
  for (const char* name : {"zygion_right", "zygion_left", "menton", "forehead"})
    if (!findLandmark(landmarks, name))
    {
      missing += missing.empty() ? "" : ", ";
      missing += name;
    }
  if (!missing.empty())
    throw std::invalid_argument("the whole-face model is placed by the landmarks " + missing +
                                ", which are missing: place them (Thickness review) and try again");
  const seg::Landmark& right = *findLandmark(landmarks, "zygion_right");
  const seg::Landmark& left = *findLandmark(landmarks, "zygion_left");
  // The face's front lies between the zygia: the right one at smaller θ
  // (θ = -π/2 is the front, θ = 0 the patient's left).
  const double front = -0.5 * kPi;
  const double thetaRight = unwrapAbout(right.theta, front), thetaLeft = unwrapAbout(left.theta, front);
  if (!(thetaRight < front && front < thetaLeft))
    throw std::invalid_argument("the zygion landmarks are not on either side of the face (right at " +
                                std::to_string(int(std::lround(thetaRight * 180.0 / kPi))) + "°, left at " +
                                std::to_string(int(std::lround(thetaLeft * 180.0 / kPi))) +
                                "°): check them in the Thickness review");
  const seg::CylindricalFrame& frame = skin.frame();
  const auto radiusAt = [&](const seg::Landmark& l) {
    const double r = skin.sample(l.theta, l.z);
    return std::isfinite(r) && r > 0.0 ? r : 80.0;
  };
  FaceRegion region;
  region.thetaMin = thetaRight - options.lateralMargin / radiusAt(right);
  region.thetaMax = thetaLeft + options.lateralMargin / radiusAt(left);
  region.zMin = findLandmark(landmarks, "menton")->z - options.marginBelowMenton;
  region.zMax = findLandmark(landmarks, "forehead")->z + options.marginAboveForehead;

  // Keep to the rows with skin across the whole width (the scan's top and
  // bottom rows are often cut by the field of view).
  const int i0 = int(std::floor(frame.thetaToIndex(region.thetaMin)));
  const int i1 = int(std::ceil(frame.thetaToIndex(region.thetaMin) +
                               (region.thetaMax - region.thetaMin) / (2.0 * kPi) * frame.nTheta()));
  const auto rowMeasured = [&](int j) {
    int missingSamples = 0;
    for (int i = i0; i <= i1; ++i)
      if (!std::isfinite(skin.at(((i % frame.nTheta()) + frame.nTheta()) % frame.nTheta(), j)))
        ++missingSamples;
    return missingSamples * 10 < (i1 - i0 + 1); // a few holes are meshed around, not a missing row
  };
  int bottom = std::max(0, int(std::ceil(frame.zToIndex(region.zMin))));
  int top = std::min(frame.nZ() - 1, int(std::floor(frame.zToIndex(region.zMax))));
  while (bottom < top && !rowMeasured(bottom))
    ++bottom;
  while (top > bottom && !rowMeasured(top))
    --top;
  region.zMin = std::max(region.zMin, frame.indexToZ(bottom));
  region.zMax = std::min(region.zMax, frame.indexToZ(top));
  if (!(region.zMax - region.zMin > 20.0))
    throw std::invalid_argument("the skin map has too few rows of skin between the menton and the forehead "
                                "to mesh the face: check the range maps");
  return region;
}

FaceMesh meshFace(const seg::RangeMap& skin, const seg::RangeMap& bone, const std::vector<seg::Landmark>& landmarks,
                  const FaceModelOptions& options)
{
  if (!(options.elementSize >= 1.0 && options.elementSize <= 20.0))
    throw std::invalid_argument("the element size of the face model must be between 1 and 20 mm");
  if (options.layerCount < 1 || options.layerCount > 8)
    throw std::invalid_argument("the face model needs 1 to 8 element layers from the skin to the bone");
  FaceMesh out;
  out.region = faceRegion(landmarks, skin, options);
  out.centreTheta = 0.5 * (out.region.thetaMin + out.region.thetaMax);
  out.centreZ = 0.5 * (out.region.zMin + out.region.zMax);
  // The chart's centre must have skin; the nose tip's column is the surest.
  double centreTheta = out.centreTheta, centreZ = out.centreZ;
  if (!std::isfinite(skin.sample(centreTheta, centreZ)))
    if (const seg::Landmark* tip = findLandmark(landmarks, "pronasale"))
    {
      centreTheta = tip->theta;
      centreZ = tip->z;
    }
  const planning::SkinChart chart(skin, centreTheta, centreZ);
  out.centreTheta = chart.centreTheta();
  out.centreZ = chart.centreZ();
  out.chartRadius = chart.radius();

  // A grid of quadrilaterals in the chart, counter-clockwise (u right, v up).
  const planning::ChartPoint low = chart.toChart({out.region.thetaMin, out.region.zMin});
  const planning::ChartPoint high = chart.toChart({out.region.thetaMax, out.region.zMax});
  const int nu = std::max(2, int(std::ceil((high.x() - low.x()) / options.elementSize)));
  const int nv = std::max(2, int(std::ceil((high.y() - low.y()) / options.elementSize)));
  const auto gridPoint = [&](int i, int j) {
    return planning::ChartPoint(low.x() + (high.x() - low.x()) * i / nu, low.y() + (high.y() - low.y()) * j / nv);
  };
  const auto hasSkin = [&](const planning::ChartPoint& c) { return chart.lift(c).allFinite(); };
  std::map<int, int> vertexOfGridPoint;
  const auto vertex = [&](int i, int j) {
    const int key = j * (nu + 1) + i;
    const auto [it, added] = vertexOfGridPoint.emplace(key, int(out.surface.vertices.size()));
    if (added)
      out.surface.vertices.push_back(gridPoint(i, j));
    return it->second;
  };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i)
    {
      const planning::ChartPoint corners[4] = {gridPoint(i, j), gridPoint(i + 1, j), gridPoint(i + 1, j + 1),
                                               gridPoint(i, j + 1)};
      bool measured = true;
      for (int k = 0; k < 4 && measured; ++k)
        measured = hasSkin(corners[k]) && hasSkin(0.5 * (corners[k] + corners[(k + 1) % 4]));
      if (!measured)
      {
        ++out.quadsWithoutSkin;
        continue;
      }
      out.surface.polygons.push_back({vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j + 1)});
    }
  if (out.surface.polygons.size() < 16)
    throw std::invalid_argument("the skin map has too little skin in the face region to mesh it: check the range maps");
  out.surface.holeVertexCount = 0;

  const seg::RangeMap boneForDepth =
    planning::boneForTissueDepth(skin, bone, options.noBoneDepth, options.boneSmoothingPasses);
  const fem::TissueGeometry geometry = planning::skinToBoneGeometry(chart, skin, boneForDepth);
  fem::ContinuumMeshOptions continuumOptions = options.continuumMeshOptions();
  continuumOptions.rim = fem::RimCondition::Free;
  out.continuum = fem::meshContinuum(out.surface, {}, geometry, continuumOptions);
  out.materials = options.layerMaterials();
  return out;
}

} // namespace caps::expression
