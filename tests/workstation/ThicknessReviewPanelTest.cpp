// The thickness review as a radiographer works through it (issue 22 item 4),
// on the demo scene of the sample CT, driving the real window: a landmark's
// row shows its measured depth as a segment on the three slices, which ends
// where the CT turns to bone; a landmark dragged on the 3D face is measured
// again where it was let go; a ruler of two clicks on a slice reads the
// distance in mm; a line drawn on the skin gets its thickness profile.
// Screenshots go to build/test-artifacts/workstation/thickness-*.png.

#include <cmath>
#include <functional>
#include <numbers>

#include <QAction>
#include <QLabel>
#include <QListWidget>
#include <QPushButton>
#include <QRegularExpression>
#include <QTableWidget>

#include <vtkImageData.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkRendererCollection.h>

#include "TestPaths.h"
#include "Workstation.h"
#include "modules/rangemap/ThicknessReview.h"
#include "report/DemoScene.h"
#include "scene/LandmarksNode.h"
#include "scene/SnapshotNode.h"
#include "scene/SurfaceNode.h"
#include "ui/SliceView.h"

namespace caps {
namespace {

namespace fs = std::filesystem;

constexpr double kDegree = std::numbers::pi / 180.0;

double distance(const std::array<double, 3>& a, const std::array<double, 3>& b)
{
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

/// The CT's HU at image-space point @a p (the slice views' space), the
/// nearest voxel.
double huAt(vtkImageData* ct, const std::array<double, 3>& p)
{
  int index[3];
  for (int a = 0; a < 3; ++a)
    index[a] = static_cast<int>(std::lround((p[size_t(a)] - ct->GetOrigin()[a]) / ct->GetSpacing()[a]));
  return ct->GetScalarComponentAsDouble(index[0], index[1], index[2], 0);
}

std::array<double, 3> along(const std::array<double, 3>& from, const std::array<double, 3>& to, double t)
{
  return {from[0] + t * (to[0] - from[0]), from[1] + t * (to[1] - from[1]), from[2] + t * (to[2] - from[2])};
}

/// Where image-space point @a p is on slice view @a view, in widget pixels.
QPoint slicePointOf(ui::SliceView& view, const std::array<double, 3>& p)
{
  vtkRenderer* renderer = view.renderWindow()->GetRenderers()->GetFirstRenderer();
  renderer->SetWorldPoint(p[0], p[1], p[2], 1.0);
  renderer->WorldToDisplay();
  double display[3];
  renderer->GetDisplayPoint(display);
  const double ratio = view.devicePixelRatioF();
  const int height = view.renderWindow()->GetSize()[1];
  return QPoint(static_cast<int>(std::lround(display[0] / ratio)),
                static_cast<int>(std::lround((height - 1 - display[1]) / ratio)));
}

/// Pixels of the view as drawn that @a is picks out by colour.
int pixelsWhere(ui::SliceView& view, const std::function<bool(const QColor&)>& is)
{
  view.renderWindow()->Render();
  const QImage image = view.grabFramebuffer();
  int count = 0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x)
      count += is(image.pixelColor(x, y));
  return count;
}

/// Pixels of the ruler's cyan.
int rulerPixels(ui::SliceView& view)
{
  return pixelsWhere(view, [](const QColor& c) { return c.red() < 140 && c.green() > 200 && c.blue() > 230; });
}

/// Pixels of the measured segment's green.
int segmentPixels(ui::SliceView& view)
{
  return pixelsWhere(view, [](const QColor& c) { return c.red() < 140 && c.green() > 200 && c.blue() < 170; });
}

ui::SliceView* axialView(test::Workstation& ws)
{
  for (auto* view : ws.window().findChildren<ui::SliceView*>())
    if (view->orientation() == ui::SliceOrientation::Axial)
      return view;
  return nullptr;
}

/// The demo scene in the Range maps module with the standard landmarks placed.
void openTheReview(test::Workstation& ws)
{
  ws.window().openPath(test::reportDemoFolder() / "sample.caps");
  ASSERT_TRUE(ws.waitUntilIdle(120)) << ws.errors();
  // The demo's predicted skins cover the face: hidden, as a reviewer does.
  for (Node* n : ws.scene().nodesOfType(NodeType::Surface))
    if (n->name() != "Skin" && n->name() != "Bone")
      static_cast<SurfaceNode*>(n)->setVisible(false);
  ws.selectModule("rangemap");
  auto* place = ws.widget<QPushButton>("rangemap.placeLandmarks");
  ASSERT_NE(place, nullptr);
  ASSERT_TRUE(place->isEnabled());
  QTest::mouseClick(place, Qt::LeftButton);
  ws.settle(300);
}

int rowOf(QTableWidget& table, const QString& name)
{
  for (int r = 0; r < table.rowCount(); ++r)
    if (table.item(r, 0)->text() == name)
      return r;
  return -1;
}

void clickRow(test::Workstation& ws, QTableWidget& table, int row)
{
  table.scrollToItem(table.item(row, 0));
  QTest::mouseClick(table.viewport(), Qt::LeftButton, Qt::NoModifier,
                    table.visualItemRect(table.item(row, 0)).center());
  ws.settle(300);
}

/// A camera on the face, from 300 mm in front of the skin at @a theta.
SnapshotNode::Camera cameraOnTheFace(const ThicknessReview& review, double theta, double z)
{
  const seg::CylindricalFrame& frame = review.skin().frame();
  const auto skin = review.probe(theta, z).skinPoint;
  const Eigen::Vector3d focus(skin[0], skin[1], skin[2]);
  const Eigen::Vector3d eye = focus + 300.0 * frame.radialDirection(theta);
  SnapshotNode::Camera camera;
  camera.position = {eye.x(), eye.y(), eye.z()};
  camera.focalPoint = {focus.x(), focus.y(), focus.z()};
  camera.viewUp = {frame.direction().x(), frame.direction().y(), frame.direction().z()};
  return camera;
}

} // namespace

TEST(ThicknessReviewPanel, ALandmarksDepthIsDrawnOnTheSlicesAndFollowsADrag)
{
  test::Workstation ws;
  openTheReview(ws);
  auto* table = ws.widget<QTableWidget>("rangemap.landmarks");
  ASSERT_NE(table, nullptr);
  const int row = rowOf(*table, "pogonion");
  ASSERT_GE(row, 0) << "no pogonion placed on the sample";
  clickRow(ws, *table, row);

  // On each slice view: the segment, as long as the table's depth, labelled
  // with it, from the skin (where the crosshair now is) into the bone.
  const double depth = table->item(row, 5)->text().toDouble();
  vtkImageData* ct = nullptr;
  for (auto* view : ws.window().findChildren<ui::SliceView*>())
  {
    ASSERT_TRUE(view->measuredSegment().has_value()) << "no segment on a slice view";
    const ui::SliceSegment& s = *view->measuredSegment();
    EXPECT_NEAR(distance(s.from, s.to), depth, 0.051) << s.label;
    EXPECT_NE(s.label.find("pogonion"), std::string::npos) << s.label;
    EXPECT_LT(distance(view->cursorPosition(), s.from), 1.0) << "the crosshair is not at the landmark's skin";
    ct = view->image();
    // Drawn, over the crosshair that runs along it: 11 mm is 15 pixels or
    // more on these views, and the line is 3 pixels wide.
    EXPECT_GT(segmentPixels(*view), 40) << "the segment is not drawn on the " << int(view->orientation()) << " view";
  }
  ASSERT_NE(ct, nullptr);
  {
    // The CT itself says where the segment runs: soft tissue half-way, bone
    // (the mandible's cortex) just past its deep end.
    const ui::SliceSegment& s = *axialView(ws)->measuredSegment();
    const double pastTheEnd = 1.0 + 1.0 / distance(s.from, s.to);
    EXPECT_LT(huAt(ct, along(s.from, s.to, 0.5)), 150.0) << "half-way down the depth is not soft tissue";
    EXPECT_GT(huAt(ct, along(s.from, s.to, pastTheEnd)), 300.0) << "1 mm past the deep end is not bone";
    EXPECT_LT(huAt(ct, along(s.from, s.to, -1.0 / distance(s.from, s.to))), -300.0) << "1 mm outside is not air";
  }
  ws.screenshot("thickness-landmark-segment");

  // Dragged on the 3D face 6 mm up the chin, let go on the skin: the
  // landmark moves there, is measured again, and its segment follows.
  auto review = ThicknessReview::fromScene(ws.scene());
  ASSERT_TRUE(review.has_value());
  auto* landmarks = static_cast<LandmarksNode*>(ws.scene().nodesOfType(NodeType::Landmarks).back());
  const std::size_t index = static_cast<std::size_t>(row);
  const auto before = landmarks->landmarks()[index].position;
  const auto chart = review->chartOf(before);
  ws.window().setThreeDViewCamera(cameraOnTheFace(*review, chart[0], chart[1]));
  ws.settle(200);
  ui::ThreeDView* view3d = ws.window().threeDView();
  ASSERT_EQ(view3d->handleCount(), landmarks->landmarks().size()) << "the landmarks are not handles on the face";
  const auto target = review->probe(chart[0], chart[1] + 6.0).skinPoint;
  ws.dragThreeDView(view3d->handleOnScreen(index), ws.threeDViewPointOf(target));
  ws.settle(300);
  ASSERT_TRUE(ws.errors().empty()) << ws.errors();
  const auto after = landmarks->landmarks()[index].position;
  EXPECT_LT(distance(after, target), 1.5) << "the landmark is not where it was let go";
  EXPECT_GT(distance(after, before), 4.0);
  EXPECT_EQ(ws.scene().undoStack().undoLabel(), "Move landmark pogonion");
  const ui::SliceSegment& moved = *axialView(ws)->measuredSegment();
  EXPECT_LT(distance(moved.from, after), 1.0) << "the segment did not follow the landmark";
  EXPECT_NEAR(distance(moved.from, moved.to), table->item(row, 5)->text().toDouble(), 0.051);
  ws.screenshot("thickness-landmark-dragged");
}

TEST(ThicknessReviewPanel, ARulerOnASliceReadsMillimetres)
{
  test::Workstation ws;
  openTheReview(ws);
  ui::SliceView* axial = axialView(ws);
  ASSERT_NE(axial, nullptr);
  auto* ruler = ws.window().findChild<QAction*>("view.ruler");
  ASSERT_NE(ruler, nullptr);
  ruler->trigger();
  ws.settle(100);
  ASSERT_TRUE(axial->rulerMode());

  // Two points 60 mm apart across the slice and 20 mm front to back: a
  // ruler from one to the other reads √(60² + 20²) = 63.2 mm, within the
  // size of a screen pixel on the slice at each end.
  const auto cursor = axial->cursorPosition();
  const std::array<double, 3> a{cursor[0] - 30.0, cursor[1] - 10.0, cursor[2]};
  const std::array<double, 3> b{cursor[0] + 30.0, cursor[1] + 10.0, cursor[2]};
  const QPoint pa = slicePointOf(*axial, a), pb = slicePointOf(*axial, b);
  const double mmPerPixel = 63.25 / std::hypot(pa.x() - pb.x(), pa.y() - pb.y());
  QTest::mouseClick(axial, Qt::LeftButton, Qt::NoModifier, pa);
  ws.settle(100);
  QTest::mouseClick(axial, Qt::LeftButton, Qt::NoModifier, pb);
  ws.settle(200);
  const auto measured = axial->ruler();
  ASSERT_TRUE(measured.has_value()) << "two clicks made no ruler";
  EXPECT_NEAR(distance(measured->from, measured->to), std::hypot(60.0, 20.0), 2.0 * mmPerPixel);
  EXPECT_NE(measured->label.find("mm"), std::string::npos);
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(axial->cursorPosition()[size_t(k)], cursor[size_t(k)]) << "a ruler click moved the crosshair";
  EXPECT_GT(rulerPixels(*axial), 30) << "the ruler is not drawn";
  ws.screenshot("thickness-ruler");
  // Kept in the scene's landmarks (LPS; the sample's axes are the patient's), undoable.
  auto* landmarks = static_cast<LandmarksNode*>(ws.scene().nodesOfType(NodeType::Landmarks).back());
  ASSERT_EQ(landmarks->distances().size(), 1u);
  EXPECT_EQ(landmarks->distances().front().name, "Ruler 1");
  EXPECT_NEAR(landmarks->distances().front().length(), distance(measured->from, measured->to), 1e-6);
  EXPECT_EQ(ws.scene().undoStack().undoLabel(), "Measure Ruler 1");
  // Listed in the Range maps panel; clicked, it is drawn on the slices; and
  // it comes back with the saved scene.
  const auto listed = [&ws]() {
    auto* list = ws.widget<QListWidget>("rangemap.distances");
    return list && list->count() == 1 && list->isVisible() ? list : nullptr;
  };
  ASSERT_NE(listed(), nullptr) << "the distance is not listed";
  EXPECT_EQ(listed()->item(0)->text(),
            "Ruler 1: " + QString::number(distance(measured->from, measured->to), 'f', 1) + " mm");

  // It belongs to its slice: gone on the next, back on its own.
  axial->handleWheel(+3);
  ws.settle(100);
  EXPECT_EQ(rulerPixels(*axial), 0);
  axial->handleWheel(-3);
  ws.settle(100);
  EXPECT_GT(rulerPixels(*axial), 30);
  // Ruler mode off: a click moves the crosshair again.
  ruler->trigger();
  ws.settle(100);
  QTest::mouseClick(axial, Qt::LeftButton, Qt::NoModifier, pa);
  ws.settle(100);
  EXPECT_LT(std::hypot(axial->cursorPosition()[0] - a[0], axial->cursorPosition()[1] - a[1]), 2.0 * mmPerPixel);

  // Saved with the scene, listed when it is opened again, and drawn on the
  // slices when clicked.
  const fs::path bundle = test::scratchFolder() / "with-ruler.caps";
  fs::remove_all(bundle);
  ASSERT_TRUE(ws.window().saveSceneTo(bundle));
  ws.window().openPath(bundle);
  ASSERT_TRUE(ws.waitUntilIdle(120)) << ws.errors();
  ws.selectModule("rangemap");
  ASSERT_NE(listed(), nullptr) << "the distance did not come back with the scene";
  QTest::mouseClick(listed()->viewport(), Qt::LeftButton, Qt::NoModifier,
                    listed()->visualItemRect(listed()->item(0)).center());
  ws.settle(200);
  ASSERT_TRUE(axial->measuredSegment().has_value());
  EXPECT_NEAR(distance(axial->measuredSegment()->from, measured->from), 0.0, 1e-6);
  EXPECT_NEAR(distance(axial->measuredSegment()->to, measured->to), 0.0, 1e-6);
}

TEST(ThicknessReviewPanel, ALineDrawnOnTheSkinGetsItsThicknessProfile)
{
  test::Workstation ws;
  openTheReview(ws);
  auto review = ThicknessReview::fromScene(ws.scene());
  ASSERT_TRUE(review.has_value());
  // Across the forehead, 15° either side of the midline (θ = −90° faces
  // front), 35 mm above the nasion.
  auto* landmarks = static_cast<LandmarksNode*>(ws.scene().nodesOfType(NodeType::Landmarks).back());
  double zNasion = NAN;
  for (const auto& l : landmarks->landmarks())
    if (l.name == "nasion")
      zNasion = review->chartOf(l.position)[1];
  ASSERT_TRUE(std::isfinite(zNasion));
  const double z = zNasion + 35.0;
  ws.window().setThreeDViewCamera(cameraOnTheFace(*review, -90.0 * kDegree, z));
  ws.settle(200);
  const auto start = review->probe(-105.0 * kDegree, z).skinPoint;
  const auto end = review->probe(-75.0 * kDegree, z).skinPoint;
  auto* draw = ws.widget<QPushButton>("rangemap.profile");
  ASSERT_NE(draw, nullptr);
  QTest::mouseClick(draw, Qt::LeftButton);
  ws.settle(100);
  ws.clickThreeDView(ws.threeDViewPointOf(start));
  ws.clickThreeDView(ws.threeDViewPointOf(end));
  ws.settle(300);
  ASSERT_TRUE(ws.errors().empty()) << ws.errors();

  auto* plot = ws.widget<QLabel>("rangemap.profilePlot");
  auto* summary = ws.widget<QLabel>("rangemap.profileSummary");
  ASSERT_NE(plot, nullptr);
  ASSERT_NE(summary, nullptr);
  EXPECT_TRUE(plot->isVisible());
  ASSERT_FALSE(plot->pixmap(Qt::ReturnByValue).isNull()) << summary->text().toStdString();
  // "Line L mm along the skin: thickness radial from A to B mm, mean M mm".
  const QRegularExpressionMatch read =
    QRegularExpression("^Line ([0-9.]+) mm along the skin: thickness radial from ([0-9.]+) to ([0-9.]+) mm")
      .match(summary->text());
  ASSERT_TRUE(read.hasMatch()) << summary->text().toStdString();
  const double length = read.captured(1).toDouble(), low = read.captured(2).toDouble(),
               high = read.captured(3).toDouble();
  // Along the skin: the forehead's arc, longer than its chord and shorter
  // than half a circle on it; the thickness is the forehead's, a few mm,
  // and the same as the map reads under the ends.
  EXPECT_GT(length, distance(start, end));
  EXPECT_LT(length, 0.5 * std::numbers::pi * distance(start, end));
  EXPECT_GT(low, 1.0);
  EXPECT_LT(high, 12.0);
  for (const auto& [theta, expected] : {std::pair{-105.0, review->probe(-105.0 * kDegree, z).thickness},
                                        std::pair{-75.0, review->probe(-75.0 * kDegree, z).thickness}})
  {
    EXPECT_GE(expected, low - 0.3) << theta;
    EXPECT_LE(expected, high + 0.3) << theta;
  }
  ws.screenshot("thickness-profile");
}

} // namespace caps
