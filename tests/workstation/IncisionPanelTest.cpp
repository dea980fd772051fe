// The incision editor (issue 6 item 4) driven as a surgeon drives it: a
// Z-plasty placed by a click on the demo scene's skin, its lines on the
// skin, its measurements against the logic's, a parameter changed, undone
// and redone, a predicted plan edited, the plan deleted.

#include <cmath>
#include <numbers>
#include <optional>

#include <QCheckBox>
#include <QDoubleSpinBox>
#include <QLabel>
#include <QListWidget>
#include <QPushButton>
#include <QSpinBox>
#include <QTableWidget>

#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkRenderer.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkUnsignedCharArray.h>

#include "Workstation.h"
#include "modules/incision/IncisionLogic.h"
#include "planning/PlanLines.h"
#include "planning/SkinTensionLines.h"
#include "segmentation/LandmarkPlacement.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "report/DemoScene.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/SurfaceNode.h"

namespace caps {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

const RangeMapNode* newestSkin(Scene& scene)
{
  const RangeMapNode* skin = nullptr;
  for (Node* n : scene.nodesOfType(NodeType::RangeMap))
    if (static_cast<RangeMapNode*>(n)->role() == "skin")
      skin = static_cast<RangeMapNode*>(n);
  return skin;
}

/// The table's value in the row whose first cell reads @a what; NaN when none.
double tableValue(QTableWidget* table, const QString& what)
{
  for (int r = 0; r < table->rowCount(); ++r)
    if (table->item(r, 0) && table->item(r, 0)->text() == what && table->item(r, 1))
      return table->item(r, 1)->text().toDouble();
  return std::nan("");
}

/// The world position of the cut points' vertices of a lines polydata, in order.
std::vector<Eigen::Vector3d> vertexPositions(vtkPolyData* lines)
{
  std::vector<Eigen::Vector3d> points;
  vtkCellArray* verts = lines->GetVerts();
  verts->InitTraversal();
  vtkIdType n = 0;
  const vtkIdType* ids = nullptr;
  while (verts->GetNextCell(n, ids))
  {
    double p[3];
    lines->GetPoint(ids[0], p);
    points.emplace_back(p[0], p[1], p[2]);
  }
  return points;
}

/// The largest distance of a line point from kIncisionLineLift above the skin map.
double worstLiftError(vtkPolyData* lines, const seg::RangeMap& skin)
{
  double worst = 0.0;
  for (vtkIdType i = 0; i < lines->GetNumberOfPoints(); ++i)
  {
    double p[3];
    lines->GetPoint(i, p);
    const seg::CylindricalPoint c = skin.frame().toCylindrical(Eigen::Vector3d(p[0], p[1], p[2]));
    worst = std::max(worst, std::abs(c.r - skin.sample(c.theta, c.z) - planning::kIncisionLineLift));
  }
  return worst;
}

/// A camera @a distance mm straight out from @a focus (on the skin at θ
/// @a theta), the head's axis up: the skin there seen face on.
SnapshotNode::Camera cameraFacing(const seg::CylindricalFrame& frame, const Eigen::Vector3d& focus, double theta,
                                  double distance)
{
  SnapshotNode::Camera camera;
  const Eigen::Vector3d eye = focus + distance * frame.radialDirection(theta);
  const Eigen::Vector3d up = frame.direction();
  camera.position = {eye.x(), eye.y(), eye.z()};
  camera.focalPoint = {focus.x(), focus.y(), focus.z()};
  camera.viewUp = {up.x(), up.y(), up.z()};
  return camera;
}

/// Hides the demo's predicted skins ("NAME skin after"), as a surgeon hides
/// them to draw on the skin beneath.
void hidePredictedSkins(Scene& scene)
{
  for (Node* n : scene.nodesOfType(NodeType::Surface))
    if (n->name().size() > 11 && n->name().substr(n->name().size() - 11) == " skin after")
      static_cast<SurfaceNode*>(n)->setVisible(false);
}

/// Checks the plan's lines against the plan and the skin: every point lift
/// mm outside the skin, one vertex per cut point at its lifted skin point.
void expectLinesOnSkin(vtkPolyData* lines, const planning::IncisionPlan& plan, const seg::RangeMap& skin)
{
  ASSERT_NE(lines, nullptr);
  ASSERT_GT(lines->GetNumberOfLines(), 0);
  EXPECT_LT(worstLiftError(lines, skin), 1.0) << "a line point is not lifted 0.5 mm off the skin map";
  const std::vector<Eigen::Vector3d> vertices = vertexPositions(lines);
  const planning::SkinChart chart = plan.chart(skin);
  const std::vector<planning::ChartPoint> path = plan.chartPath(chart);
  ASSERT_EQ(vertices.size(), path.size());
  for (std::size_t i = 0; i < path.size(); ++i)
    EXPECT_NEAR((vertices[i] - chart.lift(path[i])).norm(), planning::kIncisionLineLift, 0.05) << "cut point " << i;
}

void click(QPushButton* button)
{
  ASSERT_NE(button, nullptr);
  ASSERT_TRUE(button->isEnabled()) << button->objectName().toStdString();
  QTest::mouseClick(button, Qt::LeftButton);
}

void selectPlan(QListWidget* list, const std::string& name)
{
  const auto items = list->findItems(QString::fromStdString(name), Qt::MatchExactly);
  ASSERT_EQ(items.size(), 1) << name;
  list->setCurrentItem(items.front());
  items.front()->setSelected(true);
}

} // namespace

