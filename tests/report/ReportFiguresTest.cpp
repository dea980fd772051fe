// The report's figures on the embedded sample CT: its skin range map as a
// triangle mesh with the tissue thickness on it, seen from the three report
// views with an incision on the left cheek, and the thickness with its colour
// bar. The PNGs go to CAPS_TEST_ARTIFACTS_DIR/report/ for a person to look at.

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

#include "render/Figure.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "modules/volumes/CommandLine.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"
#include "segmentation/CylindricalFrame.h"
#include "segmentation/RangeMap.h"

namespace fs = std::filesystem;

namespace caps::report {
namespace {

using namespace caps::render;

constexpr double kPi = std::numbers::pi;

fs::path artifacts()
{
  const fs::path dir = fs::path(CAPS_TEST_ARTIFACTS_DIR) / "report";
  fs::create_directories(dir);
  return dir;
}

/// The skin map as triangles, with the thickness and a skin colour at each point.
vtkSmartPointer<vtkPolyData> skinMesh(const seg::RangeMap& skin, const seg::RangeMap& thickness)
{
  const int nt = skin.nTheta(), nz = skin.nZ();
  auto mesh = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> points;
  vtkNew<vtkFloatArray> mm;
  mm->SetName("thickness");
  vtkNew<vtkUnsignedCharArray> colour;
  colour->SetName("skin_colour");
  colour->SetNumberOfComponents(3);
  std::vector<vtkIdType> id(std::size_t(nt) * std::size_t(nz), -1);
  const seg::CylindricalFrame& frame = skin.frame();
  for (int j = 0; j < nz; ++j)
    for (int i = 0; i < nt; ++i)
    {
      const Eigen::Vector3d p = skin.surfacePoint(i, j);
      if (!p.allFinite())
        continue;
      id[std::size_t(j) * std::size_t(nt) + std::size_t(i)] = points->InsertNextPoint(p.data());
      mm->InsertNextValue(float(thickness.sample(frame.indexToTheta(i), frame.indexToZ(j))));
      const unsigned char c[3] = {226, 188, 162};
      colour->InsertNextTypedTuple(c);
    }
  vtkNew<vtkCellArray> triangles;
  for (int j = 0; j + 1 < nz; ++j)
    for (int i = 0; i < nt; ++i)
    {
      const int k = (i + 1) % nt;
      const vtkIdType a = id[std::size_t(j) * std::size_t(nt) + std::size_t(i)];
      const vtkIdType b = id[std::size_t(j) * std::size_t(nt) + std::size_t(k)];
      const vtkIdType c = id[std::size_t(j + 1) * std::size_t(nt) + std::size_t(k)];
      const vtkIdType d = id[std::size_t(j + 1) * std::size_t(nt) + std::size_t(i)];
      if (a < 0 || b < 0 || c < 0 || d < 0)
        continue;
      const vtkIdType t1[3] = {a, b, c}, t2[3] = {a, c, d};
      triangles->InsertNextCell(3, t1);
      triangles->InsertNextCell(3, t2);
    }
  mesh->SetPoints(points);
  mesh->SetPolys(triangles);
  mesh->GetPointData()->AddArray(mm);
  mesh->GetPointData()->AddArray(colour);
  return mesh;
}

TEST(ReportFiguresOnTheSample, TheSampleFaceInTheReportViews)
{
  const fs::path dicom = fs::path(CAPS_TEST_DATA_DIR) / "sample-ct" / "dicom";
  if (!fs::exists(dicom))
    GTEST_SKIP() << "no sample CT at " << dicom;
  Scene scene;
  RangeMapLogic logic(scene);
  std::ostringstream messages;
  VolumeNode* volume = cli::loadCt(logic, dicom, seg::CtReadOptions{}, messages);
  ASSERT_NE(volume, nullptr) << messages.str();
  RangeMapOutput maps;
  logic.run(*volume, RangeMapLogic::Parameters{}, {}, &maps);
  const vtkSmartPointer<vtkPolyData> face = skinMesh(maps.skin, maps.thickness);
  ASSERT_GT(face->GetNumberOfPolys(), 1000);
  const seg::CylindricalFrame& frame = maps.skin.frame();

  // An ellipse on the left cheek (θ = -60°, 20 mm below the frame's middle), on the skin.
  const double zc = 0.5 * (frame.zMin() + frame.zMax()) - 20.0;
  LineLayer incision;
  incision.closed = true;
  for (int i = 0; i < 32; ++i)
  {
    const double t = 2.0 * kPi * i / 32;
    const double theta = -kPi / 3.0 + 0.20 * std::cos(t), z = zc + 9.0 * std::sin(t);
    const double r = maps.skin.sample(theta, z);
    if (std::isfinite(r))
      incision.points.push_back(frame.toWorld(r, theta, z));
  }
  ASSERT_GE(incision.points.size(), 24u);
  incision.numberPoints({0, 8, 16, 24});

  for (const auto& [view, name] : {std::pair{View::Front, "front"}, std::pair{View::ObliqueLeft, "oblique"},
                                   std::pair{View::ProfileLeft, "profile"}})
  {
    Figure f;
    f.surfaces.push_back(SurfaceLayer::pointColours(face));
    f.lines.push_back(incision);
    f.camera = headCamera(frame, view, {face.Get()}, f.sceneAspect());
    vtkSmartPointer<vtkImageData> image = renderFigure(f);
    writePng(image, artifacts() / (std::string("sample-") + name + ".png"));
    EXPECT_GT(pixelVariance(image), 100.0) << name;
    EXPECT_GT(occupiedFraction(image), 0.2) << name;
    const auto box = boundingBoxOfNonBackground(image);
    ASSERT_TRUE(box);
    EXPECT_GT(std::max(double(box->width()) / f.width, double(box->height()) / f.height), 0.85) << name;
  }

  Figure t;
  const auto& stats = maps.radialStatistics;
  (void)stats;
  t.surfaces.push_back(SurfaceLayer::scalars(face, "thickness", 0.0, 20.0, ColourMap::Thickness));
  t.colourBar = ColourBar{"soft tissue thickness (mm)", {0.0, 20.0}, ColourMap::Thickness};
  t.lines.push_back(incision);
  t.camera = headCamera(frame, View::ObliqueLeft, {face.Get()}, t.sceneAspect());
  vtkSmartPointer<vtkImageData> image = renderFigure(t);
  writePng(image, artifacts() / "sample-thickness.png");
  EXPECT_GT(pixelVariance(image), 100.0);
}

} // namespace
} // namespace caps::report
