#include "modules/expression/ExpressionPanel.h"

#include "modules/report/PlanAnimation.h"
#include "segmentation/Progress.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <numbers>

#include <QApplication>
#include <QComboBox>
#include <QFileDialog>
#include <QFormLayout>
#include <QGroupBox>
#include <QHBoxLayout>
#include <QHideEvent>
#include <QLabel>
#include <QLineEdit>
#include <QPointer>
#include <QProgressDialog>
#include <QPushButton>
#include <QScrollArea>
#include <QShowEvent>
#include <QSignalBlocker>
#include <QSlider>
#include <QTimer>
#include <QVBoxLayout>

#include <vtkFieldData.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>

#include "scene/ExpressionNode.h"
#include "scene/Scene.h"
#include "scene/SurfaceNode.h"

namespace caps {

namespace {

constexpr const char* kFaceName = "Face expression";
/// Field data of the face: the ids of the surfaces it hides.
constexpr const char* kHiddenArray = "caps_hidden_surfaces";
constexpr double kPlaySeconds = 3.0; // rest → the mix → rest

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
  build_ = new QPushButton(tr("Build face model"), this);
  build_->setObjectName("expression.build");
  build_->setToolTip(tr("Mesh the whole face from the skin to the bone, fit the muscles to the landmarks and solve "
                        "once per muscle (a few seconds); then the sliders move the skin instantly"));
  layout->addWidget(build_);
  status_ = new QLabel(tr("No face model yet: press 'Build face model' (needs the skin and bone range maps)."), this);
  status_->setObjectName("expression.status");
  status_->setWordWrap(true);
  layout->addWidget(status_);

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
      updateFace();
    });
  }
  expressionBox_ = expressions;
  layout->addWidget(expressions);

  // One slider per muscle, made with the model (its fitted muscles).
  auto* muscles = new QGroupBox(tr("Muscles: slider added to the expressions, number the muscle's activation"), this);
  auto* muscleLayout = new QVBoxLayout(muscles);
  auto* scroll = new QScrollArea(muscles);
  scroll->setWidgetResizable(true);
  scroll->setFrameShape(QFrame::NoFrame);
  muscleBox_ = new QWidget(scroll);
  new QFormLayout(muscleBox_);
  scroll->setWidget(muscleBox_);
  muscleLayout->addWidget(scroll);
  layout->addWidget(muscles, 1);

  auto* buttons = new QHBoxLayout;
  play_ = new QPushButton(tr("Play"), this);
  play_->setObjectName("expression.play");
  play_->setToolTip(tr("Animate from rest to the expression the sliders give and back to rest in %1 s")
                      .arg(kPlaySeconds));
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

  animation_ = new QTimer(this);
  animation_->setInterval(20);

  connect(build_, &QPushButton::clicked, this, &ExpressionPanel::build);
  connect(play_, &QPushButton::clicked, this, &ExpressionPanel::play);
  connect(rest_, &QPushButton::clicked, this, &ExpressionPanel::rest);
  connect(export_, &QPushButton::clicked, this, &ExpressionPanel::exportAnimation);
  connect(animation_, &QTimer::timeout, this, &ExpressionPanel::tick);
  connect(save_, &QPushButton::clicked, this, &ExpressionPanel::saveExpression);
  connect(name_, &QLineEdit::returnPressed, this, &ExpressionPanel::saveExpression);
  connect(saved_, qOverload<int>(&QComboBox::activated), this, &ExpressionPanel::recallExpression);

  observer_ = logic_.scene().addObserver([this](SceneEvent event, const Node& node) {
    if (event == SceneEvent::NodeAboutToBeRemoved && node.id() == faceId_)
    {
      // Removed by someone else: the scene was replaced (another patient,
      // perhaps), so the model goes with its face.
      faceId_.clear();
      hidden_.clear(); // their ids may name the new scene's nodes
      QTimer::singleShot(0, this, [this]() {
        dropModel("The scene changed: build the face model again.");
      });
    }
    if (event == SceneEvent::NodeAdded && node.type() == NodeType::Surface && node.name() == kFaceName &&
        node.id() != faceId_ && !leftoverPending_)
    {
      // A scene saved while the face showed: the face is not this model's.
      leftoverPending_ = true;
      QTimer::singleShot(0, this, &ExpressionPanel::takeBackLeftoverFaces);
    }
    if (event == SceneEvent::NodeAboutToBeRemoved)
      hidden_.erase(std::remove(hidden_.begin(), hidden_.end(), node.id()), hidden_.end());
    if (node.type() == NodeType::Expression && !savedPending_)
    {
      savedPending_ = true;
      QTimer::singleShot(0, this, &ExpressionPanel::refreshSaved);
    }
  });
  dropModel({});
  refreshSaved();
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
  const Eigen::VectorXd a = activations();
  if (a.cwiseAbs().maxCoeff() <= 0.0)
  {
    host_.showError("Export animation", "Every muscle is at rest: set the sliders to the expression to animate, "
                                        "then export it.");
    return;
  }
  const QString folder =
    QFileDialog::getExistingDirectory(host_.window(), tr("Export the expression animation into the folder"));
  if (folder.isEmpty())
    return;
  // Rendered offscreen on the GUI thread (the renders share the display with
  // the views), under a modal progress dialog whose Cancel stops it.
  vtkSmartPointer<vtkPolyData> rest = expression::expressionPolyData(*model_);
  vtkSmartPointer<vtkPolyData> full = expression::expressionPolyData(*model_);
  Eigen::Matrix3Xd scratch;
  expression::applyActivations(*model_, a, full, scratch);
  QProgressDialog dialog(tr("Writing the animation..."), tr("Cancel"), 0, 1000, host_.window());
  dialog.setObjectName("expression.exportProgress");
  dialog.setWindowModality(Qt::WindowModal);
  dialog.setMinimumDuration(0);
  const TaskProgress progress = [&dialog](double fraction, const std::string& step) {
    dialog.setLabelText(QString::fromStdString(step));
    dialog.setValue(int(std::lround(1000.0 * std::clamp(fraction, 0.0, 1.0))));
    QApplication::processEvents();
    return !dialog.wasCanceled();
  };
  try
  {
    report::AnimationOptions options;
    const report::AnimationResult result = report::writeMorphAnimation(
      rest, full, "expression", model_->frame.radialDirection(-0.5 * std::numbers::pi), model_->frame.direction(),
      folder.toStdString(), 24, true, options, progress);
    std::string message = "Wrote " + std::to_string(result.prePost.frames) + " frames to " +
                          result.prePost.folder.string();
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
  model_.reset();
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
                                       "strong contraction").arg(QString::fromStdString(m.title)));
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
}

void ExpressionPanel::takeBackLeftoverFaces()
{
  leftoverPending_ = false;
  Scene& scene = logic_.scene();
  std::vector<NodeId> leftovers;
  for (Node* n : scene.nodesOfType(NodeType::Surface))
    if (n->name() == kFaceName && n->id() != faceId_)
      leftovers.push_back(n->id());
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
      description += " " + model_->muscles[k].title + " " + std::to_string(std::lround(100.0 * a[Eigen::Index(k)])) + " %;";
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
    host_.showWarning("Recall expression", "Expression '" + node->name() + "' names muscles the face model does not "
                                             "have (" + list + "); they are left at rest.");
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
  updateFace();
}

void ExpressionPanel::showEvent(QShowEvent* event)
{
  QWidget::showEvent(event);
  if (event->spontaneous())
    return;
  refreshSaved();
  if (model_)
  {
    showFace();
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
  playScale_ = 1.0;
  releaseFace();
}

} // namespace caps