TEST(IncisionPanel, PlaceMeasureEditUndoDelete)
{
  test::Workstation workstation;
  Scene& scene = workstation.scene();
  workstation.window().openPath(test::reportDemoFolder() / "sample.caps");
  ASSERT_TRUE(workstation.waitUntilIdle(60)) << workstation.errors();
  const RangeMapNode* skinNode = newestSkin(scene);
  ASSERT_NE(skinNode, nullptr) << "the demo scene has no skin range map";
  const seg::RangeMap skin = RangeMapLogic::toRangeMap(*skinNode);
  PlanNode* demoPlan = test::nodeNamed<PlanNode>(scene, "Z-plasty 1");
  ASSERT_NE(demoPlan, nullptr);

  // The skin point of the demo's Z-plasty: θ = -40°, z = -47 mm.
  const double theta = -40.0 * kDegree, z = -47.0;
  const double r = skin.sample(theta, z);
  ASSERT_TRUE(std::isfinite(r));
  const Eigen::Vector3d target = skin.frame().toWorld(r, theta, z);
  // Looked at from straight outside, so the point is in view.
  workstation.window().setThreeDViewCamera(cameraFacing(skin.frame(), target, theta, 180.0));
  // The demo's predicted skin covers the cheek where the new plan goes: hidden,
  // as a surgeon hides it to draw there (the click then lands on the skin).
  hidePredictedSkins(scene);

  workstation.selectModule("incision");
  auto* procedure = workstation.widget<QComboBox>("incision.procedure");
  ASSERT_NE(procedure, nullptr);
  const int zIndex = procedure->findData("z-plasty");
  ASSERT_GE(zIndex, 0);
  procedure->setCurrentIndex(zIndex);
  workstation.settle(100);
  auto* limbAngle = workstation.widget<QDoubleSpinBox>("incision.param.limb_angle");
  ASSERT_NE(limbAngle, nullptr);
  EXPECT_NEAR(limbAngle->value(), 60.0, 1e-9);
  EXPECT_EQ(limbAngle->suffix().trimmed().toStdString(), "°");
  EXPECT_NEAR(limbAngle->minimum(), 30.0, 1e-9);
  EXPECT_NEAR(limbAngle->maximum(), 90.0, 1e-9);

  const std::size_t plansBefore = scene.nodesOfType(NodeType::Plan).size();
  click(workstation.widget<QPushButton>("incision.place"));
  workstation.clickThreeDView(workstation.threeDViewPointOf({target.x(), target.y(), target.z()}));
  ASSERT_TRUE(workstation.waitUntil([&] { return scene.nodesOfType(NodeType::Plan).size() == plansBefore + 1; }, 10))
    << workstation.errors();
  PlanNode* planNode = test::nodeNamed<PlanNode>(scene, "Z-plasty 2");
  ASSERT_NE(planNode, nullptr) << "the new plan is not named Z-plasty 2";
  const NodeId planId = planNode->id();
  EXPECT_EQ(planNode->rangeMapId(), skinNode->id());
  const planning::IncisionPlan placed = IncisionLogic::readPlan(*planNode);
  EXPECT_EQ(placed.procedure(), "z-plasty");
  {
    const double rc = skin.sample(placed.centre().theta, placed.centre().z);
    const Eigen::Vector3d centre = skin.frame().toWorld(rc, placed.centre().theta, placed.centre().z);
    EXPECT_LT((centre - target).norm(), 1.5)
      << "centre at theta " << placed.centre().theta / kDegree << " deg, z " << placed.centre().z;
  }
  // The recipe replays to the very same plan, on the CT the demo plan names.
  {
    IncisionLogic logic(scene);
    const auto recipe = IncisionLogic::readRecipe(*planNode);
    ASSERT_TRUE(recipe.has_value());
    EXPECT_EQ(recipe->ctSha256, demoPlan->ctSha256());
    EXPECT_FALSE(recipe->ctSha256.empty());
    ASSERT_EQ(recipe->operations.size(), 1u);
    const planning::IncisionPlan replayed = logic.applyRecipe(*recipe, skin);
    PlanNode a, b;
    IncisionLogic::writePlan(placed, a);
    IncisionLogic::writePlan(replayed, b);
    EXPECT_EQ(a.toJson(), b.toJson());
  }

  // Its lines on the skin.
  SurfaceNode* lines = test::nodeNamed<SurfaceNode>(scene, "Z-plasty 2 incision");
  ASSERT_NE(lines, nullptr);
  EXPECT_DOUBLE_EQ(lines->lineWidth(), 3.0);
  expectLinesOnSkin(lines->polyData(), placed, skin);

  // The new plan is selected; its measurements are the logic's.
  auto* list = workstation.widget<QListWidget>("incision.plans");
  ASSERT_NE(list, nullptr);
  ASSERT_EQ(list->selectedItems().size(), 1);
  EXPECT_EQ(list->selectedItems().front()->text().toStdString(), "Z-plasty 2");
  auto* table = workstation.widget<QTableWidget>("incision.measurements");
  ASSERT_NE(table, nullptr);
  {
    const planning::PlanMeasurements m = planning::measurePlan(placed, skin);
    ASSERT_EQ(m.limbs.size(), 3u);
    for (const auto& l : m.limbs)
      EXPECT_NEAR(tableValue(table, QString("Limb p%1–p%2").arg(l.from).arg(l.to)), l.skin, 0.05);
    for (const auto& a : m.limbAngles)
      EXPECT_NEAR(tableValue(table, QString("Angle at p%1").arg(a.point)), a.skin / kDegree, 0.05);
    EXPECT_NEAR(tableValue(table, "Theoretical gain in length (Fig. 2.2)"), 75.0, 0.5); // Fig. 2.2: 60° → 75 %
  }
  workstation.screenshot("incision-placed");

  // Limb angle 60° → 45°: the plan is placed again, and undo gives it back exactly.
  const nlohmann::json before = planNode->toJson();
  limbAngle->setValue(45.0);
  ASSERT_TRUE(workstation.waitUntil([&] { return planNode->toJson() != before; }, 5)) << workstation.errors();
  const nlohmann::json after = planNode->toJson();
  const planning::IncisionPlan changed = IncisionLogic::readPlan(*planNode);
  EXPECT_NEAR(changed.parameters().at("limb_angle"), 45.0 * kDegree, 1e-12);
  EXPECT_NEAR(changed.centre().theta, placed.centre().theta, 1e-12);
  EXPECT_NE(changed.cutPath(), placed.cutPath());
  {
    IncisionLogic logic(scene);
    const auto recipe = IncisionLogic::readRecipe(*planNode);
    ASSERT_TRUE(recipe.has_value());
    EXPECT_EQ(recipe->operations.size(), 2u);
    PlanNode replayed;
    IncisionLogic::writePlan(logic.applyRecipe(*recipe, skin), replayed);
    PlanNode direct;
    IncisionLogic::writePlan(changed, direct);
    EXPECT_EQ(replayed.toJson(), direct.toJson());
    const planning::PlanMeasurements m = planning::measurePlan(changed, skin);
    for (const auto& l : m.limbs)
      EXPECT_NEAR(tableValue(table, QString("Limb p%1–p%2").arg(l.from).arg(l.to)), l.skin, 0.05);
    for (const auto& a : m.limbAngles)
      EXPECT_NEAR(tableValue(table, QString("Angle at p%1").arg(a.point)), a.skin / kDegree, 0.05);
  }
  expectLinesOnSkin(test::nodeNamed<SurfaceNode>(scene, "Z-plasty 2 incision")->polyData(), changed, skin);

  click(workstation.widget<QPushButton>("incision.undo"));
  ASSERT_TRUE(workstation.waitUntil([&] { return planNode->toJson() == before; }, 5));
  EXPECT_NEAR(limbAngle->value(), 60.0, 1e-9);
  workstation.settle(100);
  expectLinesOnSkin(test::nodeNamed<SurfaceNode>(scene, "Z-plasty 2 incision")->polyData(), placed, skin);
  click(workstation.widget<QPushButton>("incision.redo"));
  ASSERT_TRUE(workstation.waitUntil([&] { return planNode->toJson() == after; }, 5));
  // The keys do the same while the panel has focus.
  workstation.window().activateWindow();
  QApplication::setActiveWindow(&workstation.window());
  list->setFocus();
  workstation.settle(100);
  EXPECT_TRUE(list->hasFocus());
  QTest::keyClick(list, Qt::Key_Z, Qt::ControlModifier);
  EXPECT_TRUE(workstation.waitUntil([&] { return planNode->toJson() == before; }, 5)) << "Ctrl+Z did not undo";
  QTest::keyClick(list, Qt::Key_Z, Qt::ControlModifier | Qt::ShiftModifier);
  EXPECT_TRUE(workstation.waitUntil([&] { return planNode->toJson() == after; }, 5)) << "Ctrl+Shift+Z did not redo";
  workstation.settle(100);
  expectLinesOnSkin(test::nodeNamed<SurfaceNode>(scene, "Z-plasty 2 incision")->polyData(), changed, skin);
  workstation.screenshot("incision-editor");

  // Move: its centre re-picked 8° further round the face.
  {
    const double theta2 = theta + 8.0 * kDegree;
    const Eigen::Vector3d to = skin.frame().toWorld(skin.sample(theta2, z), theta2, z);
    click(workstation.widget<QPushButton>("incision.move"));
    workstation.clickThreeDView(workstation.threeDViewPointOf({to.x(), to.y(), to.z()}));
    ASSERT_TRUE(workstation.waitUntil([&] { return planNode->toJson() != after; }, 5)) << workstation.errors();
    const planning::IncisionPlan moved = IncisionLogic::readPlan(*planNode);
    const Eigen::Vector3d centre =
      skin.frame().toWorld(skin.sample(moved.centre().theta, moved.centre().z), moved.centre().theta, moved.centre().z);
    EXPECT_LT((centre - to).norm(), 1.5);
    EXPECT_NEAR(moved.parameters().at("limb_angle"), 45.0 * kDegree, 1e-12) << "a move keeps the parameters";
    click(workstation.widget<QPushButton>("incision.undo"));
    ASSERT_TRUE(workstation.waitUntil([&] { return planNode->toJson() == after; }, 5));
  }

  // A click on the background places nothing.
  click(workstation.widget<QPushButton>("incision.place"));
  {
    // From further out, a corner or an edge of the view shows no surface.
    workstation.window().setThreeDViewCamera(cameraFacing(skin.frame(), target, theta, 900.0));
    workstation.settle(100);
    std::optional<QPoint> background;
    const QSize size = workstation.threeDView().size();
    for (const QPoint& p : {QPoint(3, 3), QPoint(size.width() - 4, 3), QPoint(3, size.height() - 4),
                            QPoint(size.width() - 4, size.height() - 4), QPoint(3, size.height() / 2)})
    {
      std::string key;
      std::array<double, 3> at{};
      if (!workstation.threeDView().pickSurface(p.x(), p.y(), key, at))
      {
        background = p;
        break;
      }
    }
    ASSERT_TRUE(background.has_value()) << "the surfaces fill the whole 3D view";
    workstation.clickThreeDView(*background);
  }
  workstation.settle(300);
  EXPECT_EQ(scene.nodesOfType(NodeType::Plan).size(), plansBefore + 1);

  // Editing a predicted plan keeps its prediction, marked out of date.
  auto* status = workstation.widget<QLabel>("incision.predictionStatus");
  ASSERT_NE(status, nullptr);
  selectPlan(list, "Z-plasty 1");
  workstation.settle(100);
  EXPECT_TRUE(status->text().isEmpty()) << status->text().toStdString();
  auto* length = workstation.widget<QDoubleSpinBox>("incision.param.central_length");
  ASSERT_NE(length, nullptr);
  const nlohmann::json demoBefore = demoPlan->toJson();
  length->setValue(length->value() - 2.0);
  ASSERT_TRUE(workstation.waitUntil([&] { return demoPlan->toJson() != demoBefore; }, 5)) << workstation.errors();
  EXPECT_NE(test::nodeNamed<SurfaceNode>(scene, "Z-plasty 1 skin after"), nullptr);
  EXPECT_NE(status->text().indexOf("out of date"), -1) << status->text().toStdString();
  workstation.screenshot("incision-prediction-out-of-date");
  click(workstation.widget<QPushButton>("incision.undo"));
  ASSERT_TRUE(workstation.waitUntil([&] { return demoPlan->toJson() == demoBefore; }, 5));
  EXPECT_TRUE(status->text().isEmpty()) << status->text().toStdString();

  // An excision selected: drawn with its hole border; its excised area is the logic's.
  {
    PlanNode* ellipse = test::nodeNamed<PlanNode>(scene, "Elliptical excision 2");
    ASSERT_NE(ellipse, nullptr);
    selectPlan(list, ellipse->name());
    workstation.settle(200);
    const planning::IncisionPlan plan = IncisionLogic::readPlan(*ellipse);
    ASSERT_TRUE(plan.isExcision());
    SurfaceNode* ellipseLines = test::nodeNamed<SurfaceNode>(scene, "Elliptical excision 2 incision");
    ASSERT_NE(ellipseLines, nullptr);
    EXPECT_EQ(ellipseLines->polyData()->GetNumberOfLines(), 2) << "the cut and the hole border";
    expectLinesOnSkin(ellipseLines->polyData(), plan, skin);
    const double area = planning::excisedArea(plan, skin);
    EXPECT_GT(area, 10.0);
    EXPECT_NEAR(tableValue(table, "Excised area"), area, 0.05);
  }

  // Delete: the plan and its lines go.
  selectPlan(list, "Z-plasty 2");
  workstation.settle(100);
  click(workstation.widget<QPushButton>("incision.delete"));
  ASSERT_TRUE(workstation.waitUntil([&] { return scene.node(planId) == nullptr; }, 5));
  workstation.settle(100);
  EXPECT_EQ(test::nodeNamed<SurfaceNode>(scene, "Z-plasty 2 incision"), nullptr);
  EXPECT_EQ(list->findItems("Z-plasty 2", Qt::MatchExactly).size(), 0);
  EXPECT_NE(test::nodeNamed<PlanNode>(scene, "Z-plasty 1"), nullptr);
}

