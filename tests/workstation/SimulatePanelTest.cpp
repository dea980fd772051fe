// The Simulate panel (issue 6 item 5) driven as a surgeon drives it: the demo
// scene's Z-plasty predicted again from the panel, checked against a direct
// call of the simulation; Cancel; a bad material refused.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <iomanip>
#include <regex>
#include <sstream>
#include <stdexcept>

#include <QCheckBox>
#include <QDoubleSpinBox>
#include <QLabel>
#include <QPushButton>
#include <QStatusBar>
#include <QTableWidget>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>

#include "Workstation.h"
#include "modules/incision/IncisionLogic.h"
#include "planning/PlanSimulation.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "report/DemoScene.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/ScopedEdit.h"
#include "scene/SolutionNode.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"
#include "segmentation/CylindricalFrame.h"

namespace caps {
namespace {

constexpr const char* kPlan = "Z-plasty 1";

std::vector<Node*> nodesNamed(Scene& scene, NodeType type, const std::string& name)
{
  std::vector<Node*> found;
  for (Node* n : scene.nodesOfType(type))
    if (n->name() == name)
      found.push_back(n);
  return found;
}

const RangeMapNode* mapOfRole(Scene& scene, const std::string& role)
{
  for (Node* n : scene.nodesOfType(NodeType::RangeMap))
    if (static_cast<RangeMapNode*>(n)->role() == role)
      return static_cast<RangeMapNode*>(n);
  return nullptr;
}

std::vector<std::string> nodeIds(Scene& scene)
{
  std::vector<std::string> ids;
  for (Node* n : scene.nodes())
    ids.push_back(n->id());
  return ids;
}

/// The demo scene open, the Simulate panel shown, the Z-plasty chosen at @a elementSize.
void openDemo(test::Workstation& w, double elementSize)
{
  w.window().openPath(test::reportDemoFolder() / "sample.caps");
  ASSERT_TRUE(w.waitUntilIdle(300)) << "the demo scene did not open";
  ASSERT_FALSE(nodesNamed(w.scene(), NodeType::Plan, kPlan).empty()) << w.errors();
  w.selectModule("simulate");
  auto* plan = w.widget<QComboBox>("simulate.plan");
  ASSERT_NE(plan, nullptr);
  ASSERT_TRUE(w.waitUntil([&] { return plan->findText(kPlan) >= 0; }, 10));
  plan->setCurrentIndex(plan->findText(kPlan));
  w.widget<QDoubleSpinBox>("simulate.elementSize")->setValue(elementSize);
}

/// The DOF the estimate label gives once it has one.
long estimatedDofs(test::Workstation& w)
{
  auto* label = w.widget<QLabel>("simulate.estimate");
  const std::regex dofs(R"(([0-9]+) DOF)");
  std::smatch m;
  std::string text;
  const bool ready = w.waitUntil(
    [&] {
      text = label->text().toStdString();
      return std::regex_search(text, m, dofs);
    },
    60);
  EXPECT_TRUE(ready) << "no estimate: " << text;
  return ready ? std::stol(m[1].str()) : -1;
}

/// The plan of @a planNode solved directly from what the scene holds, as
/// the panel solves it in these tests: 3 mm, large deformation (the
/// prediction, not the preview), the default pre-tension with its lines
/// placed from the face.
planning::PlanPrediction directPrediction(Scene& scene, const PlanNode& planNode)
{
  const RangeMapNode* skinNode = scene.nodeAs<RangeMapNode>(planNode.rangeMapId());
  const RangeMapNode* boneNode = mapOfRole(scene, "bone");
  if (!skinNode || !boneNode)
    throw std::runtime_error("the scene has no skin or bone map for " + planNode.name());
  planning::SimulationOptions options;
  options.elementSize = 3.0;
  options.threads = 2;
  options.model = planning::TissueModel::LargeDeformation;
  options.preTension = planning::SkinPreTension::facial();
  return planning::simulatePlan(RangeMapLogic::toRangeMap(*skinNode), RangeMapLogic::toRangeMap(*boneNode),
                                IncisionLogic::readPlan(planNode), options);
}

/// The displacements the scene shows for the plan ("<plan> closure") are
/// @a direct's, to 1e-9 of the largest, and move the skin by millimetres.
void expectShownDisplacements(Scene& scene, const planning::PlanPrediction& direct)
{
  const std::vector<Node*> closure = nodesNamed(scene, NodeType::Solution, std::string(kPlan) + " closure");
  ASSERT_EQ(closure.size(), 1u);
  vtkDataArray* u = static_cast<SolutionNode*>(closure.front())->result()->GetPointData()->GetArray("displacement_mm");
  ASSERT_NE(u, nullptr);
  ASSERT_EQ(3 * u->GetNumberOfTuples(), direct.displacements.size());
  double largest = 0.0, difference = 0.0;
  for (vtkIdType i = 0; i < u->GetNumberOfTuples(); ++i)
    for (int k = 0; k < 3; ++k)
    {
      const double expected = direct.displacements[3 * i + k];
      largest = std::max(largest, std::abs(expected));
      difference = std::max(difference, std::abs(u->GetComponent(i, k) - expected));
    }
  EXPECT_GT(largest, 0.1) << "the sutures move the skin by millimetres";
  EXPECT_LE(difference, 1e-9 * largest);
}

TEST(SimulatePanel, RunMatchesADirectSimulationAndReplacesThePrediction)
{
  test::Workstation w;
  openDemo(w, 3.0);
  Scene& scene = w.scene();
  const long dofs = estimatedDofs(w);

  const std::size_t before = scene.size();
  auto* run = w.widget<QPushButton>("simulate.run");
  ASSERT_TRUE(run->isEnabled());
  const auto started = std::chrono::steady_clock::now();
  QTest::mouseClick(run, Qt::LeftButton);
  ASSERT_TRUE(w.waitUntilIdle(300));
  ASSERT_TRUE(w.window().reportedErrors().empty()) << w.errors();
  std::cout << "Run of " << kPlan
            << " at 3 mm: " << std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count()
            << " s from Run to the nodes in the scene; estimate said " << dofs << " DOF\n"
            << w.widget<QLabel>("simulate.summary")->text().toStdString() << "\n";

  // Replaced, not piled up: one of each, and the mesh drawing added.
  for (const auto& [type, suffix] : std::vector<std::pair<NodeType, std::string>>{{NodeType::Plan, ""},
                                                                                  {NodeType::FeMesh, " model"},
                                                                                  {NodeType::Solution, " closure"},
                                                                                  {NodeType::Surface, " skin before"},
                                                                                  {NodeType::Surface, " skin after"},
                                                                                  {NodeType::Surface, " skin gaping"},
                                                                                  {NodeType::Surface, " mesh"}})
    EXPECT_EQ(nodesNamed(scene, type, kPlan + suffix).size(), 1u) << kPlan << suffix;
  EXPECT_EQ(scene.size(), before + 1) << "only the mesh drawing is new";
  auto* planNode = static_cast<PlanNode*>(nodesNamed(scene, NodeType::Plan, kPlan).front());
  ASSERT_TRUE(planNode->simulation().is_object());
  EXPECT_DOUBLE_EQ(planNode->simulation().value("elementSize", 0.0), 3.0);

  // The same plan simulated directly, from what the scene holds.
  const planning::PlanPrediction direct = directPrediction(scene, *planNode); // the plan still reads
  const RangeMapNode* skinNode = scene.nodeAs<RangeMapNode>(planNode->rangeMapId());
  ASSERT_NE(skinNode, nullptr);

  EXPECT_EQ(dofs, long(direct.dofCount)) << "the estimate before the run is the solved model's size";

  expectShownDisplacements(scene, direct);

  // The summary: the closure force of the direct call at the printed precision.
  const std::string summary = w.widget<QLabel>("simulate.summary")->text().toStdString();
  std::ostringstream force;
  force << std::setprecision(4) << "Closure force: " << direct.closure.magnitudeSum << " N";
  EXPECT_NE(summary.find(force.str()), std::string::npos) << summary << "\nexpected " << force.str();
  std::ostringstream model;
  model << direct.dofCount << " DOF";
  EXPECT_NE(summary.find(model.str()), std::string::npos) << summary;
  EXPECT_NE(summary.find("kPa von Mises"), std::string::npos) << summary;

  // The model drawn (§3.3.1): the fixed nodes as points, a line per suture
  // and per skin element edge; shown and hidden with the check box.
  auto* mesh = static_cast<SurfaceNode*>(nodesNamed(scene, NodeType::Surface, std::string(kPlan) + " mesh").front());
  EXPECT_EQ(mesh->polyData()->GetNumberOfVerts(), vtkIdType(direct.continuum.fixedNodes.size()));
  EXPECT_GT(mesh->polyData()->GetNumberOfLines(), vtkIdType(direct.continuum.sutures.size()));
  auto* showMesh = w.widget<QCheckBox>("simulate.showMesh");
  EXPECT_EQ(mesh->visible(), showMesh->isChecked());
  showMesh->setChecked(true);
  w.settle(200);
  EXPECT_TRUE(mesh->visible());
  {
    // Look at the cheek from outside, as a surgeon turns the view to the plan.
    double bounds[6];
    mesh->polyData()->GetBounds(bounds);
    const Eigen::Vector3d centre(0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
                                 0.5 * (bounds[4] + bounds[5]));
    const Eigen::Vector3d axis = skinNode->axisDirection(), origin = skinNode->axisOrigin();
    Eigen::Vector3d outward = centre - origin;
    outward = (outward - outward.dot(axis) * axis).normalized();
    vtkCamera* camera = w.threeDView().renderer()->GetActiveCamera();
    camera->SetFocalPoint(centre.data());
    const Eigen::Vector3d eye = centre + 220.0 * outward;
    camera->SetPosition(eye.data());
    camera->SetViewUp(axis.z() < 0 ? (-axis).eval().data() : axis.data());
    w.threeDView().renderer()->ResetCameraClippingRange();
  }
  w.screenshot("simulate-panel");
  {
    // The model alone: the predicted skin hidden, so the fixed bone nodes and the sutures show.
    auto* after =
      static_cast<SurfaceNode*>(nodesNamed(scene, NodeType::Surface, std::string(kPlan) + " skin after").front());
    after->setVisible(false);
    w.screenshot("simulate-panel-model");
    after->setVisible(true);
  }
  showMesh->setChecked(false);
  w.settle(100);
  EXPECT_FALSE(mesh->visible());

  // Run again (F5 while the panel is shown): still one of each.
  QApplication::setActiveWindow(&w.window());
  w.settle(50);
  QTest::keyClick(&w.window(), Qt::Key_F5);
  ASSERT_TRUE(w.waitUntil([&] { return w.window().busy(); }, 5)) << "F5 did not start a run";
  ASSERT_TRUE(w.waitUntilIdle(300));
  EXPECT_TRUE(w.window().reportedErrors().empty()) << w.errors();
  EXPECT_EQ(nodesNamed(scene, NodeType::Solution, std::string(kPlan) + " closure").size(), 1u);
  EXPECT_EQ(nodesNamed(scene, NodeType::Surface, std::string(kPlan) + " skin after").size(), 1u);
  EXPECT_EQ(nodesNamed(scene, NodeType::Plan, kPlan).size(), 1u);
  EXPECT_EQ(scene.size(), before + 1);
}

/// The first cut point of plan @a planId moved by @a du mm around the head,
/// as the Incision panel records an edit (undoable); returns the new path.
std::vector<Eigen::Vector2d> moveFirstCutPoint(Scene& scene, const NodeId& planId, double du)
{
  auto* node = scene.nodeAs<PlanNode>(planId);
  const RangeMapNode* skinNode = scene.nodeAs<RangeMapNode>(node->rangeMapId());
  const seg::RangeMap skin = RangeMapLogic::toRangeMap(*skinNode);
  planning::IncisionPlan plan = IncisionLogic::readPlan(*node);
  const planning::SkinChart chart = plan.chart(skin);
  const fem::ChartPoint p = chart.fromNormalized(plan.cutPath()[0]) + fem::ChartPoint(du, 0.0);
  plan.moveCutPoint(0, chart.toNormalized(p));
  ScopedEdit edit(scene, planId, "Move cut point 1");
  IncisionLogic::writePlan(plan, *node);
  return node->cutPath();
}

// Item 8 of issue 21: with "Predict as the plan is edited" each edit gets
// the linear preview, then the large-deformation prediction replaces it;
// an edit while that runs stops it, and what is finally shown is the
// prediction of the plan as last edited (the same numbers as a direct
// call), on the same plan node, so the edits can still be undone.
TEST(SimulatePanel, LivePredictionFollowsTheEditsAndTheNextEditStopsTheOldOne)
{
  test::Workstation w;
  openDemo(w, 3.0);
  Scene& scene = w.scene();
  auto* model = w.widget<QComboBox>("simulate.model");
  model->setCurrentIndex(model->findData(QString(planning::tissueModelId(planning::TissueModel::LargeDeformation))));
  auto* status = w.widget<QLabel>("simulate.liveStatus");
  const NodeId planId = nodesNamed(scene, NodeType::Plan, kPlan).front()->id();
  const std::vector<Eigen::Vector2d> asOpened = scene.nodeAs<PlanNode>(planId)->cutPath();
  const auto shows = [&](const char* text) {
    return w.waitUntil([&] { return status->text().startsWith(text); }, 300);
  };

  // 1. Ticked: the plan as it is, preview first.
  const auto ticked = std::chrono::steady_clock::now();
  w.widget<QCheckBox>("simulate.live")->setChecked(true);
  ASSERT_TRUE(shows("Linear preview shown")) << status->text().toStdString();
  std::cout << "live: linear preview in the scene "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - ticked).count()
            << " s after the tick: " << status->text().toStdString() << "\n";
  auto* node = scene.nodeAs<PlanNode>(planId);
  ASSERT_NE(node, nullptr) << "the live prediction keeps the plan node";
  EXPECT_EQ(node->simulation().value("model", ""), planning::tissueModelId(planning::TissueModel::LinearElastic));

