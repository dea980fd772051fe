// The Expression panel (issue 8 item 4) driven as a surgeon drives it: the
// demo scene's face model built, the smile slider moved (the face against
// the logic's own superposition for the same activations, the mouth corners
// going up), the smile saved, changed and recalled, played, and kept in the
// saved scene.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <vector>

#include <unistd.h>

#include <QApplication>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QFileDialog>
#include <QImage>
#include <QLabel>
#include <QLineEdit>
#include <QPushButton>
#include <QSlider>
#include <QStatusBar>
#include <QTimer>

#include <vtkPoints.h>
#include <vtkPolyData.h>

#include "TestPaths.h"
#include "Workstation.h"
#include "modules/expression/ExpressionLogic.h"
#include "modules/expression/PlanStudy.h"
#include "modules/incision/IncisionLogic.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "modules/report/PlanAnimation.h"
#include "report/DemoScene.h"
#include "scene/ExpressionNode.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/SurfaceNode.h"

namespace caps {
namespace {

/// Largest distance between the surface's points and @a expected (3 × V).
double largestGap(vtkPolyData* surface, const Eigen::Matrix3Xd& expected)
{
  if (surface->GetNumberOfPoints() != expected.cols())
    return INFINITY;
  double worst = 0.0, p[3];
  for (vtkIdType i = 0; i < surface->GetNumberOfPoints(); ++i)
  {
    surface->GetPoint(i, p);
    worst = std::max(worst, (Eigen::Vector3d(p[0], p[1], p[2]) - expected.col(i)).norm());
  }
  return worst;
}

Eigen::Matrix3Xd pointsOf(vtkPolyData* surface)
{
  Eigen::Matrix3Xd out(3, surface->GetNumberOfPoints());
  for (vtkIdType i = 0; i < surface->GetNumberOfPoints(); ++i)
    surface->GetPoint(i, out.col(i).data());
  return out;
}

/// The window with the 3D view alone in the middle (the slice views hidden
/// for the picture), to see millimetres of movement on the face.
void largeFaceShot(test::Workstation& workstation, const std::string& name)
{
  std::vector<QWidget*> hidden;
  for (QWidget* child :
       workstation.window().centralWidget()->findChildren<QWidget*>(QString(), Qt::FindDirectChildrenOnly))
    if (child != &workstation.threeDView() && child->isVisible())
    {
      child->hide();
      hidden.push_back(child);
    }
  workstation.screenshot(name);
  for (QWidget* child : hidden)
    child->show();
  workstation.settle(100);
}

void setSlider(QSlider* slider, int value)
{
  slider->setValue(value); // valueChanged, as a drag emits it
  QApplication::processEvents();
}

/// Answers the next folder dialog with @a folder (as a user choosing it does).
void answerFolderDialog(QWidget* parent, const std::filesystem::path& folder)
{
  auto answered = std::make_shared<bool>(false);
  auto* timer = new QTimer(parent);
  timer->setInterval(50);
  QObject::connect(timer, &QTimer::timeout, [timer, folder, answered] {
    auto* dialog = qobject_cast<QFileDialog*>(QApplication::activeModalWidget());
    if (!dialog)
    {
      if (*answered)
        timer->stop();
      return;
    }
    dialog->selectFile(QString::fromStdString(folder.string()));
    if (auto* edit = dialog->findChild<QLineEdit*>("fileNameEdit"))
      edit->setText(QString::fromStdString(folder.string()));
    QMetaObject::invokeMethod(dialog, "accept", Qt::QueuedConnection);
    *answered = true;
  });
  timer->start();
}

TEST(ExpressionPanel, SmileSavedRecalledPlayedAndKeptInTheScene)
{
  const std::filesystem::path bundle = test::reportDemoFolder() / "sample.caps";
  ASSERT_TRUE(std::filesystem::exists(bundle)) << bundle;
  test::Workstation workstation;
  workstation.window().openPath(bundle);
  ASSERT_TRUE(workstation.waitUntilIdle(300)) << workstation.errors();
  Scene& scene = workstation.scene();
  SurfaceNode* skin = test::nodeNamed<SurfaceNode>(scene, "Skin");
  ASSERT_NE(skin, nullptr);
  ASSERT_TRUE(skin->visible());

  workstation.selectModule("expression");
  auto* build = workstation.widget<QPushButton>("expression.build");
  auto* smile = workstation.widget<QSlider>("expression.expression.smile");
  auto* frown = workstation.widget<QSlider>("expression.expression.frown");
  auto* name = workstation.widget<QLineEdit>("expression.name");
  auto* save = workstation.widget<QPushButton>("expression.save");
  auto* saved = workstation.widget<QComboBox>("expression.saved");
  auto* play = workstation.widget<QPushButton>("expression.play");
  auto* info = workstation.widget<QLabel>("expression.info");
  auto* status = workstation.widget<QLabel>("expression.status");
  ASSERT_TRUE(build && smile && frown && name && save && saved && play && info && status);
  EXPECT_FALSE(smile->isEnabled()); // nothing to move before the model

  QTest::mouseClick(build, Qt::LeftButton);
  ASSERT_TRUE(
    workstation.waitUntil([&] { return test::nodeNamed<SurfaceNode>(scene, "Face expression") != nullptr; }, 300))
    << workstation.errors() << status->text().toStdString();
  ASSERT_TRUE(workstation.waitUntilIdle(60));
  std::cout << "[expression panel] " << status->text().toStdString() << "\n";
  SurfaceNode* face = test::nodeNamed<SurfaceNode>(scene, "Face expression");
  ASSERT_NE(face, nullptr);
  EXPECT_TRUE(face->visible());
  EXPECT_FALSE(skin->visible()) << "the segmented skin would fight the expression face for the same pixels";
  EXPECT_EQ(face->colourArray(), "skin_colour");
  EXPECT_TRUE(smile->isEnabled());

  // The same model made here directly from the logic, from the same scene.
  ExpressionLogic logic(scene);
  const std::unique_ptr<expression::ExpressionModel> model = expression::buildExpressionModel(logic.modelInput());
  ASSERT_NE(model, nullptr);
  ASSERT_EQ(face->polyData()->GetNumberOfPoints(), model->surface.vertexCount());
  Eigen::Matrix3Xd expected;
  const Eigen::VectorXd atRest = Eigen::VectorXd::Zero(Eigen::Index(model->muscles.size()));
  model->positions(atRest, expected);
  EXPECT_LT(largestGap(face->polyData(), expected), 1e-9);
  const Eigen::Matrix3Xd rest = expected;
  workstation.screenshot("expression-rest");
  largeFaceShot(workstation, "expression-rest-large");

  // Smile at 100 %: the face is the logic's superposition for the smile's activations.
  setSlider(smile, 100);
  workstation.settle(200);
  const auto& definitions = expression::builtInExpressions();
  const auto smileDefinition =
    std::find_if(definitions.begin(), definitions.end(), [](const auto& e) { return e.name == "smile"; });
  ASSERT_NE(smileDefinition, definitions.end());
  const Eigen::VectorXd smiling = expression::expressionActivations(*smileDefinition, model->muscles);
  EXPECT_GT(smiling.sum(), 2.0);
  model->positions(smiling, expected);
  EXPECT_LT(largestGap(face->polyData(), expected), 1e-9);
  const Eigen::Matrix3Xd smileShape = expected;
  std::cout << "[expression panel] smile: " << info->text().toStdString() << "\n";
  EXPECT_TRUE(info->text().contains("mm")) << info->text().toStdString();

  // The mouth corners (the skin nearest the zygomaticus insertions) go up.
  const Eigen::Vector3d up = model->frame.direction();
  for (const char* id : {"zygomaticus_major_left", "zygomaticus_major_right"})
  {
    const int k = model->muscleIndex(id);
    ASSERT_GE(k, 0) << id;
    const Eigen::Vector3d insertion = model->muscles[std::size_t(k)].functions.front().insertion;
    Eigen::Index nearest = 0;
    (rest.colwise() - insertion).colwise().squaredNorm().minCoeff(&nearest);
    const Eigen::Vector3d moved = smileShape.col(nearest) - rest.col(nearest);
    std::cout << "[expression panel] " << id << ": corner " << (rest.col(nearest) - insertion).norm()
              << " mm from the insertion moves " << moved.norm() << " mm, " << moved.dot(up) << " mm up\n";
    EXPECT_GT(moved.dot(up), 0.2) << id << " moved " << moved.transpose();
  }
  workstation.screenshot("expression-smile");
  largeFaceShot(workstation, "expression-smile-large");

  // Mixing: smile + sneer + the left risorius slider at 70 %, each muscle
  // clamped to full contraction (the risorius: 0.6 + 0.7 → 1).
  {
    auto* sneer = workstation.widget<QSlider>("expression.expression.sneer");
    auto* risorius = workstation.widget<QSlider>("expression.muscle.risorius_left");
    ASSERT_TRUE(sneer && risorius);
    setSlider(sneer, 100);
    setSlider(risorius, 70);
    Eigen::VectorXd mixed = smiling;
    for (std::size_t k = 0; k < model->muscles.size(); ++k)
    {
      const expression::FittedMuscle& m = model->muscles[k];
      if (m.definition == "levator_labii_superioris_alaeque_nasi")
        mixed[Eigen::Index(k)] += 1.0;
      if (m.id == "risorius_left")
        mixed[Eigen::Index(k)] += 0.7;
      mixed[Eigen::Index(k)] = std::min(1.0, mixed[Eigen::Index(k)]);
    }
    EXPECT_EQ(mixed[model->muscleIndex("risorius_left")], 1.0);
    model->positions(mixed, expected);
    EXPECT_LT(largestGap(face->polyData(), expected), 1e-9);
    setSlider(sneer, 0);
    setSlider(risorius, 0);
    EXPECT_LT(largestGap(face->polyData(), smileShape), 1e-9);
  }

  // Saved as "smile test", the sliders changed, then recalled.
  name->setText("smile test");
  QTest::mouseClick(save, Qt::LeftButton);
  workstation.settle(100);
  ExpressionNode* node = test::nodeNamed<ExpressionNode>(scene, "smile test");
  ASSERT_NE(node, nullptr) << workstation.errors();
  EXPECT_EQ(node->muscleSet(), model->muscleSetId);
  for (std::size_t k = 0; k < model->muscles.size(); ++k)
    EXPECT_DOUBLE_EQ(node->activation(model->muscles[k].id), smiling[Eigen::Index(k)]) << model->muscles[k].id;
  const std::map<std::string, double> savedActivations = node->activations();

  setSlider(smile, 0);
  setSlider(frown, 100);
  workstation.settle(100);
  EXPECT_GT(largestGap(face->polyData(), smileShape), 0.5) << "the frown should not look like the smile";
  workstation.screenshot("expression-frown");
  const int index = saved->findText("smile test");
  ASSERT_GE(index, 0);
  saved->setCurrentIndex(index);
  emit saved->activated(index); // as choosing it in the list does
  workstation.settle(100);
  EXPECT_EQ(smile->value(), 0);
  EXPECT_EQ(frown->value(), 0);
  for (std::size_t k = 0; k < model->muscles.size(); ++k)
  {
    auto* slider = workstation.widget<QSlider>("expression.muscle." + model->muscles[k].id);
    ASSERT_NE(slider, nullptr);
    EXPECT_EQ(slider->value(), int(std::lround(100.0 * smiling[Eigen::Index(k)]))) << model->muscles[k].id;
  }
  EXPECT_LT(largestGap(face->polyData(), smileShape), 1e-9);

  // Play: rest → the smile → rest, then back where the sliders are.
  const Eigen::Matrix3Xd beforePlay = pointsOf(face->polyData());
  QTest::mouseClick(play, Qt::LeftButton);
  double farthest = 0.0;
  for (int i = 0; i < 30; ++i)
  {
    workstation.settle(50);
    farthest = std::max(farthest, largestGap(face->polyData(), beforePlay));
  }
  EXPECT_GT(farthest, 0.5) << "the animation did not move the face";
  workstation.settle(2500);
  EXPECT_LT(largestGap(face->polyData(), beforePlay), 1e-12) << "Play did not end where it started";

  // The expression stays in the saved scene.
  const std::filesystem::path copy =
    std::filesystem::temp_directory_path() / ("caps-expression-" + std::to_string(::getpid()) + ".caps");
  std::filesystem::remove_all(copy);
  ASSERT_TRUE(workstation.window().saveSceneTo(copy)) << workstation.errors();
  ASSERT_FALSE(skin->visible()); // saved with the face showing and the skin hidden
  workstation.window().openPath(copy);
  ASSERT_TRUE(workstation.waitUntilIdle(300)) << workstation.errors();
  workstation.settle(200);
  ExpressionNode* reloaded = test::nodeNamed<ExpressionNode>(workstation.scene(), "smile test");
  ASSERT_NE(reloaded, nullptr);
  EXPECT_EQ(reloaded->activations(), savedActivations);
  EXPECT_GE(saved->findText("smile test"), 0);
  // A new scene: the model is gone with the old one, the sliders with it;
  // the face saved with the scene goes and the skin it hid comes back.
  EXPECT_FALSE(smile->isEnabled());
  EXPECT_EQ(test::nodeNamed<SurfaceNode>(workstation.scene(), "Face expression"), nullptr);
  ASSERT_NE(test::nodeNamed<SurfaceNode>(workstation.scene(), "Skin"), nullptr);
  EXPECT_TRUE(test::nodeNamed<SurfaceNode>(workstation.scene(), "Skin")->visible());
  std::filesystem::remove_all(copy);
  EXPECT_TRUE(workstation.window().reportedErrors().empty()) << workstation.errors();
}

// Export animation: the sliders' mix written played from rest and back,
// through the folder dialog; the peak frame differs from rest, the frames
// return through the same pictures, and with ffmpeg the MP4 is there.
TEST(ExpressionPanel, TheMixIsExportedAsAnAnimation)
{
  test::Workstation workstation;
  workstation.window().openPath(test::reportDemoFolder() / "sample.caps");
  ASSERT_TRUE(workstation.waitUntilIdle(300)) << workstation.errors();
  workstation.selectModule("expression");
  auto* build = workstation.widget<QPushButton>("expression.build");
  auto* smile = workstation.widget<QSlider>("expression.expression.smile");
  auto* exportButton = workstation.widget<QPushButton>("expression.export");
  ASSERT_TRUE(build && smile && exportButton);
  EXPECT_FALSE(exportButton->isEnabled()) << "no model yet";
  QTest::mouseClick(build, Qt::LeftButton);
  ASSERT_TRUE(workstation.waitUntil([&] { return exportButton->isEnabled(); }, 300)) << workstation.errors();
  ASSERT_TRUE(workstation.waitUntilIdle(60));

  // At rest there is nothing to animate: a message, no dialog.
  const std::size_t errorsBefore = workstation.window().reportedErrors().size();
  QTest::mouseClick(exportButton, Qt::LeftButton);
  ASSERT_EQ(workstation.window().reportedErrors().size(), errorsBefore + 1);
  EXPECT_NE(workstation.window().reportedErrors().back().find("at rest"), std::string::npos);

  setSlider(smile, 100);
  const std::filesystem::path folder = test::scratchFolder();
  answerFolderDialog(&workstation.window(), folder);
  QTest::mouseClick(exportButton, Qt::LeftButton);
  EXPECT_EQ(workstation.window().reportedErrors().size(), errorsBefore + 1) << workstation.errors();
  const std::filesystem::path frames = folder / "expression";
  ASSERT_TRUE(std::filesystem::exists(frames / "frame-0045.png")) << frames; // 24 out, 22 back
  EXPECT_FALSE(std::filesystem::exists(frames / "frame-0046.png"));
  const auto read = [](const std::filesystem::path& file) {
    QImage image(QString::fromStdString(file.string()));
    return image.convertToFormat(QImage::Format_RGB888);
  };
  const QImage rest = read(frames / "frame-0000.png"), peak = read(frames / "frame-0023.png");
  ASSERT_FALSE(rest.isNull());
  EXPECT_NE(rest, peak) << "the smile does not show in the animation";
  EXPECT_EQ(read(frames / "frame-0010.png"), read(frames / "frame-0036.png")) << "out and back differ";
  if (render::findFfmpeg())
  {
    EXPECT_TRUE(std::filesystem::exists(folder / "expression.mp4"));
  }
  const std::string status = workstation.window().statusBar()->currentMessage().toStdString();
  EXPECT_NE(status.find("46 frames"), std::string::npos) << status;
}

// Plan under expression (issue 8 item 5, §5.4): the demo's Z-plasty studied
// in the face model, its skin after the operation under the smile slider
// (against the logic's own study of the same plan), the bumps measured, then
// a fingertip placed by a click on that skin pushing it along a bent path.
TEST(ExpressionPanel, APlanStudiedUnderTheSmileAndPushedByAFingertip)
{
  test::Workstation workstation;
  workstation.window().openPath(test::reportDemoFolder() / "sample.caps");
  ASSERT_TRUE(workstation.waitUntilIdle(300)) << workstation.errors();
  Scene& scene = workstation.scene();
  workstation.selectModule("expression");
  auto* build = workstation.widget<QPushButton>("expression.build");
  auto* smile = workstation.widget<QSlider>("expression.expression.smile");
  auto* plans = workstation.widget<QComboBox>("expression.plan");
  auto* studyButton = workstation.widget<QPushButton>("expression.study");
  auto* bumps = workstation.widget<QLabel>("expression.bumps");
  auto* fingertip = workstation.widget<QPushButton>("expression.fingertip");
  auto* radius = workstation.widget<QDoubleSpinBox>("expression.push.radius");
  auto* up = workstation.widget<QDoubleSpinBox>("expression.push.up");
  auto* in = workstation.widget<QDoubleSpinBox>("expression.push.in");
  auto* corner = workstation.widget<QPushButton>("expression.push.waypoint");
  auto* travel = workstation.widget<QSlider>("expression.push.travel");
  auto* planStatus = workstation.widget<QLabel>("expression.planStatus");
  auto* info = workstation.widget<QLabel>("expression.info");
  ASSERT_TRUE(build && smile && plans && studyButton && bumps && fingertip && radius && up && in && corner && travel &&
              planStatus && info);
  EXPECT_FALSE(plans->isVisible()) << "the plan group shows before the face model";

  QTest::mouseClick(build, Qt::LeftButton);
  ASSERT_TRUE(
    workstation.waitUntil([&] { return test::nodeNamed<SurfaceNode>(scene, "Face expression") != nullptr; }, 300))
    << workstation.errors();
  ASSERT_TRUE(workstation.waitUntilIdle(60));
  ASSERT_TRUE(plans->isVisible());
  const int zIndex = plans->findText("Z-plasty 1");
  ASSERT_GE(zIndex, 0) << "the demo's predicted Z-plasty is not offered";
  EXPECT_GE(plans->count(), 2) << "the demo has two predicted plans";
  plans->setCurrentIndex(zIndex);
  EXPECT_FALSE(fingertip->isEnabled()) << "a fingertip before a plan is studied";

  const auto started = std::chrono::steady_clock::now();
  QTest::mouseClick(studyButton, Qt::LeftButton);
  ASSERT_TRUE(workstation.waitUntil(
    [&] { return test::nodeNamed<SurfaceNode>(scene, "Z-plasty 1 under expression") != nullptr; }, 300))
    << workstation.errors() << planStatus->text().toStdString();
  ASSERT_TRUE(workstation.waitUntilIdle(60));
  const double studySeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::cout << "[plan under expression] studied in " << studySeconds << " s: " << planStatus->text().toStdString()
            << "\n";
  SurfaceNode* planSkin = test::nodeNamed<SurfaceNode>(scene, "Z-plasty 1 under expression");
  ASSERT_NE(planSkin, nullptr);
  EXPECT_TRUE(planSkin->visible());
  EXPECT_EQ(planSkin->colourArray(), "skin_colour");
  SurfaceNode* faceNode = test::nodeNamed<SurfaceNode>(scene, "Face expression");
  ASSERT_NE(faceNode, nullptr);
  EXPECT_TRUE(faceNode->visible()) << "the face frames the plan's skin";
  const vtkIdType faceCells = faceNode->polyData()->GetNumberOfCells();
  ASSERT_NE(test::nodeNamed<SurfaceNode>(scene, "Z-plasty 1 skin after"), nullptr);
  EXPECT_FALSE(test::nodeNamed<SurfaceNode>(scene, "Z-plasty 1 skin after")->visible());
  std::cout << "[plan under expression] at rest: " << bumps->text().toStdString() << "\n";
  EXPECT_TRUE(bumps->text().contains("mm at rest")) << bumps->text().toStdString();

  // The same study made here from the logic, from the same scene.
  ExpressionLogic logic(scene);
  expression::PlanStudyInput input;
  input.model = expression::buildExpressionModel(logic.modelInput());
  ASSERT_NE(input.model, nullptr);
  const PlanNode* planNode = nullptr;
  for (Node* n : scene.nodesOfType(NodeType::Plan))
    if (n->name() == "Z-plasty 1")
      planNode = static_cast<const PlanNode*>(n);
  ASSERT_NE(planNode, nullptr);
  input.planName = "Z-plasty 1";
  input.plan = IncisionLogic::readPlan(*planNode);
  input.options = IncisionLogic::simulationOptions(*planNode);
  const auto* skinNode = scene.nodeAs<RangeMapNode>(planNode->rangeMapId());
  ASSERT_NE(skinNode, nullptr);
  input.skin = RangeMapLogic::toRangeMap(*skinNode);
  for (Node* n : scene.nodesOfType(NodeType::RangeMap))
    if (static_cast<RangeMapNode*>(n)->role() == "bone")
      input.bone = RangeMapLogic::toRangeMap(*static_cast<RangeMapNode*>(n));
  const std::unique_ptr<expression::PlanStudy> study = expression::PlanStudy::build(input);
  ASSERT_NE(study, nullptr);
  // The face shown around the plan: every cell of the face at rest but
  // those under the plan's region, so they do not cover its skin.
  {
    const auto fullFace = expression::expressionPolyData(*input.model);
    const std::vector<char> under = study->faceCellsUnderPlan(fullFace);
    const auto covered = std::count(under.begin(), under.end(), char(1));
    EXPECT_GT(covered, 0);
    EXPECT_EQ(faceCells, fullFace->GetNumberOfCells() - vtkIdType(covered));
  }
  ASSERT_EQ(planSkin->polyData()->GetNumberOfPoints(), study->surface().vertexCount());
  Eigen::Matrix3Xd expected;
  const Eigen::VectorXd atRest = Eigen::VectorXd::Zero(study->muscleCount());
  study->positions(atRest, expected);
  EXPECT_LT(largestGap(planSkin->polyData(), expected), 1e-6);
  const Eigen::Matrix3Xd rest = expected;
  workstation.screenshot("expression-plan-rest");

  // The smile slider moves the plan's skin: the study's superposition for the smile's activations.
  setSlider(smile, 100);
  workstation.settle(600); // the bumps are measured once the slider rests
  const auto& definitions = expression::builtInExpressions();
  const auto smileDefinition =
    std::find_if(definitions.begin(), definitions.end(), [](const auto& e) { return e.name == "smile"; });
  ASSERT_NE(smileDefinition, definitions.end());
  const Eigen::VectorXd smiling = expression::expressionActivations(*smileDefinition, input.model->muscles);
  study->positions(smiling, expected);
  EXPECT_LT(largestGap(planSkin->polyData(), expected), 1e-6);
  EXPECT_GT(largestGap(planSkin->polyData(), rest), 0.3) << "the smile does not move the plan's skin";
  const expression::ContourComparison smilingBumps = study->compare(smiling);
  std::cout << "[plan under expression] smiling: " << bumps->text().toStdString() << " | " << info->text().toStdString()
            << "\n";
  EXPECT_TRUE(bumps->text().contains(QString::number(smilingBumps.loaded.largest, 'f', 2) + " mm now"))
    << bumps->text().toStdString() << " vs " << smilingBumps.loaded.largest;
  EXPECT_TRUE(bumps->text().contains(QString::number(smilingBumps.largestHeightChange, 'f', 2)))
    << bumps->text().toStdString();
  workstation.screenshot("expression-plan-smile");
  largeFaceShot(workstation, "expression-plan-smile-large");

  // A fingertip 12 mm below the cut's first point: the display vertex there,
  // clicked where it shows, is where the fingertip rests (its place after
  // the operation, whatever the sliders show).
  const planning::PlanPrediction& p = study->prediction();
  const fem::ChartPoint aim = p.surface.mesh.vertices[0] + fem::ChartPoint(0.0, -12.0);
  std::size_t nearest = 0;
  for (std::size_t v = 0; v < p.surface.mesh.vertices.size(); ++v)
    if ((p.surface.mesh.vertices[v] - aim).norm() < (p.surface.mesh.vertices[nearest] - aim).norm())
      nearest = v;
  const int node = p.continuum.vertexColumns[nearest].front();
  const Eigen::Vector3d below = p.continuum.mesh.nodes.col(node) + p.displacements.segment<3>(3 * Eigen::Index(node));
  Eigen::Index vertex = 0;
  (rest.colwise() - below).colwise().squaredNorm().minCoeff(&vertex);
  const Eigen::Matrix3Xd shown = pointsOf(planSkin->polyData());
  ASSERT_TRUE(fingertip->isEnabled());
  radius->setValue(4.0);
  QTest::mouseClick(fingertip, Qt::LeftButton);
  workstation.settle(100);
  const Eigen::Vector3d target = shown.col(vertex);
  workstation.clickThreeDView(workstation.threeDViewPointOf({target.x(), target.y(), target.z()}));
  ASSERT_TRUE(workstation.waitUntil([&] { return travel->isEnabled(); }, 60))
    << workstation.errors() << planStatus->text().toStdString();
  ASSERT_TRUE(workstation.waitUntilIdle(60));
  std::cout << "[plan under expression] " << planStatus->text().toStdString() << "\n";
  EXPECT_TRUE(workstation.window().reportedErrors().empty()) << workstation.errors();
  study->setFingertip(study->restSkinPoint(vertex), 4.0);
  const expression::Fingertip& tip = study->currentFingertip();

  // Up 6 mm, half way: the study's push at half the travel.
  up->setValue(6.0);
  setSlider(travel, 50);
  workstation.settle(600);
  expression::PushPath path;
  path.centre = tip.centre;
  path.radius = 4.0;
  path.waypoints = {tip.directions * Eigen::Vector3d(6.0, 0.0, 0.0)};
  study->pushedPositions(path.travelAt(0.5), expected);
  EXPECT_LT(largestGap(planSkin->polyData(), expected), 1e-6);
  const Eigen::Vector3d moved = pointsOf(planSkin->polyData()).col(vertex) - rest.col(vertex);
  std::cout << "[plan under expression] pushed half way: the fingertip's vertex moves " << moved.transpose()
            << " (expected " << path.travelAt(0.5).transpose() << "); " << bumps->text().toStdString() << " | "
            << info->text().toStdString() << "\n";
  EXPECT_LT((moved - path.travelAt(0.5)).norm(), 0.5) << "the skin under the fingertip does not follow it";
  EXPECT_TRUE(bumps->text().contains("mm now")) << bumps->text().toStdString();

  // A corner at 6 mm up, then 3 mm in: the path bends; at 80 % it is on the second leg.
  QTest::mouseClick(corner, Qt::LeftButton);
  in->setValue(3.0);
  setSlider(travel, 80);
  workstation.settle(600);
  path.waypoints = {tip.directions * Eigen::Vector3d(6.0, 0.0, 0.0), tip.directions * Eigen::Vector3d(6.0, 0.0, 3.0)};
  study->pushedPositions(path.travelAt(0.8), expected);
  EXPECT_LT(largestGap(planSkin->polyData(), expected), 1e-6);
  const expression::ContourComparison pushedBumps = study->comparePush(path.travelAt(0.8));
  EXPECT_TRUE(bumps->text().contains(QString::number(pushedBumps.loaded.largest, 'f', 2) + " mm now"))
    << bumps->text().toStdString() << " vs " << pushedBumps.loaded.largest;
  std::cout << "[plan under expression] bent path at 80 %: " << bumps->text().toStdString() << "\n";
  workstation.screenshot("expression-plan-pushed");
  largeFaceShot(workstation, "expression-plan-pushed-large");

  // The push exported frame by frame along the bent path, out and back.
  {
    const std::filesystem::path folder = test::scratchFolder();
    answerFolderDialog(&workstation.window(), folder);
    QTest::mouseClick(workstation.widget<QPushButton>("expression.export"), Qt::LeftButton);
    EXPECT_TRUE(workstation.window().reportedErrors().empty()) << workstation.errors();
    const std::filesystem::path frames = folder / "Z-plasty-1-pushed";
    ASSERT_TRUE(std::filesystem::exists(frames / "frame-0045.png")) << frames;
    EXPECT_FALSE(std::filesystem::exists(frames / "frame-0046.png"));
    const QImage first(QString::fromStdString((frames / "frame-0000.png").string()));
    const QImage peak(QString::fromStdString((frames / "frame-0023.png").string()));
    ASSERT_FALSE(first.isNull());
    EXPECT_NE(first.convertToFormat(QImage::Format_RGB888), peak.convertToFormat(QImage::Format_RGB888))
      << "the push does not show in the animation";
    std::filesystem::copy_file(frames / "frame-0023.png",
                               test::workstationArtifacts() / "expression-plan-push-frame.png",
                               std::filesystem::copy_options::overwrite_existing);
  }

  // Back to the muscles: a slider move shows the expression again.
  setSlider(smile, 50);
  study->positions(0.5 * smiling, expected);
  EXPECT_LT(largestGap(planSkin->polyData(), expected), 1e-6);

  // Leaving the study: the plan's skin goes, the face comes back.
  auto* leave = workstation.widget<QPushButton>("expression.leaveStudy");
  ASSERT_NE(leave, nullptr);
  QTest::mouseClick(leave, Qt::LeftButton);
  workstation.settle(100);
  EXPECT_EQ(test::nodeNamed<SurfaceNode>(scene, "Z-plasty 1 under expression"), nullptr);
  EXPECT_TRUE(test::nodeNamed<SurfaceNode>(scene, "Face expression")->visible());
  EXPECT_GT(test::nodeNamed<SurfaceNode>(scene, "Face expression")->polyData()->GetNumberOfCells(), faceCells)
    << "the whole face again";
  EXPECT_FALSE(fingertip->isEnabled());
  EXPECT_TRUE(workstation.window().reportedErrors().empty()) << workstation.errors();
}

TEST(ExpressionPanel, WithoutRangeMapsTheErrorSaysWhatToDo)
{
  test::Workstation workstation;
  workstation.selectModule("expression");
  auto* build = workstation.widget<QPushButton>("expression.build");
  ASSERT_NE(build, nullptr);
  QTest::mouseClick(build, Qt::LeftButton);
  workstation.settle(200);
  const std::string errors = workstation.errors();
  EXPECT_NE(errors.find("range map"), std::string::npos) << errors;
  EXPECT_NE(errors.find("Range maps module"), std::string::npos) << errors;
  EXPECT_EQ(workstation.scene().nodesOfType(NodeType::Surface).size(), 0u);
}

} // namespace
} // namespace caps
