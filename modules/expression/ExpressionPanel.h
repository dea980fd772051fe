#pragma once
/// @file ExpressionPanel.h
/// @brief The Expression module's panel (issue 8 item 4): builds the face
/// model, then a slider per expression and per muscle moves the skin in
/// real time by superposition (thesis §3.1.2, §5.3, Fig. 5.14–5.18);
/// expressions are saved in the scene, recalled and played.

#include <memory>
#include <string>
#include <vector>

#include <QElapsedTimer>
#include <QWidget>
#include <vtkSmartPointer.h>

#include "modules/expression/ExpressionLogic.h"

class QComboBox;
class QLabel;
class QLineEdit;
class QPushButton;
class QSlider;
class QTimer;
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
  /// The current mix played from rest and back, written as frames and MP4 (report::writeMorphAnimation).
  void exportAnimation();

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
  NodeId faceId_;
  std::vector<NodeId> hidden_; ///< surfaces hidden while the face shows
  Eigen::Matrix3Xd scratch_;
  double lastUpdateMs_ = 0.0;
  double largestMovement_ = 0.0;
};

} // namespace caps
