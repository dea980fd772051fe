#pragma once
/// @file ThreeDView.h
/// @brief The 3D view: the volume's three orthogonal slices in the patient
/// frame, plus surfaces (skin, bone, meshes) added by modules.

#include <array>
#include <map>
#include <string>

#include <QVTKOpenGLNativeWidget.h>
#include <vtkSmartPointer.h>

class vtkActor;
class vtkImageData;
class vtkImageProperty;
class vtkImageSlice;
class vtkImageSliceMapper;
class vtkOrientationMarkerWidget;
class vtkPolyData;
class vtkRenderer;

namespace caps::ui {

class ThreeDView : public QVTKOpenGLNativeWidget
{
  Q_OBJECT
public:
  explicit ThreeDView(QWidget* parent = nullptr);
  ~ThreeDView() override;

  /// Shows the three orthogonal slices of @a image (nullptr clears).
  void setImage(vtkImageData* image);
  void setWindowLevel(double window, double level);
  /// Shows or hides the three slice planes (surfaces stay).
  void setSlicesVisible(bool visible);
  bool slicesVisible() const { return slices_visible_; }
  /// Moves the three slice planes through @a position (image space, mm).
  void setCursorPosition(const std::array<double, 3>& position);

  /// Adds or replaces the surface @a key (a node id, say).
  void setSurface(const std::string& key, vtkPolyData* surface, const std::array<double, 3>& colour,
                  double opacity, bool visible);
  void removeSurface(const std::string& key);

  /// Looks at the face from the front (anterior view, superior up).
  void resetCamera();
  vtkRenderer* renderer() const;

private:
  vtkSmartPointer<vtkRenderer> renderer_;
  vtkSmartPointer<vtkImageData> image_;
  vtkSmartPointer<vtkImageProperty> image_property_;
  std::array<vtkSmartPointer<vtkImageSliceMapper>, 3> mappers_;
  std::array<vtkSmartPointer<vtkImageSlice>, 3> slices_;
  vtkSmartPointer<vtkActor> outline_;
  vtkSmartPointer<vtkOrientationMarkerWidget> orientation_marker_;
  std::map<std::string, vtkSmartPointer<vtkActor>> surfaces_;
  bool slices_visible_ = true;
};

} // namespace caps::ui