  // 2. An edit while the large-deformation prediction of the old state runs.
  const std::vector<Eigen::Vector2d> edited = moveFirstCutPoint(scene, planId, 1.5);
  ASSERT_NE(edited, asOpened);
  ASSERT_TRUE(status->text().startsWith("The plan changed")) << status->text().toStdString();
  const auto editedAt = std::chrono::steady_clock::now();
  ASSERT_TRUE(shows("Linear preview shown")) << status->text().toStdString();
  std::cout << "live: edit -> linear preview in the scene "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - editedAt).count() << " s\n";
  ASSERT_TRUE(shows("Large-deformation prediction shown")) << status->text().toStdString();
  std::cout << "live: edit -> large-deformation prediction in the scene "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - editedAt).count()
            << " s: " << status->text().toStdString() << "\n";
  EXPECT_TRUE(w.window().reportedErrors().empty()) << w.errors();
  node = scene.nodeAs<PlanNode>(planId);
  ASSERT_NE(node, nullptr);
  EXPECT_EQ(node->cutPath(), edited);
  EXPECT_EQ(node->simulation().value("model", ""), planning::tissueModelId(planning::TissueModel::LargeDeformation));
  for (const std::string suffix : {" closure", " skin after"})
    EXPECT_EQ(nodesNamed(scene, suffix == " closure" ? NodeType::Solution : NodeType::Surface, kPlan + suffix).size(),
              1u)
      << suffix;

  // What is shown is the large-deformation prediction of the edited plan.
  expectShownDisplacements(scene, directPrediction(scene, *node));

  // 3. Undo reaches the edit through the live predictions, and is predicted in turn.
  ASSERT_TRUE(scene.undoStack().undo());
  EXPECT_EQ(scene.nodeAs<PlanNode>(planId)->cutPath(), asOpened);
  ASSERT_TRUE(status->text().startsWith("The plan changed")) << status->text().toStdString();
  ASSERT_TRUE(shows("Linear preview shown")) << status->text().toStdString();
  w.widget<QCheckBox>("simulate.live")->setChecked(false); // stops the large-deformation run
  EXPECT_TRUE(w.window().reportedErrors().empty()) << w.errors();
}

