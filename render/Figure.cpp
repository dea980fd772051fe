// ReportFigures: offscreen VTK renders of the plan report's figures.

#include "render/Figure.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include <QImage>

#include <Eigen/Geometry>
#include <vtkActor.h>
#include <vtkActor2D.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkCellLocator.h>
#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkLightKit.h>
#include <vtkLookupTable.h>
#include <vtkMapper.h>
#include <vtkMatrix4x4.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkPolyDataMapper2D.h>
#include <vtkProperty2D.h>
#include <vtkPolyDataNormals.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include "render/OffscreenDisplay.h"
#include "segmentation/CylindricalFrame.h"

namespace caps::render {
namespace {

constexpr double kPi = std::numbers::pi;

vtkSmartPointer<vtkLookupTable> makeLookupTable(ColourMap map, const std::array<double, 2>& range)
{
  return colourMapLookupTable(map, range);
}

void checkRange(const std::array<double, 2>& range, const std::string& what)
{
  if (!(std::isfinite(range[0]) && std::isfinite(range[1]) && range[0] < range[1]))
    throw std::invalid_argument(what + ": the colour range must be finite with min < max (got " +
                                std::to_string(range[0]) + ", " + std::to_string(range[1]) + ")");
}

/// Unit view vectors: v towards the camera, u up, r right (u × v).
struct ViewBasis
{
  Eigen::Vector3d v, u, r;
};

ViewBasis viewBasis(const Eigen::Vector3d& toCamera, const Eigen::Vector3d& viewUp)
{
  if (toCamera.norm() == 0.0 || !toCamera.allFinite())
    throw std::invalid_argument("camera: the view direction is zero");
  ViewBasis b;
  b.v = toCamera.normalized();
  b.u = viewUp - viewUp.dot(b.v) * b.v;
  if (b.u.norm() < 1e-9 * std::max(1.0, viewUp.norm()))
    throw std::invalid_argument("camera: view-up is parallel to the view direction");
  b.u.normalize();
  b.r = b.u.cross(b.v);
  return b;
}

Camera makeCamera(const Eigen::Vector3d& focal, const ViewBasis& b, double distance, double viewAngleDeg)
{
  Camera c;
  const Eigen::Vector3d position = focal + distance * b.v;
  c.position = {position.x(), position.y(), position.z()};
  c.focalPoint = {focal.x(), focal.y(), focal.z()};
  c.viewUp = {b.u.x(), b.u.y(), b.u.z()};
  c.viewAngle = viewAngleDeg;
  return c;
}

void checkFit(double aspect, double viewAngleDeg, double margin)
{
  if (!(aspect > 0.0))
    throw std::invalid_argument("camera: the aspect ratio must be positive");
  if (!(viewAngleDeg > 0.0 && viewAngleDeg < 179.0))
    throw std::invalid_argument("camera: the view angle must be in (0°, 179°)");
  if (!(margin >= 1.0))
    throw std::invalid_argument("camera: the margin must be at least 1");
}

void applyCamera(vtkCamera* camera, const Camera& c)
{
  camera->SetPosition(c.position.data());
  camera->SetFocalPoint(c.focalPoint.data());
  camera->SetViewUp(c.viewUp.data());
  camera->SetViewAngle(c.viewAngle);
  camera->OrthogonalizeViewUp();
}

Eigen::Vector3d toEigen(const std::array<double, 3>& a)
{
  return {a[0], a[1], a[2]};
}

vtkSmartPointer<vtkPolyData> withNormals(vtkPolyData* surface)
{
  if (surface->GetPointData()->GetNormals() != nullptr ||
      surface->GetNumberOfPolys() + surface->GetNumberOfStrips() == 0)
    return surface;
  vtkNew<vtkPolyDataNormals> normals;
  normals->SetInputData(surface);
  normals->ComputePointNormalsOn();
  normals->ComputeCellNormalsOff();
  normals->SplittingOff();
  normals->ConsistencyOn();
  normals->AutoOrientNormalsOff();
  normals->Update();
  return normals->GetOutput();
}

vtkSmartPointer<vtkActor> surfaceActor(const SurfaceLayer& layer, std::size_t index)
{
  const std::string what = "figure surface " + std::to_string(index + 1);
  if (layer.surface == nullptr || layer.surface->GetNumberOfPoints() == 0)
    throw std::invalid_argument(what + " is empty");
  vtkSmartPointer<vtkPolyData> surface = withNormals(layer.surface);
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(surface);
  mapper->SetResolveCoincidentTopologyToPolygonOffset();
  mapper->SetRelativeCoincidentTopologyPolygonOffsetParameters(1.0, 1.0);
  mapper->ScalarVisibilityOff();
  if (layer.colouring != SurfaceLayer::Colouring::Solid)
  {
    vtkDataArray* array = surface->GetPointData()->GetArray(layer.array.c_str());
    if (array == nullptr)
      throw std::invalid_argument(what + " has no point array \"" + layer.array + "\"");
    mapper->ScalarVisibilityOn();
    mapper->SetScalarModeToUsePointFieldData();
    mapper->SelectColorArray(layer.array.c_str());
    if (layer.colouring == SurfaceLayer::Colouring::PointRgb)
    {
      if (array->GetDataType() != VTK_UNSIGNED_CHAR ||
          (array->GetNumberOfComponents() != 3 && array->GetNumberOfComponents() != 4))
        throw std::invalid_argument(what + ": point array \"" + layer.array +
                                    "\" is not an RGB(A) unsigned char array");
      mapper->SetColorModeToDirectScalars();
    }
    else
    {
      checkRange(layer.range, what);
      auto table = makeLookupTable(layer.colourMap, layer.range);
      if (array->GetNumberOfComponents() > 1)
        table->SetVectorModeToMagnitude();
      mapper->SetLookupTable(table);
      mapper->SetColorModeToMapScalars();
      mapper->UseLookupTableScalarRangeOff();
      mapper->SetScalarRange(layer.range[0], layer.range[1]);
      mapper->InterpolateScalarsBeforeMappingOn();
    }
  }
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  vtkProperty* p = actor->GetProperty();
  p->SetColor(layer.colour[0], layer.colour[1], layer.colour[2]);
  p->SetOpacity(std::clamp(layer.opacity, 0.0, 1.0));
  p->SetInterpolationToPhong();
  if (layer.lit)
  {
    // Mapped colours keep more ambient light so shading does not move them far along the map.
    const bool mapped = layer.colouring == SurfaceLayer::Colouring::PointScalars;
    p->SetAmbient(mapped ? 0.25 : 0.12);
    p->SetDiffuse(mapped ? 0.75 : 0.88);
    p->SetSpecular(mapped ? 0.05 : 0.1);
    p->SetSpecularPower(25.0);
  }
  else
  {
    p->SetAmbient(1.0);
    p->SetDiffuse(0.0);
    p->SetSpecular(0.0);
  }
  p->BackfaceCullingOff();
  return actor;
}

/// Display position (VTK: y up, pixels) of a world point.
Eigen::Vector2d toDisplay(const Figure& figure, const Eigen::Vector3d& point)
{
  const Eigen::Vector2d top = projectToPixel(figure, point);
  return {top.x(), double(figure.height) - top.y()};
}

/// A point label waiting for the first render, which tells whether its point is hidden.
struct PendingLabel
{
  Eigen::Vector2d at; ///< display position of the label's centre
  std::string text;
  Eigen::Vector3d probe; ///< world point whose depth decides visibility
  double fontPx = 0.0;
};

void addLineLayer(const Figure& figure, const LineLayer& line, std::size_t index, vtkRenderer* scene,
                  std::vector<PendingLabel>& labels)
{
  const std::string what = "figure line " + std::to_string(index + 1);
  if (line.points.size() < 2)
    throw std::invalid_argument(what + " has fewer than 2 points");
  if (!line.labels.empty() && line.labels.size() != line.points.size())
    throw std::invalid_argument(what + " has " + std::to_string(line.labels.size()) + " labels for " +
                                std::to_string(line.points.size()) + " points");
  const Eigen::Vector3d eye = toEigen(figure.camera.position);
  const double distance = (toEigen(figure.camera.focalPoint) - eye).norm();
  const double lift = line.lift >= 0.0 ? line.lift : 0.006 * distance;

  vtkNew<vtkPoints> points;
  for (const Eigen::Vector3d& p : line.points)
  {
    const Eigen::Vector3d towardEye = eye - p;
    const double n = towardEye.norm();
    const Eigen::Vector3d lifted = n > lift ? Eigen::Vector3d(p + towardEye * (lift / n)) : p;
    points->InsertNextPoint(lifted.data());
  }
  const vtkIdType n = points->GetNumberOfPoints();
  vtkNew<vtkCellArray> cells;
  cells->InsertNextCell(n + (line.closed ? 1 : 0));
  for (vtkIdType i = 0; i < n; ++i)
    cells->InsertCellPoint(i);
  if (line.closed)
    cells->InsertCellPoint(0);
  vtkNew<vtkPolyData> polyline;
  polyline->SetPoints(points);
  polyline->SetLines(cells);

  auto flat = [&](vtkProperty* p) {
    p->SetColor(line.colour[0], line.colour[1], line.colour[2]);
    p->SetAmbient(1.0);
    p->SetDiffuse(0.0);
    p->SetSpecular(0.0);
    p->LightingOff();
  };
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(polyline);
  mapper->ScalarVisibilityOff();
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  flat(actor->GetProperty());
  actor->GetProperty()->SetLineWidth(float(line.widthPixels));
  actor->GetProperty()->RenderLinesAsTubesOn();
  scene->AddActor(actor);

  if (line.labels.empty())
    return;

  // Dots at the labelled points.
  vtkNew<vtkCellArray> vertices;
  for (vtkIdType i = 0; i < n; ++i)
    if (!line.labels[std::size_t(i)].empty())
    {
      vertices->InsertNextCell(1);
      vertices->InsertCellPoint(i);
    }
  if (line.markLabelledPoints && vertices->GetNumberOfCells() > 0)
  {
    vtkNew<vtkPolyData> dots;
    dots->SetPoints(points);
    dots->SetVerts(vertices);
    vtkNew<vtkPolyDataMapper> dotMapper;
    dotMapper->SetInputData(dots);
    dotMapper->ScalarVisibilityOff();
    vtkNew<vtkActor> dotActor;
    dotActor->SetMapper(dotMapper);
    flat(dotActor->GetProperty());
    dotActor->GetProperty()->SetPointSize(float(2.2 * line.widthPixels));
    dotActor->GetProperty()->RenderPointsAsSpheresOn();
    scene->AddActor(dotActor);
  }

  // Numbers beside the points, pushed away from the line: perpendicular to
  // it on the side away from the line's centre, along it beyond open ends.
  std::vector<Eigen::Vector2d> screen;
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const Eigen::Vector3d& p : line.points)
  {
    screen.push_back(toDisplay(figure, p));
    centre += screen.back();
  }
  centre /= double(screen.size());
  const double fontPx = figure.textPoints * figure.pixelsPerPoint();
  const double offset = 1.1 * line.widthPixels + 0.75 * fontPx;
  const std::size_t count = screen.size();
  for (std::size_t i = 0; i < count; ++i)
  {
    if (line.labels[i].empty())
      continue;
    const bool first = i == 0, last = i + 1 == count;
    const Eigen::Vector2d previous = (first && !line.closed) ? screen[i] : screen[(i + count - 1) % count];
    const Eigen::Vector2d next = (last && !line.closed) ? screen[i] : screen[(i + 1) % count];
    Eigen::Vector2d tangent = next - previous;
    if (tangent.norm() < 1e-9)
      tangent = Eigen::Vector2d(1.0, 0.0);
    tangent.normalize();
    Eigen::Vector2d normal(-tangent.y(), tangent.x());
    const Eigen::Vector2d away = screen[i] - centre;
    if (normal.dot(away) < 0.0)
      normal = -normal;
    Eigen::Vector2d direction = normal;
    if (!line.closed && first)
      direction = (normal - tangent).normalized();
    else if (!line.closed && last)
      direction = (normal + tangent).normalized();
    // The depth probe: twice as far towards the eye as the lifted line, in
    // front of the line and its dot, behind anything that really hides the point.
    const Eigen::Vector3d towardEye = eye - line.points[i];
    const double n = towardEye.norm();
    const Eigen::Vector3d probe =
      n > 2.0 * lift ? Eigen::Vector3d(line.points[i] + towardEye * (2.0 * lift / n)) : line.points[i];
    labels.push_back(PendingLabel{screen[i] + offset * direction, line.labels[i], probe, fontPx});
  }
}

/// True when the segment from the world point to the eye crosses none of the
/// (mostly opaque) surfaces and the point projects inside the scene's viewport.
bool unoccluded(const Figure& figure, const std::vector<vtkSmartPointer<vtkCellLocator>>& locators,
                const Eigen::Vector3d& point)
{
  const auto viewport = figure.sceneViewport();
  const Eigen::Vector2d pixel = projectToPixel(figure, point);
  if (pixel.x() < viewport[0] * figure.width || pixel.x() > viewport[2] * figure.width ||
      pixel.y() < (1.0 - viewport[3]) * figure.height || pixel.y() > (1.0 - viewport[1]) * figure.height)
    return false;
  const Eigen::Vector3d eye = toEigen(figure.camera.position);
  double from[3] = {point.x(), point.y(), point.z()};
  double to[3] = {eye.x(), eye.y(), eye.z()};
  for (const auto& locator : locators)
  {
    double t = 0.0, x[3], pcoords[3];
    int subId = 0;
    if (locator->IntersectWithLine(from, to, 1e-9, t, x, pcoords, subId) != 0)
      return false;
  }
  return true;
}

/// Moves labels whose boxes overlap apart (a small face in a whole-head view
/// puts the points of a cut a few pixels apart): each overlapping pair is
/// pushed apart, half each, along the axis where they overlap least, until
/// none overlap or enough passes have run.
void spreadLabels(std::vector<PendingLabel>& labels)
{
  const auto halfSize = [](const PendingLabel& l) {
    // Bold Arial: about 0.62 em per character, plus the background's margin.
    return Eigen::Vector2d(0.5 * (0.62 * double(l.text.size()) + 0.5) * l.fontPx, 0.5 * 1.3 * l.fontPx);
  };
  for (int pass = 0; pass < 200; ++pass)
  {
    bool moved = false;
    for (std::size_t i = 0; i < labels.size(); ++i)
      for (std::size_t j = i + 1; j < labels.size(); ++j)
      {
        const Eigen::Vector2d d = labels[j].at - labels[i].at;
        const Eigen::Vector2d reach = halfSize(labels[i]) + halfSize(labels[j]);
        const double overlapX = reach.x() - std::abs(d.x()), overlapY = reach.y() - std::abs(d.y());
        if (overlapX <= 0.0 || overlapY <= 0.0)
          continue;
        Eigen::Vector2d push = Eigen::Vector2d::Zero();
        if (overlapX < overlapY)
          push.x() = (d.x() < 0.0 ? -1.0 : 1.0) * (0.5 * overlapX + 0.5);
        else
          push.y() = (d.y() < 0.0 ? -1.0 : 1.0) * (0.5 * overlapY + 0.5);
        labels[i].at -= push;
        labels[j].at += push;
        moved = true;
      }
    if (!moved)
      return;
  }
}

void addLabel(vtkRenderer* overlay, const PendingLabel& label)
{
  vtkNew<vtkTextActor> text;
  text->SetInput(label.text.c_str());
  vtkTextProperty* t = text->GetTextProperty();
  t->SetFontFamilyToArial();
  t->SetFontSize(int(std::lround(label.fontPx)));
  t->BoldOn();
  t->ShadowOff();
  t->SetColor(0.08, 0.08, 0.08);
  t->SetBackgroundColor(1.0, 1.0, 1.0);
  t->SetBackgroundOpacity(0.8);
  t->SetJustificationToCentered();
  t->SetVerticalJustificationToCentered();
  text->SetDisplayPosition(int(std::lround(label.at.x())), int(std::lround(label.at.y())));
  overlay->AddActor2D(text);
}

/// Colour bar layout in pixels (VTK: y up).
struct BarLayout
{
  double font = 0.0;
  double x0 = 0.0; ///< left of the bar
  double barWidth = 0.0;
  double boxWidth = 0.0; ///< bar and labels
  double y0 = 0.0, y1 = 0.0;
  double titleX = 0.0; ///< centre of the vertical title
  double column = 0.0; ///< width of the whole column at the right of the figure
};

BarLayout barLayout(const Figure& figure)
{
  BarLayout l;
  l.font = figure.textPoints * figure.pixelsPerPoint();
  const double pad = 0.5 * l.font;
  l.barWidth = 0.9 * l.font;
  const double labels = 3.6 * l.font; // "%.3g": up to five characters
  const double title = 1.3 * l.font;
  l.boxWidth = l.barWidth + pad + labels;
  l.column = pad + l.boxWidth + pad + title + pad;
  l.x0 = figure.width - l.column + pad;
  l.titleX = figure.width - pad - 0.5 * title;
  l.y0 = 0.1 * figure.height;
  l.y1 = 0.9 * figure.height;
  return l;
}

void addColourBar(const Figure& figure, const ColourBar& bar, vtkRenderer* overlay)
{
  checkRange(bar.range, "figure colour bar");
  const BarLayout l = barLayout(figure);
  const double x0 = l.x0, x1 = l.x0 + l.barWidth;

  // The bar, drawn here rather than by vtkScalarBarActor so that every tick
  // label sits exactly at its value: a strip of quads in display pixels whose
  // vertex colours are the map's (Gouraud interpolation is the map's own
  // piecewise-linear interpolation).
  constexpr int steps = 128;
  vtkNew<vtkPoints> points;
  vtkNew<vtkUnsignedCharArray> colours;
  colours->SetNumberOfComponents(3);
  vtkNew<vtkCellArray> quads;
  for (int i = 0; i <= steps; ++i)
  {
    const double t = double(i) / steps;
    const double y = l.y0 + t * (l.y1 - l.y0);
    points->InsertNextPoint(x0, y, 0.0);
    points->InsertNextPoint(x1, y, 0.0);
    const Rgb c = colourMapColour(bar.colourMap, t);
    const unsigned char rgb[3] = {static_cast<unsigned char>(std::lround(255.0 * c[0])),
                                  static_cast<unsigned char>(std::lround(255.0 * c[1])),
                                  static_cast<unsigned char>(std::lround(255.0 * c[2]))};
    colours->InsertNextTypedTuple(rgb);
    colours->InsertNextTypedTuple(rgb);
    if (i > 0)
    {
      const vtkIdType quad[4] = {2 * i - 2, 2 * i - 1, 2 * i + 1, 2 * i};
      quads->InsertNextCell(4, quad);
    }
  }
  vtkNew<vtkPolyData> strip;
  strip->SetPoints(points);
  strip->SetPolys(quads);
  strip->GetPointData()->SetScalars(colours);
  vtkNew<vtkPolyDataMapper2D> stripMapper;
  stripMapper->SetInputData(strip);
  stripMapper->SetColorModeToDirectScalars();
  stripMapper->ScalarVisibilityOn();
  vtkNew<vtkActor2D> stripActor;
  stripActor->SetMapper(stripMapper);
  overlay->AddActor2D(stripActor);

  // Frame and ticks, in black.
  const int labels = std::max(2, bar.labelCount);
  const double tick = 0.3 * l.font;
  vtkNew<vtkPoints> linePoints;
  vtkNew<vtkCellArray> lines;
  auto segment = [&](double ax, double ay, double bx, double by) {
    const vtkIdType a = linePoints->InsertNextPoint(ax, ay, 0.0);
    const vtkIdType b = linePoints->InsertNextPoint(bx, by, 0.0);
    const vtkIdType ids[2] = {a, b};
    lines->InsertNextCell(2, ids);
  };
  segment(x0, l.y0, x1, l.y0);
  segment(x1, l.y0, x1, l.y1);
  segment(x1, l.y1, x0, l.y1);
  segment(x0, l.y1, x0, l.y0);
  for (int k = 0; k < labels; ++k)
  {
    const double y = l.y0 + (l.y1 - l.y0) * k / (labels - 1);
    segment(x1, y, x1 + tick, y);
  }
  vtkNew<vtkPolyData> frame;
  frame->SetPoints(linePoints);
  frame->SetLines(lines);
  vtkNew<vtkPolyDataMapper2D> frameMapper;
  frameMapper->SetInputData(frame);
  frameMapper->ScalarVisibilityOff();
  vtkNew<vtkActor2D> frameActor;
  frameActor->SetMapper(frameMapper);
  frameActor->GetProperty()->SetColor(0.0, 0.0, 0.0);
  frameActor->GetProperty()->SetLineWidth(float(std::max(1.0, l.font / 24.0)));
  overlay->AddActor2D(frameActor);

  // Tick labels at their values.
  for (int k = 0; k < labels; ++k)
  {
    const double value = bar.range[0] + (bar.range[1] - bar.range[0]) * k / (labels - 1);
    char text[64];
    std::snprintf(text, sizeof text, bar.labelFormat.c_str(), value);
    vtkNew<vtkTextActor> label;
    label->SetInput(text);
    vtkTextProperty* t = label->GetTextProperty();
    t->SetFontFamilyToArial();
    t->SetFontSize(int(std::lround(l.font)));
    t->BoldOff();
    t->ShadowOff();
    t->SetColor(0.0, 0.0, 0.0);
    t->SetJustificationToLeft();
    t->SetVerticalJustificationToCentered();
    const double y = l.y0 + (l.y1 - l.y0) * k / (labels - 1);
    label->SetDisplayPosition(int(std::lround(x1 + tick + 0.25 * l.font)), int(std::lround(y)));
    overlay->AddActor2D(label);
  }

  vtkNew<vtkTextActor> title;
  title->SetInput(bar.title.c_str());
  vtkTextProperty* t = title->GetTextProperty();
  t->SetFontFamilyToArial();
  t->SetFontSize(int(std::lround(1.05 * l.font)));
  t->BoldOff();
  t->ShadowOff();
  t->SetColor(0.0, 0.0, 0.0);
  t->SetOrientation(90.0);
  t->SetJustificationToCentered();
  t->SetVerticalJustificationToCentered();
  title->SetDisplayPosition(int(std::lround(l.titleX)), int(std::lround(0.5 * (l.y0 + l.y1))));
  overlay->AddActor2D(title);
}

} // namespace

