// Figures rendered offscreen (the report's, the results' and the expressions'): a head phantom (an ellipsoid
// with a nose) seen from the front, obliquely and in profile, with an
// incision line, numbered points, scalar colours and a colour bar. The test
// binary needs no DISPLAY: OffscreenDisplay starts a private Xvfb.
// The PNGs go to CAPS_TEST_ARTIFACTS_DIR/render/ for a person to look at.

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include <QImage>

#include <Eigen/Geometry>
#include <vtkAppendPolyData.h>
#include <vtkConeSource.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPlaneSource.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSphereSource.h>
#include <vtkTransform.h>
#include <vtkTransformPolyDataFilter.h>
#include <vtkTriangleFilter.h>
#include <vtkUnsignedCharArray.h>

#include <signal.h>
#include <unistd.h>

#include "render/OffscreenDisplay.h"
#include "render/Figure.h"
#include "segmentation/CylindricalFrame.h"
#include "segmentation/RangeMap.h"

namespace fs = std::filesystem;

namespace caps::render {
namespace {

constexpr double kPi = std::numbers::pi;
// The phantom: an ellipsoid head (semi-axes 75 mm left-right, 95 mm
// front-back, 110 mm up-down) centred on the frame's origin, with a nose.
constexpr double kA = 75.0, kB = 95.0, kC = 110.0;

fs::path artifacts()
{
  const fs::path dir = fs::path(CAPS_TEST_ARTIFACTS_DIR) / "render";
  fs::create_directories(dir);
  return dir;
}

/// A point on the phantom's ellipsoid at cylindrical θ (LPS: θ = -π/2 is anterior) and height z.
Eigen::Vector3d onHead(double theta, double z)
{
  const double s = std::sqrt(1.0 - (z / kC) * (z / kC));
  return {kA * s * std::cos(theta), kB * s * std::sin(theta), z};
}

vtkSmartPointer<vtkPolyData> headPhantom(double cheekBulge = 0.0)
{
  vtkNew<vtkSphereSource> sphere;
  sphere->SetRadius(1.0);
  sphere->SetThetaResolution(128);
  sphere->SetPhiResolution(96);
  vtkNew<vtkTransform> scale;
  scale->Scale(kA, kB, kC);
  vtkNew<vtkTransformPolyDataFilter> head;
  head->SetInputConnection(sphere->GetOutputPort());
  head->SetTransform(scale);

  vtkNew<vtkConeSource> cone; // the nose: along -y (anterior), tip 25 mm in front of the face
  cone->SetResolution(48);
  cone->SetHeight(40.0);
  cone->SetRadius(14.0);
  cone->SetCenter(0.0, 0.0, 0.0);
  cone->SetDirection(0.0, -1.0, 0.0);
  vtkNew<vtkTransform> place;
  place->Translate(0.0, -kB - 5.0, -10.0);
  place->Scale(0.8, 1.0, 1.4);
  vtkNew<vtkTransformPolyDataFilter> nose;
  nose->SetInputConnection(cone->GetOutputPort());
  nose->SetTransform(place);

  vtkNew<vtkAppendPolyData> append;
  append->AddInputConnection(head->GetOutputPort());
  append->AddInputConnection(nose->GetOutputPort());
  vtkNew<vtkTriangleFilter> triangles;
  triangles->SetInputConnection(append->GetOutputPort());
  triangles->Update();
  auto out = vtkSmartPointer<vtkPolyData>::New();
  out->DeepCopy(triangles->GetOutput());

  // Post-operative stand-in: the left cheek bulges out by cheekBulge mm.
  const Eigen::Vector3d cheek = onHead(-kPi / 4.0, -20.0);
  vtkPoints* points = out->GetPoints();
  vtkNew<vtkUnsignedCharArray> colour;
  colour->SetName("skin_colour");
  colour->SetNumberOfComponents(3);
  vtkNew<vtkFloatArray> stress;
  stress->SetName("stress");
  for (vtkIdType i = 0; i < points->GetNumberOfPoints(); ++i)
  {
    double p[3];
    points->GetPoint(i, p);
    Eigen::Vector3d x(p[0], p[1], p[2]);
    if (cheekBulge != 0.0)
    {
      const double w = std::exp(-(x - cheek).squaredNorm() / (2.0 * 25.0 * 25.0));
      const Eigen::Vector3d outward =
        Eigen::Vector3d(x.x() / (kA * kA), x.y() / (kB * kB), x.z() / (kC * kC)).normalized();
      x += cheekBulge * w * outward;
      points->SetPoint(i, x.data());
    }
    const unsigned char skin[3] = {228, 190, 165};
    colour->InsertNextTypedTuple(skin);
    // A stress-like field: peaks at the cheek, kPa.
    stress->InsertNextValue(float(40.0 * std::exp(-(x - cheek).squaredNorm() / (2.0 * 30.0 * 30.0))));
  }
  out->GetPointData()->AddArray(colour);
  out->GetPointData()->AddArray(stress);
  return out;
}

/// An elliptical excision on the left cheek, as a closed loop of points on the phantom.
std::vector<Eigen::Vector3d> cheekEllipse(int n = 24)
{
  std::vector<Eigen::Vector3d> loop;
  for (int i = 0; i < n; ++i)
  {
    const double t = 2.0 * kPi * i / n;
    loop.push_back(onHead(-kPi / 3.0 + 0.22 * std::cos(t), -15.0 + 9.0 * std::sin(t)));
  }
  return loop;
}

LineLayer loopLine(std::vector<Eigen::Vector3d> points)
{
  LineLayer line;
  line.points = std::move(points);
  line.closed = true;
  return line;
}

/// The pixel (top-down) of a world point, by a pinhole model written out here.
Eigen::Vector2d pinhole(const Camera& c, int width, int height, const Eigen::Vector3d& p)
{
  const Eigen::Vector3d eye(c.position[0], c.position[1], c.position[2]);
  const Eigen::Vector3d focal(c.focalPoint[0], c.focalPoint[1], c.focalPoint[2]);
  const Eigen::Vector3d v = (eye - focal).normalized();
  Eigen::Vector3d u(c.viewUp[0], c.viewUp[1], c.viewUp[2]);
  u = (u - u.dot(v) * v).normalized();
  const Eigen::Vector3d r = u.cross(v);
  const Eigen::Vector3d d = p - eye;
  const double depth = -d.dot(v);
  const double tanV = std::tan(0.5 * c.viewAngle * kPi / 180.0);
  const double aspect = double(width) / height;
  const double x = d.dot(r) / depth / (tanV * aspect), y = d.dot(u) / depth / tanV;
  return {0.5 * width * (1.0 + x), 0.5 * height * (1.0 - y)};
}

double colourDistance(const std::array<std::uint8_t, 3>& a, const Rgb& b)
{
  double worst = 0.0;
  for (int k = 0; k < 3; ++k)
    worst = std::max(worst, std::abs(double(a[std::size_t(k)]) - 255.0 * b[std::size_t(k)]));
  return worst;
}

double meanAbsoluteDifference(vtkImageData* a, vtkImageData* b)
{
  const RgbBytes x = rgbBytesTopDown(a), y = rgbBytesTopDown(b);
  if (x.bytes.size() != y.bytes.size())
    return 1e9;
  double sum = 0.0;
  for (std::size_t i = 0; i < x.bytes.size(); ++i)
    sum += std::abs(int(x.bytes[i]) - int(y.bytes[i]));
  return sum / double(x.bytes.size());
}

class ReportFigures : public ::testing::Test
{
protected:
  static void SetUpTestSuite() { head_ = headPhantom(); }
  static void TearDownTestSuite() { head_ = nullptr; }

