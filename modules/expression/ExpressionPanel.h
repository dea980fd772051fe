#pragma once
/// @file ExpressionPanel.h
/// @brief The Expression module's panel: builds the face
/// model, then a slider per expression and per muscle moves the skin in
/// real time by superposition (thesis §3.1.2, §5.3, Fig. 5.14–5.18);
/// expressions are saved in the scene, recalled and played. A predicted
/// plan is studied in the face (§5.4): its skin after the operation
/// follows the sliders and a fingertip, its contour bumps compared with rest.

#include <memory>
#include <string>
#include <vector>

#include <QElapsedTimer>
#include <QWidget>
#include <vtkSmartPointer.h>

#include "modules/expression/ExpressionLogic.h"
#include "modules/expression/PlanStudy.h"

class QComboBox;
class QDoubleSpinBox;
class QGroupBox;
class QLabel;
class QLineEdit;
class QPushButton;
class QSlider;
class QTimer;
class QVBoxLayout;
class vtkPolyData;

namespace caps {

class ModuleHost;

class ExpressionPanel : public QWidget
{
  Q_OBJECT
public:
  ExpressionPanel(ExpressionLogic& logic, ModuleHost& host, QWidget* parent = nullptr);
  ~ExpressionPanel() override;

  /// The muscles' activations the sliders give now (mixActivations()); empty
  /// before the face model is built.
  Eigen::VectorXd activations() const;

protected:
  void showEvent(QShowEvent* event) override;
  void hideEvent(QHideEvent* event) override;

private:
  /// @name The panel's parts, top to bottom, and their wiring
  ///@{
  void addModelControls(QVBoxLayout* layout);
  void addExpressionSliders(QVBoxLayout* layout);
  void addMuscleSliders(QVBoxLayout* layout);
  void addPlaybackControls(QVBoxLayout* layout);
  QVBoxLayout* addPlanStudy();
  void addFingertip(QVBoxLayout* planLayout);
  void addSavedExpressions(QVBoxLayout* layout);
  void connectControls();
  void observeTheScene();
  ///@}
  void build();
  /// Takes a freshly built model: the sliders, the face node, the camera.
  void setModel(std::shared_ptr<const expression::ExpressionModel> model);
  /// Drops the model (its scene was replaced) and the sliders with it.
  void dropModel(const std::string& why);
  void rebuildMuscleSliders();
  /// Shows the face under the sliders' mix (times the play scale).
  void updateFace();
  /// Adds the "Face expression" node and hides the other surfaces.
  void showFace();
  /// Removes the face node and shows the surfaces it hid again.
  void releaseFace();
  /// Removes faces another model left in the scene (a scene saved while the
  /// face showed), showing the surfaces each hid again.
  void takeBackLeftoverFaces();
  void faceOnCamera();
  void saveExpression();
  void recallExpression(int index);
  void refreshSaved();
  void play();
  void tick();
  void rest();
  /// The current mix played from rest and back, written as frames and MP4 (render::writeMorphAnimation).
  void exportAnimation();

  /// @name Plan under expression (§5.4)
  ///@{
  /// The scene's plans with a prediction, in the combo.
  void refreshPlans();
  /// Predicts the chosen plan again inside the face model (runTask).
  void studyPlan();
  void setStudy(std::shared_ptr<expression::PlanStudy> study);
  /// Drops the study: the face comes back.
  void leaveStudy();
  /// Adds the plan's skin node in place of the face.
  void showStudy();
  /// Removes the plan's skin node and shows the face again.
  void releaseStudy();
  /// Moves the plan's skin to the sliders' mix or the fingertip's travel
  /// (times the play scale); returns the largest movement from rest (mm).
  double updateStudy(const Eigen::VectorXd& activations);
  void planOnCamera();
  /// The bumps label for the skin as shown now (compareContours: after the sliders settle).
  void updateBumps();
  /// Asks for a point on the plan's skin, then builds the push (runTask).
  void placeFingertip();
  void buildFingertip(const Eigen::Vector3d& centre);
  /// The fingertip's path in world mm: the corners, then the travel boxes.
  expression::PushPath pushPath() const;
  /// The travel boxes (up, across, in) in world mm at the fingertip.
  Eigen::Vector3d travelBoxes() const;
  void addCorner();
  void clearCorners();
  /// The fingertip's controls enabled as the study and the fingertip allow; the path's text.
  void updatePushControls();
  ///@}

  ExpressionLogic& logic_;
  ModuleHost& host_;
  int observer_ = -1;
  bool savedPending_ = false;
  bool leftoverPending_ = false;

  QPushButton* build_ = nullptr;
  QLabel* status_ = nullptr;
  QWidget* expressionBox_ = nullptr;
  QWidget* muscleBox_ = nullptr;
  std::vector<QSlider*> expressionSliders_;
  std::vector<QSlider*> muscleSliders_;
  std::vector<QLabel*> muscleValues_;
  QLineEdit* name_ = nullptr;
  QPushButton* save_ = nullptr;
  QComboBox* saved_ = nullptr;
  QPushButton* play_ = nullptr;
  QPushButton* rest_ = nullptr;
  QPushButton* export_ = nullptr;
  QLabel* info_ = nullptr;
  QTimer* animation_ = nullptr;
  QElapsedTimer clock_;
  double playScale_ = 1.0;

  std::shared_ptr<const expression::ExpressionModel> model_;
  /// Per built-in expression, its activations on the model's muscles.
  std::vector<Eigen::VectorXd> expressionActivations_;
  vtkSmartPointer<vtkPolyData> face_;
  /// While a plan is studied: the face without the cells under the plan's
  /// region (its points are face_'s), so the plan's skin shows in its face.
  vtkSmartPointer<vtkPolyData> faceAround_;
  NodeId faceId_;
  std::vector<NodeId> hidden_; ///< surfaces hidden while the face shows
  Eigen::Matrix3Xd scratch_;
  double lastUpdateMs_ = 0.0;
  double largestMovement_ = 0.0;

  // Plan under expression.
  QGroupBox* planBox_ = nullptr;
  QComboBox* plans_ = nullptr;
  QPushButton* study_ = nullptr;
  QPushButton* leave_ = nullptr;
  QLabel* planStatus_ = nullptr;
  QLabel* bumps_ = nullptr;
  QPushButton* fingertip_ = nullptr;
  QDoubleSpinBox* radius_ = nullptr;
  QDoubleSpinBox* up_ = nullptr;
  QDoubleSpinBox* across_ = nullptr;
  QDoubleSpinBox* in_ = nullptr;
  QPushButton* corner_ = nullptr;
  QPushButton* clearCorners_ = nullptr;
  QSlider* travel_ = nullptr;
  QLabel* pathInfo_ = nullptr;
  QTimer* bumpsTimer_ = nullptr;
  bool plansPending_ = false;
  bool studyPending_ = false;
  /// The plan's skin shows the fingertip's push (the last control touched
  /// was the fingertip's), not the muscles' mix.
  bool pushing_ = false;
  std::shared_ptr<expression::PlanStudy> planStudy_;
  vtkSmartPointer<vtkPolyData> planSkin_;
  NodeId planSkinId_;
  /// The path's corners in the fingertip's frame (up, across, in; mm).
  std::vector<Eigen::Vector3d> corners_;
  Eigen::Matrix3Xd planRest_;
  Eigen::Matrix3Xd planScratch_;
  double lastCompareMs_ = 0.0;
};

} // namespace caps