// ---------------------------------------------------------------------------
// Colour maps and layers

SurfaceLayer SurfaceLayer::solid(vtkSmartPointer<vtkPolyData> surface, const Rgb& colour, double opacity)
{
  SurfaceLayer layer;
  layer.surface = std::move(surface);
  layer.colour = colour;
  layer.opacity = opacity;
  return layer;
}

SurfaceLayer SurfaceLayer::pointColours(vtkSmartPointer<vtkPolyData> surface, std::string array)
{
  SurfaceLayer layer;
  layer.surface = std::move(surface);
  layer.colouring = Colouring::PointRgb;
  layer.array = std::move(array);
  return layer;
}

SurfaceLayer SurfaceLayer::scalars(vtkSmartPointer<vtkPolyData> surface, std::string array, double min, double max,
                                   ColourMap map)
{
  SurfaceLayer layer;
  layer.surface = std::move(surface);
  layer.colouring = Colouring::PointScalars;
  layer.array = std::move(array);
  layer.range = {min, max};
  layer.colourMap = map;
  return layer;
}

void LineLayer::numberPoints()
{
  labels.assign(points.size(), std::string());
  for (std::size_t i = 0; i < points.size(); ++i)
    labels[i] = std::to_string(i + 1);
}

void LineLayer::numberPoints(const std::vector<std::size_t>& indices)
{
  labels.assign(points.size(), std::string());
  for (std::size_t k = 0; k < indices.size(); ++k)
  {
    if (indices[k] >= points.size())
      throw std::invalid_argument("numberPoints: point " + std::to_string(indices[k]) + " of a line of " +
                                  std::to_string(points.size()));
    labels[indices[k]] = std::to_string(k + 1);
  }
}