TEST(SimulatePanel, SimulatePlanReportsItsPhasesAndStopsWhenAsked)
{
  test::Workstation w;
  w.window().openPath(test::reportDemoFolder() / "sample.caps");
  ASSERT_TRUE(w.waitUntilIdle(300));
  Scene& scene = w.scene();
  const auto plans = nodesNamed(scene, NodeType::Plan, kPlan);
  ASSERT_EQ(plans.size(), 1u);
  const auto* planNode = static_cast<PlanNode*>(plans.front());
  const planning::IncisionPlan plan = IncisionLogic::readPlan(*planNode);
  const seg::RangeMap skin = RangeMapLogic::toRangeMap(*scene.nodeAs<RangeMapNode>(planNode->rangeMapId()));
  const seg::RangeMap bone = RangeMapLogic::toRangeMap(*mapOfRole(scene, "bone"));
  planning::SimulationOptions options;
  options.elementSize = 3.0;

  std::vector<std::string> phases;
  std::vector<double> fractions;
  options.progress = [&](double fraction, const std::string& phase) {
    phases.push_back(phase);
    fractions.push_back(fraction);
    return true;
  };
  const planning::PlanPrediction reported = planning::simulatePlan(skin, bone, plan, options);
  ASSERT_EQ(phases.size(), 5u);
  EXPECT_NE(phases[0].find("Surface mesh"), std::string::npos);
  EXPECT_NE(phases[1].find("Continuum mesh"), std::string::npos);
  EXPECT_NE(phases[2].find("Assembly"), std::string::npos);
  EXPECT_NE(phases[3].find("Solve"), std::string::npos);
  EXPECT_NE(phases[4].find("Closure"), std::string::npos);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));

  // The callback changes nothing of the result, and meshPlan() meshes the same model.
  planning::SimulationOptions plain = options;
  plain.progress = nullptr;
  const planning::PlanPrediction silent = planning::simulatePlan(skin, bone, plan, plain);
  EXPECT_EQ((reported.displacements - silent.displacements).cwiseAbs().maxCoeff(), 0.0);
  const planning::PlanPrediction meshed = planning::meshPlan(skin, bone, plan, plain);
  EXPECT_EQ(meshed.continuum.mesh.dofCount(), silent.dofCount);
  EXPECT_EQ(meshed.continuum.mesh.elements.size(), silent.continuum.mesh.elements.size());
  EXPECT_EQ(meshed.displacements.size(), 0);

  // Stopped before the assembly: the distinct exception, nothing solved.
  int calls = 0;
  options.progress = [&](double, const std::string&) { return ++calls < 3; };
  EXPECT_THROW(planning::simulatePlan(skin, bone, plan, options), seg::Cancelled);
  EXPECT_EQ(calls, 3);
}

