#pragma once
/// @file ResultsPanel.h
/// @brief The Results module's panel: a predicted plan
/// shown between before and after the operation (slider, pre/post, play),
/// coloured by stress, displacement or strain, its numbers, the stress and
/// displacement along the incision, and snapshots for the storyboard
/// (thesis §4.7, §3.3.3).

#include <map>
#include <memory>
#include <string>

#include <QElapsedTimer>
#include <QWidget>
#include <vtkSmartPointer.h>

#include "modules/results/ResultsLogic.h"

class QVBoxLayout;
class QComboBox;
class QLabel;
class QListWidget;
class QListWidgetItem;
class QPushButton;
class QSlider;
class QTimer;
class vtkPolyData;

namespace caps {

class ModuleHost;
class IncisionPlot;
class PlanComparison;
class SurfaceNode;

class ResultsPanel : public QWidget
{
  Q_OBJECT
public:
  ResultsPanel(ResultsLogic& logic, ModuleHost& host, QWidget* parent = nullptr);
  ~ResultsPanel() override;

protected:
  void showEvent(QShowEvent* event) override;
  void hideEvent(QHideEvent* event) override;

private:
  /// @name The panel's parts, top to bottom, and their wiring
  ///@{
  void addViewControls(QVBoxLayout* layout);
  void addSummaryAndProfile(QVBoxLayout* layout);
  void addStoryboard(QVBoxLayout* layout);
  void connectControls();
  void observeTheScene();
  ///@}
  void scheduleRefresh();
  void refresh();
  void refreshStoryboard();
  /// Shows the plan of that name (empty: none), releasing the one shown;
  /// @a again: even when it is the one shown (its surfaces were replaced).
  void showPlan(const std::string& name, bool again = false);
  /// Removes the panel's nodes and shows the plan's own surfaces again.
  void releasePlan();
  void setDeformation(int percent);
  void applyColour();
  /// Colours @a node by the quantity chosen (colour array, range, map, bar title).
  void setColouring(SurfaceNode& node) const;
  void updateSummary();
  void startClosure();
  void play();
  void tick();
  void takeSnapshot();
  /// Opens the two plans side by side (PlanComparison).
  void compare();
  void deleteSnapshots();
  void restoreSnapshotCamera(QListWidgetItem* item);
  std::string stateWord() const;

  ResultsLogic& logic_;
  ModuleHost& host_;
  int observer_ = -1;
  bool refreshPending_ = false;
  bool storyboardPending_ = false;

  QComboBox* plan_ = nullptr;
  QSlider* deformation_ = nullptr;
  QLabel* deformationLabel_ = nullptr;
  QPushButton* prePost_ = nullptr;
  QPushButton* play_ = nullptr;
  QComboBox* colourBy_ = nullptr;
  QComboBox* compareWith_ = nullptr;
  QPushButton* compare_ = nullptr;
  PlanComparison* comparison_ = nullptr; ///< a window of its own, owned by the main window
  QLabel* summary_ = nullptr;
  QPushButton* computeClosure_ = nullptr;
  IncisionPlot* plot_ = nullptr;
  QPushButton* snapshot_ = nullptr;
  QListWidget* storyboard_ = nullptr;
  QPushButton* deleteSnapshot_ = nullptr;
  QTimer* animation_ = nullptr;
  QElapsedTimer clock_;
  int animationFrom_ = 0, animationTo_ = 100;

  /// The plan shown and the nodes the panel changed or added for it.
  PredictedPlan shown_;
  bool shownFailed_ = false; ///< the shown plan's solve stopped short: no deformation to show
  NodeId resultId_, headId_, headCutId_;
  bool beforeWasVisible_ = false, afterWasVisible_ = true, headWasVisible_ = true;
  vtkSmartPointer<vtkPolyData> before_;
  vtkSmartPointer<vtkPolyData> result_;

  /// Closure numbers by ResultsLogic::closureKey(); errors likewise.
  std::map<std::string, ClosureNumbers> closure_;
  std::map<std::string, std::string> closureError_;
  std::string computingKey_;
};

} // namespace caps
