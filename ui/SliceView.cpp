#include "ui/SliceView.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <vtkActor.h>
#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkCornerAnnotation.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkImageData.h>
#include <vtkImageProperty.h>
#include <vtkImageSlice.h>
#include <vtkImageStack.h>
#include <vtkScalarsToColors.h>
#include <vtkImageSliceMapper.h>
#include <vtkInteractorStyleImage.h>
#include <vtkLineSource.h>
#include <vtkObjectFactory.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>

namespace caps::ui {
namespace {

// Routes the mouse to the view: wheel scrolls slices, a click (press and
// release without moving) places the crosshair, a drag does the usual image
// interaction (window/level, zoom, pan).
class SliceInteractorStyle : public vtkInteractorStyleImage
{
public:
  static SliceInteractorStyle* New();
  vtkTypeMacro(SliceInteractorStyle, vtkInteractorStyleImage);

  SliceView* view = nullptr;

  void OnMouseWheelForward() override { view->handleWheel(+1); }
  void OnMouseWheelBackward() override { view->handleWheel(-1); }
  void OnMouseMove() override
  {
    vtkInteractorStyleImage::OnMouseMove();
    const int* p = this->Interactor->GetEventPosition();
    view->handleHover(p[0], p[1]);
  }
  void OnLeftButtonDown() override
  {
    const int* p = this->Interactor->GetEventPosition();
    press_[0] = p[0];
    press_[1] = p[1];
    vtkInteractorStyleImage::OnLeftButtonDown();
  }
  void OnLeftButtonUp() override
  {
    vtkInteractorStyleImage::OnLeftButtonUp();
    const int* p = this->Interactor->GetEventPosition();
    if (std::abs(p[0] - press_[0]) + std::abs(p[1] - press_[1]) <= 2)
      view->handleClick(p[0], p[1]);
  }
  void WindowLevel() override
  {
    vtkInteractorStyleImage::WindowLevel();
    view->handleWindowLevelChanged();
  }
  // Keys 'r' (reset) and 'x/y/z' (reorient) of the base style would break the
  // view's fixed radiological orientation.
  void OnChar() override {}

private:
  int press_[2] = {0, 0};
};
vtkStandardNewMacro(SliceInteractorStyle);

const char* orientationName(SliceOrientation o)
{
  switch (o)
  {
  case SliceOrientation::Axial:
    return "Axial";
  case SliceOrientation::Coronal:
    return "Coronal";
  case SliceOrientation::Sagittal:
    return "Sagittal";
  }
  return "";
}

vtkSmartPointer<vtkActor> makeLineActor(vtkLineSource* source, const std::array<double, 3>& rgb = {1.0, 0.85, 0.2},
                                        double opacity = 0.7, double width = 1.0)
{
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputConnection(source->GetOutputPort());
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetColor(rgb[0], rgb[1], rgb[2]);
  actor->GetProperty()->SetOpacity(opacity);
  actor->GetProperty()->SetLineWidth(width);
  actor->PickableOff();
  return actor;
}

/// A label pinned to a point of the slice (world coordinates).
vtkSmartPointer<vtkTextActor> makeLabel(const std::array<double, 3>& rgb)
{
  auto label = vtkSmartPointer<vtkTextActor>::New();
  label->GetTextProperty()->SetFontSize(14);
  label->GetTextProperty()->SetBold(true);
  label->GetTextProperty()->SetColor(rgb[0], rgb[1], rgb[2]);
  label->GetTextProperty()->SetShadow(true);
  label->GetPositionCoordinate()->SetCoordinateSystemToWorld();
  label->PickableOff();
  label->VisibilityOff();
  return label;
}

double distance(const std::array<double, 3>& a, const std::array<double, 3>& b)
{
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

// The measured segment in green, the ruler in cyan: both stand out on grey
// CT and on the segmentation's warm overlay.
constexpr std::array<double, 3> kMeasuredColour{0.3, 1.0, 0.4};
constexpr std::array<double, 3> kRulerColour{0.3, 0.9, 1.0};

} // namespace

SliceView::SliceView(SliceOrientation orientation, QWidget* parent)
  : QVTKOpenGLNativeWidget(parent), orientation_(orientation)
{
  auto window = vtkSmartPointer<vtkGenericOpenGLRenderWindow>::New();
  setRenderWindow(window);
  renderer_ = vtkSmartPointer<vtkRenderer>::New();
  renderer_->SetBackground(0.0, 0.0, 0.0);
  window->AddRenderer(renderer_);

  auto style = vtkSmartPointer<SliceInteractorStyle>::New();
  style->view = this;
  style->SetDefaultRenderer(renderer_);
  window->GetInteractor()->SetInteractorStyle(style);

  mapper_ = vtkSmartPointer<vtkImageSliceMapper>::New();
  mapper_->SetOrientation(sliceAxis());
  slice_actor_ = vtkSmartPointer<vtkImageSlice>::New();
  slice_actor_->SetMapper(mapper_);
  slice_actor_->GetProperty()->SetInterpolationTypeToLinear();
  slice_actor_->GetProperty()->SetColorWindow(400.0);
  slice_actor_->GetProperty()->SetColorLevel(40.0);
  overlay_mapper_ = vtkSmartPointer<vtkImageSliceMapper>::New();
  overlay_actor_ = vtkSmartPointer<vtkImageSlice>::New();
  overlay_actor_->SetMapper(overlay_mapper_);
  overlay_actor_->GetProperty()->SetInterpolationTypeToNearest();
  overlay_actor_->GetProperty()->UseLookupTableScalarRangeOn();
  overlay_actor_->GetProperty()->SetLayerNumber(1);
  overlay_actor_->VisibilityOff();
  slice_actor_->GetProperty()->SetLayerNumber(0);
  stack_ = vtkSmartPointer<vtkImageStack>::New();
  stack_->AddImage(slice_actor_);
  stack_->AddImage(overlay_actor_);
  stack_->SetActiveLayer(0);

  line_a_ = vtkSmartPointer<vtkLineSource>::New();
  line_b_ = vtkSmartPointer<vtkLineSource>::New();
  crosshair_a_ = makeLineActor(line_a_);
  crosshair_b_ = makeLineActor(line_b_);

  measured_line_ = vtkSmartPointer<vtkLineSource>::New();
  measured_actor_ = makeLineActor(measured_line_, kMeasuredColour, 1.0, 3.0);
  measured_label_ = makeLabel(kMeasuredColour);
  ruler_line_ = vtkSmartPointer<vtkLineSource>::New();
  ruler_actor_ = makeLineActor(ruler_line_, kRulerColour, 1.0, 2.0);
  ruler_label_ = makeLabel(kRulerColour);
  for (vtkActor* actor : {measured_actor_.Get(), ruler_actor_.Get()})
  {
    actor->VisibilityOff();
    renderer_->AddActor(actor);
  }
  renderer_->AddViewProp(measured_label_);
  renderer_->AddViewProp(ruler_label_);

  corners_ = vtkSmartPointer<vtkCornerAnnotation>::New();
  corners_->SetMaximumFontSize(14);
  corners_->GetTextProperty()->SetColor(0.9, 0.9, 0.9);
  corners_->SetText(vtkCornerAnnotation::UpperLeft, orientationName(orientation_));
  renderer_->AddViewProp(corners_);

  for (auto& label : edge_labels_)
  {
    label = vtkSmartPointer<vtkTextActor>::New();
    label->GetTextProperty()->SetFontSize(14);
    label->GetTextProperty()->SetColor(0.6, 0.8, 1.0);
    label->GetTextProperty()->SetJustificationToCentered();
    label->GetTextProperty()->SetVerticalJustificationToCentered();
    label->GetPositionCoordinate()->SetCoordinateSystemToNormalizedViewport();
    renderer_->AddViewProp(label);
  }
  // Radiological convention: what lies at the top, bottom, left, right.
  const char* letters[3][4] = {{"A", "P", "R", "L"},  // axial, seen from the feet
                               {"S", "I", "R", "L"},  // coronal, seen from the front
                               {"S", "I", "A", "P"}}; // sagittal, seen from the left
  const double where[4][2] = {{0.5, 0.97}, {0.5, 0.03}, {0.02, 0.5}, {0.98, 0.5}};
  for (int e = 0; e < 4; ++e)
  {
    edge_labels_[e]->SetInput(letters[static_cast<int>(orientation_)][e]);
    edge_labels_[e]->SetPosition(where[e][0], where[e][1]);
  }
  setMinimumSize(160, 160);
}

SliceView::~SliceView() = default;

int SliceView::sliceAxis() const
{
  switch (orientation_)
  {
  case SliceOrientation::Axial:
    return 2;
  case SliceOrientation::Coronal:
    return 1;
  case SliceOrientation::Sagittal:
    return 0;
  }
  return 2;
}

void SliceView::setImage(vtkImageData* image)
{
  if (!image)
  {
    image_ = nullptr;
    renderer_->RemoveViewProp(stack_);
    overlay_actor_->VisibilityOff();
    renderer_->RemoveActor(crosshair_a_);
    renderer_->RemoveActor(crosshair_b_);
    ruler_ends_ = 0;
    updateMeasurements();
    updateAnnotation();
    renderWindow()->Render();
    return;
  }
  // Display copy with identity direction: the view works along index axes.
  image_ = vtkSmartPointer<vtkImageData>::New();
  image_->ShallowCopy(image);
  image_->SetDirectionMatrix(1, 0, 0, 0, 1, 0, 0, 0, 1);
  mapper_->SetInputData(image_);

  const int* dims = image_->GetDimensions();
  const double* origin = image_->GetOrigin();
  const double* spacing = image_->GetSpacing();
  for (int a = 0; a < 3; ++a)
    cursor_[a] = origin[a] + spacing[a] * (dims[a] - 1) / 2.0;
  slice_ = (dims[sliceAxis()] - 1) / 2;
  ruler_ends_ = 0; // a ruler belongs to the image it measured
  renderer_->AddViewProp(stack_);
  renderer_->AddActor(crosshair_a_);
  renderer_->AddActor(crosshair_b_);
  updateSlicePlane();
  resetCamera();
  renderWindow()->Render();
}

void SliceView::setOverlay(vtkImageData* overlay, vtkScalarsToColors* colours)
{
  if (!overlay || !colours || !image_)
  {
    overlay_actor_->VisibilityOff();
    renderWindow()->Render();
    return;
  }
  // On the CT's display grid (identity direction), as the CT itself.
  auto copy = vtkSmartPointer<vtkImageData>::New();
  copy->ShallowCopy(overlay);
  copy->SetDirectionMatrix(1, 0, 0, 0, 1, 0, 0, 0, 1);
  overlay_mapper_->SetInputData(copy);
  overlay_mapper_->SetOrientation(mapper_->GetOrientation());
  overlay_mapper_->SetSliceNumber(slice_);
  overlay_actor_->GetProperty()->SetLookupTable(colours);
  overlay_actor_->VisibilityOn();
  renderWindow()->Render();
}

bool SliceView::hasOverlay() const
{
  return overlay_actor_->GetVisibility() != 0;
}

vtkImageData* SliceView::image() const
{
  return image_;
}

void SliceView::setWindowLevel(double window, double level)
{
  slice_actor_->GetProperty()->SetColorWindow(window);
  slice_actor_->GetProperty()->SetColorLevel(level);
  updateAnnotation();
  renderWindow()->Render();
}

double SliceView::window() const
{
  return slice_actor_->GetProperty()->GetColorWindow();
}

double SliceView::level() const
{
  return slice_actor_->GetProperty()->GetColorLevel();
}

int SliceView::sliceCount() const
{
  return image_ ? image_->GetDimensions()[sliceAxis()] : 0;
}

void SliceView::setSlice(int slice)
{
  if (!image_)
    return;
  slice = std::clamp(slice, 0, sliceCount() - 1);
  const int axis = sliceAxis();
  cursor_[axis] = image_->GetOrigin()[axis] + image_->GetSpacing()[axis] * slice;
  if (slice == slice_)
    return;
  slice_ = slice;
  updateSlicePlane();
  renderWindow()->Render();
  emit sliceChanged(slice_);
}

void SliceView::setCursorPosition(const std::array<double, 3>& position)
{
  cursor_ = position;
  if (!image_)
    return;
  const int axis = sliceAxis();
  const int slice =
    static_cast<int>(std::lround((position[axis] - image_->GetOrigin()[axis]) / image_->GetSpacing()[axis]));
  const int clamped = std::clamp(slice, 0, sliceCount() - 1);
  const bool changed = clamped != slice_;
  slice_ = clamped;
  updateSlicePlane();
  renderWindow()->Render();
  if (changed)
    emit sliceChanged(slice_);
}

std::array<double, 3> SliceView::pointAtDisplay(int x, int y) const
{
  renderer_->SetDisplayPoint(x, y, 0.0);
  renderer_->DisplayToWorld();
  const double* w = renderer_->GetWorldPoint();
  std::array<double, 3> p{w[0], w[1], w[2]};
  if (w[3] != 0.0)
    for (auto& c : p)
      c /= w[3];
  // Parallel projection along the slice axis: drop the point onto the slice.
  if (image_)
  {
    const int axis = sliceAxis();
    p[axis] = image_->GetOrigin()[axis] + image_->GetSpacing()[axis] * slice_;
  }
  return p;
}

void SliceView::setMeasuredSegment(const std::optional<SliceSegment>& segment)
{
  measured_ = segment;
  updateMeasurements();
  renderWindow()->Render();
}

void SliceView::setRulerMode(bool on)
{
  ruler_mode_ = on;
  if (!on && ruler_ends_ == 1)
    ruler_ends_ = 0; // a ruler with one end is no measurement
  updateMeasurements();
  renderWindow()->Render();
}

std::optional<SliceSegment> SliceView::ruler() const
{
  if (ruler_ends_ != 2)
    return std::nullopt;
  char text[32];
  std::snprintf(text, sizeof text, "%.1f mm", distance(ruler_from_, ruler_to_));
  return SliceSegment{ruler_from_, ruler_to_, text};
}

void SliceView::clearRuler()
{
  ruler_ends_ = 0;
  updateMeasurements();
  renderWindow()->Render();
}

void SliceView::placeRulerEnd(const std::array<double, 3>& point)
{
  if (ruler_ends_ == 1 && ruler_slice_ == slice_)
  {
    ruler_to_ = point;
    ruler_ends_ = 2;
    updateMeasurements();
    renderWindow()->Render();
    emit rulerMeasured(distance(ruler_from_, ruler_to_));
    return;
  }
  // A new ruler (or its start again, on the slice now shown).
  ruler_from_ = ruler_to_ = point;
  ruler_slice_ = slice_;
  ruler_ends_ = 1;
  updateMeasurements();
  renderWindow()->Render();
}

std::array<double, 3> SliceView::onTopOfSlice(std::array<double, 3> point, double lift) const
{
  // Lift the lines a little towards the camera so they draw over the slice.
  lift = orientation_ == SliceOrientation::Sagittal ? lift : -lift;
  const int axis = sliceAxis();
  point[axis] = image_->GetOrigin()[axis] + image_->GetSpacing()[axis] * slice_ + lift;
  return point;
}

void SliceView::updateMeasurements()
{
  const bool measured = image_ && measured_;
  measured_actor_->SetVisibility(measured);
  measured_label_->SetVisibility(measured);
  if (measured)
  {
    // Over the crosshair, which often runs along it from the same skin point.
    const auto from = onTopOfSlice(measured_->from, 1.0), to = onTopOfSlice(measured_->to, 1.0);
    measured_line_->SetPoint1(from.data());
    measured_line_->SetPoint2(to.data());
    measured_label_->SetInput(measured_->label.c_str());
    measured_label_->GetPositionCoordinate()->SetValue(to[0], to[1], to[2]);
  }
  const bool ruler = image_ && ruler_ends_ > 0 && ruler_slice_ == slice_;
  ruler_actor_->SetVisibility(ruler);
  ruler_label_->SetVisibility(ruler && ruler_ends_ == 2);
  if (ruler)
  {
    const auto from = onTopOfSlice(ruler_from_, 1.0), to = onTopOfSlice(ruler_to_, 1.0);
    ruler_line_->SetPoint1(from.data());
    ruler_line_->SetPoint2(to.data());
    char text[32];
    std::snprintf(text, sizeof text, "%.1f mm", distance(ruler_from_, ruler_to_));
    ruler_label_->SetInput(text);
    ruler_label_->GetPositionCoordinate()->SetValue(to[0], to[1], to[2]);
  }
}

void SliceView::handleWheel(int steps)
{
  setSlice(slice_ + steps);
  updateAnnotation();
  renderWindow()->Render();
}

void SliceView::handleHover(int x, int y)
{
  if (!image_)
    return;
  const auto p = pointAtDisplay(x, y);
  const int* dims = image_->GetDimensions();
  bool inside = true;
  for (int a = 0; a < 3; ++a)
  {
    const double index = (p[a] - image_->GetOrigin()[a]) / image_->GetSpacing()[a];
    inside = inside && index > -0.5 && index < dims[a] - 0.5;
  }
  if (ruler_mode_ && ruler_ends_ == 1 && ruler_slice_ == slice_)
  { // the ruler follows the mouse until its second end is placed
    ruler_to_ = p;
    updateMeasurements();
    renderWindow()->Render();
  }
  emit hovered(p[0], p[1], p[2], inside);
}

void SliceView::handleClick(int x, int y)
{
  if (!image_)
    return;
  const auto p = pointAtDisplay(x, y);
  if (ruler_mode_)
    placeRulerEnd(p);
  else
    emit clicked(p[0], p[1], p[2]);
}

void SliceView::handleWindowLevelChanged()
{
  updateAnnotation();
  emit windowLevelChanged(window(), level());
}

void SliceView::resetCamera()
{
  vtkCamera* camera = renderer_->GetActiveCamera();
  camera->ParallelProjectionOn();
  // Camera direction and up vector of the radiological views (LPS frame).
  double direction[3] = {0, 0, 1}, up[3] = {0, -1, 0};
  if (orientation_ == SliceOrientation::Coronal)
  {
    direction[1] = 1, direction[2] = 0;
    up[1] = 0, up[2] = 1;
  }
  else if (orientation_ == SliceOrientation::Sagittal)
  {
    direction[0] = -1, direction[2] = 0;
    up[1] = 0, up[2] = 1;
  }
  double bounds[6];
  image_->GetBounds(bounds);
  const double centre[3] = {(bounds[0] + bounds[1]) / 2, (bounds[2] + bounds[3]) / 2, (bounds[4] + bounds[5]) / 2};
  const double distance = 1000.0;
  camera->SetFocalPoint(centre);
  camera->SetPosition(centre[0] - direction[0] * distance, centre[1] - direction[1] * distance,
                      centre[2] - direction[2] * distance);
  camera->SetViewUp(up);
  renderer_->ResetCamera(bounds);
  // Fill the view with the slice: half the larger in-plane extent, with the
  // view's aspect ratio taken into account.
  double extent[3] = {bounds[1] - bounds[0], bounds[3] - bounds[2], bounds[5] - bounds[4]};
  const double verticalExtent = orientation_ == SliceOrientation::Axial ? extent[1] : extent[2];
  const double horizontalExtent = orientation_ == SliceOrientation::Sagittal ? extent[1] : extent[0];
  const double aspect = height() > 0 ? static_cast<double>(width()) / height() : 1.0;
  camera->SetParallelScale(0.52 * std::max(verticalExtent, horizontalExtent / aspect));
  renderer_->ResetCameraClippingRange();
}

void SliceView::updateSlicePlane()
{
  if (!image_)
    return;
  mapper_->SetSliceNumber(slice_);
  overlay_mapper_->SetSliceNumber(slice_);
  updateCrosshair();
  updateMeasurements();
  updateAnnotation();
}

void SliceView::updateCrosshair()
{
  double bounds[6];
  image_->GetBounds(bounds);
  const int axis = sliceAxis();
  const std::array<double, 3> p = onTopOfSlice(cursor_);
  const int u = axis == 0 ? 1 : 0;
  const int v = axis == 2 ? 1 : 2;
  std::array<double, 3> a0 = p, a1 = p, b0 = p, b1 = p;
  a0[u] = bounds[2 * u];
  a1[u] = bounds[2 * u + 1];
  b0[v] = bounds[2 * v];
  b1[v] = bounds[2 * v + 1];
  line_a_->SetPoint1(a0.data());
  line_a_->SetPoint2(a1.data());
  line_b_->SetPoint1(b0.data());
  line_b_->SetPoint2(b1.data());
}

void SliceView::updateAnnotation()
{
  if (!image_)
  {
    corners_->SetText(vtkCornerAnnotation::LowerLeft, "");
    corners_->SetText(vtkCornerAnnotation::LowerRight, "");
    return;
  }
  char text[96];
  std::snprintf(text, sizeof text, "Slice %d / %d", slice_ + 1, sliceCount());
  corners_->SetText(vtkCornerAnnotation::LowerLeft, text);
  std::snprintf(text, sizeof text, "W %.0f  L %.0f", window(), level());
  corners_->SetText(vtkCornerAnnotation::LowerRight, text);
}

} // namespace caps::ui
