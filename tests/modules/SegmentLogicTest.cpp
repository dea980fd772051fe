// The Segment module's logic on a synthetic head (HeadPhantom.h): label map
// values at known places, volumes and surface areas against the analytic
// ellipsoids, display surfaces in the scene, re-running replaces, cancelling
// leaves the scene alone.

#include <gtest/gtest.h>

#include "HeadPhantom.h"
#include "modules/segment/SegmentLogic.h"
#include "scene/LabelMapNode.h"
#include "scene/Scene.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"
#include "segmentation/Progress.h"

namespace {

using caps::test::HeadPhantom;

const HeadPhantom& phantom()
{
  return HeadPhantom::instance();
}

caps::VolumeNode* addPhantomVolume(caps::Scene& scene)
{
  auto* volume = scene.add<caps::VolumeNode>();
  volume->setName("Phantom");
  volume->setImage(phantom().images.ct);
  return volume;
}

caps::SegmentLogic::Parameters midThresholds()
{
  caps::SegmentLogic::Parameters p;
  p.skinThresholdHu = HeadPhantom::skinThreshold;
  p.boneThresholdHu = HeadPhantom::boneThreshold;
  return p;
}

int labelAt(vtkImageData* labels, const Eigen::Vector3d& world)
{
  double x[3] = {world.x(), world.y(), world.z()}, pcoords[3];
  int ijk[3];
  EXPECT_TRUE(labels->ComputeStructuredCoordinates(x, ijk, pcoords));
  // Nearest voxel.
  for (int a = 0; a < 3; ++a)
    ijk[a] += pcoords[a] > 0.5;
  return *static_cast<unsigned char*>(labels->GetScalarPointer(ijk));
}

} // namespace

TEST(SegmentLogic, PhantomLabelsVolumesAndSurfaces)
{
  caps::Scene scene;
  caps::SegmentLogic logic(scene);
  caps::VolumeNode* volume = addPhantomVolume(scene);
  const caps::SegmentationResult result = logic.segment(*volume, midThresholds());
  EXPECT_FALSE(result.notes.empty());

  auto* labels = scene.nodeAs<caps::LabelMapNode>(result.labelMapId);
  ASSERT_NE(labels, nullptr);
  EXPECT_EQ(labels->referenceVolumeId(), volume->id());
  EXPECT_EQ(logic.findLabelMap(*volume), labels);
  ASSERT_EQ(labels->labels().size(), 3u);
  EXPECT_EQ(labels->labels().at(1).name, "Soft tissue");
  EXPECT_EQ(labels->labels().at(2).name, "Bone");
  vtkImageData* image = labels->image();
  int dims[3], ctDims[3];
  image->GetDimensions(dims);
  phantom().images.ct->GetDimensions(ctDims);
  EXPECT_EQ(std::vector<int>(dims, dims + 3), std::vector<int>(ctDims, ctDims + 3));

  // Along patient left from the centre: brain (inside the skull), skull
  // (56..62 mm), scalp (62..70 mm), air.
  const Eigen::Vector3d c = phantom().centre, left = Eigen::Vector3d::UnitX();
  EXPECT_EQ(labelAt(image, c), 1);
  EXPECT_EQ(labelAt(image, c + 40 * left), 1);
  EXPECT_EQ(labelAt(image, c + 59 * left), 2);
  EXPECT_EQ(labelAt(image, c + 66 * left), 1);
  EXPECT_EQ(labelAt(image, c + 75 * left), 0);
  EXPECT_EQ(labelAt(image, c + 89 * Eigen::Vector3d::UnitZ()), 2); // top of the skull

  // Voxel volumes within 2 % of the ellipsoids' (the mask of a blurred,
  // noisy partial-volume edge cut at its middle).
  const double head = HeadPhantom::ellipsoidVolume(70, 85, 100);
  const double skull = HeadPhantom::ellipsoidVolume(62, 77, 92) - HeadPhantom::ellipsoidVolume(56, 71, 86);
  EXPECT_NEAR(caps::SegmentLogic::volumeMm3(image, 1), head, 0.02 * head);
  EXPECT_NEAR(caps::SegmentLogic::volumeMm3(image, 2), skull, 0.04 * skull);

  // Display surfaces: in the scene, from this label map; areas within 5 % of
  // the ellipsoids' (half resolution, smoothed).
  auto* skin = scene.nodeAs<caps::SurfaceNode>(result.skinSurfaceId);
  auto* bone = scene.nodeAs<caps::SurfaceNode>(result.boneSurfaceId);
  ASSERT_NE(skin, nullptr);
  ASSERT_NE(bone, nullptr);
  EXPECT_EQ(skin->name(), "Skin");
  EXPECT_EQ(bone->name(), "Bone");
  EXPECT_EQ(skin->sourceLabelMapId(), labels->id());
  EXPECT_GT(skin->polyData()->GetNumberOfPolys(), 1000);
  const double skinArea = HeadPhantom::ellipsoidArea(70, 85, 100);
  const double skullArea = HeadPhantom::ellipsoidArea(62, 77, 92) + HeadPhantom::ellipsoidArea(56, 71, 86);
  EXPECT_NEAR(caps::SegmentLogic::surfaceAreaMm2(skin->polyData()), skinArea, 0.05 * skinArea);
  EXPECT_NEAR(caps::SegmentLogic::surfaceAreaMm2(bone->polyData()), skullArea, 0.05 * skullArea);
  // The full-resolution surface has more triangles than the display one.
  const auto full = caps::SegmentLogic::fullSurface(caps::SegmentLogic::maskOf(image, 1));
  EXPECT_GT(full->GetNumberOfPolys(), 2 * skin->polyData()->GetNumberOfPolys());
  EXPECT_NEAR(caps::SegmentLogic::surfaceAreaMm2(full), skinArea, 0.03 * skinArea);

  // Segmenting again replaces the label map and its surfaces.
  const caps::SegmentationResult again = logic.segment(*volume, midThresholds());
  EXPECT_EQ(scene.nodesOfType(caps::NodeType::LabelMap).size(), 1u);
  EXPECT_EQ(scene.nodesOfType(caps::NodeType::Surface).size(), 2u);
  EXPECT_EQ(scene.node(result.labelMapId), nullptr);
  EXPECT_NE(scene.node(again.labelMapId), nullptr);
}

