#pragma once
/// @file IncisionPanel.h
/// @brief The incision editor: a procedure placed by a
/// click on the 3D skin, drawn on it, measured on it, and edited with undo.

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <QWidget>
#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "planning/PlanRecipe.h"
#include "scene/Node.h"

class QVBoxLayout;
class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QFormLayout;
class QGroupBox;
class QLabel;
class QListWidget;
class QPushButton;
class QSpinBox;
class QTableWidget;

namespace caps {

class ModuleHost;
class IncisionLogic;
class PlanNode;
class RangeMapNode;
struct SurfacePick;

namespace seg {
class RangeMap;
}
namespace planning {
class IncisionPlan;
struct PlanRecipe;
class ProcedureTemplate;
class SkinTensionLines;
} // namespace planning

/// @class IncisionPanel
/// @brief Procedure and parameters, "Place on the skin", the scene's plans,
/// their live measurements on the skin, and edits recorded on the scene's
/// undo stack. Each plan the panel draws has a Surface node
/// "<plan name> incision" of lines (PlanLines.h) kept in step with it.
class IncisionPanel : public QWidget
{
  Q_OBJECT
public:
  IncisionPanel(IncisionLogic& logic, ModuleHost& host, QWidget* parent = nullptr);
  ~IncisionPanel() override;

private:
  /// @name The panel's parts, top to bottom, and their wiring
  ///@{
  void addNewPlanControls(QVBoxLayout* layout);
  void addPlanList(QVBoxLayout* layout);
  void addPlanEditing(QVBoxLayout* layout);
  void addGuidesAndMeasurements(QVBoxLayout* layout);
  void connectControls();
  ///@}
  /// @name Building the form
  ///@{
  void fillProcedures();
  /// The parameter form of a procedure, with these values (API units) or its defaults.
  void buildForm(const planning::ProcedureTemplate& procedure, const std::map<std::string, double>* values);
  /// The form's values in API units, defaults exactly where untouched.
  std::map<std::string, double> formValues(const planning::ProcedureTemplate& procedure) const;
  const planning::ProcedureTemplate* currentProcedure();
  ///@}

  /// @name Placing and editing
  ///@{
  void armPlace();
  void placeAt(const SurfacePick& pick);
  /// Collects the points of a cut drawn by hand, one click each, in scalpel order.
  void armDraw();
  /// Makes the drawn points a plan "Cut n" (planning::DrawCut).
  void finishDraw();
  /// Adds a plan "<title> n" (n the first number free) with its recipe and lines, and selects it; returns its name.
  std::string addPlan(const std::string& title, const planning::IncisionPlan& plan, const planning::PlanRecipe& recipe,
                      const NodeId& skinId);
  void armMove();
  void moveTo(const NodeId& planId, const SurfacePick& pick);
  void parameterChanged(const std::string& name);
  /// Moves cut point n (the spin box) to the next point clicked on the skin.
  void armMovePoint();
  /// Moves cut point @a point of plan @a planId to a point on the skin (one undoable edit).
  void movePointTo(const NodeId& planId, int point, const SurfacePick& pick);
  /// Shows the selected plan's cut points as handles to drag along the skin
  /// in the 3D view (none while the panel is hidden or nothing is selected).
  void updateHandles();
  /// Offsets border point n (hole loop, Fig. 4.11) by the chart offset typed (§4.4.4).
  void offsetBorderPoint();
  /// Collects the corners of an undermined region clicked on the skin (§3.2.4).
  void armUndermine();
  void finishUndermining();
  void clearUndermining();
  /// Applies the recipe operation @a operation makes of the plan as it is to
  /// plan @a planId, and records it in its recipe as one undoable edit.
  bool recordOperation(
    const NodeId& planId, const std::string& label,
    const std::function<planning::PlanOperation(const planning::IncisionPlan&, const seg::RangeMap&)>& operation);
  /// Runs @a edit on plan @a planId and its recipe as one undoable edit.
  bool editPlan(const NodeId& planId, const std::string& label,
                const std::function<void(planning::IncisionPlan&, planning::PlanRecipe&, const seg::RangeMap&)>& edit);
  void undo();
  void redo();
  void deletePlan();
  ///@}