TEST(SimulatePanel, CancelLeavesTheSceneAsItWas)
{
  test::Workstation w;
  openDemo(w, 2.0);
  const std::vector<std::string> before = nodeIds(w.scene());

  QTest::mouseClick(w.widget<QPushButton>("simulate.run"), Qt::LeftButton);
  QPushButton* cancel = nullptr;
  ASSERT_TRUE(w.waitUntil(
    [&] {
      for (auto* b : w.window().statusBar()->findChildren<QPushButton*>())
        if (b->text().remove('&') == "Cancel" && b->isVisible() && b->isEnabled())
          cancel = b;
      return cancel != nullptr;
    },
    10))
    << "no Cancel button in the status bar";
  const auto pressed = std::chrono::steady_clock::now();
  QTest::mouseClick(cancel, Qt::LeftButton);
  ASSERT_TRUE(w.waitUntilIdle(300));
  std::cout << "Cancel took " << std::chrono::duration<double>(std::chrono::steady_clock::now() - pressed).count()
            << " s to stop the run\n";
  EXPECT_EQ(nodeIds(w.scene()), before);
  EXPECT_TRUE(w.window().reportedErrors().empty()) << w.errors();
}

TEST(SimulatePanel, BadMaterialIsRefusedAndNothingRuns)
{
  test::Workstation w;
  openDemo(w, 3.0);
  const std::vector<std::string> before = nodeIds(w.scene());
  auto* table = w.widget<QTableWidget>("simulate.materials");
  ASSERT_EQ(table->rowCount(), 3);
  auto* run = w.widget<QPushButton>("simulate.run");

  // ν = 0.5 (incompressible) in the fat, then E = 0 in the skin.
  for (const auto& [row, column, text] : std::vector<std::tuple<int, int, QString>>{{1, 2, "0.5"}, {0, 1, "0"}})
  {
    const std::size_t errors = w.window().reportedErrors().size();
    table->item(row, column)->setText(text);
    w.settle(50);
    EXPECT_EQ(w.window().reportedErrors().size(), errors + 1) << "refused as typed: " << text.toStdString();
    QTest::mouseClick(run, Qt::LeftButton);
    w.settle(200);
    EXPECT_FALSE(w.window().busy()) << "a run started with a bad material";
    EXPECT_EQ(w.window().reportedErrors().size(), errors + 2) << "Run refused with a message";
    ASSERT_TRUE(w.waitUntilIdle(300));
    EXPECT_EQ(nodeIds(w.scene()), before);
    const std::string last = w.window().reportedErrors().back();
    EXPECT_NE(last.find(column == 2 ? "Poisson" : "Young"), std::string::npos) << last;
  }
}