// Editing a plan by hand (the recipe's operations from the panel): a cut
// point moved by a click on the skin, a border point offset into an
// excision, a region undermined by clicking its corners; each undoable, and
// the recipe replays to the plan shown.
TEST(IncisionPanel, PointsOffsetsAndUnderminingByHand)
{
  test::Workstation workstation;
  Scene& scene = workstation.scene();
  workstation.window().openPath(test::reportDemoFolder() / "sample.caps");
  ASSERT_TRUE(workstation.waitUntilIdle(60)) << workstation.errors();
  const seg::RangeMap skin = RangeMapLogic::toRangeMap(*newestSkin(scene));
  const seg::CylindricalFrame& frame = skin.frame();
  PlanNode* node = test::nodeNamed<PlanNode>(scene, "Z-plasty 1");
  ASSERT_NE(node, nullptr);
  const NodeId planId = node->id();
  hidePredictedSkins(scene);
  auto skinPoint = [&](double theta, double z) { return frame.toWorld(skin.sample(theta, z), theta, z); };
  auto chartOf = [&](const Eigen::Vector2d& n) {
    const seg::CylindricalPoint c = frame.fromNormalized({1.0, n.x(), n.y()});
    return std::pair{c.theta, c.z};
  };
  const planning::IncisionPlan original = IncisionLogic::readPlan(*node);
  const auto [t1, z1] = chartOf(original.cutPath()[1]);
  workstation.window().setThreeDViewCamera(cameraFacing(frame, skinPoint(t1, z1), t1, 180.0));
  workstation.selectModule("incision");
  auto* list = workstation.widget<QListWidget>("incision.plans");
  ASSERT_NE(list, nullptr);
  selectPlan(list, "Z-plasty 1");
  workstation.settle(100);
  auto click3d = [&](const Eigen::Vector3d& p) {
    workstation.clickThreeDView(workstation.threeDViewPointOf({p.x(), p.y(), p.z()}));
  };

  // Cut point p1 moved 3 mm up the face by a click there.
  auto* point = workstation.widget<QSpinBox>("incision.point");
  ASSERT_NE(point, nullptr);
  point->setValue(1);
  const Eigen::Vector3d moveTo = skinPoint(t1, z1 + 3.0);
  click(workstation.widget<QPushButton>("incision.movePoint"));
  click3d(moveTo);
  workstation.settle(200);
  ASSERT_TRUE(workstation.errors().empty()) << workstation.errors();
  node = scene.nodeAs<PlanNode>(planId);
  const planning::IncisionPlan moved = IncisionLogic::readPlan(*node);
  {
    const auto [t, z] = chartOf(moved.cutPath()[1]);
    EXPECT_LT((skinPoint(t, z) - moveTo).norm(), 1.5);
    EXPECT_EQ(moved.cutPath()[0], original.cutPath()[0]);
  }
  click(workstation.widget<QPushButton>("incision.undo"));
  workstation.settle(100);
  EXPECT_EQ(IncisionLogic::readPlan(*scene.nodeAs<PlanNode>(planId)).cutPath(), original.cutPath());
  click(workstation.widget<QPushButton>("incision.redo"));
  workstation.settle(100);

  // Border point 1 (a side of p1) offset 1 mm along the bisector of the
  // corner at p1: an excision. Which side of the cut the vertex is on
  // depends on the loop's turn; the offset across the cut is refused with a message.
  auto* border = workstation.widget<QSpinBox>("incision.borderPoint");
  auto* u = workstation.widget<QDoubleSpinBox>("incision.offsetU");
  auto* v = workstation.widget<QDoubleSpinBox>("incision.offsetV");
  ASSERT_TRUE(border && u && v);
  border->setValue(1);
  const planning::IncisionPlan current = IncisionLogic::readPlan(*scene.nodeAs<PlanNode>(planId));
  const std::vector<planning::ChartPoint> path = current.chartPath(current.chart(skin));
  const planning::ChartPoint across =
    ((path[0] - path[1]).normalized() + (path[2] - path[1]).normalized()).normalized();
  planning::ChartPoint applied = planning::ChartPoint::Zero();
  for (double side : {1.0, -1.0})
  {
    const std::size_t errorsBefore = workstation.window().reportedErrors().size();
    u->setValue(side * across.x());
    v->setValue(side * across.y());
    click(workstation.widget<QPushButton>("incision.offset"));
    workstation.settle(100);
    if (workstation.window().reportedErrors().size() == errorsBefore)
    {
      applied = planning::ChartPoint(u->value(), v->value());
      break;
    }
  }
  ASSERT_GT(applied.norm(), 0.5) << workstation.errors();
  const planning::IncisionPlan excised = IncisionLogic::readPlan(*scene.nodeAs<PlanNode>(planId));
  EXPECT_TRUE(excised.isExcision());
  EXPECT_NEAR((excised.borderOffsets()[1] - applied).norm(), 0.0, 1e-12);
  EXPECT_GT(tableValue(workstation.widget<QTableWidget>("incision.measurements"), "Excised area"), 1.0);

  // A region undermined by three corners clicked around p0.
  const auto [t0, z0] = chartOf(original.cutPath()[0]);
  const std::vector<Eigen::Vector3d> corners{skinPoint(t0 - 0.05, z0 - 4.0), skinPoint(t0 + 0.05, z0 - 4.0),
                                             skinPoint(t0, z0 + 4.0)};
  const std::size_t errorsBeforeRegion = workstation.window().reportedErrors().size();
  click(workstation.widget<QPushButton>("incision.undermine"));
  for (const Eigen::Vector3d& c : corners)
    click3d(c);
  click(workstation.widget<QPushButton>("incision.finishRegion"));
  workstation.settle(200);
  ASSERT_EQ(workstation.window().reportedErrors().size(), errorsBeforeRegion) << workstation.errors();
  node = scene.nodeAs<PlanNode>(planId);
  const planning::IncisionPlan undermined = IncisionLogic::readPlan(*node);
  ASSERT_EQ(undermined.underminedRegions().size(), 1u);
  ASSERT_EQ(undermined.underminedRegions()[0].size(), 3u);
  for (std::size_t k = 0; k < 3; ++k)
  {
    const auto [t, z] = chartOf(undermined.underminedRegions()[0][k]);
    EXPECT_LT((skinPoint(t, z) - corners[k]).norm(), 1.5) << "corner " << k;
  }
  // The recipe holds the edits and replays to this plan.
  IncisionLogic logic(scene);
  const auto recipe = IncisionLogic::readRecipe(*node);
  ASSERT_TRUE(recipe.has_value());
  PlanNode a, b;
  IncisionLogic::writePlan(undermined, a);
  IncisionLogic::writePlan(logic.applyRecipe(*recipe, skin), b);
  EXPECT_EQ(a.toJson(), b.toJson());
  // The region's outline is drawn on the skin in the undermining tint.
  {
    auto* lines = test::nodeNamed<SurfaceNode>(scene, "Z-plasty 1 incision");
    ASSERT_NE(lines, nullptr);
    auto* colours = vtkUnsignedCharArray::SafeDownCast(lines->polyData()->GetPointData()->GetArray("line_colour"));
    ASSERT_NE(colours, nullptr);
    int tinted = 0;
    for (vtkIdType i = 0; i < colours->GetNumberOfTuples(); ++i)
      tinted += colours->GetTypedComponent(i, 0) == planning::kUnderminedTint[0] &&
                colours->GetTypedComponent(i, 2) == planning::kUnderminedTint[2];
    EXPECT_GT(tinted, 10);
  }
  workstation.screenshot("incision-edited-by-hand");
  // A cut of the surgeon's own: three points clicked one by one become a
  // plan "Cut 1" whose points are where the clicks landed.
  const std::vector<Eigen::Vector3d> cutPoints{skinPoint(t0 - 0.06, z0 + 8.0), skinPoint(t0 - 0.03, z0 + 12.0),
                                               skinPoint(t0 + 0.01, z0 + 14.0)};
  click(workstation.widget<QPushButton>("incision.draw"));
  for (const Eigen::Vector3d& c : cutPoints)
    click3d(c);
  click(workstation.widget<QPushButton>("incision.finishDraw"));
  workstation.settle(200);
  ASSERT_EQ(workstation.window().reportedErrors().size(), errorsBeforeRegion) << workstation.errors();
  PlanNode* drawnNode = test::nodeNamed<PlanNode>(scene, "Cut 1");
  ASSERT_NE(drawnNode, nullptr);
  const planning::IncisionPlan drawn = IncisionLogic::readPlan(*drawnNode);
  ASSERT_EQ(drawn.pointCount(), 3);
  for (int k = 0; k < 3; ++k)
  {
    const auto [t, z] = chartOf(drawn.cutPath()[std::size_t(k)]);
    EXPECT_LT((skinPoint(t, z) - cutPoints[std::size_t(k)]).norm(), 1.5) << "cut point " << k;
  }
  EXPECT_EQ(drawn.writtenSutures(), planning::straightClosureSutures(3));
  EXPECT_NE(test::nodeNamed<SurfaceNode>(scene, "Cut 1 incision"), nullptr);
  selectPlan(list, "Z-plasty 1");
  workstation.settle(100);
  // Clear takes the regions away again.
  click(workstation.widget<QPushButton>("incision.clearUndermining"));
  workstation.settle(100);
  EXPECT_TRUE(IncisionLogic::readPlan(*scene.nodeAs<PlanNode>(planId)).underminedRegions().empty());
}

