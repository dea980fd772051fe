// What `caps demo` writes on the embedded sample CT: the files a user is
// told about, the landmark table, the CT's description, and the saved scene,
// which loads back with the CT, the two predicted plans (each with its
// operations, the CT's hash, its model and a solution that closes the wound),
// their skins and the storyboard. The demo runs once per test run, as the
// ctest fixture the report's tests share (DemoScene.h).

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>

#include "DemoScene.h"
#include "scene/FeMeshNode.h"
#include "scene/PlanNode.h"
#include "scene/Scene.h"
#include "scene/SceneBundle.h"
#include "scene/SnapshotNode.h"
#include "scene/SolutionNode.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"
#include "segmentation/Landmarks.h"

namespace fs = std::filesystem;

namespace {

TEST(DemoOutput, TheDemoWritesItsFilesAndItsSceneLoadsBack)
{
  const fs::path& out = caps::test::reportDemoFolder();
  for (const char* file : {"info.txt", "axial.png", "coronal.png", "sagittal.png", "thickness.png", "landmarks.csv",
                           "sample.caps/scene.json", "z-plasty/skin-after.vtp", "z-plasty/measurements.csv",
                           "elliptical-excision/skin-after.vtp", "elliptical-excision/model.vtu", "plan-report.pdf"})
    EXPECT_TRUE(fs::exists(out / file)) << file;
  // The landmark table: the nose tip and the chin are placed, with a
  // thickness in the plausible range (see tests/modules/SampleThicknessTest).
  const auto landmarks = caps::seg::readLandmarkCsv(out / "landmarks.csv");
  bool chin = false;
  for (const auto& row : landmarks)
    if (row.landmark.name == "pogonion")
    {
      chin = true;
      EXPECT_GT(row.radial, 6.0);
      EXPECT_LT(row.radial, 18.0);
    }
  EXPECT_TRUE(chin);
  std::ifstream info(out / "info.txt");
  std::string text((std::istreambuf_iterator<char>(info)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("512 x 512 x 295"), std::string::npos) << text;
  // The saved scene loads back with the CT in it.
  caps::Scene scene;
  caps::loadSceneBundle(scene, out / "sample.caps");
  const auto volumes = scene.nodesOfType(caps::NodeType::Volume);
  ASSERT_EQ(volumes.size(), 1u);
  const auto* volume = static_cast<caps::VolumeNode*>(volumes[0]);
  EXPECT_EQ(volume->image()->GetDimensions()[2], 295);
  EXPECT_EQ(volume->metadata().at("PatientID"), "ANON48576");
  // ... and the two predicted plans: each Plan node with the operations that
  // made it and the CT's hash, its model, its solution (the wound closed)
  // and the skin before and after.
  const auto plans = scene.nodesOfType(caps::NodeType::Plan);
  ASSERT_EQ(plans.size(), 2u);
  for (caps::Node* n : plans)
  {
    const auto* plan = static_cast<caps::PlanNode*>(n);
    EXPECT_FALSE(plan->operations().empty()) << plan->name();
    EXPECT_EQ(plan->ctSha256().size(), 64u) << plan->name();
    EXPECT_FALSE(plan->rangeMapId().empty());
    EXPECT_NE(scene.node(plan->rangeMapId()), nullptr) << "the plan is drawn on the scene's skin map";
  }
  const auto meshes = scene.nodesOfType(caps::NodeType::FeMesh);
  const auto solutions = scene.nodesOfType(caps::NodeType::Solution);
  ASSERT_EQ(meshes.size(), 2u);
  ASSERT_EQ(solutions.size(), 2u);
  for (caps::Node* n : solutions)
  {
    const auto* solution = static_cast<caps::SolutionNode*>(n);
    const auto* mesh = static_cast<const caps::FeMeshNode*>(scene.node(solution->meshId()));
    ASSERT_NE(mesh, nullptr);
    ASSERT_NE(solution->result(), nullptr);
    EXPECT_EQ(solution->result()->GetNumberOfPoints(), mesh->mesh()->GetNumberOfPoints());
    vtkDataArray* u = solution->result()->GetPointData()->GetArray("displacement_mm");
    ASSERT_NE(u, nullptr);
    double largest = 0.0;
    for (vtkIdType i = 0; i < u->GetNumberOfTuples(); ++i)
      largest =
        std::max(largest, std::sqrt(u->GetTuple3(i)[0] * u->GetTuple3(i)[0] + u->GetTuple3(i)[1] * u->GetTuple3(i)[1] +
                                    u->GetTuple3(i)[2] * u->GetTuple3(i)[2]));
    EXPECT_GT(largest, 2.0) << "the wound closes by millimetres";
  }
  // Each plan's skin before and after, and its wound gaping under the skin's pre-tension.
  int skins = 0, gaping = 0;
  for (caps::Node* n : scene.nodesOfType(caps::NodeType::Surface))
  {
    skins += n->name().ends_with(" skin before") || n->name().ends_with(" skin after");
    gaping += n->name().ends_with(" skin gaping");
  }
  EXPECT_EQ(skins, 4);
  EXPECT_EQ(gaping, 2);
  // The storyboard: the Z-plasty before and after, with their pictures.
  const auto snapshots = scene.nodesOfType(caps::NodeType::Snapshot);
  ASSERT_EQ(snapshots.size(), 2u);
  for (caps::Node* n : snapshots)
    EXPECT_NE(static_cast<caps::SnapshotNode*>(n)->image(), nullptr) << n->name();
}

} // namespace
