// The whole flow of issue 6 on the sample CT, through the workstation's own
// panels as a surgeon goes through them: load the CT, segment skin and bone,
// build the thickness maps and review them, place a Z-plasty by a click on
// the 3D face, simulate it, look at the result, take a snapshot, save the
// scene and reopen it. A screenshot of every step goes to
// build/test-artifacts/workstation/flow-NN-*.png.

#include <cmath>
#include <cstdio>
#include <numbers>
#include <set>

#include <QCheckBox>
#include <QComboBox>
#include <QImage>
#include <QLabel>
#include <QMouseEvent>
#include <QPushButton>
#include <QSlider>
#include <QTableWidget>

#include <vtkCamera.h>
#include <vtkImageData.h>
#include <vtkPolyData.h>

#include "TestPaths.h"
#include "modules/rangemap/ThicknessReview.h"
#include "ui/SliceView.h"
#include "Workstation.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/SnapshotNode.h"
#include "scene/SolutionNode.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"
#include "segmentation/CylindricalFrame.h"

namespace fs = std::filesystem;

namespace {

using caps::test::Workstation;

template <class T> std::vector<T*> nodesOf(caps::Scene& scene, caps::NodeType type)
{
  std::vector<T*> nodes;
  for (caps::Node* node : scene.nodesOfType(type))
    nodes.push_back(static_cast<T*>(node));
  return nodes;
}

const caps::RangeMapNode* rangeMap(caps::Scene& scene, const std::string& role)
{
  const caps::RangeMapNode* found = nullptr;
  for (auto* node : nodesOf<caps::RangeMapNode>(scene, caps::NodeType::RangeMap))
    if (node->role() == role)
      found = node;
  return found;
}

/// The skin point of the skin range map nearest θ (degrees) and z (mm).
std::array<double, 3> skinPoint(const caps::RangeMapNode& skin, double thetaDegrees, double z)
{
  const Eigen::MatrixXf& values = skin.values();
  const caps::seg::CylindricalFrame frame(skin.axisOrigin(), skin.axisDirection(), skin.zMin(), skin.zMax(),
                                          int(values.rows()), int(values.cols()));
  const double theta = thetaDegrees * std::numbers::pi / 180.0;
  Eigen::Index bestI = 0, bestJ = 0;
  for (Eigen::Index i = 0; i < values.rows(); ++i)
    if (std::abs(std::remainder(skin.thetaAt(i) - theta, 2 * std::numbers::pi)) <
        std::abs(std::remainder(skin.thetaAt(bestI) - theta, 2 * std::numbers::pi)))
      bestI = i;
  for (Eigen::Index j = 0; j < values.cols(); ++j)
    if (std::abs(skin.zAt(j) - z) < std::abs(skin.zAt(bestJ) - z))
      bestJ = j;
  const Eigen::Vector3d p = frame.toWorld(values(bestI, bestJ), skin.thetaAt(bestI), skin.zAt(bestJ));
  return {p.x(), p.y(), p.z()};
}

/// Spread of the grey levels in a rectangle of an image (fractions of its size).
double greySpread(const QImage& image, double x0, double y0, double x1, double y1)
{
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int y = int(y0 * image.height()); y < int(y1 * image.height()); ++y)
    for (int x = int(x0 * image.width()); x < int(x1 * image.width()); ++x)
    {
      const double g = qGray(image.pixel(x, y));
      sum += g;
      sum2 += g * g;
      ++n;
    }
  const double mean = sum / n;
  return std::sqrt(std::max(0.0, sum2 / n - mean * mean));
}

/// The 3D view's own pixels, as a picture of the window shows them.
QImage threeDViewImage(Workstation& ws)
{
  ws.threeDView().renderWindow()->Render();
  return ws.threeDView().grabFramebuffer();
}

void press(Workstation& ws, const std::string& button)
{
  auto* b = ws.widget<QPushButton>(button);
  ASSERT_NE(b, nullptr);
  ASSERT_TRUE(b->isEnabled()) << button << " is disabled";
  QTest::mouseClick(b, Qt::LeftButton);
  ws.settle(100);
}

} // namespace