TEST(SegmentLogic, CancelAndBadInput)
{
  caps::Scene scene;
  caps::SegmentLogic logic(scene);
  caps::VolumeNode* volume = addPhantomVolume(scene);
  int calls = 0;
  EXPECT_THROW(logic.segment(*volume, midThresholds(), [&calls](double, const std::string&) { return ++calls < 3; }),
               caps::seg::Cancelled);
  EXPECT_EQ(scene.size(), 1u); // nothing added

  caps::SegmentLogic::Parameters swapped;
  swapped.skinThresholdHu = 300;
  swapped.boneThresholdHu = 200;
  EXPECT_THROW(logic.segment(*volume, swapped), std::invalid_argument);
  // Everything above the threshold: no body to find is an error with a message.
  caps::SegmentLogic::Parameters tooHigh;
  tooHigh.skinThresholdHu = 5000;
  tooHigh.boneThresholdHu = 6000;
  EXPECT_THROW(logic.segment(*volume, tooHigh), std::invalid_argument);
  EXPECT_EQ(scene.size(), 1u);
}

TEST(SegmentLogic, HalfResolutionKeepsTheGeometry)
{
  // A 4 x 4 x 4 mask with a 2 x 2 x 2 block set at voxels 2..3: at half
  // resolution only block (1, 1, 1) is set, centred where the full block is.
  auto mask = vtkSmartPointer<vtkImageData>::New();
  mask->SetDimensions(5, 4, 4); // an odd size: the last block is cut by the border
  mask->SetSpacing(0.5, 0.7, 1.5);
  mask->SetOrigin(10, 20, 30);
  mask->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  auto* m = static_cast<unsigned char*>(mask->GetScalarPointer());
  std::fill(m, m + 5 * 4 * 4, 0);
  for (int k = 2; k < 4; ++k)
    for (int j = 2; j < 4; ++j)
      for (int i = 2; i < 4; ++i)
        m[i + 5 * (j + 4 * k)] = 1;
  const auto half = caps::SegmentLogic::halfResolution(mask);
  int dims[3];
  half->GetDimensions(dims);
  EXPECT_EQ(dims[0], 3);
  EXPECT_EQ(dims[1], 2);
  EXPECT_EQ(dims[2], 2);
  double p[3];
  half->TransformIndexToPhysicalPoint(1, 1, 1, p);
  EXPECT_DOUBLE_EQ(p[0], 10 + 2.5 * 0.5);
  EXPECT_DOUBLE_EQ(p[1], 20 + 2.5 * 0.7);
  EXPECT_DOUBLE_EQ(p[2], 30 + 2.5 * 1.5);
  const auto* h = static_cast<unsigned char*>(half->GetScalarPointer());
  int set = 0;
  for (int v = 0; v < 3 * 2 * 2; ++v)
    set += h[v];
  EXPECT_EQ(set, 1);
  EXPECT_EQ(h[1 + 3 * (1 + 2 * 1)], 1);
}