// Cut points dragged along the skin (issue 6 item 4, §3.2.4): the selected
// plan's points are handles in the 3D view; a press on one and a drag moves
// that point to where the mouse lets go, as one undoable edit, and the view
// does not turn meanwhile. Let go over the background, nothing changes.
TEST(IncisionPanel, CutPointsDraggedAlongTheSkin)
{
  test::Workstation workstation;
  Scene& scene = workstation.scene();
  workstation.window().openPath(test::reportDemoFolder() / "sample.caps");
  ASSERT_TRUE(workstation.waitUntilIdle(60)) << workstation.errors();
  const seg::RangeMap skin = RangeMapLogic::toRangeMap(*newestSkin(scene));
  const seg::CylindricalFrame& frame = skin.frame();
  hidePredictedSkins(scene);
  PlanNode* node = test::nodeNamed<PlanNode>(scene, "Z-plasty 1");
  ASSERT_NE(node, nullptr);
  const NodeId planId = node->id();
  auto skinPoint = [&](double theta, double z) { return frame.toWorld(skin.sample(theta, z), theta, z); };
  auto chartOf = [&](const Eigen::Vector2d& n) {
    const seg::CylindricalPoint c = frame.fromNormalized({1.0, n.x(), n.y()});
    return std::pair{c.theta, c.z};
  };
  const planning::IncisionPlan original = IncisionLogic::readPlan(*node);
  const auto [t0, z0] = chartOf(original.cutPath()[0]);
  workstation.window().setThreeDViewCamera(cameraFacing(frame, skinPoint(t0, z0 - 10.0), t0, 180.0));
  ui::ThreeDView* view = workstation.window().threeDView();
  EXPECT_EQ(view->handleCount(), 0U) << "handles before the Incision panel is shown";
  workstation.selectModule("incision");
  selectPlan(workstation.widget<QListWidget>("incision.plans"), "Z-plasty 1");
  workstation.settle(200);
  ASSERT_EQ(view->handleCount(), original.cutPath().size());
  const Eigen::Vector3d lifted0 = frame.toWorld(skin.sample(t0, z0) + planning::kIncisionLineLift, t0, z0);
  const QPoint grip = view->handleOnScreen(0);
  EXPECT_LE((grip - workstation.threeDViewPointOf({lifted0.x(), lifted0.y(), lifted0.z()})).manhattanLength(), 2);

  // p0 dragged about 5 mm along the skin.
  const double t = t0 + 0.04, z = z0 + 3.0;
  const Eigen::Vector3d target = skinPoint(t, z);
  const QPoint drop = workstation.threeDViewPointOf({target.x(), target.y(), target.z()});
  ASSERT_GT((drop - grip).manhattanLength(), 15) << "the drag is too short to tell from a click";
  const double cameraBefore[3] = {view->renderer()->GetActiveCamera()->GetPosition()[0],
                                  view->renderer()->GetActiveCamera()->GetPosition()[1],
                                  view->renderer()->GetActiveCamera()->GetPosition()[2]};
  workstation.dragThreeDView(grip, drop);
  workstation.settle(200);
  ASSERT_TRUE(workstation.errors().empty()) << workstation.errors();
  const double* cameraAfter = view->renderer()->GetActiveCamera()->GetPosition();
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(cameraAfter[k], cameraBefore[k]) << "the view turned during the drag";
  const planning::IncisionPlan moved = IncisionLogic::readPlan(*scene.nodeAs<PlanNode>(planId));
  const auto [tm, zm] = chartOf(moved.cutPath()[0]);
  EXPECT_LT((skinPoint(tm, zm) - target).norm(), 1.5) << "p0 is not where it was let go";
  for (std::size_t k = 1; k < original.cutPath().size(); ++k)
    EXPECT_LT((moved.cutPath()[k] - original.cutPath()[k]).norm(), 1e-12) << "point " << k << " moved too";
  EXPECT_EQ(scene.undoStack().undoLabel(), "Move point p0 of Z-plasty 1");
  EXPECT_LE((view->handleOnScreen(0) - drop).manhattanLength(), 4) << "the handle did not follow the point";
  workstation.screenshot("incision-dragged-point");

  // Let go over the background (seen from further away): the plan stays as it is.
  {
    workstation.window().setThreeDViewCamera(cameraFacing(frame, skinPoint(t0, z0), t0, 900.0));
    workstation.settle(100);
    std::string key;
    std::array<double, 3> hit{};
    ASSERT_FALSE(view->pickSurface(3, 3, key, hit)) << "the corner of the view is on " << key;
  }
  workstation.dragThreeDView(view->handleOnScreen(1), QPoint(3, 3));
  workstation.settle(100);
  EXPECT_TRUE(workstation.errors().empty()) << workstation.errors();
  const planning::IncisionPlan after = IncisionLogic::readPlan(*scene.nodeAs<PlanNode>(planId));
  for (std::size_t k = 0; k < after.cutPath().size(); ++k)
    EXPECT_LT((after.cutPath()[k] - moved.cutPath()[k]).norm(), 1e-12) << "point " << k;

  // Undo takes p0 back.
  click(workstation.widget<QPushButton>("incision.undo"));
  workstation.settle(200);
  EXPECT_LT((IncisionLogic::readPlan(*scene.nodeAs<PlanNode>(planId)).cutPath()[0] - original.cutPath()[0]).norm(),
            1e-12);
  // Another module: no handles.
  workstation.selectModule("results");
  EXPECT_EQ(view->handleCount(), 0U);
}