TEST(WorkstationFlow, FromTheSampleCtToASavedPrediction)
{
  const fs::path scratch = caps::test::scratchFolder();
  Workstation ws;
  caps::Scene& scene = ws.scene();

  // 1. Load: the sample CT's one series loads straight away.
  ws.window().openPath(caps::test::sampleCt());
  ASSERT_TRUE(ws.waitUntil([&] { return !scene.nodesOfType(caps::NodeType::Volume).empty(); }, 120)) << ws.errors();
  ASSERT_TRUE(ws.waitUntilIdle(120));
  const QImage loaded(QString::fromStdString(ws.screenshot("flow-01-loaded").string()));
  ASSERT_FALSE(loaded.isNull());
  EXPECT_GT(greySpread(loaded, 0.66, 0.15, 0.98, 0.45), 20.0) << "the axial view shows no CT";

  // 2. Segment skin and bone with the default thresholds.
  ws.selectModule("segment");
  // The thresholds are previewed on the slices while the panel is shown.
  const auto sliceViews = ws.window().findChildren<caps::ui::SliceView*>();
  ASSERT_EQ(sliceViews.size(), 3);
  EXPECT_TRUE(sliceViews.front()->hasOverlay());
  ws.screenshot("flow-02a-thresholds");
  press(ws, "segment.run");
  ASSERT_TRUE(ws.waitUntilIdle(600)) << "segmentation did not finish";
  ASSERT_TRUE(ws.errors().empty()) << ws.errors();
  const auto surfaces = nodesOf<caps::SurfaceNode>(scene, caps::NodeType::Surface);
  ASSERT_GE(surfaces.size(), 2u) << "no skin and bone surfaces";
  // The default 3D view looks at the face: the camera is in front (anterior is -y in LPS).
  vtkCamera* camera = ws.threeDView().renderer()->GetActiveCamera();
  EXPECT_LT(camera->GetPosition()[1], camera->GetFocalPoint()[1] - 100.0);
  EXPECT_GT(camera->GetViewUp()[2], 0.9);
  ws.screenshot("flow-02-segmented");
  EXPECT_GT(greySpread(threeDViewImage(ws), 0.25, 0.2, 0.75, 0.8), 15.0) << "the 3D view shows no face";

  // 3. Range and thickness maps, reviewed on the face.
  ws.selectModule("rangemap");
  // Away from the Segment panel the slices show the segmentation's labels.
  EXPECT_TRUE(sliceViews.front()->hasOverlay());
  press(ws, "rangemap.run");
  ASSERT_TRUE(ws.waitUntilIdle(900)) << "the range maps did not finish";
  ASSERT_TRUE(ws.errors().empty()) << ws.errors();
  const caps::RangeMapNode* skin = rangeMap(scene, "skin");
  ASSERT_NE(skin, nullptr);
  ASSERT_NE(rangeMap(scene, "bone"), nullptr);
  ASSERT_NE(rangeMap(scene, "thickness"), nullptr);
  auto* status = ws.widget<QLabel>("rangemap.status");
  ASSERT_NE(status, nullptr);
  EXPECT_NE(status->text().indexOf("mean"), -1) << status->text().toStdString();
  // Hovering over the unwrapped map reads it; a click there moves the
  // cursor of the slice views to that point of the skin.
  auto* map = ws.widget<QWidget>("rangemap.map");
  auto* probe = ws.widget<QLabel>("rangemap.probe");
  ASSERT_TRUE(map && probe);
  const QPoint onMap(map->width() / 2 + 20, map->height() / 3);
  QMouseEvent move(QEvent::MouseMove, onMap, Qt::NoButton, Qt::NoButton, Qt::NoModifier);
  QApplication::sendEvent(map, &move);
  const QString reading = probe->text();
  double theta = 0, z = 0, radial = 0;
  ASSERT_EQ(std::sscanf(reading.toUtf8().constData(), "θ %lf°  z %lf mm", &theta, &z), 2) << reading.toStdString();
  const int at = reading.indexOf("radial ");
  ASSERT_GE(at, 0) << reading.toStdString();
  radial = reading.mid(at + 7).split(' ').front().toDouble();
  const caps::ThicknessReview review = *caps::ThicknessReview::fromScene(scene);
  // The label rounds θ and z to 0.1 and the thickness to 0.1 mm: the map
  // read anywhere in that rounding box must bracket the label's value.
  const double degree = std::numbers::pi / 180.0;
  const caps::ThicknessProbe expected = review.probe(theta * degree, z);
  double low = expected.thickness, high = expected.thickness;
  for (double dt : {-0.05, 0.05})
    for (double dz : {-0.05, 0.05})
    {
      const double t = review.probe((theta + dt) * degree, z + dz).thickness;
      low = std::min(low, t);
      high = std::max(high, t);
    }
  EXPECT_GE(radial, low - 0.05) << reading.toStdString();
  EXPECT_LE(radial, high + 0.05) << reading.toStdString();
  QTest::mouseClick(map, Qt::LeftButton, Qt::NoModifier, onMap);
  ws.settle(100);
  const std::array<double, 3> cursor = sliceViews.front()->cursorPosition();
  // The slice views snap to voxel centres: within a voxel's diagonal.
  for (int k = 0; k < 3; ++k)
    EXPECT_NEAR(cursor[size_t(k)], expected.skinPoint[size_t(k)], 1.5) << k;
  // The thickness painted on the 3D skin.
  auto* paint = ws.widget<QCheckBox>("rangemap.paintThickness");
  ASSERT_NE(paint, nullptr);
  paint->setChecked(true);
  ws.settle(200);
  auto* skinSurface = static_cast<caps::SurfaceNode*>(caps::test::nodeNamed(scene, "Skin"));
  ASSERT_NE(skinSurface, nullptr);
  EXPECT_EQ(skinSurface->colourArray(), "thickness_mm");
  EXPECT_NE(skinSurface->colourBarTitle().find("radial"), std::string::npos) << skinSurface->colourBarTitle();
  // Thickness along the normal chosen: the paint on the skin and the
  // histogram follow the map (they stayed radial before).
  auto* mapKind = ws.widget<QComboBox>("rangemap.mapKind");
  ASSERT_NE(mapKind, nullptr);
  mapKind->setCurrentIndex(1);
  ws.settle(200);
  EXPECT_NE(skinSurface->colourBarTitle().find("along the skin normal"), std::string::npos)
    << skinSurface->colourBarTitle();
  auto* histogram = ws.widget<QWidget>("rangemap.histogram");
  ASSERT_NE(histogram, nullptr);
  EXPECT_TRUE(histogram->accessibleDescription().contains("along the skin normal"))
    << histogram->accessibleDescription().toStdString();
  mapKind->setCurrentIndex(0);
  ws.settle(200);
  EXPECT_NE(skinSurface->colourBarTitle().find("radial"), std::string::npos) << skinSurface->colourBarTitle();
  // The standard landmarks placed from the maps, each with its depth measured
  // in the CT by its convention (saved with the scene below).
  press(ws, "rangemap.placeLandmarks");
  ws.settle(300);
  auto* table = ws.widget<QTableWidget>("rangemap.landmarks");
  ASSERT_NE(table, nullptr);
  EXPECT_GE(table->rowCount(), 10);
  bool chin = false;
  for (int r = 0; r < table->rowCount(); ++r)
    if (table->item(r, 0)->text() == "pogonion")
    {
      chin = true;
      const double depth = table->item(r, 5)->text().toDouble();
      EXPECT_GT(depth, 6.0); // De Greef et al. 2006: about 10-12 mm at the chin
      EXPECT_LT(depth, 18.0);
      EXPECT_EQ(table->item(r, 6)->text().toStdString(), "perpendicular to the skin");
    }
  EXPECT_TRUE(chin);
  ws.screenshot("flow-03-thickness");

  // 4. A Z-plasty placed by a click on the left cheek of the 3D face.
  ws.selectModule("incision");
  auto* procedure = ws.widget<QComboBox>("incision.procedure");
  ASSERT_NE(procedure, nullptr);
  const int zPlasty = procedure->findData("z-plasty");
  ASSERT_GE(zPlasty, 0);
  procedure->setCurrentIndex(zPlasty);
  press(ws, "incision.place");
  const std::array<double, 3> cheek = skinPoint(*skin, -40.0, -47.0);
  ws.clickThreeDView(ws.threeDViewPointOf(cheek));
  ASSERT_TRUE(ws.waitUntil([&] { return !scene.nodesOfType(caps::NodeType::Plan).empty(); }, 10))
    << "the click placed no plan. " << ws.errors();
  // The node itself is replaced when the plan is simulated: keep its name.
  const std::string planName = nodesOf<caps::PlanNode>(scene, caps::NodeType::Plan).back()->name();
  {
    // Closer, as the surgeon looks at what was placed: the cheek face on.
    const caps::seg::CylindricalFrame frame(skin->axisOrigin(), skin->axisDirection(), skin->zMin(), skin->zMax(),
                                            int(skin->values().rows()), int(skin->values().cols()));
    const double theta = -40.0 * std::numbers::pi / 180.0;
    const Eigen::Vector3d focus(cheek[0], cheek[1], cheek[2]);
    const Eigen::Vector3d eye = focus + 260.0 * frame.radialDirection(theta);
    caps::SnapshotNode::Camera camera;
    camera.position = {eye.x(), eye.y(), eye.z()};
    camera.focalPoint = {focus.x(), focus.y(), focus.z()};
    camera.viewUp = {frame.direction().x(), frame.direction().y(), frame.direction().z()};
    ws.window().setThreeDViewCamera(camera);
  }
  ws.screenshot("flow-04-incision");

  // 5. Simulate it (a coarser mesh than the default keeps the test short).
  ws.selectModule("simulate");
  auto* planChoice = ws.widget<QComboBox>("simulate.plan");
  ASSERT_NE(planChoice, nullptr);
  planChoice->setCurrentIndex(planChoice->findText(QString::fromStdString(planName)));
  press(ws, "simulate.run");
  ASSERT_TRUE(ws.waitUntilIdle(900)) << "the simulation did not finish";
  ASSERT_TRUE(ws.errors().empty()) << ws.errors();
  ASSERT_NE(caps::test::nodeNamed(scene, planName + " skin after"), nullptr);
  ASSERT_NE(caps::test::nodeNamed(scene, planName + " closure"), nullptr);
  ws.screenshot("flow-05-simulated");

  // 6. Results: von Mises on the face after the operation, then a snapshot.
  ws.selectModule("results");
  auto* resultPlan = ws.widget<QComboBox>("results.plan");
  ASSERT_NE(resultPlan, nullptr);
  resultPlan->setCurrentIndex(resultPlan->findText(QString::fromStdString(planName)));
  auto* colourBy = ws.widget<QComboBox>("results.colourBy");
  ASSERT_NE(colourBy, nullptr);
  const int vonMises = colourBy->findText("von Mises", Qt::MatchContains);
  ASSERT_GE(vonMises, 0);
  colourBy->setCurrentIndex(vonMises);
  auto* deformation = ws.widget<QSlider>("results.deformation");
  ASSERT_NE(deformation, nullptr);
  deformation->setValue(deformation->maximum());
  ws.settle(300);
  ws.screenshot("flow-06-results");
  const size_t snapshotsBefore = scene.nodesOfType(caps::NodeType::Snapshot).size();
  press(ws, "results.snapshot");
  ASSERT_TRUE(
    ws.waitUntil([&] { return scene.nodesOfType(caps::NodeType::Snapshot).size() == snapshotsBefore + 1; }, 10));
  auto* snapshot = nodesOf<caps::SnapshotNode>(scene, caps::NodeType::Snapshot).back();
  ASSERT_NE(snapshot->image(), nullptr);
  EXPECT_GT(snapshot->image()->GetDimensions()[0], 200);

  // 7. Save, and reopen in a fresh workstation: the same nodes come back.
  const fs::path bundle = scratch / "flow.caps";
  ASSERT_TRUE(ws.window().saveSceneTo(bundle)) << ws.errors();
  std::multiset<std::string> names;
  for (caps::Node* node : scene.nodes())
    names.insert(node->name());
  caps::Node* plan = caps::test::nodeNamed(scene, planName);
  ASSERT_NE(plan, nullptr);
  const nlohmann::json planJson = plan->toJson();

  Workstation reopened;
  reopened.window().openPath(bundle);
  ASSERT_TRUE(reopened.waitUntilIdle(120));
  ASSERT_TRUE(reopened.errors().empty()) << reopened.errors();
  std::multiset<std::string> reopenedNames;
  for (caps::Node* node : reopened.scene().nodes())
    reopenedNames.insert(node->name());
  EXPECT_EQ(reopenedNames, names);
  auto* reopenedPlan = caps::test::nodeNamed(reopened.scene(), planName);
  ASSERT_NE(reopenedPlan, nullptr);
  EXPECT_EQ(reopenedPlan->toJson(), planJson);
  reopened.screenshot("flow-07-reopened");
}