// A plan saved before its CT's metal was known (here: a dental filling put
// into the demo CT's voxels after the plan was made, in the slice of its
// first cut point) is refused when it is simulated, with where and what to do,
// and nothing runs.
TEST(SimulatePanel, APlanThroughMetalStreaksIsRefused)
{
  test::Workstation w;
  openDemo(w, 3.0);
  auto* plan = static_cast<PlanNode*>(nodesNamed(w.scene(), NodeType::Plan, kPlan).front());
  const RangeMapNode* skinNode = w.scene().nodeAs<RangeMapNode>(plan->rangeMapId());
  ASSERT_NE(skinNode, nullptr);
  auto* volume = w.scene().nodeAs<VolumeNode>(skinNode->sourceVolumeId());
  ASSERT_NE(volume, nullptr);
  const seg::RangeMap skin = RangeMapLogic::toRangeMap(*skinNode);
  const seg::CylindricalPoint c =
    skin.frame().fromNormalized({1.0, plan->cutPath().front().x(), plan->cutPath().front().y()});
  // 2 x 2 x 2 voxels of metal 30 mm inside the skin at the cut's first point.
  const Eigen::Vector3d inside = skin.frame().toWorld(skin.sample(c.theta, c.z) - 30.0, c.theta, c.z);
  vtkImageData* ct = volume->image();
  int ijk[3];
  double pcoords[3];
  double at[3] = {inside.x(), inside.y(), inside.z()};
  ASSERT_NE(ct->ComputeStructuredCoordinates(at, ijk, pcoords), 0);
  for (int dk = 0; dk <= 1; ++dk)
    for (int dj = 0; dj <= 1; ++dj)
      for (int di = 0; di <= 1; ++di)
        ct->SetScalarComponentFromDouble(ijk[0] + di, ijk[1] + dj, ijk[2] + dk, 0, 3071.0);
  ct->Modified();

  const std::vector<std::string> before = nodeIds(w.scene());
  const std::size_t errors = w.window().reportedErrors().size();
  QTest::mouseClick(w.widget<QPushButton>("simulate.run"), Qt::LeftButton);
  w.settle(200);
  ASSERT_TRUE(w.waitUntilIdle(300));
  ASSERT_EQ(w.window().reportedErrors().size(), errors + 1) << "Run was not refused";
  const std::string message = w.window().reportedErrors().back();
  EXPECT_NE(message.find("metal"), std::string::npos) << message;
  EXPECT_EQ(nodeIds(w.scene()), before) << "something ran";
}

} // namespace
} // namespace caps