double Figure::pixelsPerPoint() const
{
  if (!(printWidthMm > 0.0))
    return 1.0;
  return double(width) / (printWidthMm / 25.4) / 72.0;
}

std::array<double, 4> Figure::sceneViewport() const
{
  if (!colourBar || width <= 0)
    return {0.0, 0.0, 1.0, 1.0};
  const double column = barLayout(*this).column;
  return {0.0, 0.0, std::clamp(1.0 - column / double(width), 0.2, 1.0), 1.0};
}

double Figure::sceneAspect() const
{
  const auto v = sceneViewport();
  return (v[2] - v[0]) * double(width) / ((v[3] - v[1]) * double(height));
}

// ---------------------------------------------------------------------------
// Cameras

double viewTheta(View view)
{
  switch (view)
  {
  case View::Front:
    return -kPi / 2.0;
  case View::ObliqueLeft:
    return -kPi / 4.0;
  case View::ObliqueRight:
    return -3.0 * kPi / 4.0;
  case View::ProfileLeft:
    return 0.0;
  case View::ProfileRight:
    return -kPi;
  }
  return -kPi / 2.0;
}

Camera lookAtCamera(const Eigen::Vector3d& target, const Eigen::Vector3d& toCamera, const Eigen::Vector3d& viewUp,
                    double radius, double aspect, double viewAngleDeg, double margin)
{
  checkFit(aspect, viewAngleDeg, margin);
  if (!(radius > 0.0))
    throw std::invalid_argument("camera: the radius to frame must be positive");
  const ViewBasis b = viewBasis(toCamera, viewUp);
  const double halfV = 0.5 * viewAngleDeg * kPi / 180.0;
  const double halfH = std::atan(aspect * std::tan(halfV));
  const double distance = margin * radius / std::sin(std::min(halfV, halfH));
  return makeCamera(target, b, distance, viewAngleDeg);
}

