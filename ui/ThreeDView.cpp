#include "ui/ThreeDView.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <QMouseEvent>
#include <QTimer>

#include <vtkActor.h>
#include <vtkCellPicker.h>
#include <vtkDataArray.h>
#include <vtkLookupTable.h>
#include <vtkPointData.h>
#include <vtkScalarBarActor.h>
#include <vtkSphereSource.h>
#include <vtkGlyph3D.h>
#include <vtkPoints.h>
#include <vtkScalarsToColors.h>
#include <vtkUnsignedCharArray.h>
#include <vtkAxesActor.h>
#include <vtkCamera.h>
#include <vtkCaptionActor2D.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkImageData.h>
#include <vtkImageProperty.h>
#include <vtkImageSlice.h>
#include <vtkImageSliceMapper.h>
#include <vtkInteractorStyleTrackballCamera.h>
#include <vtkOrientationMarkerWidget.h>
#include <vtkOutlineSource.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkTextProperty.h>

#include "render/ColourMaps.h"

namespace caps::ui {

ThreeDView::ThreeDView(QWidget* parent) : QVTKOpenGLNativeWidget(parent)
{
  auto window = vtkSmartPointer<vtkGenericOpenGLRenderWindow>::New();
  setRenderWindow(window);
  // Whatever starts a render (a resize, an explicit Render()) draws what a
  // pending request asked for: that request is then done.
  render_observer_ = window->AddObserver(vtkCommand::StartEvent, this, &ThreeDView::renderStarted);
  renderer_ = vtkSmartPointer<vtkRenderer>::New();
  renderer_->SetBackground(0.10, 0.11, 0.14);
  renderer_->SetBackground2(0.25, 0.27, 0.32);
  renderer_->GradientBackgroundOn();
  window->AddRenderer(renderer_);
  auto style = vtkSmartPointer<vtkInteractorStyleTrackballCamera>::New();
  window->GetInteractor()->SetInteractorStyle(style);

  image_property_ = vtkSmartPointer<vtkImageProperty>::New();
  image_property_->SetColorWindow(400.0);
  image_property_->SetColorLevel(40.0);
  image_property_->SetInterpolationTypeToLinear();
  for (int axis = 0; axis < 3; ++axis)
  {
    mappers_[axis] = vtkSmartPointer<vtkImageSliceMapper>::New();
    mappers_[axis]->SetOrientation(axis);
    slices_[axis] = vtkSmartPointer<vtkImageSlice>::New();
    slices_[axis]->SetMapper(mappers_[axis]);
    slices_[axis]->SetProperty(image_property_);
  }

  // Patient axes: L(x), P(y), S(z), as in DICOM LPS.
  auto axes = vtkSmartPointer<vtkAxesActor>::New();
  axes->SetXAxisLabelText("L");
  axes->SetYAxisLabelText("P");
  axes->SetZAxisLabelText("S");
  orientation_marker_ = vtkSmartPointer<vtkOrientationMarkerWidget>::New();
  orientation_marker_->SetOrientationMarker(axes);
  orientation_marker_->SetInteractor(window->GetInteractor());
  orientation_marker_->SetViewport(0.0, 0.0, 0.18, 0.18);
  orientation_marker_->SetEnabled(1);
  orientation_marker_->InteractiveOff();
  setMinimumSize(160, 160);
}

ThreeDView::~ThreeDView()
{
  renderWindow()->RemoveObserver(render_observer_);
}

vtkRenderer* ThreeDView::renderer() const
{
  return renderer_;
}

void ThreeDView::setImage(vtkImageData* image)
{
  for (auto& slice : slices_)
    renderer_->RemoveViewProp(slice);
  if (outline_)
    renderer_->RemoveActor(outline_);
  image_ = nullptr;
  if (image)
  {
    image_ = vtkSmartPointer<vtkImageData>::New();
    image_->ShallowCopy(image);
    image_->SetDirectionMatrix(1, 0, 0, 0, 1, 0, 0, 0, 1);
    const int* dims = image_->GetDimensions();
    for (int axis = 0; axis < 3; ++axis)
    {
      mappers_[axis]->SetInputData(image_);
      mappers_[axis]->SetSliceNumber((dims[axis] - 1) / 2);
      renderer_->AddViewProp(slices_[axis]);
    }
    auto box = vtkSmartPointer<vtkOutlineSource>::New();
    box->SetBounds(image_->GetBounds());
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputConnection(box->GetOutputPort());
    outline_ = vtkSmartPointer<vtkActor>::New();
    outline_->SetMapper(mapper);
    outline_->GetProperty()->SetColor(0.8, 0.8, 0.5);
    renderer_->AddActor(outline_);
  }
  resetCamera();
  requestRender();
}

void ThreeDView::setSlicesVisible(bool visible)
{
  slices_visible_ = visible;
  for (auto& slice : slices_)
    slice->SetVisibility(visible);
  requestRender();
}

void ThreeDView::setWindowLevel(double window, double level)
{
  image_property_->SetColorWindow(window);
  image_property_->SetColorLevel(level);
  requestRender();
}

void ThreeDView::setCursorPosition(const std::array<double, 3>& position)
{
  if (!image_)
    return;
  const int* dims = image_->GetDimensions();
  for (int axis = 0; axis < 3; ++axis)
  {
    const long index = std::lround((position[axis] - image_->GetOrigin()[axis]) / image_->GetSpacing()[axis]);
    mappers_[axis]->SetSliceNumber(static_cast<int>(std::clamp<long>(index, 0, dims[axis] - 1)));
  }
  requestRender();
}

void ThreeDView::setSurface(const std::string& key, vtkPolyData* surface, const SurfaceStyle& style)
{
  removeSurface(key);
  if (!surface)
    return;
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputData(surface);
  mapper->ScalarVisibilityOff();
  vtkDataArray* scalars =
    style.colourArray.empty() ? nullptr : surface->GetPointData()->GetArray(style.colourArray.c_str());
  if (scalars)
  {
    mapper->ScalarVisibilityOn();
    mapper->SetScalarModeToUsePointFieldData();
    mapper->SelectColorArray(style.colourArray.c_str());
    if (vtkUnsignedCharArray::SafeDownCast(scalars) && scalars->GetNumberOfComponents() == 3)
      mapper->SetColorModeToDirectScalars();
    else
    {
      std::array<double, 2> range = style.range;
      if (!(range[0] < range[1]))
      {
        scalars->GetRange(range.data(), scalars->GetNumberOfComponents() == 1 ? 0 : -1);
        if (!(range[0] < range[1]))
          range = {range[0] - 0.5, range[0] + 0.5};
      }
      const render::ColourMap map = render::colourMapFromName(style.colourMap).value_or(render::ColourMap::Viridis);
      auto table = render::colourMapLookupTable(map, range);
      if (scalars->GetNumberOfComponents() > 1)
        table->SetVectorModeToMagnitude();
      mapper->SetLookupTable(table);
      mapper->UseLookupTableScalarRangeOn();
      mapper->SetColorModeToMapScalars();
    }
  }
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetColor(style.colour[0], style.colour[1], style.colour[2]);
  actor->GetProperty()->SetOpacity(style.opacity);
  actor->GetProperty()->SetLineWidth(static_cast<float>(style.lineWidth));
  actor->GetProperty()->SetPointSize(static_cast<float>(style.lineWidth));
  actor->SetVisibility(style.visible);
  renderer_->AddActor(actor);
  surfaces_[key] = actor;
  styles_[key] = style;
  updateColourBar();
  requestRender();
}

std::optional<std::array<double, 2>> ThreeDView::colourBarRange() const
{
  if (!colour_bar_ || !colour_bar_->GetVisibility() || !colour_bar_->GetLookupTable())
    return std::nullopt;
  const double* range = colour_bar_->GetLookupTable()->GetRange();
  return std::array<double, 2>{range[0], range[1]};
}

void ThreeDView::requestRender()
{
  // A prediction adds and edits a dozen surfaces in a row; one render after
  // them, not one each (software OpenGL takes most of a second for the head).
  if (render_pending_)
    return;
  render_pending_ = true;
  QTimer::singleShot(0, this, [this]() {
    if (render_pending_)
      renderWindow()->Render(); // clears render_pending_
  });
}

void ThreeDView::renderStarted()
{
  render_pending_ = false;
}

void ThreeDView::setMarker(const std::array<double, 3>& position)
{
  if (!marker_)
  {
    auto sphere = vtkSmartPointer<vtkSphereSource>::New();
    sphere->SetRadius(1.5);
    sphere->SetThetaResolution(16);
    sphere->SetPhiResolution(12);
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputConnection(sphere->GetOutputPort());
    marker_ = vtkSmartPointer<vtkActor>::New();
    marker_->SetMapper(mapper);
    marker_->GetProperty()->SetColor(1.0, 0.85, 0.0);
    marker_->PickableOff();
    renderer_->AddActor(marker_);
  }
  marker_->SetPosition(position[0], position[1], position[2]);
  marker_->SetVisibility(true);
  requestRender();
}

void ThreeDView::hideMarker()
{
  if (marker_)
    marker_->SetVisibility(false);
  requestRender();
}

void ThreeDView::updateColourBar()
{
  // One bar, for the first visible surface coloured through a colour map.
  vtkScalarsToColors* table = nullptr;
  std::string title;
  for (const auto& [key, actor] : surfaces_)
  {
    vtkMapper* mapper = actor->GetMapper();
    if (!actor->GetVisibility() || !mapper->GetScalarVisibility() ||
        mapper->GetColorMode() == VTK_COLOR_MODE_DIRECT_SCALARS)
      continue;
    table = mapper->GetLookupTable();
    const SurfaceStyle& style = styles_[key];
    title = style.colourBarTitle.empty() ? style.colourArray : style.colourBarTitle;
    break;
  }
  if (!table)
  {
    if (colour_bar_)
      colour_bar_->SetVisibility(false);
    return;
  }
  if (!colour_bar_)
  {
    colour_bar_ = vtkSmartPointer<vtkScalarBarActor>::New();
    colour_bar_->SetOrientationToVertical();
    colour_bar_->SetNumberOfLabels(5);
    colour_bar_->SetLabelFormat("%.3g");
    colour_bar_->SetPosition(0.84, 0.08);
    colour_bar_->SetWidth(0.15);
    colour_bar_->SetHeight(0.80);
    colour_bar_->SetBarRatio(0.3);
    colour_bar_->UnconstrainedFontSizeOn();
    colour_bar_->GetTitleTextProperty()->SetFontSize(13);
    colour_bar_->GetTitleTextProperty()->SetJustificationToRight();
    colour_bar_->GetLabelTextProperty()->SetFontSize(12);
    colour_bar_->GetTitleTextProperty()->ItalicOff();
    colour_bar_->GetLabelTextProperty()->ItalicOff();
    renderer_->AddViewProp(colour_bar_);
  }
  colour_bar_->SetLookupTable(table);
  // A long title ("Soft-tissue thickness (mm)") goes on lines of at most
  // about 12 characters, so it stays inside the view above the narrow bar.
  {
    std::string wrapped, line, word;
    std::istringstream words(title);
    while (words >> word)
    {
      if (!line.empty() && line.size() + 1 + word.size() > 12)
      {
        wrapped += wrapped.empty() ? "" : "\n";
        wrapped += line;
        line.clear();
      }
      line += line.empty() ? "" : " ";
      line += word;
    }
    if (!line.empty())
    {
      wrapped += wrapped.empty() ? "" : "\n";
      wrapped += line;
    }
    title = wrapped;
  }
  colour_bar_->SetTitle(title.c_str());
  colour_bar_->SetVisibility(true);
}

bool ThreeDView::pickSurface(int x, int y, std::string& key, std::array<double, 3>& position) const
{
  auto picker = vtkSmartPointer<vtkCellPicker>::New();
  picker->SetTolerance(0.0005);
  picker->PickFromListOn();
  for (const auto& [name, actor] : surfaces_)
    if (actor->GetVisibility())
      picker->AddPickList(actor);
  const double ratio = devicePixelRatioF();
  const int* size = renderWindow()->GetSize();
  const double displayX = x * ratio;
  const double displayY = size[1] - 1 - y * ratio;
  if (!picker->Pick(displayX, displayY, 0.0, renderer_))
    return false;
  vtkActor* hit = picker->GetActor();
  for (const auto& [name, actor] : surfaces_)
    if (actor == hit)
    {
      key = name;
      picker->GetPickPosition(position.data());
      return true;
    }
  return false;
}

void ThreeDView::setHandles(const std::vector<std::array<double, 3>>& points)
{
  handles_ = points;
  if (dragging_ >= int(handles_.size()))
    dragging_ = -1;
  updateHandles();
}

void ThreeDView::updateHandles()
{
  if (!handle_actor_)
  {
    handle_points_ = vtkSmartPointer<vtkPoints>::New();
    auto cloud = vtkSmartPointer<vtkPolyData>::New();
    cloud->SetPoints(handle_points_);
    auto sphere = vtkSmartPointer<vtkSphereSource>::New();
    sphere->SetRadius(1.3); // mm: a grip the size of a fingertip on the screen at face scale
    sphere->SetThetaResolution(16);
    sphere->SetPhiResolution(12);
    auto glyphs = vtkSmartPointer<vtkGlyph3D>::New();
    glyphs->SetInputData(cloud);
    glyphs->SetSourceConnection(sphere->GetOutputPort());
    glyphs->ScalingOff();
    auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    mapper->SetInputConnection(glyphs->GetOutputPort());
    handle_actor_ = vtkSmartPointer<vtkActor>::New();
    handle_actor_->SetMapper(mapper);
    handle_actor_->GetProperty()->SetColor(1.0, 1.0, 1.0);
    handle_actor_->GetProperty()->SetAmbient(0.3);
    handle_actor_->PickableOff(); // picks find the skin under a handle, not the handle
    renderer_->AddActor(handle_actor_);
  }
  handle_points_->Reset();
  for (const auto& p : handles_)
    handle_points_->InsertNextPoint(p.data());
  handle_points_->Modified();
  handle_actor_->SetVisibility(!handles_.empty());
  requestRender();
}

QPoint ThreeDView::handleOnScreen(std::size_t index) const
{
  const auto& p = handles_.at(index);
  renderer_->SetWorldPoint(p[0], p[1], p[2], 1.0);
  renderer_->WorldToDisplay();
  double display[3];
  renderer_->GetDisplayPoint(display);
  const double ratio = devicePixelRatioF();
  const int* size = const_cast<ThreeDView*>(this)->renderWindow()->GetSize();
  return QPoint(int(std::lround(display[0] / ratio)), int(std::lround((size[1] - 1 - display[1]) / ratio)));
}

int ThreeDView::handleNear(const QPoint& at) const
{
  int best = -1;
  if (!handles_grabbable_)
    return best;
  double bestDistance = 9.0; // pixels
  for (std::size_t i = 0; i < handles_.size(); ++i)
  {
    const QPoint d = handleOnScreen(i) - at;
    const double distance = std::hypot(double(d.x()), double(d.y()));
    if (distance <= bestDistance)
    {
      bestDistance = distance;
      best = int(i);
    }
  }
  return best;
}

bool ThreeDView::event(QEvent* event)
{
  const auto type = event->type();
  if (type == QEvent::MouseButtonPress || type == QEvent::MouseMove || type == QEvent::MouseButtonRelease ||
      type == QEvent::MouseButtonDblClick)
  {
    auto* mouse = static_cast<QMouseEvent*>(event);
    const bool grab =
      type == QEvent::MouseButtonPress && mouse->button() == Qt::LeftButton && handleNear(mouse->pos()) >= 0;
    if (dragging_ >= 0 || grab)
    {
      if (type == QEvent::MouseButtonPress)
        mousePressEvent(mouse);
      else if (type == QEvent::MouseMove)
        mouseMoveEvent(mouse);
      else if (type == QEvent::MouseButtonRelease)
        mouseReleaseEvent(mouse);
      event->accept();
      return true;
    }
    if (type == QEvent::MouseButtonPress)
      moved_since_press_ = false;
    else if (type == QEvent::MouseMove && mouse->buttons() != Qt::NoButton)
      moved_since_press_ = true;
    if (type == QEvent::MouseButtonRelease && !moved_since_press_)
    {
      // A click leaves the camera as it was: the interactor style's closing
      // render would draw the same picture again (most of a second with
      // software OpenGL). Rendering is back on before mouseReleaseEvent
      // reports the click, so whatever the click changes is drawn.
      vtkRenderWindowInteractor* interactor = renderWindow()->GetInteractor();
      interactor->EnableRenderOff();
      const bool handled = QVTKOpenGLNativeWidget::event(event);
      interactor->EnableRenderOn();
      return handled;
    }
  }
  return QVTKOpenGLNativeWidget::event(event);
}

void ThreeDView::mousePressEvent(QMouseEvent* event)
{
  press_valid_ = event->button() == Qt::LeftButton;
  press_position_ = event->pos();
  if (press_valid_)
    if (const int handle = handleNear(event->pos()); handle >= 0)
    {
      // A drag of the handle: the camera does not see this press.
      dragging_ = handle;
      drag_over_surface_ = false;
      press_valid_ = false;
      setCursor(Qt::ClosedHandCursor);
      return;
    }
  QVTKOpenGLNativeWidget::mousePressEvent(event);
}

void ThreeDView::mouseMoveEvent(QMouseEvent* event)
{
  if (dragging_ < 0)
  {
    // An open hand over a handle says it can be taken.
    if (!handles_.empty() && !(event->buttons() & Qt::LeftButton))
    {
      if (handleNear(event->pos()) >= 0)
        setCursor(Qt::OpenHandCursor);
      else
        unsetCursor();
    }
    QVTKOpenGLNativeWidget::mouseMoveEvent(event);
    return;
  }
  std::string key;
  std::array<double, 3> position{};
  drag_over_surface_ = pickSurface(event->pos().x(), event->pos().y(), key, position);
  if (drag_over_surface_)
  {
    drag_key_ = key;
    drag_position_ = position;
    // The handle follows the skin under the cursor; the plan changes on release.
    handle_points_->SetPoint(vtkIdType(dragging_), position.data());
    handle_points_->Modified();
    requestRender();
  }
}

void ThreeDView::mouseReleaseEvent(QMouseEvent* event)
{
  renderWindow()->GetInteractor()->EnableRenderOn();
  if (dragging_ >= 0)
  {
    const int handle = dragging_;
    dragging_ = -1;
    setCursor(Qt::OpenHandCursor);
    if (event->button() == Qt::LeftButton && drag_over_surface_)
      emit handleDropped(handle, QString::fromStdString(drag_key_), drag_position_[0], drag_position_[1],
                         drag_position_[2]);
    else
      updateHandles(); // let go over the background: back where it was
    return;
  }
  QVTKOpenGLNativeWidget::mouseReleaseEvent(event);
  if (!press_valid_ || event->button() != Qt::LeftButton)
    return;
  press_valid_ = false;
  // A drag turns the view; only a click picks.
  if ((event->pos() - press_position_).manhattanLength() > 4)
    return;
  std::string key;
  std::array<double, 3> position{};
  if (pickSurface(event->pos().x(), event->pos().y(), key, position))
    emit surfaceClicked(QString::fromStdString(key), position[0], position[1], position[2]);
}

void ThreeDView::removeSurface(const std::string& key)
{
  auto it = surfaces_.find(key);
  if (it == surfaces_.end())
    return;
  renderer_->RemoveActor(it->second);
  surfaces_.erase(it);
  styles_.erase(key);
  updateColourBar();
  requestRender();
}

void ThreeDView::resetCamera()
{
  vtkCamera* camera = renderer_->GetActiveCamera();
  camera->ParallelProjectionOff();
  camera->SetFocalPoint(0, 0, 0);
  camera->SetPosition(0, -1, 0); // anterior is -y (LPS)
  camera->SetViewUp(0, 0, 1);
  renderer_->ResetCamera();
  // The face faces the viewer (issue 6), seen a little from above as a
  // surgeon standing at the table sees it.
  camera->Elevation(10.0);
  camera->OrthogonalizeViewUp();
  renderer_->ResetCameraClippingRange();
}

} // namespace caps::ui