  /// The phantom in its skin colours from a view, camera fitted to the figure.
  static Figure headFigure(View view, int width = 1600, int height = 1200)
  {
    Figure f;
    f.width = width;
    f.height = height;
    f.surfaces.push_back(SurfaceLayer::pointColours(head_));
    f.camera = headCamera(seg::CylindricalFrame(), view, {head_.Get()}, f.sceneAspect());
    return f;
  }

  static vtkSmartPointer<vtkPolyData> head_;
};

vtkSmartPointer<vtkPolyData> ReportFigures::head_;

// ---------------------------------------------------------------------------
// OffscreenDisplay

TEST(OffscreenDisplay, EnsureGivesADisplayAndIsIdempotent)
{
  OffscreenDisplay::ensure();
  const char* display = std::getenv("DISPLAY");
  ASSERT_NE(display, nullptr);
  EXPECT_EQ(OffscreenDisplay::display(), display);
  const int pid = OffscreenDisplay::serverPid();
  for (int i = 0; i < 5; ++i)
    OffscreenDisplay::ensure();
  EXPECT_EQ(OffscreenDisplay::serverPid(), pid);
  EXPECT_EQ(OffscreenDisplay::display(), std::getenv("DISPLAY"));
}

TEST(OffscreenDisplay, ShutdownReapsThePrivateServerAndEnsureStartsAnother)
{
  OffscreenDisplay::ensure();
  if (!OffscreenDisplay::ownsServer())
    GTEST_SKIP() << "DISPLAY=" << OffscreenDisplay::display() << " is usable: no private Xvfb to stop";
  const int pid = OffscreenDisplay::serverPid();
  OffscreenDisplay::shutdown();
  EXPECT_FALSE(OffscreenDisplay::ownsServer());
  // Reaped, not a zombie: the pid no longer exists.
  EXPECT_EQ(::kill(pid, 0), -1);
  EXPECT_EQ(errno, ESRCH);
  OffscreenDisplay::ensure();
  EXPECT_TRUE(OffscreenDisplay::ownsServer());
  EXPECT_NE(OffscreenDisplay::serverPid(), pid);
  // A server killed behind our back is noticed and replaced.
  const int second = OffscreenDisplay::serverPid();
  ::kill(second, SIGKILL);
  ::usleep(200000);
  OffscreenDisplay::ensure();
  EXPECT_TRUE(OffscreenDisplay::ownsServer());
  EXPECT_NE(OffscreenDisplay::serverPid(), second);
  EXPECT_EQ(::kill(second, 0), -1);
}

TEST(OffscreenDisplay, WithoutXvfbTheMessageSaysWhatToDo)
{
  OffscreenDisplay::shutdown();
  const char* outer = std::getenv("DISPLAY");
  const std::string saved = outer ? outer : "";
  ::unsetenv("DISPLAY");
  ::setenv("CAPS_XVFB", "/nonexistent/Xvfb", 1);
  try
  {
    OffscreenDisplay::ensure();
    ADD_FAILURE() << "no exception without DISPLAY and without Xvfb";
  }
  catch (const std::runtime_error& e)
  {
    const std::string message = e.what();
    EXPECT_NE(message.find("install the Debian package xvfb"), std::string::npos) << message;
    EXPECT_NE(message.find("xvfb-run -a"), std::string::npos) << message;
  }
  ::unsetenv("CAPS_XVFB");
  if (!saved.empty())
    ::setenv("DISPLAY", saved.c_str(), 1);
  OffscreenDisplay::ensure();
  EXPECT_FALSE(OffscreenDisplay::display().empty());
}

TEST(OffscreenDisplay, ObjectsKeepTheServerWhileTheyLive)
{
  {
    OffscreenDisplay a;
    OffscreenDisplay b;
    EXPECT_FALSE(OffscreenDisplay::display().empty());
  }
  // Rendering after the objects are gone still works (ensure() starts what is needed).
  Figure f;
  f.width = 64;
  f.height = 48;
  f.surfaces.push_back(SurfaceLayer::solid(headPhantom(), {0.8, 0.6, 0.5}));
  f.camera = lookAtCamera(Eigen::Vector3d::Zero(), {0, -1, 0}, {0, 0, 1}, 120.0, 64.0 / 48.0);
  EXPECT_GT(pixelVariance(renderFigure(f)), 10.0);
}

TEST(OffscreenDisplay, ARenderingThreadMayStartTheServerAndRender)
{
  OffscreenDisplay::shutdown(); // so that the thread starts the private server, if one is needed
  double variance = 0.0;
  std::string error;
  std::thread worker([&] {
    try
    {
      for (int i = 0; i < 3; ++i)
      {
        Figure f;
        f.width = 320;
        f.height = 240;
        f.surfaces.push_back(SurfaceLayer::solid(headPhantom(), {0.8, 0.6, 0.5}));
        f.camera = lookAtCamera(Eigen::Vector3d::Zero(), {0, -1, 0}, {0, 0, 1}, 120.0, 320.0 / 240.0);
        variance = pixelVariance(renderFigure(f));
      }
    }
    catch (const std::exception& e)
    {
      error = e.what();
    }
  });
  worker.join();
  EXPECT_EQ(error, "");
  EXPECT_GT(variance, 10.0);
  // The server outlives the thread that started it.
  Figure f;
  f.width = 64;
  f.height = 48;
  f.surfaces.push_back(SurfaceLayer::solid(headPhantom(), {0.8, 0.6, 0.5}));
  f.camera = lookAtCamera(Eigen::Vector3d::Zero(), {0, -1, 0}, {0, 0, 1}, 120.0, 64.0 / 48.0);
  EXPECT_GT(pixelVariance(renderFigure(f)), 10.0);
}

// ---------------------------------------------------------------------------
// Figures

TEST_F(ReportFigures, FrontRenderHasTheRequestedSizeIsNotBlankAndFillsTheFrame)
{
  Figure f = headFigure(View::Front);
  f.lines.push_back(loopLine(cheekEllipse()));
  f.lines.back().numberPoints({0, 6, 12, 18});
  const auto start = std::chrono::steady_clock::now();
  vtkSmartPointer<vtkImageData> image = renderFigure(f);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "1600 x 1200 render: " << seconds << " s (DISPLAY=" << OffscreenDisplay::display()
            << (OffscreenDisplay::ownsServer() ? ", private Xvfb" : "") << ")\n";
  writePng(image, artifacts() / "head-front.png");

  int dims[3];
  image->GetDimensions(dims);
  EXPECT_EQ(dims[0], 1600);
  EXPECT_EQ(dims[1], 1200);
  EXPECT_GT(pixelVariance(image), 100.0);

  // The head is 220 mm tall and 150 mm wide: fitted with a 10 % margin, it
  // spans about 1/1.1 of the height and is centred.
  const double occupied = occupiedFraction(image);
  EXPECT_GT(occupied, 0.25); // an ellipse of 150 × 220 mm in a 4:3 frame: about 0.33
  EXPECT_LT(occupied, 0.75);
  const auto box = boundingBoxOfNonBackground(image);
  ASSERT_TRUE(box);
  EXPECT_NEAR(double(box->height()) / 1200.0, 1.0 / 1.1, 0.03);
  EXPECT_NEAR(0.5 * (box->y0 + box->y1), 600.0, 12.0);
  EXPECT_NEAR(0.5 * (box->x0 + box->x1), 800.0, 12.0);

  const RgbBytes bytes = rgbBytesTopDown(image);
  EXPECT_EQ(bytes.width, 1600);
  EXPECT_EQ(bytes.height, 1200);
  ASSERT_EQ(bytes.bytes.size(), std::size_t(1600 * 1200 * 3));
  const QImage q = toQImage(image);
  EXPECT_EQ(q.width(), 1600);
  EXPECT_EQ(q.height(), 1200);
  // Top-down: the pixel at the top-left of the QImage is the one pixelAt(0, 0) reads.
  const auto top = pixelAt(image, 800, box->y0 + 5);
  EXPECT_EQ(qRed(q.pixel(800, box->y0 + 5)), top[0]);
  EXPECT_EQ(bytes.bytes[(std::size_t(box->y0 + 5) * 1600 + 800) * 3 + 1], top[1]);
}

TEST_F(ReportFigures, OtherPixelSizesAreHonoured)
{
  for (const auto& [w, h] : {std::pair{640, 480}, std::pair{900, 1200}, std::pair{1201, 333}})
  {
    vtkSmartPointer<vtkImageData> image = renderFigure(headFigure(View::ObliqueLeft, w, h));
    int dims[3];
    image->GetDimensions(dims);
    EXPECT_EQ(dims[0], w);
    EXPECT_EQ(dims[1], h);
    const auto box = boundingBoxOfNonBackground(image);
    ASSERT_TRUE(box);
    // Fitted whatever the aspect: inside the frame with a margin, touching it on one axis.
    EXPECT_GT(box->x0, 0);
    EXPECT_GT(box->y0, 0);
    EXPECT_LT(box->x1, w - 1);
    EXPECT_LT(box->y1, h - 1);
    EXPECT_GT(std::max(double(box->width()) / w, double(box->height()) / h), 0.85);
  }
  // FXAA instead of multisampling.
  Figure fxaa = headFigure(View::Front, 800, 600);
  fxaa.multiSamples = 0;
  fxaa.fxaa = true;
  vtkSmartPointer<vtkImageData> smoothed = renderFigure(fxaa);
  EXPECT_GT(pixelVariance(smoothed), 100.0);
  writePng(smoothed, artifacts() / "head-front-fxaa.png");

  Figure tooSmall = headFigure(View::Front);
  tooSmall.width = 4;
  EXPECT_THROW(renderFigure(tooSmall), std::invalid_argument);
}

TEST_F(ReportFigures, TheLineIsDrawnWhereItsPointsProject)
{
  Figure f = headFigure(View::Front);
  LineLayer line;
  for (int i = 0; i <= 30; ++i) // across the forehead, θ from -130° to -50°
    line.points.push_back(onHead((-130.0 + 80.0 * i / 30.0) * kPi / 180.0, 45.0));
  line.colour = {0.85, 0.05, 0.05};
  line.widthPixels = 8.0;
  f.lines.push_back(line);
  vtkSmartPointer<vtkImageData> image = renderFigure(f);
  writePng(image, artifacts() / "head-front-line.png");

  int checked = 0;
  for (std::size_t i = 2; i + 2 < line.points.size(); i += 3)
  {
    const Eigen::Vector3d mid = 0.5 * (line.points[i] + line.points[i + 1]);
    const Eigen::Vector2d expected = pinhole(f.camera, f.width, f.height, mid);
    const Eigen::Vector2d library = projectToPixel(f, mid);
    EXPECT_NEAR(library.x(), expected.x(), 0.5);
    EXPECT_NEAR(library.y(), expected.y(), 0.5);
    // The midpoint of the chord lies a little inside the ellipsoid, behind the
    // skin; the lifted line still shows there.
    const auto pixel = pixelAt(image, int(expected.x()), int(expected.y()));
    EXPECT_LT(colourDistance(pixel, line.colour), 30.0)
      << "at (" << expected.x() << ", " << expected.y() << "): " << int(pixel[0]) << " " << int(pixel[1]) << " "
      << int(pixel[2]);
    ++checked;
  }
  EXPECT_GE(checked, 8);

  // Without the line those pixels are skin.
  Figure bare = headFigure(View::Front);
  vtkSmartPointer<vtkImageData> skin = renderFigure(bare);
  const Eigen::Vector2d p = pinhole(f.camera, f.width, f.height, line.points[15]);
  EXPECT_GT(colourDistance(pixelAt(skin, int(p.x()), int(p.y())), line.colour), 60.0);
}

TEST_F(ReportFigures, NumberedPointsHaveLabelsBesideThem)
{
  Figure f = headFigure(View::ObliqueLeft);
  LineLayer line = loopLine(cheekEllipse());
  line.numberPoints({0, 6, 12, 18});
  EXPECT_EQ(line.labels[6], "2");
  EXPECT_TRUE(line.labels[1].empty());
  f.lines.push_back(line);
  vtkSmartPointer<vtkImageData> image = renderFigure(f);
  writePng(image, artifacts() / "head-oblique-incision.png");

  LineLayer unlabelled = loopLine(cheekEllipse());
  Figure plain = f;
  plain.lines = {unlabelled};
  vtkSmartPointer<vtkImageData> without = renderFigure(plain);

  // Around each numbered point, within a label's reach, dark text pixels that
  // the unlabelled render does not have.
  const double reach = 1.1 * line.widthPixels + 1.6 * f.textPoints * f.pixelsPerPoint();
  for (const std::size_t i : {0, 6, 12, 18})
  {
    const Eigen::Vector2d c = projectToPixel(f, line.points[i]);
    int dark = 0, darkBefore = 0;
    for (int y = int(c.y() - reach); y <= int(c.y() + reach); ++y)
      for (int x = int(c.x() - reach); x <= int(c.x() + reach); ++x)
      {
        if (x < 0 || y < 0 || x >= f.width || y >= f.height)
          continue;
        const auto a = pixelAt(image, x, y), b = pixelAt(without, x, y);
        dark += (a[0] < 70 && a[1] < 70 && a[2] < 70) ? 1 : 0;
        darkBefore += (b[0] < 70 && b[1] < 70 && b[2] < 70) ? 1 : 0;
      }
    EXPECT_GT(dark - darkBefore, 100) << "no label near point " << i;
  }
  EXPECT_THROW(line.numberPoints({99}), std::invalid_argument);
}

TEST_F(ReportFigures, LabelsOfHiddenPointsAreLeftOut)
{
  Figure f = headFigure(View::Front);
  LineLayer line; // from the front of the head, through it, to the back
  line.points = {onHead(-kPi / 2.0 + 0.4, 20.0), onHead(kPi / 2.0 + 0.4, -30.0)};
  line.numberPoints();
  f.lines.push_back(line);
  vtkSmartPointer<vtkImageData> image = renderFigure(f);
  Figure plain = headFigure(View::Front);
  vtkSmartPointer<vtkImageData> without = renderFigure(plain);
  const double reach = 1.1 * line.widthPixels + 1.6 * f.textPoints * f.pixelsPerPoint();
  auto newDark = [&](const Eigen::Vector3d& point) {
    const Eigen::Vector2d c = projectToPixel(f, point);
    int count = 0;
    for (int y = int(c.y() - reach); y <= int(c.y() + reach); ++y)
      for (int x = int(c.x() - reach); x <= int(c.x() + reach); ++x)
      {
        const auto a = pixelAt(image, x, y), b = pixelAt(without, x, y);
        count += ((a[0] < 70 && a[1] < 70 && a[2] < 70) && !(b[0] < 70 && b[1] < 70 && b[2] < 70)) ? 1 : 0;
      }
    return count;
  };
  EXPECT_GT(newDark(line.points[0]), 100) << "the front point's label is missing";
  EXPECT_EQ(newDark(line.points[1]), 0) << "the hidden point's label shows through the head";
}

TEST_F(ReportFigures, ColourBarDrawsOnTheRightAndShowsTheMap)
{
  Figure f = headFigure(View::ObliqueLeft);
  f.surfaces = {SurfaceLayer::scalars(head_, "stress", 0.0, 40.0, ColourMap::Viridis)};
  f.colourBar = ColourBar{"von Mises stress (kPa)", {0.0, 40.0}, ColourMap::Viridis};
  f.camera = headCamera(seg::CylindricalFrame(), View::ObliqueLeft, {head_.Get()}, f.sceneAspect());
  vtkSmartPointer<vtkImageData> withBar = renderFigure(f);
  writePng(withBar, artifacts() / "head-oblique-stress.png");

  const auto viewport = f.sceneViewport();
  ASSERT_LT(viewport[2], 0.95);
  ASSERT_GT(viewport[2], 0.6);
  Figure g = f;
  g.colourBar.reset();
  EXPECT_EQ(g.sceneViewport()[2], 1.0);

  // The bar's column: well inked; the strip between the scene and the bar: empty.
  const int column = int(viewport[2] * f.width) + 1;
  int ink = 0, strip = 0;
  for (int y = 0; y < f.height; ++y)
  {
    for (int x = column; x < f.width; ++x)
    {
      const auto a = pixelAt(withBar, x, y);
      ink += (a[0] < 240 || a[1] < 240 || a[2] < 240) ? 1 : 0;
    }
    for (int x = column - 8; x < column; ++x)
    {
      const auto a = pixelAt(withBar, x, y);
      strip += (a[0] < 250 || a[1] < 250 || a[2] < 250) ? 1 : 0;
    }
  }
  EXPECT_GT(ink, (f.width - column) * f.height / 20);
  EXPECT_EQ(strip, 0);

  // The bar shows the map: its bottom the low end, its top the high end.
  int barX = -1;
  for (int x = column; x < f.width && barX < 0; ++x)
    if (colourDistance(pixelAt(withBar, x, f.height / 2), colourMapColour(ColourMap::Viridis, 0.5)) < 25.0)
      barX = x;
  ASSERT_GE(barX, 0) << "no bar colour at mid-height in the right column";
  barX += 10;
  int top = f.height / 2, bottom = f.height / 2;
  auto inked = [&](int y) {
    const auto a = pixelAt(withBar, barX, y);
    return a[0] < 245 || a[1] < 245 || a[2] < 245;
  };
  while (top > 0 && inked(top - 1))
    --top;
  while (bottom + 1 < f.height && inked(bottom + 1))
    ++bottom;
  EXPECT_GT(bottom - top, f.height / 2);
  EXPECT_LT(colourDistance(pixelAt(withBar, barX, bottom - 6), colourMapColour(ColourMap::Viridis, 0.0)), 25.0);
  EXPECT_LT(colourDistance(pixelAt(withBar, barX, top + 6), colourMapColour(ColourMap::Viridis, 1.0)), 25.0);

  // Tick labels ("0", "40") sit level with the bar's ends: dark text pixels
  // in a band a third of the font tall centred on each end, right of the bar.
  const int band = int(f.textPoints * f.pixelsPerPoint() / 6.0);
  auto darkNear = [&](int yc) {
    int dark = 0;
    for (int y = yc - band; y <= yc + band; ++y)
      for (int x = barX + 40; x < std::min(f.width, barX + 250); ++x)
      {
        const auto a = pixelAt(withBar, x, y);
        dark += (a[0] < 80 && a[1] < 80 && a[2] < 80) ? 1 : 0;
      }
    return dark;
  };
  EXPECT_GT(darkNear(top), 30);
  EXPECT_GT(darkNear(bottom), 30);
}

TEST_F(ReportFigures, ScalarColouringMapsTheRangeEndsToTheMapEnds)
{
  // A plate facing the camera, value = x, range [-30, 30] mm; unlit, so the
  // pixels are the map's colours.
  vtkNew<vtkPlaneSource> plane;
  plane->SetOrigin(-50, 0, -30);
  plane->SetPoint1(50, 0, -30);
  plane->SetPoint2(-50, 0, 30);
  plane->SetResolution(50, 10);
  plane->Update();
  auto plate = vtkSmartPointer<vtkPolyData>::New();
  plate->DeepCopy(plane->GetOutput());
  vtkNew<vtkFloatArray> value;
  value->SetName("value");
  for (vtkIdType i = 0; i < plate->GetNumberOfPoints(); ++i)
    value->InsertNextValue(float(plate->GetPoint(i)[0]));
  plate->GetPointData()->AddArray(value);

  for (const ColourMap map : {ColourMap::Viridis, ColourMap::Thickness, ColourMap::CoolWarm})
  {
    Figure f;
    f.width = 800;
    f.height = 600;
    SurfaceLayer layer = SurfaceLayer::scalars(plate, "value", -30.0, 30.0, map);
    layer.lit = false;
    f.surfaces.push_back(layer);
    f.camera = fitCamera({plate.Get()}, {0, -1, 0}, {0, 0, 1}, f.sceneAspect());
    vtkSmartPointer<vtkImageData> image = renderFigure(f);
    writePng(image, artifacts() / ("plate-" + std::to_string(int(map)) + ".png"));
    for (const auto& [x, t] : {std::pair{-45.0, 0.0}, std::pair{-30.0 - 5.0, 0.0}, std::pair{0.0, 0.5},
                               std::pair{15.0, 0.75}, std::pair{45.0, 1.0}})
    {
      const Eigen::Vector2d p = projectToPixel(f, {x, 0.0, 0.0});
      const auto pixel = pixelAt(image, int(p.x()), int(p.y()));
      EXPECT_LT(colourDistance(pixel, colourMapColour(map, t)), 6.0)
        << "map " << int(map) << " at x = " << x << ": " << int(pixel[0]) << " " << int(pixel[1]) << " "
        << int(pixel[2]);
    }
  }
  // The map ends are what they claim: viridis dark violet → yellow, thickness pale → dark blue.
  EXPECT_LT(colourMapColour(ColourMap::Viridis, 0.0)[1], 0.05);
  EXPECT_GT(colourMapColour(ColourMap::Viridis, 1.0)[0], 0.95);
  EXPECT_GT(colourMapColour(ColourMap::Thickness, 0.0)[0], 0.9);
  EXPECT_LT(colourMapColour(ColourMap::Thickness, 1.0)[2], 0.4);

  Figure missing;
  missing.surfaces.push_back(SurfaceLayer::scalars(plate, "no-such-array", 0.0, 1.0, ColourMap::Viridis));
  try
  {
    renderFigure(missing);
    FAIL() << "no exception";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("no-such-array"), std::string::npos) << e.what();
  }
  Figure badRange;
  badRange.surfaces.push_back(SurfaceLayer::scalars(plate, "value", 1.0, 1.0, ColourMap::Viridis));
  EXPECT_THROW(renderFigure(badRange), std::invalid_argument);
}

TEST_F(ReportFigures, FrontObliqueAndProfileDiffer)
{
  vtkSmartPointer<vtkImageData> front = renderFigure(headFigure(View::Front));
  vtkSmartPointer<vtkImageData> oblique = renderFigure(headFigure(View::ObliqueLeft));
  vtkSmartPointer<vtkImageData> profile = renderFigure(headFigure(View::ProfileLeft));
  writePng(oblique, artifacts() / "head-oblique.png");
  writePng(profile, artifacts() / "head-profile.png");
  EXPECT_GT(meanAbsoluteDifference(front, profile), 3.0);
  EXPECT_GT(meanAbsoluteDifference(front, oblique), 3.0);
  EXPECT_GT(meanAbsoluteDifference(oblique, profile), 3.0);

  // Seen from the patient's left, the face looks to the viewer's left (the
  // image's right is posterior): the nose tip projects left of centre, and
  // the head is deeper (190 + nose) than wide (150).
  Figure p = headFigure(View::ProfileLeft);
  const Eigen::Vector2d tip = projectToPixel(p, {0.0, -kB - 25.0, -10.0});
  EXPECT_LT(tip.x(), 400.0);
  const auto nose = pixelAt(profile, int(tip.x()) + 15, int(tip.y()));
  EXPECT_LT(int(nose[0]) + nose[1] + nose[2], 3 * 245) << "no nose at the tip's pixel";
  const auto frontBox = boundingBoxOfNonBackground(front);
  const auto profileBox = boundingBoxOfNonBackground(profile);
  ASSERT_TRUE(frontBox && profileBox);
  EXPECT_GT(double(profileBox->width()) / profileBox->height(), 1.1 * double(frontBox->width()) / frontBox->height());
}

TEST_F(ReportFigures, PreAndPostWithTheSameCameraKeepTheFraming)
{
  vtkSmartPointer<vtkPolyData> post = headPhantom(6.0);
  for (const View view : {View::Front, View::ObliqueLeft})
  {
    Figure pre;
    pre.surfaces.push_back(SurfaceLayer::pointColours(head_));
    pre.camera = headCamera(seg::CylindricalFrame(), view, {head_.Get(), post.Get()}, pre.sceneAspect());
    Figure after = pre;
    after.surfaces = {SurfaceLayer::pointColours(post)};
    EXPECT_EQ(after.camera, pre.camera);
    vtkSmartPointer<vtkImageData> a = renderFigure(pre);
    vtkSmartPointer<vtkImageData> b = renderFigure(after);
    const std::string name = view == View::Front ? "front" : "oblique";
    writePng(a, artifacts() / ("pre-" + name + ".png"));
    writePng(b, artifacts() / ("post-" + name + ".png"));
    const auto boxA = boundingBoxOfNonBackground(a), boxB = boundingBoxOfNonBackground(b);
    ASSERT_TRUE(boxA && boxB);
    // Top and bottom (crown, chin) do not move; the cheek may widen the silhouette a little.
    EXPECT_LE(std::abs(boxA->y0 - boxB->y0), 2);
    EXPECT_LE(std::abs(boxA->y1 - boxB->y1), 2);
    EXPECT_LE(std::abs(boxA->x0 - boxB->x0), 12);
    EXPECT_LE(std::abs(boxA->x1 - boxB->x1), 12);
    // What differs is around the cheek.
    const Eigen::Vector2d cheek = projectToPixel(pre, onHead(-kPi / 4.0, -20.0));
    const RgbBytes x = rgbBytesTopDown(a), y = rgbBytesTopDown(b);
    double near = 0.0, far = 0.0;
    for (int r = 0; r < x.height; ++r)
      for (int c = 0; c < x.width; ++c)
      {
        const std::size_t i = (std::size_t(r) * std::size_t(x.width) + std::size_t(c)) * 3;
        const int d = std::abs(int(x.bytes[i]) - int(y.bytes[i])) + std::abs(int(x.bytes[i + 1]) - int(y.bytes[i + 1]));
        (Eigen::Vector2d(c, r) - cheek).norm() < 300.0 ? near += d : far += d;
      }
    EXPECT_GT(near, 2.0 * far) << name;
  }
}

TEST_F(ReportFigures, ThicknessOnTheFaceWithItsColourBar)
{
  Figure f = headFigure(View::Front);
  f.surfaces = {SurfaceLayer::scalars(head_, "stress", 0.0, 40.0, ColourMap::Thickness)};
  f.colourBar = ColourBar{"soft tissue thickness (mm)", {0.0, 40.0}, ColourMap::Thickness};
  f.camera = headCamera(seg::CylindricalFrame(), View::Front, {head_.Get()}, f.sceneAspect());
  vtkSmartPointer<vtkImageData> image = renderFigure(f);
  writePng(image, artifacts() / "head-front-thickness.png");
  EXPECT_GT(pixelVariance(image), 100.0);
  EXPECT_GT(occupiedFraction(image), 0.3);
}

TEST(ReportCameras, HeadCamerasLookFromTheCylindricalFrame)
{
  const seg::CylindricalFrame frame;
  const std::vector<Eigen::Vector3d> ball{{-10, -10, -10}, {10, 10, 10}};
  auto direction = [](const Camera& c) {
    return Eigen::Vector3d(c.position[0] - c.focalPoint[0], c.position[1] - c.focalPoint[1],
                           c.position[2] - c.focalPoint[2])
      .normalized();
  };
  const Camera front = fitCamera(ball, frame.radialDirection(viewTheta(View::Front)), frame.direction(), 4.0 / 3.0);
  EXPECT_TRUE(direction(front).isApprox(Eigen::Vector3d(0, -1, 0), 1e-12)); // anterior
  const Camera left = fitCamera(ball, frame.radialDirection(viewTheta(View::ProfileLeft)), frame.direction(), 1.0);
  EXPECT_TRUE(direction(left).isApprox(Eigen::Vector3d(1, 0, 0), 1e-12)); // patient left
  const Camera oblique = fitCamera(ball, frame.radialDirection(viewTheta(View::ObliqueLeft)), frame.direction(), 1.0);
  EXPECT_NEAR(direction(oblique).dot(Eigen::Vector3d(0, -1, 0)), std::cos(kPi / 4.0), 1e-12);
  EXPECT_NEAR(front.viewUp[2], 1.0, 1e-12);

  // lookAtCamera frames a sphere: its silhouette's half-angle is the smaller half view angle / margin.
  const Camera c = lookAtCamera({1, 2, 3}, {0, -1, 0}, {0, 0, 1}, 50.0, 2.0, 20.0, 1.0);
  const double d = std::hypot(c.position[0] - 1, c.position[1] - 2, c.position[2] - 3);
  EXPECT_NEAR(std::asin(50.0 / d), 10.0 * kPi / 180.0, 1e-12);
  EXPECT_THROW(lookAtCamera({0, 0, 0}, {0, 0, 1}, {0, 0, 2}, 1.0, 1.0), std::invalid_argument);
}

} // namespace
} // namespace caps::render