Camera fitCamera(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& toCamera,
                 const Eigen::Vector3d& viewUp, double aspect, double viewAngleDeg, double margin)
{
  checkFit(aspect, viewAngleDeg, margin);
  if (points.empty())
    throw std::invalid_argument("camera: nothing to frame");
  const ViewBasis b = viewBasis(toCamera, viewUp);
  const double tanV = std::tan(0.5 * viewAngleDeg * kPi / 180.0) / margin;
  const double tanH = aspect * tanV;

  Eigen::Vector3d lo = points.front(), hi = points.front();
  for (const Eigen::Vector3d& p : points)
  {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  Eigen::Vector3d focal = 0.5 * (lo + hi);
  double distance = 0.0;
  // Fit the distance for the current focal point, then re-centre the focal
  // point on the projected extent; a few rounds converge for perspective.
  for (int round = 0; round < 6; ++round)
  {
    double xLo = 1e300, xHi = -1e300, yLo = 1e300, yHi = -1e300;
    for (const Eigen::Vector3d& p : points)
    {
      const Eigen::Vector3d d = p - focal;
      xLo = std::min(xLo, d.dot(b.r));
      xHi = std::max(xHi, d.dot(b.r));
      yLo = std::min(yLo, d.dot(b.u));
      yHi = std::max(yHi, d.dot(b.u));
    }
    if (round == 0)
      focal += 0.5 * (xLo + xHi) * b.r + 0.5 * (yLo + yHi) * b.u;
    distance = 0.0;
    double sxLo = 1e300, sxHi = -1e300, syLo = 1e300, syHi = -1e300;
    for (const Eigen::Vector3d& p : points)
    {
      const Eigen::Vector3d d = p - focal;
      const double a = d.dot(b.v), x = d.dot(b.r), y = d.dot(b.u);
      distance = std::max({distance, a + std::abs(x) / tanH, a + std::abs(y) / tanV});
    }
    for (const Eigen::Vector3d& p : points)
    {
      const Eigen::Vector3d d = p - focal;
      const double depth = distance - d.dot(b.v);
      const double sx = d.dot(b.r) / depth, sy = d.dot(b.u) / depth;
      sxLo = std::min(sxLo, sx);
      sxHi = std::max(sxHi, sx);
      syLo = std::min(syLo, sy);
      syHi = std::max(syHi, sy);
    }
    // Shift the focal point (in the plane through it) by the projected off-centre amount.
    const double cx = 0.5 * (sxLo + sxHi), cy = 0.5 * (syLo + syHi);
    if (std::abs(cx) < 1e-6 * tanH && std::abs(cy) < 1e-6 * tanV)
      break;
    focal += distance * (cx * b.r + cy * b.u);
  }
  // Final distance for the final focal point.
  distance = 0.0;
  for (const Eigen::Vector3d& p : points)
  {
    const Eigen::Vector3d d = p - focal;
    const double a = d.dot(b.v), x = d.dot(b.r), y = d.dot(b.u);
    distance = std::max({distance, a + std::abs(x) / tanH, a + std::abs(y) / tanV});
  }
  if (!(distance > 0.0))
    throw std::invalid_argument("camera: nothing to frame (all points coincide)");
  return makeCamera(focal, b, distance, viewAngleDeg);
}

Camera fitCamera(const std::array<double, 6>& bounds, const Eigen::Vector3d& toCamera, const Eigen::Vector3d& viewUp,
                 double aspect, double viewAngleDeg, double margin)
{
  if (!(bounds[0] <= bounds[1] && bounds[2] <= bounds[3] && bounds[4] <= bounds[5]))
    throw std::invalid_argument("camera: empty bounds");
  std::vector<Eigen::Vector3d> corners;
  for (int i = 0; i < 8; ++i)
    corners.emplace_back(bounds[std::size_t(i & 1)], bounds[std::size_t(2 + ((i >> 1) & 1))],
                         bounds[std::size_t(4 + ((i >> 2) & 1))]);
  return fitCamera(corners, toCamera, viewUp, aspect, viewAngleDeg, margin);
}

Camera fitCamera(const std::vector<vtkPolyData*>& surfaces, const Eigen::Vector3d& toCamera,
                 const Eigen::Vector3d& viewUp, double aspect, double viewAngleDeg, double margin)
{
  std::vector<Eigen::Vector3d> points;
  for (vtkPolyData* surface : surfaces)
  {
    if (surface == nullptr)
      continue;
    for (vtkIdType i = 0; i < surface->GetNumberOfPoints(); ++i)
    {
      double p[3];
      surface->GetPoint(i, p);
      points.emplace_back(p[0], p[1], p[2]);
    }
  }
  return fitCamera(points, toCamera, viewUp, aspect, viewAngleDeg, margin);
}

Camera headCamera(const seg::CylindricalFrame& frame, double theta, const std::vector<vtkPolyData*>& surfaces,
                  double aspect, double viewAngleDeg, double margin)
{
  return fitCamera(surfaces, frame.radialDirection(theta), frame.direction(), aspect, viewAngleDeg, margin);
}

Camera headCamera(const seg::CylindricalFrame& frame, View view, const std::vector<vtkPolyData*>& surfaces,
                  double aspect, double viewAngleDeg, double margin)
{
  return headCamera(frame, viewTheta(view), surfaces, aspect, viewAngleDeg, margin);
}

// ---------------------------------------------------------------------------
// Rendering

Eigen::Vector2d projectToPixel(const Figure& figure, const Eigen::Vector3d& point)
{
  vtkNew<vtkCamera> camera;
  applyCamera(camera, figure.camera);
  camera->SetClippingRange(1.0, 1e6);
  const auto viewport = figure.sceneViewport();
  const double vw = (viewport[2] - viewport[0]) * figure.width;
  const double vh = (viewport[3] - viewport[1]) * figure.height;
  vtkMatrix4x4* m = camera->GetCompositeProjectionTransformMatrix(vw / vh, -1.0, 1.0);
  const double in[4] = {point.x(), point.y(), point.z(), 1.0};
  double out[4];
  m->MultiplyPoint(in, out);
  const double x = out[0] / out[3], y = out[1] / out[3];
  const double px = viewport[0] * figure.width + 0.5 * (x + 1.0) * vw;
  const double py = viewport[1] * figure.height + 0.5 * (y + 1.0) * vh;
  return {px, double(figure.height) - py};
}

vtkSmartPointer<vtkImageData> renderFigure(const Figure& figure)
{
  if (figure.width < 16 || figure.height < 16 || figure.width > 8192 || figure.height > 8192)
    throw std::invalid_argument("figure: the size must be within 16–8192 pixels a side (got " +
                                std::to_string(figure.width) + " × " + std::to_string(figure.height) + ")");
  if (figure.surfaces.empty() && figure.lines.empty())
    throw std::invalid_argument("figure: nothing to draw");
  OffscreenDisplay::ensure();

  vtkNew<vtkRenderer> scene;
  const Rgb& bg = figure.background;
  scene->SetBackground(bg[0], bg[1], bg[2]);
  const auto viewport = figure.sceneViewport();
  scene->SetViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
  scene->SetUseFXAA(figure.fxaa);
  scene->SetLayer(0);
  scene->AutomaticLightCreationOff();
  vtkNew<vtkLightKit> lights;
  // Softer than the light kit's defaults (which leave the chin in shadow)
  // without washing out the colours: key from above-left, generous fill.
  lights->SetKeyLightIntensity(0.82);
  lights->SetKeyLightElevation(35.0);
  lights->SetKeyToFillRatio(1.8);
  lights->SetKeyToHeadRatio(3.0);
  lights->AddLightsToRenderer(scene);
  scene->TwoSidedLightingOn();

  // The paper: clears the whole window (the scene's viewport may leave a
  // column for the colour bar, which no other layer-0 renderer clears).
  vtkNew<vtkRenderer> paper;
  paper->SetBackground(bg[0], bg[1], bg[2]);
  paper->SetViewport(0.0, 0.0, 1.0, 1.0);
  paper->SetLayer(0);
  paper->InteractiveOff();

  vtkNew<vtkRenderer> overlay;
  overlay->SetLayer(1);
  overlay->SetViewport(0.0, 0.0, 1.0, 1.0);
  overlay->InteractiveOff();

  vtkNew<vtkRenderWindow> window;
  window->SetOffScreenRendering(1);
  window->SetNumberOfLayers(2);
  window->SetSize(figure.width, figure.height);
  window->SetMultiSamples(std::max(0, figure.multiSamples));
  window->SetAlphaBitPlanes(0);
  window->AddRenderer(paper);
  window->AddRenderer(scene);
  window->AddRenderer(overlay);

  applyCamera(scene->GetActiveCamera(), figure.camera);
  for (std::size_t i = 0; i < figure.surfaces.size(); ++i)
    scene->AddActor(surfaceActor(figure.surfaces[i], i));
  std::vector<PendingLabel> labels;
  for (std::size_t i = 0; i < figure.lines.size(); ++i)
    addLineLayer(figure, figure.lines[i], i, scene, labels);
  if (figure.colourBar)
    addColourBar(figure, *figure.colourBar, overlay);
  scene->ResetCameraClippingRange();

  if (!labels.empty())
  {
    // Labels are 2D and would show through the head: keep those whose point
    // no surface (at least half opaque) hides from the eye.
    std::vector<vtkSmartPointer<vtkCellLocator>> locators;
    for (const SurfaceLayer& layer : figure.surfaces)
      if (layer.opacity >= 0.5 && layer.surface->GetNumberOfCells() > 0)
      {
        auto locator = vtkSmartPointer<vtkCellLocator>::New();
        locator->SetDataSet(layer.surface);
        locator->BuildLocator();
        locators.push_back(locator);
      }
    std::vector<PendingLabel> shown;
    for (const PendingLabel& label : labels)
      if (unoccluded(figure, locators, label.probe))
        shown.push_back(label);
    spreadLabels(shown);
    for (const PendingLabel& label : shown)
      addLabel(overlay, label);
  }

  window->Render();
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->ShouldRerenderOff();
  grab->Update();
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->DeepCopy(grab->GetOutput());
  window->Finalize(); // close the X connection now, not at some later destruction
  int dims[3];
  image->GetDimensions(dims);
  if (dims[0] != figure.width || dims[1] != figure.height)
    throw std::runtime_error("figure: the renderer returned " + std::to_string(dims[0]) + " × " +
                             std::to_string(dims[1]) + " pixels instead of " + std::to_string(figure.width) + " × " +
                             std::to_string(figure.height));
  return image;
}

void writePng(vtkImageData* image, const std::filesystem::path& path)
{
  if (image == nullptr)
    throw std::invalid_argument("writePng: no image");
  if (path.has_parent_path())
    std::filesystem::create_directories(path.parent_path());
  vtkNew<vtkPNGWriter> writer;
  writer->SetInputData(image);
  writer->SetFileName(path.string().c_str());
  writer->Write();
  if (writer->GetErrorCode() != 0 || !std::filesystem::exists(path))
    throw std::runtime_error("could not write the figure " + path.string());
}

// ---------------------------------------------------------------------------
// Pixels

namespace {

struct Pixels
{
  int width = 0, height = 0, components = 0;
  const unsigned char* data = nullptr;
  /// Row y counted from the top.
  const unsigned char* at(int x, int y) const
  {
    return data + (std::size_t(height - 1 - y) * std::size_t(width) + std::size_t(x)) * std::size_t(components);
  }
};

Pixels pixels(vtkImageData* image)
{
  if (image == nullptr)
    throw std::invalid_argument("image: none");
  vtkDataArray* scalars = image->GetPointData()->GetScalars();
  if (scalars == nullptr || scalars->GetDataType() != VTK_UNSIGNED_CHAR || scalars->GetNumberOfComponents() < 3)
    throw std::invalid_argument("image: not an RGB(A) unsigned char image");
  int dims[3];
  image->GetDimensions(dims);
  Pixels p;
  p.width = dims[0];
  p.height = dims[1];
  p.components = scalars->GetNumberOfComponents();
  p.data = static_cast<const unsigned char*>(scalars->GetVoidPointer(0));
  return p;
}

bool differs(const unsigned char* c, const std::array<int, 3>& background, int tolerance)
{
  return std::abs(int(c[0]) - background[0]) > tolerance || std::abs(int(c[1]) - background[1]) > tolerance ||
         std::abs(int(c[2]) - background[2]) > tolerance;
}

std::array<int, 3> bytes(const Rgb& c)
{
  return {int(std::lround(255.0 * c[0])), int(std::lround(255.0 * c[1])), int(std::lround(255.0 * c[2]))};
}

} // namespace

RgbBytes rgbBytesTopDown(vtkImageData* image)
{
  const Pixels p = pixels(image);
  RgbBytes out;
  out.width = p.width;
  out.height = p.height;
  out.bytes.resize(std::size_t(p.width) * std::size_t(p.height) * 3);
  std::uint8_t* o = out.bytes.data();
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x)
    {
      const unsigned char* c = p.at(x, y);
      *o++ = c[0];
      *o++ = c[1];
      *o++ = c[2];
    }
  return out;
}

