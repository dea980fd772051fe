#pragma once
/// @file ThreeDView.h
/// @brief The 3D view: the volume's three orthogonal slices in the patient
/// frame, plus surfaces (skin, bone, meshes) added by modules.

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <QPoint>
#include <QVTKOpenGLNativeWidget.h>
#include <vtkSmartPointer.h>

class vtkActor;
class vtkPoints;
class vtkImageData;
class vtkImageProperty;
class vtkImageSlice;
class vtkImageSliceMapper;
class vtkOrientationMarkerWidget;
class vtkPolyData;
class vtkRenderer;

class vtkScalarBarActor;

namespace caps::ui {

/// How the 3D view draws a surface (what a SurfaceNode says).
struct SurfaceStyle
{
  std::array<double, 3> colour{0.9, 0.75, 0.65};
  double opacity = 1.0;
  bool visible = true;
  /// Point array to colour by; empty: the solid colour. 3-component unsigned
  /// char arrays are RGB as they are; others go through colourMap over range.
  std::string colourArray;
  std::array<double, 2> range{0.0, 0.0}; ///< lo >= hi: the array's own range
  std::string colourMap = "viridis";     ///< render/ColourMaps.h name
  std::string colourBarTitle;            ///< empty: the array name
  double lineWidth = 1.0;
};

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

  /// Shows a small marker at @a position (world, mm): the point the user
  /// chose in another view (a thickness map, a table).
  void setMarker(const std::array<double, 3>& position);
  void hideMarker();

  /// Points the user moves by dragging them along the surfaces (a plan's
  /// cut points, §3.2.4): drawn as small spheres; a left press within a few
  /// pixels of one drags it instead of turning the view. Replaces any
  /// handles shown; an empty list takes them away.
  void setHandles(const std::vector<std::array<double, 3>>& points);
  std::size_t handleCount() const { return handles_.size(); }
  /// While false, a press near a handle is an ordinary press (a click the
  /// workstation is waiting for, say); the handles stay drawn.
  void setHandlesGrabbable(bool grabbable) { handles_grabbable_ = grabbable; }
  /// Where handle @a index is drawn in widget pixels (Qt's origin top left).
  QPoint handleOnScreen(std::size_t index) const;

  /// Adds or replaces the surface @a key (a node id, say).
  void setSurface(const std::string& key, vtkPolyData* surface, const SurfaceStyle& style);
  void removeSurface(const std::string& key);

  /// The value range of the colour bar shown; std::nullopt when none is.
  std::optional<std::array<double, 2>> colourBarRange() const;

  /// Renders once control returns to the event loop, however many changes
  /// ask for it before then.
  void requestRender();

  /// Looks at the face from the front (anterior view, superior up).
  void resetCamera();
  vtkRenderer* renderer() const;

  /// The surface under display point (x, y) (widget pixels, Qt's origin top
  /// left): its key and the world point hit; false on background or slices.
  bool pickSurface(int x, int y, std::string& key, std::array<double, 3>& position) const;

signals:
  /// A left click (press and release within a few pixels, so not a turn of
  /// the view) on surface @a key at world @a position.
  void surfaceClicked(const QString& key, double x, double y, double z);
  /// A handle was dragged and let go over surface @a key at world @a x, y, z
  /// (not sent when it was let go over the background: it goes back).
  void handleDropped(int index, const QString& key, double x, double y, double z);

protected:
  void mousePressEvent(QMouseEvent* event) override;
  void mouseReleaseEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;
  /// QVTKOpenGLNativeWidget hands every event to the VTK interactor before
  /// the mouse handlers run; a handle's drag is kept from it here, so the
  /// view does not turn while a point is dragged.
  bool event(QEvent* event) override;

private:
  void updateColourBar();
  /// Any render of the window (observer of its StartEvent).
  void renderStarted();
  /// The handle within a few pixels of @a at (the nearest), or -1.
  int handleNear(const QPoint& at) const;
  void updateHandles();

  vtkSmartPointer<vtkRenderer> renderer_;
  vtkSmartPointer<vtkScalarBarActor> colour_bar_;
  vtkSmartPointer<vtkActor> marker_;
  std::vector<std::array<double, 3>> handles_;
  vtkSmartPointer<vtkPoints> handle_points_;
  vtkSmartPointer<vtkActor> handle_actor_;
  bool handles_grabbable_ = true;
  int dragging_ = -1; ///< the handle being dragged, or -1
  bool drag_over_surface_ = false;
  std::string drag_key_;
  std::array<double, 3> drag_position_{};
  std::map<std::string, SurfaceStyle> styles_;
  QPoint press_position_;
  bool press_valid_ = false;
  bool moved_since_press_ = false; ///< a button was down while the mouse moved (the camera turned)
  bool render_pending_ = false;    ///< a render was asked for and none has started since
  unsigned long render_observer_ = 0;
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
