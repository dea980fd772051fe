#pragma once
/// @file RangeMapPanel.h
/// @brief The RangeMap module's panel: builds the range and thickness maps,
/// then the thickness review: the unwrapped map with a
/// probe, the thickness painted on the 3D skin, its histogram, and
/// landmarks with their thickness, exportable as CSV.

#include <map>
#include <optional>

#include <QWidget>

#include "modules/core/Module.h"
#include "modules/rangemap/ThicknessReview.h"

class QVBoxLayout;
class QCheckBox;
class QComboBox;
class QLabel;
class QLineEdit;
class QListWidget;
class QPushButton;
class QTableWidget;

namespace caps {

class ModuleHost;
class RangeMapLogic;
class RangeMapView;
class ThicknessHistogram;
class LandmarksNode;

class RangeMapPanel : public QWidget
{
  Q_OBJECT
public:
  RangeMapPanel(RangeMapLogic& logic, ModuleHost& host, QWidget* parent = nullptr);
  ~RangeMapPanel() override;

protected:
  void showEvent(QShowEvent* event) override;
  void hideEvent(QHideEvent* event) override;

private:
  /// @name The panel's parts, top to bottom, and their wiring
  ///@{
  void addBuildControls(QVBoxLayout* layout);
  void addThicknessReview(QVBoxLayout* layout);
  void addLandmarks(QVBoxLayout* layout);
  void connectControls();
  void observeTheScene();
  ///@}
  void run();
  void updateFromScene();
  void reloadMaps();
  /// The thickness colours' top and the histogram, for the measure shown.
  void updateThicknessScale();
  /// The map kind chosen: the measure every thickness view follows.
  void chooseMap();
  void showMap();
  void showProbe(double theta, double z);
  void locate(double theta, double z);
  void paintThickness(bool on);
  /// Arms two picks on the 3D skin: the ends of the line whose thickness
  /// profile is plotted.
  void drawProfileLine();
  /// The profile of the line drawn, by the measure shown: plotted, summed
  /// up and drawn on the map (nothing while no line is drawn).
  void updateProfile();
  void addLandmark();
  /// The standard landmarks placed from the maps (seg::placeLandmarks) into
  /// the scene's landmarks, replacing those of the same names; the user's own
  /// stay. Those not placed are named in the status bar with why.
  void placeStandardLandmarks();
  void removeLandmark();
  /// Distance @a row of the list (a ruler kept in the scene) drawn on the
  /// slices, the cursor at its start (the slice it was measured on).
  void showDistance(int row);
  void removeDistance();
  /// Landmark @a row of the table on the face (the cursor), on the map and
  /// in the three slices with its measured depth drawn.
  void showLandmark(int row);
  /// The landmarks as handles on the 3D face while the panel is shown: one
  /// dragged and let go on the skin moves there and is measured again.
  void updateHandles();
  void moveLandmark(std::size_t index, const SurfacePick& pick);
  void exportLandmarks();
  void updateLandmarks();
  LandmarksNode* landmarksNode(bool create);
  /// The depth at a landmark measured in the CT by its convention, and the
  /// convention, kept per name and position (the measure reads the CT).
  struct MeasuredDepth
  {
    std::array<double, 3> position{};
    double depth = 0.0;
    std::string convention;
    std::string note; ///< what spoils it (metal streaks), if anything
    /// The measured segment, skin to bone (patient LPS); NaN where none.
    std::array<double, 3> skinEnd{};
    std::array<double, 3> boneEnd{};
  };
  const MeasuredDepth* depthOf(const LandmarksNode::Landmark& landmark);
  std::map<std::string, MeasuredDepth> depths_;

  RangeMapLogic& logic_;
  ModuleHost& host_;
  int observer_ = -1;
  std::optional<ThicknessReview> review_;
  double thickness_top_ = 25.0; ///< top of the thickness colour range (mm)
  /// The thickness the map, the paint on the skin and the histogram show
  /// (the last one chosen while the map shows a skin or bone radius).
  ThicknessMeasure measure_ = ThicknessMeasure::Radial;
  bool reload_pending_ = false;
  bool filling_table_ = false; ///< the table is being rebuilt: its selection means nothing yet
  std::string dragged_;        ///< the landmark just dragged, shown once measured again
  QCheckBox* smooth_ = nullptr;
  QPushButton* run_ = nullptr;
  QLabel* status_ = nullptr;
  QComboBox* map_kind_ = nullptr;
  QCheckBox* paint_ = nullptr;
  RangeMapView* map_view_ = nullptr;
  QLabel* probe_ = nullptr;
  ThicknessHistogram* histogram_ = nullptr;
  QPushButton* profile_button_ = nullptr;
  QLabel* profile_plot_ = nullptr;
  QLabel* profile_summary_ = nullptr;
  /// The line drawn for the profile: its ends on the chart (θ, z).
  std::optional<std::array<std::array<double, 2>, 2>> profile_line_;
  QLineEdit* landmark_name_ = nullptr;
  QTableWidget* landmarks_ = nullptr;
  QPushButton* add_landmark_ = nullptr;
  QPushButton* place_landmarks_ = nullptr;
  QPushButton* remove_landmark_ = nullptr;
  QPushButton* export_landmarks_ = nullptr;
  QPushButton* locate_ = nullptr;
  QLabel* distances_label_ = nullptr;
  QListWidget* distances_ = nullptr;
  QPushButton* remove_distance_ = nullptr;
};

} // namespace caps
