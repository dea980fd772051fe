#include "ui/ThreeDView.h"

#include <algorithm>
#include <cmath>

#include <vtkActor.h>
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

namespace caps::ui {

ThreeDView::ThreeDView(QWidget* parent) : QVTKOpenGLNativeWidget(parent)
{
  auto window = vtkSmartPointer<vtkGenericOpenGLRenderWindow>::New();
  setRenderWindow(window);
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

ThreeDView::~ThreeDView() = default;

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
  renderWindow()->Render();
}

void ThreeDView::setSlicesVisible(bool visible)
{
  slices_visible_ = visible;
  for (auto& slice : slices_)
    slice->SetVisibility(visible);
  renderWindow()->Render();
}

void ThreeDView::setWindowLevel(double window, double level)
{
  image_property_->SetColorWindow(window);
  image_property_->SetColorLevel(level);
  renderWindow()->Render();
}

void ThreeDView::setCursorPosition(const std::array<double, 3>& position)
{
  if (!image_)
    return;
  const int* dims = image_->GetDimensions();
  for (int axis = 0; axis < 3; ++axis)
  {
    const long index =
      std::lround((position[axis] - image_->GetOrigin()[axis]) / image_->GetSpacing()[axis]);
    mappers_[axis]->SetSliceNumber(static_cast<int>(std::clamp<long>(index, 0, dims[axis] - 1)));
  }
  renderWindow()->Render();
}

void ThreeDView::setSurface(const std::string& key, vtkPolyData* surface,
                            const std::array<double, 3>& colour, double opacity, bool visible)
{
  removeSurface(key);
  if (!surface)
    return;
  auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  mapper->SetInputData(surface);
  mapper->ScalarVisibilityOff();
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetColor(colour[0], colour[1], colour[2]);
  actor->GetProperty()->SetOpacity(opacity);
  actor->SetVisibility(visible);
  renderer_->AddActor(actor);
  surfaces_[key] = actor;
  renderWindow()->Render();
}

void ThreeDView::removeSurface(const std::string& key)
{
  auto it = surfaces_.find(key);
  if (it == surfaces_.end())
    return;
  renderer_->RemoveActor(it->second);
  surfaces_.erase(it);
  renderWindow()->Render();
}

void ThreeDView::resetCamera()
{
  vtkCamera* camera = renderer_->GetActiveCamera();
  camera->ParallelProjectionOff();
  camera->SetFocalPoint(0, 0, 0);
  camera->SetPosition(0, -1, 0); // anterior is -y (LPS)
  camera->SetViewUp(0, 0, 1);
  renderer_->ResetCamera();
  camera->Azimuth(-30.0); // a three-quarter view shows all three planes
  camera->Elevation(15.0);
  camera->OrthogonalizeViewUp();
  renderer_->ResetCameraClippingRange();
}

} // namespace caps::ui
