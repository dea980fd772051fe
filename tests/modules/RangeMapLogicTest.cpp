// The RangeMap module's logic on a synthetic head (HeadPhantom.h): it
// segments first when there is no label map, the four maps are in the scene
// with their roles, size and axis, and the thickness matches the analytic
// thickness between the two ellipsoids.

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "HeadPhantom.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "modules/segment/SegmentLogic.h"
#include "scene/LabelMapNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"

namespace {

using caps::test::HeadPhantom;

struct Error
{
  double rms = 0, max = 0;
  std::size_t compared = 0, missing = 0;
};

// Compares a map with an analytic value over the samples where it is finite
// and the sample lies within |z - centre| < zLimit (the poles of the
// ellipsoids are grazed by the rays and left out).
template <class Analytic>
Error compare(const caps::RangeMapNode& node, double zCentre, double zLimit, Analytic analytic)
{
  Error e;
  double sum = 0;
  for (Eigen::Index j = 0; j < node.values().cols(); ++j)
  {
    const double z = node.zAt(j);
    const double height = node.axisOrigin().z() + z * node.axisDirection().z() - zCentre;
    if (std::abs(height) >= zLimit)
      continue;
    for (Eigen::Index i = 0; i < node.values().rows(); ++i)
    {
      const double expected = analytic(node.thetaAt(i), z);
      const float value = node.values()(i, j);
      if (!std::isfinite(value))
      {
        ++e.missing;
        continue;
      }
      const double d = value - expected;
      sum += d * d;
      e.max = std::max(e.max, std::abs(d));
      ++e.compared;
    }
  }
  e.rms = std::sqrt(sum / std::max<std::size_t>(1, e.compared));
  return e;
}

} // namespace

TEST(RangeMapLogic, PhantomMapsMatchTheAnalyticThickness)
{
  const HeadPhantom& phantom = HeadPhantom::instance();
  caps::Scene scene;
  caps::RangeMapLogic logic(scene);
  auto* volume = scene.add<caps::VolumeNode>();
  volume->setName("Phantom");
  volume->setImage(phantom.images.ct);

  caps::RangeMapLogic::Parameters parameters;
  parameters.nTheta = 256;
  parameters.nZ = 128;
  parameters.skinThresholdHu = HeadPhantom::skinThreshold;
  parameters.boneThresholdHu = HeadPhantom::boneThreshold;
  caps::RangeMapOutput output;
  const caps::RangeMapResult result = logic.run(*volume, parameters, {}, &output);

  // No label map yet: run() segmented first, through the Segment logic.
  EXPECT_TRUE(result.segmented);
  ASSERT_NE(scene.nodeAs<caps::LabelMapNode>(result.labelMapId), nullptr);
  EXPECT_EQ(scene.nodesOfType(caps::NodeType::Surface).size(), 2u);

  // Four maps, with roles, size and the fitted axis (through the centre, along z).
  const std::pair<std::string, const char*> expected[] = {{result.skinId, "skin"},
                                                          {result.boneId, "bone"},
                                                          {result.thicknessId, "thickness"},
                                                          {result.thicknessNormalId,
                                                           "thickness-normal"}};
  for (const auto& [id, role] : expected)
  {
    auto* node = scene.nodeAs<caps::RangeMapNode>(id);
    ASSERT_NE(node, nullptr) << role;
    EXPECT_EQ(node->role(), role);
    EXPECT_EQ(node->values().rows(), 256);
    EXPECT_EQ(node->values().cols(), 128);
    EXPECT_NEAR(node->axisDirection().z(), 1.0, 1e-4) << role;
    const Eigen::Vector3d offset = node->axisOrigin() - phantom.centre;
    EXPECT_LT(std::hypot(offset.x(), offset.y()), 0.2) << role;
    EXPECT_LT(node->zMin(), -95.0);
    EXPECT_GT(node->zMax(), 95.0);
  }
  EXPECT_EQ(scene.nodesOfType(caps::NodeType::RangeMap).size(), 4u);
  const auto& skin = *scene.nodeAs<caps::RangeMapNode>(result.skinId);
  const auto& radial = *scene.nodeAs<caps::RangeMapNode>(result.thicknessId);
  const auto& normal = *scene.nodeAs<caps::RangeMapNode>(result.thicknessNormalId);

  // The node's map and the library's map agree, both ways.
  const caps::seg::RangeMap back = caps::RangeMapLogic::toRangeMap(skin);
  EXPECT_EQ(back.frame(), output.skin.frame());
  const Eigen::MatrixXf m = caps::RangeMapLogic::toMatrix(back);
  ASSERT_EQ(m.size(), skin.values().size());
  std::size_t differ = 0;
  for (Eigen::Index k = 0; k < m.size(); ++k)
    differ += !(m(k) == skin.values()(k) || (std::isnan(m(k)) && std::isnan(skin.values()(k))));
  EXPECT_EQ(differ, 0u);

  // Analytic thickness along each sample's ray (radial) and along the true
  // inward normal at the true skin point (normal), on the node's own axis.
  const caps::seg::CylindricalFrame& frame = output.skin.frame();
  auto radialExpected = [&](double theta, double z) {
    return phantom.radialThickness(frame.axisPoint(z), frame.radialDirection(theta));
  };
  auto normalExpected = [&](double theta, double z) {
    const Eigen::Vector3d dir = frame.radialDirection(theta);
    const Eigen::Vector3d base = frame.axisPoint(z);
    return phantom.normalThickness(base + phantom.skin.outermostHit(base, dir) * dir);
  };
  // Within 70 % of the bone's half height: there the rays meet both surfaces
  // at less than 45 degrees.
  const double zLimit = 0.7 * HeadPhantom::boneC;
  const Error radialError = compare(radial, phantom.centre.z(), zLimit, radialExpected);
  const Error normalError = compare(normal, phantom.centre.z(), zLimit, normalExpected);
  std::printf("[ phantom  ] radial thickness: rms %.3f mm, max %.3f mm over %zu samples, %zu NaN\n",
              radialError.rms, radialError.max, radialError.compared, radialError.missing);
  std::printf("[ phantom  ] normal thickness: rms %.3f mm, max %.3f mm over %zu samples, %zu NaN\n",
              normalError.rms, normalError.max, normalError.compared, normalError.missing);
  // Tolerance: 0.3 voxel RMS (the sub-voxel target; 2 mm voxels).
  EXPECT_LT(radialError.rms, 0.3 * HeadPhantom::spacing);
  EXPECT_LT(normalError.rms, 0.3 * HeadPhantom::spacing);
  EXPECT_EQ(radialError.missing, 0u);
  EXPECT_EQ(normalError.missing, 0u);
  // The statistics cover the same maps: 8 mm on the axes, more in between.
  EXPECT_GT(output.radialStatistics.min, 6.0);
  EXPECT_LT(output.radialStatistics.median, 16.0);

  // Running again replaces the four maps; the label map is reused.
  const caps::RangeMapResult again = logic.run(*volume, parameters);
  EXPECT_FALSE(again.segmented);
  EXPECT_EQ(again.labelMapId, result.labelMapId);
  EXPECT_EQ(scene.nodesOfType(caps::NodeType::RangeMap).size(), 4u);
  EXPECT_EQ(scene.node(result.skinId), nullptr);
}

