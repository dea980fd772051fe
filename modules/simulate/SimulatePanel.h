#pragma once
/// @file SimulatePanel.h
/// @brief The Simulate module's panel: a planned incision
/// turned into a prediction. Choose a plan, the tissue materials and the
/// mesh; see the model's size before running; Run (F5) in the background
/// with Cancel; read the closure force and the skin stress near the wound;
/// show the model's mesh; or let the prediction follow the plan's edits
/// (linear preview at once, large deformation in the background:
/// LivePrediction.h). The work is in PlanSimulationRun.h.

#include <memory>
#include <string>

#include <QString>
#include <QWidget>

#include "planning/PlanSimulation.h"
#include "scene/Node.h"

class QCheckBox;
class QComboBox;
class QDoubleSpinBox;
class QLabel;
class QPushButton;
class QSpinBox;
class QTableWidget;
class QTableWidgetItem;
class QThread;
class QTimer;
class QVBoxLayout;

namespace caps {

class ModuleHost;
class SimulateLogic;
class Node;

namespace simulate {
class LivePrediction;
struct PlanRunInput;
struct PlanRunResult;
enum class LiveStage;
} // namespace simulate

class SimulatePanel : public QWidget
{
  Q_OBJECT
public:
  SimulatePanel(SimulateLogic& logic, ModuleHost& host, QWidget* parent = nullptr);
  ~SimulatePanel() override;

private:
  /// @name The panel's parts, top to bottom, and their wiring
  ///@{
  void addPlanChooser(QWidget* content, QVBoxLayout* layout);
  void addMaterials(QWidget* content, QVBoxLayout* layout);
  void addMeshOptions(QWidget* content, QVBoxLayout* layout);
  void addRunAndResults(QWidget* content, QVBoxLayout* layout);
  void setDefaults();
  void connectControls();
  void observeTheScene();
  ///@}
  /// The plan combo from the scene's Plan nodes, keeping the choice.
  void updatePlans();
  /// The chosen plan's recorded options into the widgets.
  void loadPlanOptions();
  /// The material table's rows for the layer count (new rows from the preset).
  void resizeMaterials(int layers);
  /// Every row from the preset.
  void fillMaterialsFromPreset();
  /// Checks an edited cell; refuses a bad value with a message.
  void materialEdited(QTableWidgetItem* item);
  /// The options the widgets give; materials only when all are valid
  /// (@a problem says what is wrong otherwise).
  planning::SimulationOptions options(std::string* problem) const;
  /// Recomputes the estimate after a short pause (parameters change in bursts).
  void scheduleEstimate();
  void estimate();
  void run();
  /// @name The prediction that follows the edits
  ///@{
  /// An edit of the chosen plan (not one of ours): what runs for the old
  /// state stops at once; the new state runs after a short pause.
  void planEdited(const Node& node);
  /// The chosen plan as it is now, to LivePrediction.
  void predictLive();
  void liveReady(simulate::LiveStage stage, const std::shared_ptr<const simulate::PlanRunInput>& input,
                 const std::shared_ptr<const simulate::PlanRunResult>& result, double seconds);
  void liveFailed(simulate::LiveStage stage, const std::string& message);
  ///@}
  /// The chosen plan's "<name> mesh" node shown or hidden as the check box says.
  void applyShowMesh();
  NodeId currentPlan() const;

  SimulateLogic& logic_;
  ModuleHost& host_;
  int observer_ = -1;
  bool updatePending_ = false;
  bool loading_ = false;

  QComboBox* plan_ = nullptr;
  QComboBox* preset_ = nullptr;
  QLabel* source_ = nullptr;
  QTableWidget* materials_ = nullptr;
  QSpinBox* layers_ = nullptr;
  QDoubleSpinBox* regionRadius_ = nullptr;
  QDoubleSpinBox* elementSize_ = nullptr;
  QSpinBox* cutDepth_ = nullptr;
  QDoubleSpinBox* undermining_ = nullptr;
  QDoubleSpinBox* tensionAlong_ = nullptr;  ///< skin pre-tension along the lines, kPa
  QDoubleSpinBox* tensionAcross_ = nullptr; ///< and across them
  QComboBox* model_ = nullptr;              ///< the tissue model: linear preview or large deformation
  QLabel* estimate_ = nullptr;
  QPushButton* run_ = nullptr;
  QLabel* summary_ = nullptr;
  QCheckBox* showMesh_ = nullptr;
  QCheckBox* live_ = nullptr;    ///< the prediction follows the plan's edits
  QLabel* liveStatus_ = nullptr; ///< what the live prediction shows and what runs
  QString liveShown_;            ///< the line saying what is shown, while a later stage runs
  QTimer* liveTimer_ = nullptr;  ///< the pause after an edit (edits come in bursts)
  simulate::LivePrediction* livePrediction_ = nullptr;
  bool applying_ = false; ///< our own nodes going into the scene: their events are not edits

  QTimer* estimateTimer_ = nullptr;
  QThread* estimateThread_ = nullptr;
  bool estimateAgain_ = false;
  int estimateGeneration_ = 0;
};

} // namespace caps