// The relaxed skin tension lines as a guide (issue 6 item 4): shown over the
// face from the landmarks found on the skin map, on the skin, and the angle
// of the selected plan's axis to them in the measurements.
TEST(IncisionPanel, SkinTensionLinesGuide)
{
  test::Workstation workstation;
  Scene& scene = workstation.scene();
  workstation.window().openPath(test::reportDemoFolder() / "sample.caps");
  ASSERT_TRUE(workstation.waitUntilIdle(60)) << workstation.errors();
  const seg::RangeMap skin = RangeMapLogic::toRangeMap(*newestSkin(scene));
  hidePredictedSkins(scene);
  workstation.selectModule("incision");
  selectPlan(workstation.widget<QListWidget>("incision.plans"), "Z-plasty 1");
  workstation.settle(100);
  auto* table = workstation.widget<QTableWidget>("incision.measurements");
  const QString axisRow = QString::fromUtf8("Axis p1–p2 to skin tension lines");
  EXPECT_TRUE(std::isnan(tableValue(table, axisRow))) << "the angle is shown before the guide";

  auto* guide = workstation.widget<QCheckBox>("incision.tensionLines");
  guide->setChecked(true);
  workstation.settle(200);
  ASSERT_TRUE(workstation.window().reportedErrors().empty()) << workstation.errors();
  SurfaceNode* lines = test::nodeNamed<SurfaceNode>(scene, "Skin tension lines");
  ASSERT_NE(lines, nullptr);
  vtkPolyData* data = lines->polyData();
  ASSERT_NE(data, nullptr);
  EXPECT_GT(data->GetNumberOfLines(), 30);
  EXPECT_LT(worstLiftError(data, skin), 0.05) << "a guide line leaves the skin";

  // The plan's axis against the lines, as the logic measures it on the same landmarks.
  const double shown = tableValue(table, axisRow);
  ASSERT_FALSE(std::isnan(shown)) << "no angle to the skin tension lines in the measurements";
  const seg::LandmarkPlacement found = seg::placeLandmarks(skin);
  const planning::SkinTensionLines logic(skin, planning::FaceLayout::fromLandmarks(found.landmarks, skin));
  const double expected =
    planning::axisToTensionLines(IncisionLogic::readPlan(*test::nodeNamed<PlanNode>(scene, "Z-plasty 1")), logic)
      .degrees;
  EXPECT_NEAR(shown, expected, 0.5);
  EXPECT_GE(shown, 0.0);
  EXPECT_LE(shown, 90.0);
  {
    // Face on, the whole face in view, for the screenshot.
    const seg::CylindricalFrame& frame = skin.frame();
    const seg::Landmark* nose = found.find("pronasale");
    ASSERT_NE(nose, nullptr);
    const Eigen::Vector3d focus = frame.toWorld(skin.sample(nose->theta, nose->z) - 30.0, nose->theta, nose->z);
    workstation.window().setThreeDViewCamera(cameraFacing(frame, focus, nose->theta, 420.0));
    table->scrollToBottom();
    workstation.settle(200);
  }
  workstation.screenshot("incision-tension-lines");

  guide->setChecked(false);
  workstation.settle(100);
  EXPECT_EQ(test::nodeNamed<SurfaceNode>(scene, "Skin tension lines"), nullptr);
  EXPECT_TRUE(std::isnan(tableValue(table, axisRow)));
}

TEST(IncisionPanel, NoSkinMapSaysWhatToDo)
{
  test::Workstation workstation;
  workstation.selectModule("incision");
  const std::size_t errors = workstation.window().reportedErrors().size();
  click(workstation.widget<QPushButton>("incision.place"));
  workstation.settle(100);
  ASSERT_EQ(workstation.window().reportedErrors().size(), errors + 1);
  EXPECT_NE(workstation.errors().find("Build the range maps in the Range maps module first"), std::string::npos)
    << workstation.errors();
  EXPECT_TRUE(workstation.scene().nodesOfType(NodeType::Plan).empty());
}

} // namespace caps
