#pragma once
/// @file SliceView.h
/// @brief One 2D slice view of a CT volume (axial, coronal or sagittal).

#include <array>
#include <optional>
#include <string>

#include <QVTKOpenGLNativeWidget.h>
#include <vtkSmartPointer.h>

class vtkActor;
class vtkCornerAnnotation;
class vtkImageData;
class vtkImageSlice;
class vtkImageStack;
class vtkScalarsToColors;
class vtkImageSliceMapper;
class vtkLineSource;
class vtkRenderer;
class vtkTextActor;

namespace caps::ui {

/// A straight measurement drawn on the slices: its two ends (image space)
/// and what it says ("6.2 mm").
struct SliceSegment
{
  std::array<double, 3> from{};
  std::array<double, 3> to{};
  std::string label;
};

enum class SliceOrientation
{
  Axial,
  Coronal,
  Sagittal
};

/// A slice through a volume in radiological convention (patient left on the
/// right of the screen, anterior up in axial views, face to the left in
/// sagittal views).
///
/// Mouse: wheel scrolls slices, left drag sets window/level, a left click
/// puts the crosshair there, right drag zooms, middle drag pans. In ruler
/// mode a left click starts a ruler and the next one ends it (the length in
/// mm is drawn beside it, as on a radiology viewer's slice).
///
/// Positions exchanged with the outside are in image space: origin +
/// spacing * index, along the volume's index axes. For the usual axial CT
/// (identity direction) this is the patient frame; an oblique volume is shown
/// along its own axes.
class SliceView : public QVTKOpenGLNativeWidget
{
  Q_OBJECT
public:
  explicit SliceView(SliceOrientation orientation, QWidget* parent = nullptr);
  ~SliceView() override;

  SliceOrientation orientation() const { return orientation_; }

  /// Shows @a image (nullptr clears the view) at its middle slice.
  void setImage(vtkImageData* image);
  vtkImageData* image() const;

  /// Draws @a overlay (an image on the same grid as the CT: a label map, or
  /// the CT itself) over the slice through @a colours (RGBA per value; alpha
  /// 0 leaves the CT visible). nullptr hides the overlay.
  void setOverlay(vtkImageData* overlay, vtkScalarsToColors* colours);
  bool hasOverlay() const;

  void setWindowLevel(double window, double level);
  double window() const;
  double level() const;

  int slice() const { return slice_; }
  int sliceCount() const;
  void setSlice(int slice);

  /// Moves the slice to contain @a position and the crosshair onto it.
  void setCursorPosition(const std::array<double, 3>& position);
  const std::array<double, 3>& cursorPosition() const { return cursor_; }

  /// Image-space point under display pixel (x, y) on the current slice.
  std::array<double, 3> pointAtDisplay(int x, int y) const;

  /// @name Measurements drawn on the slice
  ///@{
  /// A measured segment (a landmark's depth from the skin to the bone),
  /// drawn projected onto the slice shown, with its label at the deep end;
  /// std::nullopt takes it away.
  void setMeasuredSegment(const std::optional<SliceSegment>& segment);
  const std::optional<SliceSegment>& measuredSegment() const { return measured_; }
  /// Ruler mode: left clicks place a ruler's ends instead of the crosshair.
  void setRulerMode(bool on);
  bool rulerMode() const { return ruler_mode_; }
  /// The ruler: its ends in image space, on the slice it was drawn on (shown
  /// only there), and its length (mm); std::nullopt while there is none or
  /// only its first end is placed.
  std::optional<SliceSegment> ruler() const;
  int rulerSlice() const { return ruler_slice_; }
  void clearRuler();
  ///@}

  /// Internal: called by the view's interactor style.
  void handleWheel(int steps);
  void handleHover(int x, int y);
  void handleClick(int x, int y);
  void handleWindowLevelChanged();

signals:
  /// The mouse is over @a position; @a inside tells whether it is in the volume.
  void hovered(double x, double y, double z, bool inside);
  /// The user clicked at @a position (to move the linked crosshair).
  void clicked(double x, double y, double z);
  void windowLevelChanged(double window, double level);
  void sliceChanged(int slice);
  /// A ruler was finished: its length in mm.
  void rulerMeasured(double millimetres);

private:
  int sliceAxis() const;
  void resetCamera();
  void updateSlicePlane();
  void updateCrosshair();
  void updateAnnotation();
  /// Puts the measured segment and the ruler on the slice shown.
  void updateMeasurements();
  void placeRulerEnd(const std::array<double, 3>& point);
  /// @a point moved onto the slice plane and @a lift mm towards the camera
  /// (what is lifted more draws over what is lifted less).
  std::array<double, 3> onTopOfSlice(std::array<double, 3> point, double lift = 0.5) const;

  SliceOrientation orientation_;
  vtkSmartPointer<vtkRenderer> renderer_;
  vtkSmartPointer<vtkImageData> image_;
  vtkSmartPointer<vtkImageSliceMapper> mapper_;
  vtkSmartPointer<vtkImageSlice> slice_actor_;
  vtkSmartPointer<vtkImageSliceMapper> overlay_mapper_;
  vtkSmartPointer<vtkImageSlice> overlay_actor_;
  vtkSmartPointer<vtkImageStack> stack_; ///< the CT below, the overlay above (no z-fighting)
  vtkSmartPointer<vtkLineSource> line_a_;
  vtkSmartPointer<vtkLineSource> line_b_;
  vtkSmartPointer<vtkActor> crosshair_a_;
  vtkSmartPointer<vtkActor> crosshair_b_;
  vtkSmartPointer<vtkCornerAnnotation> corners_;
  std::array<vtkSmartPointer<vtkTextActor>, 4> edge_labels_; ///< top, bottom, left, right
  std::optional<SliceSegment> measured_;
  vtkSmartPointer<vtkLineSource> measured_line_;
  vtkSmartPointer<vtkActor> measured_actor_;
  vtkSmartPointer<vtkTextActor> measured_label_;
  bool ruler_mode_ = false;
  int ruler_ends_ = 0; ///< 0: no ruler, 1: its start placed, 2: finished
  int ruler_slice_ = -1;
  std::array<double, 3> ruler_from_{};
  std::array<double, 3> ruler_to_{};
  vtkSmartPointer<vtkLineSource> ruler_line_;
  vtkSmartPointer<vtkActor> ruler_actor_;
  vtkSmartPointer<vtkTextActor> ruler_label_;
  std::array<double, 3> cursor_{0.0, 0.0, 0.0};
  int slice_ = 0;
};

} // namespace caps::ui