TEST(RangeMapLogic, SmoothingAndBadInput)
{
  const HeadPhantom& phantom = HeadPhantom::instance();
  caps::Scene scene;
  caps::SegmentLogic segment(scene);
  auto* volume = scene.add<caps::VolumeNode>();
  volume->setImage(phantom.images.ct);
  caps::SegmentLogic::Parameters p;
  p.skinThresholdHu = HeadPhantom::skinThreshold;
  p.boneThresholdHu = HeadPhantom::boneThreshold;
  const auto labels = segment.segment(*volume, p);
  vtkImageData* labelImage = scene.nodeAs<caps::LabelMapNode>(labels.labelMapId)->image();

  caps::RangeMapLogic::Parameters parameters;
  parameters.nTheta = 64;
  parameters.nZ = 32;
  parameters.skinThresholdHu = HeadPhantom::skinThreshold;
  parameters.boneThresholdHu = HeadPhantom::boneThreshold;
  const auto rough = caps::RangeMapLogic::compute(volume->image(), labelImage, parameters);
  parameters.smooth = true;
  const auto smooth = caps::RangeMapLogic::compute(volume->image(), labelImage, parameters);
  // Smoothing changes the maps a little (the ellipsoid is curved; most near
  // the poles, where r changes fastest with z), and not the mean thickness much.
  std::vector<double> change;
  for (std::size_t k = 0; k < rough.skin.values().size(); ++k)
    if (std::isfinite(rough.skin.values()[k]) && std::isfinite(smooth.skin.values()[k]))
      change.push_back(std::abs(rough.skin.values()[k] - smooth.skin.values()[k]));
  ASSERT_FALSE(change.empty());
  std::nth_element(change.begin(), change.begin() + change.size() / 2, change.end());
  EXPECT_GT(change[change.size() / 2], 0.0);
  EXPECT_LT(change[change.size() / 2], 0.5);
  EXPECT_NEAR(smooth.radialStatistics.median, rough.radialStatistics.median, 0.5);

  parameters.nTheta = 2;
  EXPECT_THROW(caps::RangeMapLogic::compute(volume->image(), labelImage, parameters),
               std::invalid_argument);
  EXPECT_THROW(caps::RangeMapLogic::compute(volume->image(), nullptr, parameters),
               std::invalid_argument);
}