  /// @name The scene
  ///@{
  /// The newest skin range map; nullptr when there is none.
  const RangeMapNode* newestSkin() const;
  /// The skin map a plan is drawn on (its own, else the newest).
  const RangeMapNode* skinOf(const PlanNode& plan) const;
  /// The map of a node, converted once and kept until the node changes.
  const seg::RangeMap& rangeMap(const RangeMapNode& node);
  /// The CT's content hash for a plan on this skin map, as `caps plan` records it; "" when unknown.
  std::string ctHash(const NodeId& skinId);
  PlanNode* selectedPlan() const;
  /// Draws (or redraws) the lines of a plan; @a create makes the node when there is none.
  void drawLines(const NodeId& planId, bool create);
  void sceneChanged(int event, const Node& node);
  void scheduleRefresh();
  void refresh();
  ///@}

  /// @name What the panel shows
  ///@{
  void refreshPlans();
  void planSelected();
  void showSelection();
  void fillMeasurements(const PlanNode* plan);
  void refreshButtons();
  void showEvent(QShowEvent* event) override;
  void hideEvent(QHideEvent* event) override;
  /// The skin tension lines on a skin map, placed by the landmarks found on
  /// it; nullptr (and @a why) when they cannot be placed.
  const planning::SkinTensionLines* tensionLines(const RangeMapNode& skin, std::string* why = nullptr);
  /// Shows or hides the skin tension lines on the newest skin map.
  void showTensionLines(bool show);
  /// Whether a plan has prediction nodes made for another state of it.
  bool predictionOutOfDate(const PlanNode& plan) const;
  ///@}

  IncisionLogic& logic_;
  ModuleHost& host_;
  int observer_ = -1;
  bool writing_ = false; ///< our own edits in progress: their events are not ours to redraw
  bool refreshPending_ = false;
  std::set<NodeId> redraw_;    ///< plans whose lines follow a change made elsewhere (undo)
  std::set<NodeId> dropLines_; ///< line nodes of plans removed
  std::set<NodeId> dirtyMaps_;
  std::map<NodeId, std::shared_ptr<seg::RangeMap>> maps_;
  std::map<NodeId, std::string> hashes_; ///< volume id → content hash
  struct TensionLinesOnMap
  {
    std::shared_ptr<seg::RangeMap> map; ///< the map they were placed on (they point into it)
    std::unique_ptr<planning::SkinTensionLines> lines;
    std::string why; ///< why there are none
  };
  std::map<NodeId, TensionLinesOnMap> tension_;
  QCheckBox* showTension_ = nullptr;
  /// Plan state (toJson without its name) when its prediction was made, or first seen with one.
  std::map<NodeId, nlohmann::json> predicted_;

  QComboBox* procedure_ = nullptr;
  QGroupBox* formBox_ = nullptr;
  QFormLayout* form_ = nullptr;
  std::map<std::string, QDoubleSpinBox*> spins_;
  std::string formProcedure_; ///< the procedure the form is of
  QPushButton* place_ = nullptr;
  QPushButton* draw_ = nullptr;
  QPushButton* finishDraw_ = nullptr;
  QLabel* drawStatus_ = nullptr;
  NodeId drawSkin_;                    ///< the skin map the cut being drawn is on
  std::vector<Eigen::Vector2d> drawn_; ///< its points so far (θn, zn)
  QListWidget* plans_ = nullptr;
  QPushButton* move_ = nullptr;
  QPushButton* undo_ = nullptr;
  QPushButton* redo_ = nullptr;
  QPushButton* delete_ = nullptr;
  QLabel* predictionStatus_ = nullptr;
  QGroupBox* editBox_ = nullptr;
  QSpinBox* point_ = nullptr;
  QPushButton* movePoint_ = nullptr;
  QSpinBox* borderPoint_ = nullptr;
  QDoubleSpinBox* offsetU_ = nullptr;
  QDoubleSpinBox* offsetV_ = nullptr;
  QPushButton* offset_ = nullptr;
  QPushButton* undermine_ = nullptr;
  QPushButton* finishRegion_ = nullptr;
  QPushButton* clearRegions_ = nullptr;
  QLabel* regionStatus_ = nullptr;
  NodeId regionPlan_;                         ///< the plan the region being clicked is for
  std::vector<std::array<double, 2>> region_; ///< its corners so far (θn, zn)
  QTableWidget* table_ = nullptr;
};

} // namespace caps