QImage toQImage(vtkImageData* image)
{
  const RgbBytes rgb = rgbBytesTopDown(image);
  QImage wrapped(rgb.bytes.data(), rgb.width, rgb.height, 3 * rgb.width, QImage::Format_RGB888);
  return wrapped.copy();
}

std::array<std::uint8_t, 3> pixelAt(vtkImageData* image, int x, int y)
{
  const Pixels p = pixels(image);
  if (x < 0 || y < 0 || x >= p.width || y >= p.height)
    throw std::out_of_range("pixelAt: (" + std::to_string(x) + ", " + std::to_string(y) + ") outside " +
                            std::to_string(p.width) + " × " + std::to_string(p.height));
  const unsigned char* c = p.at(x, y);
  return {c[0], c[1], c[2]};
}

double pixelVariance(vtkImageData* image)
{
  const Pixels p = pixels(image);
  const std::size_t n = std::size_t(p.width) * std::size_t(p.height);
  if (n == 0)
    return 0.0;
  double sum = 0.0, sum2 = 0.0;
  for (std::size_t i = 0; i < n; ++i)
  {
    const unsigned char* c = p.data + i * std::size_t(p.components);
    const double luminance = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    sum += luminance;
    sum2 += luminance * luminance;
  }
  const double mean = sum / double(n);
  return std::max(0.0, sum2 / double(n) - mean * mean);
}

double occupiedFraction(vtkImageData* image, const Rgb& background, int tolerance)
{
  const Pixels p = pixels(image);
  const std::size_t n = std::size_t(p.width) * std::size_t(p.height);
  if (n == 0)
    return 0.0;
  const auto bg = bytes(background);
  std::size_t occupied = 0;
  for (std::size_t i = 0; i < n; ++i)
    occupied += differs(p.data + i * std::size_t(p.components), bg, tolerance) ? 1 : 0;
  return double(occupied) / double(n);
}

std::optional<PixelBox> boundingBoxOfNonBackground(vtkImageData* image, const Rgb& background, int tolerance)
{
  const Pixels p = pixels(image);
  const auto bg = bytes(background);
  PixelBox box{p.width, p.height, -1, -1};
  for (int y = 0; y < p.height; ++y)
    for (int x = 0; x < p.width; ++x)
      if (differs(p.at(x, y), bg, tolerance))
      {
        box.x0 = std::min(box.x0, x);
        box.y0 = std::min(box.y0, y);
        box.x1 = std::max(box.x1, x);
        box.y1 = std::max(box.y1, y);
      }
  if (box.x1 < 0)
    return std::nullopt;
  return box;
}

} // namespace caps::render
