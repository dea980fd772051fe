#include "modules/expression/ExpressionPanel.h"

#include "modules/report/PlanAnimation.h"
#include "segmentation/Progress.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <map>
#include <numbers>

#include <Eigen/Geometry>

#include <QApplication>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QFileDialog>
#include <QFormLayout>
#include <QGroupBox>
#include <QHBoxLayout>
#include <QHideEvent>
#include <QLabel>
#include <QLineEdit>
#include <QPointer>
#include <QPushButton>
#include <QScrollArea>
#include <QShowEvent>
#include <QSignalBlocker>
#include <QSlider>
#include <QTimer>
#include <QVBoxLayout>

#include <vtkCellArray.h>
#include <vtkFieldData.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>

#include "modules/core/ModalProgress.h"
#include "modules/incision/IncisionLogic.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "scene/ExpressionNode.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"
#include "scene/SurfaceNode.h"

namespace caps {

namespace {

constexpr const char* kFaceName = "Face expression";
/// Field data of the face: the ids of the surfaces it hides.
constexpr const char* kHiddenArray = "caps_hidden_surfaces";
constexpr double kPlaySeconds = 3.0; // rest → the mix → rest
/// Field data of a plan's skin under expression: marks it, so a scene saved
/// while it showed loses it when opened again.
constexpr const char* kStudyArray = "caps_plan_under_expression";
/// How long the sliders rest before the bumps are measured again (ms).
constexpr int kBumpsDelayMs = 250;

QDoubleSpinBox* millimetres(QWidget* parent, const QString& objectName, double low, double high, double value,
                            const QString& tip)
{
  auto* box = new QDoubleSpinBox(parent);
  box->setObjectName(objectName);
  box->setRange(low, high);
  box->setDecimals(1);
  box->setSingleStep(0.5);
  box->setSuffix(" mm");
  box->setValue(value);
  box->setToolTip(tip);
  return box;
}

/// Whether plan @a name was predicted: its closure or its skin after is in the scene.
bool predicted(const Scene& scene, const std::string& name)
{
  for (Node* n : scene.nodesOfType(NodeType::Solution))
    if (n->name() == name + " closure")
      return true;
  for (Node* n : scene.nodesOfType(NodeType::Surface))
    if (n->name() == name + " skin after")
      return true;
  return false;
}

QSlider* percentSlider(QWidget* parent, const QString& objectName, const QString& tip)
{
  auto* slider = new QSlider(Qt::Horizontal, parent);
  slider->setObjectName(objectName);
  slider->setRange(0, 100);
  slider->setToolTip(tip);
  return slider;
}

} // namespace

ExpressionPanel::ExpressionPanel(ExpressionLogic& logic, ModuleHost& host, QWidget* parent)
  : QWidget(parent), logic_(logic), host_(host)
{
  auto* layout = new QVBoxLayout(this);
  addModelControls(layout);
  addExpressionSliders(layout);
  addMuscleSliders(layout);
  addPlaybackControls(layout);
  QVBoxLayout* planLayout = addPlanStudy();
  addFingertip(planLayout);
  layout->addWidget(planBox_);
  addSavedExpressions(layout);
  animation_ = new QTimer(this);
  animation_->setInterval(20);

  connectControls();
  observeTheScene();
  dropModel({});
  refreshSaved();
  refreshPlans();
}

/// The Build button and the model's status.
void ExpressionPanel::addModelControls(QVBoxLayout* layout)
{
  build_ = new QPushButton(tr("Build face model"), this);
  build_->setObjectName("expression.build");
  build_->setToolTip(tr("Mesh the whole face from the skin to the bone, fit the muscles to the landmarks and solve "
                        "once per muscle (a few seconds); then the sliders move the skin instantly"));
  layout->addWidget(build_);
  status_ = new QLabel(tr("No face model yet: press 'Build face model' (needs the skin and bone range maps)."), this);
  status_->setObjectName("expression.status");
  status_->setWordWrap(true);
  layout->addWidget(status_);
}

void ExpressionPanel::addExpressionSliders(QVBoxLayout* layout)
{
  // One slider per built-in expression.
  auto* expressions = new QGroupBox(tr("Expressions"), this);
  auto* expressionForm = new QFormLayout(expressions);
  for (const expression::ExpressionDefinition& e : expression::builtInExpressions())
  {
    QSlider* slider = percentSlider(expressions, QString::fromStdString("expression.expression." + e.name),
                                    QString::fromStdString(e.description));
    expressionSliders_.push_back(slider);
    auto* label = new QLabel(QString::fromStdString(e.title), expressions);
    label->setToolTip(QString::fromStdString(e.description));
    expressionForm->addRow(label, slider);
    connect(slider, &QSlider::valueChanged, this, [this](int) {
      animation_->stop();
      playScale_ = 1.0;
      pushing_ = false;
      updateFace();
    });
  }
  expressionBox_ = expressions;
  layout->addWidget(expressions);
}

void ExpressionPanel::addMuscleSliders(QVBoxLayout* layout)
{
  // One slider per muscle, made with the model (its fitted muscles).
  auto* muscles = new QGroupBox(tr("Muscles: slider added to the expressions, number the muscle's activation"), this);
  auto* muscleLayout = new QVBoxLayout(muscles);
  auto* scroll = new QScrollArea(muscles);
  scroll->setWidgetResizable(true);
  scroll->setFrameShape(QFrame::NoFrame);
  muscleBox_ = new QWidget(scroll);
  new QFormLayout(muscleBox_);
  scroll->setWidget(muscleBox_);
  // Six muscles in view at least: below the plan's group the panel scrolls.
  scroll->setMinimumHeight(6 * (fontMetrics().height() + 8));
  muscleLayout->addWidget(scroll);
  layout->addWidget(muscles, 1);
}

/// Play, Rest, Export and what they report.
void ExpressionPanel::addPlaybackControls(QVBoxLayout* layout)
{
  auto* buttons = new QHBoxLayout;
  play_ = new QPushButton(tr("Play"), this);
  play_->setObjectName("expression.play");
  play_->setToolTip(
    tr("Animate from rest to the expression the sliders give and back to rest in %1 s").arg(kPlaySeconds));
  rest_ = new QPushButton(tr("Rest"), this);
  rest_->setObjectName("expression.rest");
  rest_->setToolTip(tr("Every slider to 0: the face at rest"));
  export_ = new QPushButton(tr("Export animation..."), this);
  export_->setObjectName("expression.export");
  export_->setToolTip(tr("Write the expression the sliders give, played from rest and back, as PNG frames and "
                         "(with ffmpeg) an MP4, into a folder you choose"));
  buttons->addWidget(play_);
  buttons->addWidget(rest_);
  buttons->addWidget(export_);
  layout->addLayout(buttons);
  info_ = new QLabel(this);
  info_->setObjectName("expression.info");
  info_->setWordWrap(true);
  layout->addWidget(info_);
}

/// The group of the plan under expression; returns its layout.
QVBoxLayout* ExpressionPanel::addPlanStudy()
{
  // A predicted plan in the face (§5.4): its skin after the operation under
  // the sliders and under a fingertip, its contour bumps against rest.
  planBox_ = new QGroupBox(tr("Plan under expression"), this);
  planBox_->setObjectName("expression.planGroup");
  auto* planLayout = new QVBoxLayout(planBox_);
  auto* planRow = new QHBoxLayout;
  plans_ = new QComboBox(planBox_);
  plans_->setObjectName("expression.plan");
  plans_->setToolTip(tr("The scene's predicted plans (predict a plan in the Simulate panel first)"));
  study_ = new QPushButton(tr("Study plan"), planBox_);
  study_->setObjectName("expression.study");
  study_->setToolTip(tr("Predict the plan again inside the face model (a few seconds); then its skin after the "
                        "operation follows the sliders and the bumps around the cut are compared with rest"));
  leave_ = new QPushButton(tr("Back to face"), planBox_);
  leave_->setObjectName("expression.leaveStudy");
  leave_->setToolTip(tr("Show the whole face again instead of the plan's skin"));
  planRow->addWidget(plans_, 1);
  planRow->addWidget(study_);
  planRow->addWidget(leave_);
  planLayout->addLayout(planRow);
  planStatus_ = new QLabel(planBox_);
  planStatus_->setObjectName("expression.planStatus");
  planStatus_->setWordWrap(true);
  planLayout->addWidget(planStatus_);
  bumps_ = new QLabel(planBox_);
  bumps_->setObjectName("expression.bumps");
  bumps_->setWordWrap(true);
  bumps_->setToolTip(tr("Contour bumps within 20 mm of the cut: each skin vertex's height above or below the smooth "
                        "surface fitted to the skin within 10 mm around it (a dog-ear or a ridge stands out)"));
  planLayout->addWidget(bumps_);
  bumpsTimer_ = new QTimer(this);
  bumpsTimer_->setSingleShot(true);
  bumpsTimer_->setInterval(kBumpsDelayMs);
  return planLayout;
}

/// The fingertip pushing the plan's skin along a path of corners.
void ExpressionPanel::addFingertip(QVBoxLayout* planLayout)
{
  auto* pushForm = new QFormLayout;
  fingertip_ = new QPushButton(tr("Fingertip..."), planBox_);
  fingertip_->setObjectName("expression.fingertip");
  fingertip_->setToolTip(tr("Click on the plan's skin in the 3D view where the fingertip goes; the skin under it "
                            "then follows the travel below (a second or two to prepare)"));
  radius_ = millimetres(planBox_, "expression.push.radius", 1.0, 20.0, 5.0,
                        tr("The fingertip's radius: the skin within it moves with the fingertip"));
  auto* tipRow = new QHBoxLayout;
  tipRow->addWidget(fingertip_, 1);
  tipRow->addWidget(new QLabel(tr("radius"), planBox_));
  tipRow->addWidget(radius_);
  pushForm->addRow(tipRow);
  up_ =
    millimetres(planBox_, "expression.push.up", -20.0, 20.0, 6.0, tr("Travel up the head's axis (mm); negative: down"));
  across_ = millimetres(planBox_, "expression.push.across", -20.0, 20.0, 0.0,
                        tr("Travel across the face, around the head's axis (mm)"));
  in_ = millimetres(planBox_, "expression.push.in", -20.0, 20.0, 0.0,
                    tr("Travel into the face, towards the head's axis (mm); negative: pulled out"));
  auto* travelRow = new QHBoxLayout;
  for (auto [label, box] : {std::pair{tr("Up"), up_}, std::pair{tr("Across"), across_}, std::pair{tr("In"), in_}})
  {
    travelRow->addWidget(new QLabel(label, planBox_));
    travelRow->addWidget(box, 1);
  }
  pushForm->addRow(travelRow);
  corner_ = new QPushButton(tr("Add corner"), planBox_);
  corner_->setObjectName("expression.push.waypoint");
  corner_->setToolTip(tr("Keep the travel above as a corner of the path; set the next travel, and the fingertip "
                         "goes through the corners in order, then to it"));
  clearCorners_ = new QPushButton(tr("Straight path"), planBox_);
  clearCorners_->setObjectName("expression.push.clear");
  clearCorners_->setToolTip(tr("Forget the corners: the fingertip goes straight to the travel above"));
  auto* cornerRow = new QHBoxLayout;
  cornerRow->addWidget(corner_);
  cornerRow->addWidget(clearCorners_);
  pushForm->addRow(cornerRow);
  travel_ = percentSlider(planBox_, "expression.push.travel",
                          tr("How far along the path the fingertip is: 0 % resting on the skin, 100 % at the end"));
  pushForm->addRow(tr("Along the path:"), travel_);
  planLayout->addLayout(pushForm);
  pathInfo_ = new QLabel(planBox_);
  pathInfo_->setObjectName("expression.push.info");
  pathInfo_->setWordWrap(true);
  planLayout->addWidget(pathInfo_);
}

void ExpressionPanel::addSavedExpressions(QVBoxLayout* layout)
{
  auto* store = new QGroupBox(tr("Saved expressions"), this);
  auto* storeForm = new QFormLayout(store);
  name_ = new QLineEdit(store);
  name_->setObjectName("expression.name");
  name_->setPlaceholderText(tr("Name, e.g. broad smile"));
  save_ = new QPushButton(tr("Save expression..."), store);
  save_->setObjectName("expression.save");
  save_->setToolTip(tr("Keep the muscles' activations as they are now in the scene, under the name given"));
  auto* saveRow = new QHBoxLayout;
  saveRow->addWidget(name_, 1);
  saveRow->addWidget(save_);
  storeForm->addRow(tr("Name:"), saveRow);
  saved_ = new QComboBox(store);
  saved_->setObjectName("expression.saved");
  saved_->setToolTip(tr("Choose a saved expression to set the muscle sliders to it"));
  storeForm->addRow(tr("Recall:"), saved_);
  layout->addWidget(store);
}

void ExpressionPanel::connectControls()
{
  connect(build_, &QPushButton::clicked, this, &ExpressionPanel::build);
  connect(play_, &QPushButton::clicked, this, &ExpressionPanel::play);
  connect(rest_, &QPushButton::clicked, this, &ExpressionPanel::rest);
  connect(export_, &QPushButton::clicked, this, &ExpressionPanel::exportAnimation);
  connect(animation_, &QTimer::timeout, this, &ExpressionPanel::tick);
  connect(save_, &QPushButton::clicked, this, &ExpressionPanel::saveExpression);
  connect(name_, &QLineEdit::returnPressed, this, &ExpressionPanel::saveExpression);
  connect(saved_, qOverload<int>(&QComboBox::activated), this, &ExpressionPanel::recallExpression);
  connect(study_, &QPushButton::clicked, this, &ExpressionPanel::studyPlan);
  connect(leave_, &QPushButton::clicked, this, &ExpressionPanel::leaveStudy);
  connect(fingertip_, &QPushButton::clicked, this, &ExpressionPanel::placeFingertip);
  connect(corner_, &QPushButton::clicked, this, &ExpressionPanel::addCorner);
  connect(clearCorners_, &QPushButton::clicked, this, &ExpressionPanel::clearCorners);
  connect(bumpsTimer_, &QTimer::timeout, this, &ExpressionPanel::updateBumps);
  connect(travel_, &QSlider::valueChanged, this, [this](int) {
    animation_->stop();
    playScale_ = 1.0;
    pushing_ = true;
    updateFace();
  });
  for (QDoubleSpinBox* box : {up_, across_, in_})
    connect(box, qOverload<double>(&QDoubleSpinBox::valueChanged), this, [this](double) {
      updatePushControls();
      if (planStudy_ && planStudy_->hasFingertip())
      {
        pushing_ = true;
        updateFace();
      }
    });
  connect(radius_, &QDoubleSpinBox::editingFinished, this, [this]() {
    // A new radius is a new fingertip: the push is prepared again.
    if (planStudy_ && planStudy_->hasFingertip() &&
        std::abs(planStudy_->currentFingertip().radius - radius_->value()) > 1e-9)
      buildFingertip(planStudy_->currentFingertip().centre);
  });
}

/// Follows the scene: the face removed by someone else, a leftover face of a
/// saved scene, the plan's skin gone, plans, solutions and expressions
/// added or removed.
void ExpressionPanel::observeTheScene()
{
  observer_ = logic_.scene().addObserver([this](SceneEvent event, const Node& node) {
    if (event == SceneEvent::NodeAboutToBeRemoved && node.id() == faceId_)
    {
      // Removed by someone else: the scene was replaced (another patient,
      // perhaps), so the model goes with its face.
      faceId_.clear();
      hidden_.clear(); // their ids may name the new scene's nodes
      QTimer::singleShot(0, this, [this]() { dropModel("The scene changed: build the face model again."); });
    }
    if (event == SceneEvent::NodeAdded && node.type() == NodeType::Surface && node.name() == kFaceName &&
        node.id() != faceId_ && !leftoverPending_)
    {
      // A scene saved while the face showed: the face is not this model's.
      leftoverPending_ = true;
      QTimer::singleShot(0, this, &ExpressionPanel::takeBackLeftoverFaces);
    }
    if (event == SceneEvent::NodeAboutToBeRemoved && node.id() == planSkinId_)
    {
      planSkinId_.clear();
      planSkin_ = nullptr;
    }
    if ((node.type() == NodeType::Plan || node.type() == NodeType::Solution) && event != SceneEvent::NodeModified &&
        !plansPending_)
    {
      plansPending_ = true;
      QTimer::singleShot(0, this, &ExpressionPanel::refreshPlans);
    }
    if (event == SceneEvent::NodeAboutToBeRemoved)
      hidden_.erase(std::remove(hidden_.begin(), hidden_.end(), node.id()), hidden_.end());
    if (node.type() == NodeType::Expression && !savedPending_)
    {
      savedPending_ = true;
      QTimer::singleShot(0, this, &ExpressionPanel::refreshSaved);
    }
  });
}

ExpressionPanel::~ExpressionPanel()
{
  logic_.scene().removeObserver(observer_);
}

Eigen::VectorXd ExpressionPanel::activations() const
{
  if (!model_)
    return {};
  std::vector<double> weights;
  for (QSlider* s : expressionSliders_)
    weights.push_back(s->value() / 100.0);
  Eigen::VectorXd offsets(Eigen::Index(muscleSliders_.size()));
  for (std::size_t k = 0; k < muscleSliders_.size(); ++k)
    offsets[Eigen::Index(k)] = muscleSliders_[k]->value() / 100.0;
  return expression::mixActivations(expressionActivations_, weights, offsets);
}

void ExpressionPanel::build()
{
  expression::ExpressionModelInput input;
  try
  {
    input = logic_.modelInput();
  }
  catch (const std::exception& e)
  {
    host_.showError("Build face model", std::string("The face model cannot be built: ") + e.what());
    return;
  }
  build_->setEnabled(false);
  status_->setText(tr("Building the face model..."));
  QPointer<ExpressionPanel> self(this);
  auto in = std::make_shared<expression::ExpressionModelInput>(std::move(input));
  auto started = std::make_shared<std::atomic<bool>>(false);
  auto work = [self, in, started](const TaskProgress& progress) -> std::function<void()> {
    started->store(true);
    std::shared_ptr<const expression::ExpressionModel> model;
    std::string error;
    try
    {
      model = expression::buildExpressionModel(*in, progress);
    }
    catch (const std::exception& e)
    {
      error = e.what();
    }
    // Told through the event loop: the finishing function is skipped when
    // the user cancels, and the button must come back either way.
    QMetaObject::invokeMethod(
      self.data(),
      [self, model, error]() {
        if (!self)
          return;
        self->build_->setEnabled(true);
        if (model)
          self->setModel(model);
        else if (!error.empty())
        {
          self->status_->setText(tr("No face model: %1").arg(QString::fromStdString(error)));
          self->host_.showError("Build face model",
                                "The face model could not be built: " + error +
                                  ". Check the range maps and the landmarks in the Range maps module.");
        }
        else
          self->status_->setText(tr("Building the face model was cancelled."));
      },
      Qt::QueuedConnection);
    return {};
  };
  host_.runTask("Face model for expressions", work);
  // runTask refuses (with a message) while other work runs: then the work
  // never starts, and the button comes back to try again.
  QTimer::singleShot(1500, this, [this, started]() {
    if (!started->load() && !build_->isEnabled())
    {
      build_->setEnabled(true);
      status_->setText(tr("The face model was not built: other work was running. Press 'Build face model' again."));
    }
  });
}

void ExpressionPanel::setModel(std::shared_ptr<const expression::ExpressionModel> model)
{
  animation_->stop();
  playScale_ = 1.0;
  releaseFace();
  planStudy_.reset();
  model_ = std::move(model);
  expressionActivations_.clear();
  for (const expression::ExpressionDefinition& e : expression::builtInExpressions())
    expressionActivations_.push_back(expression::expressionActivations(e, model_->muscles));
  rebuildMuscleSliders();
  for (QWidget* w : std::initializer_list<QWidget*>{expressionBox_, muscleBox_, play_, rest_, export_, save_, name_})
    w->setEnabled(true);
  const fem::Mesh& mesh = model_->face.continuum.mesh;
  QString text = tr("Face model: %1 muscles, %2 elements, %3 nodes; %4 display vertices. Built in %5 s "
                    "(mesh %6 s, factor %7 s, %8 solves %9 s). Landmarks %10.")
                   .arg(model_->muscles.size())
                   .arg(mesh.elements.size())
                   .arg(mesh.nodeCount())
                   .arg(model_->surface.vertexCount())
                   .arg(model_->totalSeconds, 0, 'f', 1)
                   .arg(model_->meshSeconds, 0, 'f', 1)
                   .arg(model_->factorSeconds, 0, 'f', 1)
                   .arg(model_->muscles.size())
                   .arg(model_->responseSeconds, 0, 'f', 1)
                   .arg(QString::fromStdString(model_->landmarkSource));
  if (!model_->shadeNote.empty())
    text += " " + QString::fromStdString(model_->shadeNote) + ".";
  status_->setText(text);
  planBox_->setVisible(true);
  planStatus_->setText(tr("Choose a predicted plan and press 'Study plan' to see its result under the sliders."));
  bumps_->clear();
  refreshPlans();
  updatePushControls();
  if (isVisible())
  {
    showFace();
    faceOnCamera();
  }
  host_.showStatus("Face model ready: move the sliders");
}

void ExpressionPanel::exportAnimation()
{
  if (!model_)
    return;
  // Studying a plan, the plan's skin is animated as it shows: under the
  // mix, or pushed along the fingertip's path (frame by frame: a bent path
  // is not a blend of two surfaces).
  const bool onPlan = planStudy_ && planSkin_;
  const bool pushed = onPlan && pushing_ && planStudy_->hasFingertip();
  const Eigen::VectorXd a = activations();
  if (pushed ? !(pushPath().length() > 0.0 && travel_->value() > 0) : a.cwiseAbs().maxCoeff() <= 0.0)
  {
    host_.showError("Export animation", pushed ? "The fingertip is at rest: set its travel and move 'Along the "
                                                 "path', then export the push."
                                               : "Every muscle is at rest: set the sliders to the expression to "
                                                 "animate, then export it.");
    return;
  }
  const QString folder =
    QFileDialog::getExistingDirectory(host_.window(), tr("Export the expression animation into the folder"));
  if (folder.isEmpty())
    return;
  // Rendered offscreen on the GUI thread (the renders share the display with
  // the views), under a modal progress dialog whose Cancel stops it.
  vtkSmartPointer<vtkPolyData> rest, full;
  std::vector<vtkSmartPointer<vtkPolyData>> frames;
  std::string name = "expression";
  Eigen::Vector3d toCamera = model_->frame.radialDirection(-0.5 * std::numbers::pi);
  if (onPlan)
  {
    // 24 frames out to the skin as shown, 22 back (as the face's morph).
    constexpr int kOut = 24;
    std::vector<double> scales;
    for (int k = 0; k < kOut; ++k)
      scales.push_back(double(k) / (kOut - 1));
    for (int k = kOut - 2; k >= 1; --k)
      scales.push_back(double(k) / (kOut - 1));
    const expression::PushPath path = pushPath();
    Eigen::Matrix3Xd at;
    for (double scale : scales)
    {
      if (pushed)
        planStudy_->pushedPositions(path.travelAt(scale * travel_->value() / 100.0), at);
      else
        planStudy_->positions(scale * a, at);
      vtkSmartPointer<vtkPolyData> frame = planStudy_->polyData();
      expression::setPoints(frame, at, at);
      frames.push_back(frame);
    }
    name.clear();
    for (char c : planStudy_->planName())
      name += std::isalnum(static_cast<unsigned char>(c)) ? c : '-';
    name += pushed ? "-pushed" : "-expression";
    const Eigen::Vector3d centre = planStudy_->surface().surface().undeformedPositions().rowwise().mean();
    toCamera = planStudy_->frame().radialDirection(planStudy_->frame().toCylindrical(centre).theta);
  }
  else
  {
    rest = expression::expressionPolyData(*model_);
    full = expression::expressionPolyData(*model_);
    Eigen::Matrix3Xd scratch;
    expression::applyActivations(*model_, a, full, scratch);
  }
  ModalProgress dialog(host_.window(), tr("Writing the animation..."), tr("Export animation"),
                       "expression.exportProgress");
  const TaskProgress progress = dialog.progress();
  try
  {
    render::AnimationOptions options;
    const render::AnimationResult result =
      onPlan ? render::writeSurfaceAnimation(frames, name, toCamera, model_->frame.direction(), folder.toStdString(),
                                             options, progress)
             : render::writeMorphAnimation(rest, full, name, toCamera, model_->frame.direction(), folder.toStdString(),
                                           24, true, options, progress);
    std::string message =
      "Wrote " + std::to_string(result.prePost.frames) + " frames to " + result.prePost.folder.string();
    if (!result.prePost.video.empty())
      message += " and " + result.prePost.video.string();
    host_.showStatus(message);
    if (!result.videoMessage.empty())
      host_.showWarning("Export animation", result.videoMessage);
  }
  catch (const seg::Cancelled&)
  {
    host_.showStatus("The animation export was cancelled; the frames written so far are in the folder.");
  }
  catch (const std::exception& e)
  {
    host_.showError("Export animation", e.what());
  }
}

void ExpressionPanel::dropModel(const std::string& why)
{
  animation_->stop();
  releaseFace();
  planStudy_.reset();
  corners_.clear();
  planBox_->setVisible(false);
  bumps_->clear();
  model_.reset();
  updatePushControls();
  expressionActivations_.clear();
  rebuildMuscleSliders();
  for (QWidget* w : std::initializer_list<QWidget*>{expressionBox_, muscleBox_, play_, rest_, export_, save_, name_})
    w->setEnabled(false);
  info_->clear();
  if (!why.empty())
    status_->setText(QString::fromStdString(why));
}

void ExpressionPanel::rebuildMuscleSliders()
{
  auto* form = static_cast<QFormLayout*>(muscleBox_->layout());
  while (form->rowCount() > 0)
    form->removeRow(0);
  muscleSliders_.clear();
  muscleValues_.clear();
  if (!model_)
    return;
  for (const expression::FittedMuscle& m : model_->muscles)
  {
    QSlider* slider = percentSlider(muscleBox_, QString::fromStdString("expression.muscle." + m.id),
                                    tr("Contraction of %1 added to the expressions: 100 % is the muscle file's "
                                       "strong contraction")
                                      .arg(QString::fromStdString(m.title)));
    auto* value = new QLabel(muscleBox_);
    value->setObjectName(QString::fromStdString("expression.muscleValue." + m.id));
    value->setMinimumWidth(fontMetrics().horizontalAdvance("100 %") + 4);
    value->setToolTip(tr("The muscle's activation in the mix"));
    auto* row = new QHBoxLayout;
    row->addWidget(slider, 1);
    row->addWidget(value);
    form->addRow(QString::fromStdString(m.title), row);
    muscleSliders_.push_back(slider);
    muscleValues_.push_back(value);
    connect(slider, &QSlider::valueChanged, this, [this](int) {
      animation_->stop();
      playScale_ = 1.0;
      pushing_ = false;
      updateFace();
    });
  }
}

void ExpressionPanel::updateFace()
{
  if (!model_)
    return;
  QElapsedTimer clock;
  clock.start();
  const Eigen::VectorXd a = activations();
  for (std::size_t k = 0; k < muscleValues_.size(); ++k)
    muscleValues_[k]->setText(QString("%1 %").arg(std::lround(100.0 * a[Eigen::Index(k)])));
  if (planStudy_ && !planSkinId_.empty())
  {
    // The plan's skin in the face around it: both move under the muscles
    // (the plan's rim follows the face model); under the fingertip the face
    // stays at rest.
    largestMovement_ = updateStudy(playScale_ * a);
    if (auto* node = logic_.scene().nodeAs<SurfaceNode>(faceId_); node && face_)
    {
      const Eigen::VectorXd faceA = pushing_ ? Eigen::VectorXd::Zero(a.size()) : Eigen::VectorXd(playScale_ * a);
      expression::applyActivations(*model_, faceA, face_, scratch_);
      if (faceAround_)
        faceAround_->Modified();
      node->modified();
    }
    lastUpdateMs_ = clock.nsecsElapsed() / 1e6;
    info_->setText(tr("%1: the skin moves up to %2 mm from the plan at rest. Slider update: %3 ms.")
                     .arg(pushing_ ? tr("Pushed by the fingertip") : tr("Under the expression"))
                     .arg(largestMovement_, 0, 'f', 2)
                     .arg(lastUpdateMs_, 0, 'f', 1));
    bumpsTimer_->start(); // measured once the sliders settle
    return;
  }
  auto* node = logic_.scene().nodeAs<SurfaceNode>(faceId_);
  if (!node || !face_)
    return;
  // No finite element work: one small matrix-vector product (§3.1.2), the
  // points rewritten in place, the node says so and the 3D view redraws.
  largestMovement_ = expression::applyActivations(*model_, playScale_ * a, face_, scratch_);
  node->modified();
  lastUpdateMs_ = clock.nsecsElapsed() / 1e6;
  info_->setText(tr("Largest skin movement: %1 mm. Slider update: %2 ms.")
                   .arg(largestMovement_, 0, 'f', 2)
                   .arg(lastUpdateMs_, 0, 'f', 1));
}

void ExpressionPanel::showFace()
{
  if (!model_ || !faceId_.empty())
    return;
  Scene& scene = logic_.scene();
  takeBackLeftoverFaces();
  // The face replaces the skin (and whatever else covers it) while shown.
  hidden_.clear();
  for (Node* n : scene.nodesOfType(NodeType::Surface))
    if (auto* s = static_cast<SurfaceNode*>(n); s->visible())
    {
      hidden_.push_back(s->id());
      s->setVisible(false);
    }
  face_ = expression::expressionPolyData(*model_);
  // Which surfaces the face hides, kept with it: a scene saved while the face
  // shows gets them back when it is opened again (takeBackLeftoverFace()).
  auto ids = vtkSmartPointer<vtkStringArray>::New();
  ids->SetName(kHiddenArray);
  for (const NodeId& id : hidden_)
    ids->InsertNextValue(id);
  face_->GetFieldData()->AddArray(ids);
  auto node = std::make_unique<SurfaceNode>();
  node->setName(kFaceName);
  node->setPolyData(face_);
  node->setColourArray("skin_colour");
  faceId_ = scene.addNode(std::move(node))->id();
  updateFace();
  if (planStudy_)
    showStudy();
}

void ExpressionPanel::takeBackLeftoverFaces()
{
  leftoverPending_ = false;
  Scene& scene = logic_.scene();
  std::vector<NodeId> leftovers;
  for (Node* n : scene.nodesOfType(NodeType::Surface))
  {
    if (n->name() == kFaceName && n->id() != faceId_)
      leftovers.push_back(n->id());
    // A plan's skin saved while it showed over a face.
    const auto* surface = static_cast<const SurfaceNode*>(n);
    if (n->id() != planSkinId_ && surface->polyData() &&
        surface->polyData()->GetFieldData()->GetAbstractArray(kStudyArray))
      leftovers.push_back(n->id());
  }
  for (const NodeId& id : leftovers)
  {
    const auto* face = scene.nodeAs<SurfaceNode>(id);
    vtkAbstractArray* hidden =
      face && face->polyData() ? face->polyData()->GetFieldData()->GetAbstractArray(kHiddenArray) : nullptr;
    std::vector<NodeId> restore;
    if (auto* names = vtkStringArray::SafeDownCast(hidden))
      for (vtkIdType i = 0; i < names->GetNumberOfValues(); ++i)
        restore.push_back(names->GetValue(i));
    scene.removeNode(id);
    for (const NodeId& other : restore)
      if (auto* s = scene.nodeAs<SurfaceNode>(other); s && !s->visible())
        s->setVisible(true);
  }
}

void ExpressionPanel::releaseFace()
{
  releaseStudy();
  Scene& scene = logic_.scene();
  if (!faceId_.empty())
  {
    const NodeId id = faceId_;
    faceId_.clear();
    scene.removeNode(id);
  }
  face_ = nullptr;
  for (const NodeId& id : hidden_)
    if (auto* s = scene.nodeAs<SurfaceNode>(id))
      s->setVisible(true);
  hidden_.clear();
}

void ExpressionPanel::faceOnCamera()
{
  if (!model_ || !face_)
    return;
  // Face on: from the front of the face (θ = -π/2), the head's axis up.
  // The face's height and width as seen (along the axis and across) fill
  // the view with a small margin, so a few millimetres of movement show.
  const Eigen::Matrix3Xd& x = model_->surface.surface().undeformedPositions();
  const Eigen::Vector3d lo = x.rowwise().minCoeff(), hi = x.rowwise().maxCoeff();
  Eigen::Vector3d centre = 0.5 * (lo + hi);
  const Eigen::Vector3d up = model_->frame.direction();
  const Eigen::Vector3d across = model_->frame.xAxis();
  const Eigen::RowVectorXd heights = up.transpose() * x, widths = across.transpose() * x;
  const double half = 0.58 * std::max(heights.maxCoeff() - heights.minCoeff(), widths.maxCoeff() - widths.minCoeff());
  // The middle of the face as seen, not of its 3D box (the chin stands out).
  centre += up * (0.5 * (heights.maxCoeff() + heights.minCoeff()) - up.dot(centre)) +
            across * (0.5 * (widths.maxCoeff() + widths.minCoeff()) - across.dot(centre));
  SnapshotNode::Camera camera;
  camera.viewAngle = 30.0;
  const double distance = half / std::tan(0.5 * camera.viewAngle * 3.141592653589793 / 180.0);
  const Eigen::Vector3d eye = centre + distance * model_->frame.radialDirection(-1.5707963267948966);
  camera.focalPoint = {centre.x(), centre.y(), centre.z()};
  camera.position = {eye.x(), eye.y(), eye.z()};
  camera.viewUp = {up.x(), up.y(), up.z()};
  host_.setThreeDViewCamera(camera);
}

void ExpressionPanel::saveExpression()
{
  if (!model_)
  {
    host_.showError("Save expression", "Build the face model first, then set the sliders to the expression.");
    return;
  }
  const std::string name = name_->text().trimmed().toStdString();
  if (name.empty())
  {
    host_.showError("Save expression", "Type a name for the expression in the box beside 'Save expression...'.");
    return;
  }
  const Eigen::VectorXd a = activations();
  std::map<std::string, double> values;
  std::string description = "Muscles:";
  for (std::size_t k = 0; k < model_->muscles.size(); ++k)
    if (a[Eigen::Index(k)] > 0.0)
    {
      values[model_->muscles[k].id] = a[Eigen::Index(k)];
      description +=
        " " + model_->muscles[k].title + " " + std::to_string(std::lround(100.0 * a[Eigen::Index(k)])) + " %;";
    }
  try
  {
    logic_.saveExpression(name, model_->muscleSetId, values, description);
  }
  catch (const std::exception& e)
  {
    host_.showError("Save expression", e.what());
    return;
  }
  refreshSaved();
  saved_->setCurrentIndex(saved_->findText(QString::fromStdString(name)));
  host_.showStatus("Expression '" + name + "' saved in the scene");
}

void ExpressionPanel::recallExpression(int index)
{
  if (index < 0)
    return;
  const ExpressionNode* node = logic_.savedExpression(saved_->itemText(index).toStdString());
  if (!node)
    return;
  if (!model_)
  {
    host_.showError("Recall expression", "Build the face model first: the expression is shown on it.");
    return;
  }
  std::vector<std::string> unknown;
  const Eigen::VectorXd a = expression::expressionActivations(node->activations(), model_->muscles, &unknown);
  animation_->stop();
  playScale_ = 1.0;
  // The saved activations become the muscle sliders; the expressions go to 0.
  for (QSlider* s : expressionSliders_)
  {
    const QSignalBlocker block(s);
    s->setValue(0);
  }
  for (std::size_t k = 0; k < muscleSliders_.size(); ++k)
  {
    const QSignalBlocker block(muscleSliders_[k]);
    muscleSliders_[k]->setValue(int(std::lround(100.0 * a[Eigen::Index(k)])));
  }
  updateFace();
  name_->setText(QString::fromStdString(node->name()));
  if (!unknown.empty())
  {
    std::string list;
    for (const std::string& id : unknown)
      list += (list.empty() ? "" : ", ") + id;
    host_.showWarning("Recall expression", "Expression '" + node->name() +
                                             "' names muscles the face model does not "
                                             "have (" +
                                             list + "); they are left at rest.");
  }
}

void ExpressionPanel::refreshSaved()
{
  savedPending_ = false;
  const QString current = saved_->currentText();
  const QSignalBlocker block(saved_);
  saved_->clear();
  for (const ExpressionNode* n : logic_.savedExpressions())
    saved_->addItem(QString::fromStdString(n->name()));
  saved_->setCurrentIndex(saved_->findText(current));
  saved_->setEnabled(saved_->count() > 0);
}

void ExpressionPanel::play()
{
  if (!model_)
    return;
  clock_.start();
  playScale_ = 0.0;
  updateFace();
  animation_->start();
}

void ExpressionPanel::tick()
{
  const double t = clock_.elapsed() / 1000.0 / kPlaySeconds;
  if (t >= 1.0)
  {
    // Back where the sliders are.
    animation_->stop();
    playScale_ = 1.0;
  }
  else
    playScale_ = 0.5 - 0.5 * std::cos(2.0 * 3.141592653589793 * t); // 0 → 1 → 0, smooth at the ends
  updateFace();
}

void ExpressionPanel::rest()
{
  animation_->stop();
  playScale_ = 1.0;
  for (QSlider* s : expressionSliders_)
  {
    const QSignalBlocker block(s);
    s->setValue(0);
  }
  for (QSlider* s : muscleSliders_)
  {
    const QSignalBlocker block(s);
    s->setValue(0);
  }
  {
    const QSignalBlocker block(travel_);
    travel_->setValue(0);
  }
  updateFace();
}

void ExpressionPanel::showEvent(QShowEvent* event)
{
  QWidget::showEvent(event);
  if (event->spontaneous())
    return;
  refreshSaved();
  refreshPlans();
  if (model_)
  {
    showFace();
    if (planStudy_)
      planOnCamera();
    else
      faceOnCamera();
  }
}

void ExpressionPanel::hideEvent(QHideEvent* event)
{
  QWidget::hideEvent(event);
  if (event->spontaneous())
    return;
  // Other modules see the scene as it was.
  animation_->stop();
  bumpsTimer_->stop();
  playScale_ = 1.0;
  releaseFace();
}

void ExpressionPanel::refreshPlans()
{
  plansPending_ = false;
  const QString current = plans_->currentText();
  const QSignalBlocker block(plans_);
  plans_->clear();
  const Scene& scene = logic_.scene();
  for (Node* n : scene.nodesOfType(NodeType::Plan))
    if (predicted(scene, n->name()))
      plans_->addItem(QString::fromStdString(n->name()));
  const int index = plans_->findText(current);
  plans_->setCurrentIndex(index >= 0 ? index : 0);
  study_->setEnabled(model_ != nullptr && plans_->count() > 0 && !studyPending_);
  if (plans_->count() == 0)
    plans_->setToolTip(tr("The scene has no predicted plan: place a plan in the Incision panel and predict it in "
                          "the Simulate panel first"));
  else
    plans_->setToolTip(tr("The scene's predicted plans"));
}

void ExpressionPanel::studyPlan()
{
  if (!model_)
  {
    host_.showError("Study plan", "Build the face model first: the plan is studied inside it.");
    return;
  }
  const std::string name = plans_->currentText().toStdString();
  const Scene& scene = logic_.scene();
  const PlanNode* planNode = nullptr;
  for (Node* n : scene.nodesOfType(NodeType::Plan))
    if (n->name() == name)
      planNode = static_cast<const PlanNode*>(n);
  if (name.empty() || !planNode || !predicted(scene, name))
  {
    host_.showError("Study plan", "The scene has no predicted plan to study: place a plan in the Incision panel "
                                  "and predict it in the Simulate panel, then choose it here.");
    return;
  }
  // Copies for the worker: the plan as the node holds it, predicted with the
  // options it was predicted with, on its own skin map.
  auto input = std::make_shared<expression::PlanStudyInput>();
  try
  {
    const auto [skinNode, boneNode] = RangeMapLogic::mapsOf(scene, *planNode);
    if (!skinNode || !boneNode)
      throw std::invalid_argument("the scene has no skin and bone range maps to predict it on: build them in the "
                                  "Range maps module");
    input->planName = name;
    input->plan = IncisionLogic::readPlan(*planNode);
    input->options = IncisionLogic::simulationOptions(*planNode);
    input->skin = RangeMapLogic::toRangeMap(*skinNode);
    input->bone = RangeMapLogic::toRangeMap(*boneNode);
    input->model = model_;
    const auto volumes = scene.nodesOfType(NodeType::Volume);
    if (!volumes.empty())
      input->ct = static_cast<const VolumeNode*>(volumes.front())->image();
  }
  catch (const std::exception& e)
  {
    host_.showError("Study plan", "Plan '" + name + "' cannot be studied: " + e.what());
    return;
  }
  studyPending_ = true;
  study_->setEnabled(false);
  planStatus_->setText(tr("Predicting %1 inside the face model...").arg(QString::fromStdString(name)));
  QPointer<ExpressionPanel> self(this);
  auto started = std::make_shared<std::atomic<bool>>(false);
  auto work = [self, input, started](const TaskProgress& progress) -> std::function<void()> {
    started->store(true);
    std::shared_ptr<expression::PlanStudy> study;
    std::string error;
    try
    {
      study = expression::PlanStudy::build(*input, progress);
    }
    catch (const std::exception& e)
    {
      error = e.what();
    }
    // Told through the event loop, as build() does: the button comes back
    // even when the user cancels.
    QMetaObject::invokeMethod(
      self.data(),
      [self, study, error, model = input->model, name = input->planName]() {
        if (!self)
          return;
        self->studyPending_ = false;
        self->refreshPlans();
        if (study && self->model_ == model)
          self->setStudy(study);
        else if (study)
          self->planStatus_->setText(
            tr("The face model changed while %1 was predicted: study it again.").arg(QString::fromStdString(name)));
        else if (!error.empty())
        {
          self->planStatus_->setText(
            tr("%1 could not be studied: %2").arg(QString::fromStdString(name), QString::fromStdString(error)));
          self->host_.showError("Study plan", "Plan '" + name + "' could not be studied in the face: " + error);
        }
        else
          self->planStatus_->setText(tr("Studying the plan was cancelled."));
      },
      Qt::QueuedConnection);
    return {};
  };
  host_.runTask("Plan under expression", work);
  QTimer::singleShot(1500, this, [this, started]() {
    if (!started->load() && studyPending_)
    {
      studyPending_ = false;
      refreshPlans();
      planStatus_->setText(tr("The plan was not studied: other work was running. Press 'Study plan' again."));
    }
  });
}

void ExpressionPanel::setStudy(std::shared_ptr<expression::PlanStudy> study)
{
  releaseStudy();
  planStudy_ = std::move(study);
  corners_.clear();
  pushing_ = false;
  {
    const QSignalBlocker block(travel_);
    travel_->setValue(0);
  }
  const expression::PlanStudy& p = *planStudy_;
  QString text = tr("%1 in the face: %2 display vertices; predicted again in %3 s, %4 muscle responses of its model "
                    "in %5 s (rim following the face), skin in %6 s.")
                   .arg(QString::fromStdString(p.planName()))
                   .arg(p.surface().vertexCount())
                   .arg(p.predictSeconds, 0, 'f', 1)
                   .arg(p.muscleCount())
                   .arg(p.responseSeconds, 0, 'f', 1)
                   .arg(p.displaySeconds, 0, 'f', 1);
  if (!p.shadeNote().empty())
    text += " " + QString::fromStdString(p.shadeNote()) + ".";
  planStatus_->setText(text);
  updatePushControls();
  if (isVisible() && !faceId_.empty())
  {
    showStudy();
    planOnCamera();
  }
  updateBumps();
  host_.showStatus("Plan " + p.planName() + " under expression: move the sliders, or place a fingertip");
}

void ExpressionPanel::leaveStudy()
{
  host_.cancelPick();
  bumpsTimer_->stop();
  releaseStudy();
  planStudy_.reset();
  corners_.clear();
  pushing_ = false;
  bumps_->clear();
  planStatus_->setText(tr("Choose a predicted plan and press 'Study plan' to see its result under the sliders."));
  updatePushControls();
  updateFace();
  faceOnCamera();
}

void ExpressionPanel::showStudy()
{
  if (!planStudy_ || !planSkinId_.empty())
    return;
  Scene& scene = logic_.scene();
  // The face keeps the cells around the plan's region and gives up those
  // under it to the plan's skin (they lie on the same skin).
  if (auto* face = scene.nodeAs<SurfaceNode>(faceId_); face && face_)
  {
    const std::vector<char> under = planStudy_->faceCellsUnderPlan(expression::expressionPolyData(*model_));
    faceAround_ = vtkSmartPointer<vtkPolyData>::New();
    faceAround_->SetPoints(face_->GetPoints());
    faceAround_->GetPointData()->ShallowCopy(face_->GetPointData());
    faceAround_->GetFieldData()->ShallowCopy(face_->GetFieldData());
    auto polys = vtkSmartPointer<vtkCellArray>::New();
    vtkIdType n = 0;
    const vtkIdType* ids = nullptr;
    face_->GetPolys()->InitTraversal();
    for (std::size_t cell = 0; face_->GetPolys()->GetNextCell(n, ids); ++cell)
      if (cell >= under.size() || !under[cell])
        polys->InsertNextCell(n, ids);
    faceAround_->SetPolys(polys);
    face->setPolyData(faceAround_);
    face->setColourArray("skin_colour");
  }
  planSkin_ = planStudy_->polyData();
  auto mark = vtkSmartPointer<vtkStringArray>::New();
  mark->SetName(kStudyArray);
  mark->InsertNextValue(planStudy_->planName());
  planSkin_->GetFieldData()->AddArray(mark);
  planStudy_->positions(Eigen::VectorXd::Zero(planStudy_->muscleCount()), planRest_);
  auto node = std::make_unique<SurfaceNode>();
  node->setName(planStudy_->planName() + " under expression");
  node->setPolyData(planSkin_);
  node->setColourArray("skin_colour");
  planSkinId_ = scene.addNode(std::move(node))->id();
  updateFace();
}

void ExpressionPanel::releaseStudy()
{
  Scene& scene = logic_.scene();
  if (!planSkinId_.empty())
  {
    const NodeId id = planSkinId_;
    planSkinId_.clear();
    scene.removeNode(id);
  }
  planSkin_ = nullptr;
  if (auto* face = scene.nodeAs<SurfaceNode>(faceId_); face && faceAround_)
  {
    face->setPolyData(face_);
    face->setColourArray("skin_colour");
  }
  faceAround_ = nullptr;
}

double ExpressionPanel::updateStudy(const Eigen::VectorXd& activations)
{
  auto* node = logic_.scene().nodeAs<SurfaceNode>(planSkinId_);
  if (!planStudy_ || !node || !planSkin_)
    return 0.0;
  // One small matrix-vector product on the plan's display skin (§3.1.2).
  if (pushing_ && planStudy_->hasFingertip())
    planStudy_->pushedPositions(pushPath().travelAt(playScale_ * travel_->value() / 100.0), planScratch_);
  else
    planStudy_->positions(activations, planScratch_);
  const double moved = expression::setPoints(planSkin_, planScratch_, planRest_);
  node->modified();
  return moved;
}

void ExpressionPanel::planOnCamera()
{
  if (!planStudy_ || !model_)
    return;
  // Facing the plan from outside (its θ), the head's axis up, the plan's
  // skin filling the view with a margin.
  const Eigen::Matrix3Xd& x = planStudy_->surface().surface().undeformedPositions();
  Eigen::Vector3d centre = x.rowwise().mean();
  const seg::CylindricalFrame& frame = planStudy_->frame();
  const Eigen::Vector3d outward = frame.radialDirection(frame.toCylindrical(centre).theta);
  const Eigen::Vector3d up = frame.direction();
  const Eigen::Vector3d across = up.cross(outward).normalized();
  const Eigen::RowVectorXd heights = up.transpose() * x, widths = across.transpose() * x;
  const double half = 0.55 * std::max(heights.maxCoeff() - heights.minCoeff(), widths.maxCoeff() - widths.minCoeff());
  // The middle of the skin as seen, not its mean.
  centre += up * (0.5 * (heights.maxCoeff() + heights.minCoeff()) - up.dot(centre)) +
            across * (0.5 * (widths.maxCoeff() + widths.minCoeff()) - across.dot(centre));
  SnapshotNode::Camera camera;
  camera.viewAngle = 30.0;
  const double distance = half / std::tan(0.5 * camera.viewAngle * std::numbers::pi / 180.0);
  const Eigen::Vector3d eye = centre + distance * outward;
  camera.focalPoint = {centre.x(), centre.y(), centre.z()};
  camera.position = {eye.x(), eye.y(), eye.z()};
  camera.viewUp = {up.x(), up.y(), up.z()};
  host_.setThreeDViewCamera(camera);
}

void ExpressionPanel::updateBumps()
{
  if (!planStudy_)
    return;
  QElapsedTimer clock;
  clock.start();
  expression::ContourComparison c;
  try
  {
    c = pushing_ && planStudy_->hasFingertip() ? planStudy_->comparePush(pushPath().travelAt(travel_->value() / 100.0))
                                               : planStudy_->compare(activations());
  }
  catch (const std::exception& e)
  {
    bumps_->setText(tr("The bumps cannot be measured: %1").arg(QString::fromStdString(e.what())));
    return;
  }
  lastCompareMs_ = clock.nsecsElapsed() / 1e6;
  const double change = c.bumpChange();
  const QString verdict = change > 0.05    ? tr("the bumps get worse")
                          : change < -0.05 ? tr("the bumps ease")
                                           : tr("about the same");
  bumps_->setText(tr("Largest bump within %1 mm of the cut: %2 mm at rest, %3 mm now (%4 mm, %5). The skin's "
                     "height changes by up to %6 mm. (%7 vertices; measured in %8 ms)")
                    .arg(planStudy_->window(), 0, 'f', 0)
                    .arg(c.rest.largest, 0, 'f', 2)
                    .arg(c.loaded.largest, 0, 'f', 2)
                    .arg(QString::asprintf("%+.2f", change))
                    .arg(verdict)
                    .arg(c.largestHeightChange, 0, 'f', 2)
                    .arg(c.rest.vertices)
                    .arg(lastCompareMs_, 0, 'f', 0));
}

void ExpressionPanel::placeFingertip()
{
  if (!planStudy_ || planSkinId_.empty())
  {
    host_.showError("Fingertip", "Study a plan first ('Study plan'): the fingertip pushes the plan's skin.");
    return;
  }
  planStatus_->setText(tr("Click on %1's skin in the 3D view where the fingertip goes (Esc: cancel).")
                         .arg(QString::fromStdString(planStudy_->planName())));
  QPointer<ExpressionPanel> self(this);
  host_.pickInThreeDView("Click on the plan's skin where the fingertip goes", [self](const SurfacePick& pick) {
    if (!self || !self->planStudy_ || !self->planSkin_)
      return;
    const std::string plan = self->planStudy_->planName();
    if (pick.surface != self->planSkinId_)
    {
      self->host_.showError("Fingertip", "That click was not on the skin of " + plan +
                                           ": press 'Fingertip...' again and click on the coloured skin around "
                                           "the incision.");
      return;
    }
    // The vertex under the click, where the closure put it: the fingertip
    // rests on the skin after the operation whatever the sliders show.
    const Eigen::Vector3d at(pick.position[0], pick.position[1], pick.position[2]);
    Eigen::Matrix3Xd shown(3, self->planSkin_->GetNumberOfPoints());
    for (vtkIdType i = 0; i < self->planSkin_->GetNumberOfPoints(); ++i)
      self->planSkin_->GetPoint(i, shown.col(i).data());
    const Eigen::Index v = expression::PlanStudy::nearestVertex(shown, at, 5.0);
    if (v < 0)
    {
      self->host_.showError("Fingertip", "No vertex of " + plan +
                                           "'s skin is near that click: press "
                                           "'Fingertip...' again and click on the skin itself.");
      return;
    }
    self->buildFingertip(self->planStudy_->restSkinPoint(v));
  });
}

void ExpressionPanel::buildFingertip(const Eigen::Vector3d& centre)
{
  if (!planStudy_)
    return;
  fingertip_->setEnabled(false);
  planStatus_->setText(tr("Preparing the push (one factorisation of the plan's model)..."));
  std::shared_ptr<const expression::PlanStudy> study = planStudy_;
  const double radius = radius_->value();
  QPointer<ExpressionPanel> self(this);
  auto started = std::make_shared<std::atomic<bool>>(false);
  auto work = [self, study, centre, radius, started](const TaskProgress& progress) -> std::function<void()> {
    started->store(true);
    auto tip = std::make_shared<expression::Fingertip>();
    std::string error;
    try
    {
      if (progress)
        progress(0.1, "Holding the skin under the fingertip and factoring the plan's model");
      *tip = study->fingertip(centre, radius);
    }
    catch (const std::exception& e)
    {
      error = e.what();
    }
    QMetaObject::invokeMethod(
      self.data(),
      [self, study, tip, error]() {
        if (!self)
          return;
        self->fingertip_->setEnabled(true);
        if (self->planStudy_ != study)
          return; // another plan meanwhile
        if (!error.empty())
        {
          self->planStatus_->setText(tr("No fingertip: %1").arg(QString::fromStdString(error)));
          self->host_.showError("Fingertip", "The fingertip could not be placed: " + error + ".");
          self->updatePushControls();
          return;
        }
        self->planStudy_->setFingertip(std::move(*tip));
        const expression::Fingertip& f = self->planStudy_->currentFingertip();
        self->planStatus_->setText(
          tr("Fingertip at (%1, %2, %3) mm, radius %4 mm, holding %5 skin nodes; prepared in %6 s. Set the travel "
             "and move 'Along the path'.")
            .arg(f.centre.x(), 0, 'f', 1)
            .arg(f.centre.y(), 0, 'f', 1)
            .arg(f.centre.z(), 0, 'f', 1)
            .arg(f.radius, 0, 'f', 1)
            .arg(f.push->pushedNodes().size())
            .arg(f.seconds, 0, 'f', 2));
        self->pushing_ = true;
        self->updatePushControls();
        self->updateFace();
        self->host_.setCursorPosition({f.centre.x(), f.centre.y(), f.centre.z()});
      },
      Qt::QueuedConnection);
    return {};
  };
  host_.runTask("Fingertip on the plan's skin", work);
  // Refused while other work runs: the button comes back to try again.
  QTimer::singleShot(1500, this, [this, started]() {
    if (!started->load() && !fingertip_->isEnabled())
    {
      updatePushControls();
      planStatus_->setText(tr("The fingertip was not placed: other work was running. Press 'Fingertip...' again."));
    }
  });
}

Eigen::Vector3d ExpressionPanel::travelBoxes() const
{
  const Eigen::Vector3d local(up_->value(), across_->value(), in_->value());
  if (!planStudy_ || !planStudy_->hasFingertip())
    return local;
  return planStudy_->currentFingertip().directions * local;
}

expression::PushPath ExpressionPanel::pushPath() const
{
  expression::PushPath path;
  if (!planStudy_ || !planStudy_->hasFingertip())
    return path;
  const expression::Fingertip& f = planStudy_->currentFingertip();
  path.centre = f.centre;
  path.radius = f.radius;
  for (const Eigen::Vector3d& corner : corners_)
    path.waypoints.push_back(f.directions * corner);
  path.waypoints.push_back(travelBoxes());
  return path;
}

void ExpressionPanel::addCorner()
{
  corners_.emplace_back(up_->value(), across_->value(), in_->value());
  updatePushControls();
  pushing_ = true;
  updateFace();
}

void ExpressionPanel::clearCorners()
{
  corners_.clear();
  updatePushControls();
  pushing_ = true;
  updateFace();
}

void ExpressionPanel::updatePushControls()
{
  const bool studying = planStudy_ != nullptr;
  const bool tip = studying && planStudy_->hasFingertip();
  leave_->setEnabled(studying);
  fingertip_->setEnabled(studying);
  radius_->setEnabled(studying);
  for (QWidget* w : std::initializer_list<QWidget*>{up_, across_, in_, corner_, clearCorners_, travel_})
    w->setEnabled(tip);
  clearCorners_->setEnabled(tip && !corners_.empty());
  if (!tip)
  {
    pathInfo_->setText(studying ? tr("Press 'Fingertip...' and click on the plan's skin to push it.") : QString());
    return;
  }
  QString corners;
  for (const Eigen::Vector3d& c : corners_)
    corners += QString("(%1, %2, %3) → ").arg(c.x(), 0, 'f', 1).arg(c.y(), 0, 'f', 1).arg(c.z(), 0, 'f', 1);
  pathInfo_->setText(tr("Path (up, across, in; mm): rest → %1(%2, %3, %4); %5 mm long.")
                       .arg(corners)
                       .arg(up_->value(), 0, 'f', 1)
                       .arg(across_->value(), 0, 'f', 1)
                       .arg(in_->value(), 0, 'f', 1)
                       .arg(pushPath().length(), 0, 'f', 1));
}

} // namespace caps
