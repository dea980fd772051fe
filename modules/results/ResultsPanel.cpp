#include "modules/results/ResultsPanel.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <iomanip>
#include <sstream>

#include <QComboBox>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QHideEvent>
#include <QImage>
#include <QLabel>
#include <QListWidget>
#include <QPainter>
#include <QPainterPath>
#include <QPointer>
#include <QPushButton>
#include <QShortcut>
#include <QShowEvent>
#include <QSlider>
#include <QTimer>
#include <QVBoxLayout>

#include <vtkImageData.h>
#include <vtkPolyData.h>

#include "modules/results/PlanComparison.h"
#include "scene/PlanNode.h"
#include "scene/Scene.h"
#include "scene/SnapshotNode.h"
#include "scene/SurfaceNode.h"

namespace caps {

/// Von Mises stress and displacement along the incision against arc length:
/// stress on the left axis, displacement on the right.
class IncisionPlot : public QWidget
{
public:
  explicit IncisionPlot(QWidget* parent) : QWidget(parent) { setMinimumHeight(210); }
  void setProfile(IncisionProfile profile, std::string message = {})
  {
    profile_ = std::move(profile);
    message_ = std::move(message);
    update();
  }

protected:
  void paintEvent(QPaintEvent*) override;

private:
  IncisionProfile profile_;
  std::string message_;
};

namespace {

/// Whether a recorded prediction is shown deformed: every linear preview
/// (under its warning), and a large-deformation prediction that passed its
/// check.
bool shownAsAFace(const planning::PredictionCheck& check)
{
  return check.model == planning::TissueModel::LinearElastic || check.admissible();
}

constexpr double kPlaySeconds = 2.0; // 0 → 100 % in this long
const QColor kStressColour(200, 70, 20);
const QColor kDisplacementColour(30, 90, 200);

std::string fixed(double value, int decimals)
{
  std::ostringstream s;
  s << std::fixed << std::setprecision(decimals) << value;
  return s.str();
}

/// A tick step of 1, 2 or 5 × 10^k giving about @a ticks intervals over @a span.
double tickStep(double span, int ticks)
{
  if (!(span > 0.0))
    return 1.0;
  const double raw = span / ticks;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * power >= raw)
      return m * power;
  return 10.0 * power;
}

QString tickText(double value, double step)
{
  const int decimals = std::max(0, -int(std::floor(std::log10(step) + 1e-9)));
  return QString::number(value, 'f', decimals);
}

/// A snapshot's picture as a QImage (VTK's rows run bottom up).
QImage toQImage(vtkImageData* image)
{
  if (!image || image->GetScalarType() != VTK_UNSIGNED_CHAR)
    return {};
  const int* dims = image->GetDimensions();
  const int components = image->GetNumberOfScalarComponents();
  if (dims[0] < 1 || dims[1] < 1 || (components != 3 && components != 4))
    return {};
  QImage out(dims[0], dims[1], QImage::Format_RGB888);
  const auto* data = static_cast<const unsigned char*>(image->GetScalarPointer());
  for (int y = 0; y < dims[1]; ++y)
  {
    uchar* line = out.scanLine(dims[1] - 1 - y);
    for (int x = 0; x < dims[0]; ++x)
      for (int c = 0; c < 3; ++c)
        line[3 * x + c] = data[(std::size_t(y) * dims[0] + x) * components + c];
  }
  return out;
}

} // namespace

void IncisionPlot::paintEvent(QPaintEvent*)
{
  QPainter p(this);
  p.setRenderHint(QPainter::Antialiasing);
  p.fillRect(rect(), palette().base());
  const QFontMetrics fm(font());
  const int left = fm.horizontalAdvance("0000") + fm.height() + 10;
  const int right = left;
  const int top = fm.height() + 8;
  const int bottom = 2 * fm.height() + 10;
  const QRect area(left, top, std::max(10, width() - left - right), std::max(10, height() - top - bottom));
  p.setPen(palette().text().color());
  if (profile_.arcLength.size() < 2)
  {
    p.drawText(rect(), Qt::AlignCenter | Qt::TextWordWrap,
               message_.empty() ? QString("No plan with a prediction.") : QString::fromStdString(message_));
    return;
  }
  const double length = std::max(profile_.arcLength.back(), 1e-6);
  const auto top2 = [](const std::vector<double>& v) {
    double m = 0.0;
    for (double x : v)
      if (std::isfinite(x))
        m = std::max(m, x);
    return m > 0.0 ? m : 1.0;
  };
  const double stressStep = tickStep(top2(profile_.vonMises), 4);
  const double stressTop = std::ceil(top2(profile_.vonMises) / stressStep) * stressStep;
  const double moveStep = tickStep(top2(profile_.displacement), 4);
  const double moveTop = std::ceil(top2(profile_.displacement) / moveStep) * moveStep;
  const double lengthStep = tickStep(length, 6);
  const auto px = [&](double s) { return area.left() + s / length * area.width(); };
  const auto py = [&](double v, double topValue) { return area.bottom() - v / topValue * area.height(); };

  // Grid and axes.
  p.setPen(QPen(palette().mid().color(), 0.5));
  for (double v = 0.0; v <= stressTop + 1e-9; v += stressStep)
    p.drawLine(QPointF(area.left(), py(v, stressTop)), QPointF(area.right(), py(v, stressTop)));
  p.setPen(palette().text().color());
  p.drawRect(area);
  for (double s = 0.0; s <= length + 1e-9; s += lengthStep)
  {
    p.drawLine(QPointF(px(s), area.bottom()), QPointF(px(s), area.bottom() + 4));
    p.drawText(QRectF(px(s) - 30, area.bottom() + 5, 60, fm.height()), Qt::AlignHCenter, tickText(s, lengthStep));
  }
  p.drawText(QRect(area.left(), area.bottom() + fm.height() + 6, area.width(), fm.height()), Qt::AlignHCenter,
             tr("arc length along the incision (mm)"));
  p.setPen(kStressColour);
  for (double v = 0.0; v <= stressTop + 1e-9; v += stressStep)
    p.drawText(QRectF(0, py(v, stressTop) - fm.height() / 2.0, area.left() - 4, fm.height()),
               Qt::AlignRight | Qt::AlignVCenter, tickText(v, stressStep));
  p.setPen(kDisplacementColour);
  for (double v = 0.0; v <= moveTop + 1e-9; v += moveStep)
    p.drawText(QRectF(area.right() + 4, py(v, moveTop) - fm.height() / 2.0, right - 4, fm.height()),
               Qt::AlignLeft | Qt::AlignVCenter, tickText(v, moveStep));
  // Axis titles, turned along the axes.
  p.save();
  p.setPen(kStressColour);
  p.translate(fm.height() / 2.0 + 1, area.center().y());
  p.rotate(-90);
  p.drawText(QRectF(-area.height() / 2.0, -fm.height() / 2.0, area.height(), fm.height()), Qt::AlignCenter,
             tr("von Mises (kPa)"));
  p.restore();
  p.save();
  p.setPen(kDisplacementColour);
  p.translate(width() - fm.height() / 2.0 - 1, area.center().y());
  p.rotate(90);
  p.drawText(QRectF(-area.height() / 2.0, -fm.height() / 2.0, area.height(), fm.height()), Qt::AlignCenter,
             tr("displacement (mm)"));
  p.restore();
  p.setPen(palette().text().color());
  p.drawText(QRect(area.left(), 2, area.width(), fm.height()), Qt::AlignHCenter,
             tr("Along the incision, after the closure"));

  const auto curve = [&](const std::vector<double>& v, double topValue, const QColor& colour) {
    QPainterPath path;
    bool started = false;
    for (std::size_t i = 0; i < v.size() && i < profile_.arcLength.size(); ++i)
    {
      if (!std::isfinite(v[i]))
      {
        started = false;
        continue;
      }
      const QPointF q(px(profile_.arcLength[i]), py(v[i], topValue));
      if (started)
        path.lineTo(q);
      else
        path.moveTo(q);
      started = true;
    }
    p.setPen(QPen(colour, 1.8));
    p.drawPath(path);
  };
  curve(profile_.displacement, moveTop, kDisplacementColour);
  curve(profile_.vonMises, stressTop, kStressColour);
}

ResultsPanel::ResultsPanel(ResultsLogic& logic, ModuleHost& host, QWidget* parent)
  : QWidget(parent), logic_(logic), host_(host)
{
  auto* layout = new QVBoxLayout(this);
  addViewControls(layout);
  addSummaryAndProfile(layout);
  addStoryboard(layout);
  animation_ = new QTimer(this);
  animation_->setInterval(20);

  connectControls();
  observeTheScene();
  refresh();
  refreshStoryboard();
}

/// The plan, the deformation slider, pre/post and play, the colouring and the
/// plan to compare with.
void ResultsPanel::addViewControls(QVBoxLayout* layout)
{
  auto* form = new QFormLayout;
  plan_ = new QComboBox(this);
  plan_->setObjectName("results.plan");
  plan_->setToolTip(tr("The predicted plans of the scene (predict one in the Incision module)"));
  form->addRow(tr("Plan:"), plan_);

  deformation_ = new QSlider(Qt::Horizontal, this);
  deformation_->setObjectName("results.deformation");
  deformation_->setRange(0, 100);
  deformation_->setValue(100);
  deformation_->setToolTip(tr("How far the skin has moved: 0 % before the operation, 100 % after the closure"));
  deformationLabel_ = new QLabel(this);
  deformationLabel_->setMinimumWidth(fontMetrics().horizontalAdvance("100 %") + 4);
  auto* slider = new QHBoxLayout;
  slider->addWidget(deformation_, 1);
  slider->addWidget(deformationLabel_);
  form->addRow(tr("Deformation:"), slider);

  prePost_ = new QPushButton(tr("Post-op"), this);
  prePost_->setObjectName("results.prePost");
  prePost_->setCheckable(true);
  prePost_->setChecked(true);
  prePost_->setToolTip(tr("Switch between the skin before the operation and after the closure"));
  play_ = new QPushButton(tr("Play"), this);
  play_->setObjectName("results.play");
  play_->setToolTip(tr("Animate from before to after the closure in %1 s; press again to go back").arg(kPlaySeconds));
  auto* buttons = new QHBoxLayout;
  buttons->addWidget(prePost_);
  buttons->addWidget(play_);
  form->addRow(QString(), buttons);

  colourBy_ = new QComboBox(this);
  colourBy_->setObjectName("results.colourBy");
  for (ResultQuantity q : resultQuantities())
  {
    const QuantityStyle style = quantityStyle(q);
    colourBy_->addItem(QString::fromStdString(style.barTitle.empty() ? style.label : style.barTitle), int(q));
  }
  form->addRow(tr("Colour by:"), colourBy_);
  compareWith_ = new QComboBox(this);
  compareWith_->setObjectName("results.compareWith");
  compareWith_->setToolTip(tr("Another predicted plan to see beside this one, same camera and colours"));
  compare_ = new QPushButton(tr("Side by side"), this);
  compare_->setObjectName("results.compare");
  auto* compareRow = new QHBoxLayout;
  compareRow->addWidget(compareWith_, 1);
  compareRow->addWidget(compare_);
  form->addRow(tr("Compare with:"), compareRow);
  layout->addLayout(form);
}

/// The numbers of the plan and the profile along its incision.
void ResultsPanel::addSummaryAndProfile(QVBoxLayout* layout)
{
  summary_ = new QLabel(this);
  summary_->setObjectName("results.summary");
  summary_->setWordWrap(true);
  summary_->setTextInteractionFlags(Qt::TextSelectableByMouse);
  layout->addWidget(summary_);
  computeClosure_ = new QPushButton(tr("Compute closure force"), this);
  computeClosure_->setObjectName("results.computeClosure");
  computeClosure_->hide();
  layout->addWidget(computeClosure_);

  plot_ = new IncisionPlot(this);
  plot_->setObjectName("results.plot");
  layout->addWidget(plot_);
}

/// The snapshots for the report's storyboard.
void ResultsPanel::addStoryboard(QVBoxLayout* layout)
{
  auto* storyRow = new QHBoxLayout;
  snapshot_ = new QPushButton(tr("Snapshot (Ctrl+T)"), this);
  snapshot_->setObjectName("results.snapshot");
  snapshot_->setToolTip(tr("Keep the 3D view with a caption for the report's storyboard"));
  deleteSnapshot_ = new QPushButton(tr("Delete"), this);
  deleteSnapshot_->setObjectName("results.deleteSnapshot");
  deleteSnapshot_->setToolTip(tr("Delete the selected snapshots"));
  storyRow->addWidget(snapshot_, 1);
  storyRow->addWidget(deleteSnapshot_);
  layout->addWidget(new QLabel(tr("Storyboard (double-click: back to that view):"), this));
  storyboard_ = new QListWidget(this);
  storyboard_->setObjectName("results.storyboard");
  storyboard_->setViewMode(QListView::IconMode);
  storyboard_->setIconSize(QSize(128, 96));
  storyboard_->setGridSize(QSize(150, 150));
  storyboard_->setResizeMode(QListView::Adjust);
  storyboard_->setMovement(QListView::Static);
  storyboard_->setWordWrap(true);
  storyboard_->setSelectionMode(QAbstractItemView::ExtendedSelection);
  storyboard_->setMinimumHeight(170);
  layout->addWidget(storyboard_, 1);
  layout->addLayout(storyRow);
}

void ResultsPanel::connectControls()
{
  connect(plan_, qOverload<int>(&QComboBox::currentIndexChanged), this, [this](int) {
    if (isVisible())
      showPlan(plan_->currentText().toStdString());
  });
  connect(deformation_, &QSlider::valueChanged, this, &ResultsPanel::setDeformation);
  connect(prePost_, &QPushButton::clicked, this, [this](bool post) {
    animation_->stop();
    deformation_->setValue(post ? 100 : 0);
  });
  connect(play_, &QPushButton::clicked, this, &ResultsPanel::play);
  connect(animation_, &QTimer::timeout, this, &ResultsPanel::tick);
  connect(colourBy_, qOverload<int>(&QComboBox::currentIndexChanged), this, [this](int) { applyColour(); });
  connect(compare_, &QPushButton::clicked, this, &ResultsPanel::compare);
  connect(computeClosure_, &QPushButton::clicked, this, &ResultsPanel::startClosure);
  connect(snapshot_, &QPushButton::clicked, this, &ResultsPanel::takeSnapshot);
  // A QShortcut of a hidden widget does not fire: Ctrl+T only while the panel shows.
  auto* shortcut = new QShortcut(QKeySequence(tr("Ctrl+T")), this);
  connect(shortcut, &QShortcut::activated, this, &ResultsPanel::takeSnapshot);
  connect(deleteSnapshot_, &QPushButton::clicked, this, &ResultsPanel::deleteSnapshots);
  connect(storyboard_, &QListWidget::itemDoubleClicked, this, &ResultsPanel::restoreSnapshotCamera);
  connect(storyboard_, &QListWidget::itemSelectionChanged, this,
          [this]() { deleteSnapshot_->setEnabled(!storyboard_->selectedItems().isEmpty()); });
}

void ResultsPanel::observeTheScene()
{
  observer_ = logic_.scene().addObserver([this](SceneEvent event, const Node& node) {
    const NodeId& id = node.id();
    if (event == SceneEvent::NodeAboutToBeRemoved)
    {
      // Removed by someone else (a scene loaded): forget it, never touch a
      // node that takes its id later.
      if (id == resultId_)
        resultId_.clear(), result_ = nullptr;
      if (id == headCutId_)
        headCutId_.clear();
      if (id == headId_)
        headId_.clear();
      if (id == shown_.before)
        shown_.before.clear();
      if (id == shown_.after)
        shown_.after.clear();
      if (id == shown_.plan)
        shown_.plan.clear();
    }
    if (node.type() == NodeType::Snapshot)
    {
      if (!storyboardPending_)
      {
        storyboardPending_ = true;
        QTimer::singleShot(0, this, &ResultsPanel::refreshStoryboard);
      }
      return;
    }
    const bool mine = id == resultId_ || id == headCutId_;
    if (mine || (event == SceneEvent::NodeModified && node.type() != NodeType::Plan))
      return;
    if (node.type() == NodeType::Plan || node.type() == NodeType::Surface)
      scheduleRefresh();
  });
}

ResultsPanel::~ResultsPanel()
{
  logic_.scene().removeObserver(observer_);
}

void ResultsPanel::scheduleRefresh()
{
  // Coalesced: loading a scene adds many nodes at once.
  if (refreshPending_)
    return;
  refreshPending_ = true;
  QTimer::singleShot(0, this, &ResultsPanel::refresh);
}

void ResultsPanel::refresh()
{
  refreshPending_ = false;
  const std::vector<PredictedPlan> plans = logic_.predictedPlans();
  const QString current = plan_->currentText();
  {
    const QSignalBlocker block(plan_);
    plan_->clear();
    for (const PredictedPlan& p : plans)
      plan_->addItem(QString::fromStdString(p.name));
    const int index = plan_->findText(current);
    plan_->setCurrentIndex(index >= 0 ? index : (plans.empty() ? -1 : 0));
  }
  const bool any = !plans.empty();
  for (QWidget* w : std::initializer_list<QWidget*>{plan_, colourBy_})
    w->setEnabled(any);
  for (QWidget* w : std::initializer_list<QWidget*>{deformation_, prePost_, play_})
    w->setEnabled(any && !shownFailed_);
  {
    const QSignalBlocker block(compareWith_);
    const QString other = compareWith_->currentText();
    compareWith_->clear();
    for (const PredictedPlan& p : plans)
      compareWith_->addItem(QString::fromStdString(p.name));
    // Another plan than the one shown, by default.
    int index = compareWith_->findText(other);
    if (index < 0 || other == plan_->currentText())
      index = plans.size() > 1 ? (plan_->currentIndex() == 0 ? 1 : 0) : -1;
    compareWith_->setCurrentIndex(index);
  }
  compareWith_->setEnabled(plans.size() > 1);
  compare_->setEnabled(plans.size() > 1);
  if (!isVisible())
    return;
  const std::string name = plan_->currentText().toStdString();
  // Shown again when its surfaces were replaced (a new prediction of the same name).
  const std::optional<PredictedPlan> p = logic_.predictedPlan(name);
  const bool same = p && p->plan == shown_.plan && p->before == shown_.before && p->after == shown_.after &&
                    logic_.scene().node(resultId_);
  if (!same)
    showPlan(name, true);
}

void ResultsPanel::compare()
{
  const auto left = logic_.predictedPlan(plan_->currentText().toStdString());
  const auto right = logic_.predictedPlan(compareWith_->currentText().toStdString());
  if (!left || !right || left->plan == right->plan)
  {
    host_.showError("Side by side", "Choose two different predicted plans: the one shown above and another in "
                                    "'Compare with'. Simulate a second plan first if there is only one.");
    return;
  }
  // Each plan's closure numbers when known (computed for the plan shown).
  auto summary = [this](const PredictedPlan& p) {
    auto* surface = logic_.scene().nodeAs<SurfaceNode>(p.after);
    QString text = tr("peak von Mises %1 kPa, largest displacement %2 mm")
                     .arg(ResultsLogic::arrayMaximum(surface->polyData(), "von_mises_kPa"), 0, 'f', 1)
                     .arg(ResultsLogic::arrayMaximum(surface->polyData(), "displacement_magnitude_mm"), 0, 'f', 2);
    if (const auto* planNode = logic_.scene().nodeAs<PlanNode>(p.plan))
      if (const auto it = closure_.find(ResultsLogic::closureKey(*planNode)); it != closure_.end())
        text += tr(", closure force %1 N").arg(it->second.closureForce, 0, 'f', 2);
    return text;
  };
  if (!comparison_)
    comparison_ = new PlanComparison(host_.window());
  try
  {
    comparison_->show(logic_, *left, *right, ResultQuantity(colourBy_->currentData().toInt()),
                      {summary(*left), summary(*right)});
  }
  catch (const std::exception& e)
  {
    host_.showError("Side by side", e.what());
  }
}

void ResultsPanel::showEvent(QShowEvent* event)
{
  QWidget::showEvent(event);
  if (event->spontaneous())
    return;
  refresh();
  refreshStoryboard();
}

void ResultsPanel::hideEvent(QHideEvent* event)
{
  QWidget::hideEvent(event);
  if (event->spontaneous())
    return;
  // Other modules see the plan as the Incision module left it.
  animation_->stop();
  releasePlan();
}

void ResultsPanel::releasePlan()
{
  Scene& scene = logic_.scene();
  if (!resultId_.empty())
    scene.removeNode(resultId_);
  if (!headCutId_.empty())
    scene.removeNode(headCutId_);
  resultId_.clear();
  headCutId_.clear();
  result_ = nullptr;
  before_ = nullptr;
  const auto restore = [&](const NodeId& id, bool visible) {
    if (auto* node = scene.nodeAs<SurfaceNode>(id); node && node->visible() != visible)
      node->setVisible(visible);
  };
  restore(shown_.before, beforeWasVisible_);
  restore(shown_.after, afterWasVisible_);
  restore(headId_, headWasVisible_);
  headId_.clear();
  shown_ = PredictedPlan{};
}

void ResultsPanel::showPlan(const std::string& name, bool again)
{
  if (!again && !shown_.plan.empty() && shown_.name == name && !resultId_.empty())
    return;
  releasePlan();
  const std::optional<PredictedPlan> plan = logic_.predictedPlan(name);
  if (!plan)
  {
    summary_->setText(tr("No predicted plan in the scene: place a procedure and predict it in the Incision module."));
    plot_->setProfile({});
    computeClosure_->hide();
    return;
  }
  Scene& scene = logic_.scene();
  // A scene saved while this panel showed the plan holds its nodes: they go,
  // and the plan's surfaces come back as the prediction left them.
  bool leftover = false;
  for (Node* n : scene.nodesOfType(NodeType::Surface))
    if (n->name() == name + " result" || n->name() == name + " result head")
    {
      scene.removeNode(n->id());
      leftover = true;
    }
  auto* before = scene.nodeAs<SurfaceNode>(plan->before);
  auto* after = scene.nodeAs<SurfaceNode>(plan->after);
  shown_ = *plan;
  before_ = before->polyData();
  beforeWasVisible_ = leftover ? false : before->visible();
  afterWasVisible_ = leftover ? true : after->visible();
  // The result replaces the plan's own surfaces while shown.
  before->setVisible(false);
  after->setVisible(false);
  // The head's skin under the patch would fight with it for the same
  // pixels: shown without the cells the patch covers.
  // New nodes are set up before they join the scene: one redraw each.
  if (SurfaceNode* head = logic_.headSkin())
  {
    headId_ = head->id();
    headWasVisible_ = leftover || head->visible();
    auto cut = std::make_unique<SurfaceNode>();
    cut->setName(name + " result head");
    cut->setPolyData(ResultsLogic::headWithoutPatch(head->polyData(), before_));
    cut->setColor(head->color());
    cut->setOpacity(head->opacity());
    cut->setVisible(headWasVisible_);
    headCutId_ = scene.addNode(std::move(cut))->id();
    head->setVisible(false);
  }
  // A large-deformation solve that stopped short of the closure, or whose
  // deformed mesh is not a body (an element turned inside out, the skin
  // through itself), is not a prediction: the face is shown before the
  // operation, the deformation held there, and the summary says what failed
  // and what to try. (A linear preview that is not a body is still shown,
  // as the preview it is, under its warning.)
  const auto* planNode = scene.nodeAs<PlanNode>(shown_.plan);
  const std::optional<planning::PredictionCheck> check =
    planNode ? ResultsLogic::recordedCheck(*planNode) : std::nullopt;
  const bool failed = check && !shownAsAFace(*check);
  shownFailed_ = failed;
  for (QWidget* control : std::initializer_list<QWidget*>{deformation_, play_, prePost_})
    control->setEnabled(!failed);
  if (failed)
  {
    const QSignalBlocker block(deformation_);
    deformation_->setValue(0);
  }
  result_ = ResultsLogic::makeResultSurface(before_);
  ResultsLogic::deform(before_, result_, deformation_->value() / 100.0);
  setDeformation(deformation_->value()); // the labels: there is no node to move yet
  auto node = std::make_unique<SurfaceNode>();
  node->setName(name + " result");
  node->setColor(after->color());
  node->setPolyData(result_);
  setColouring(*node);
  resultId_ = scene.addNode(std::move(node))->id();

  if (planNode)
  {
    if (const auto camera = logic_.planCamera(*planNode, before_))
      host_.setThreeDViewCamera(*camera);
    try
    {
      if (failed)
        plot_->setProfile({}, "No profile along the incision: the solve did not reach the closure.");
      else
        plot_->setProfile(logic_.incisionProfile(*planNode, before_));
    }
    catch (const std::exception& e)
    {
      plot_->setProfile({}, std::string("No plot along the incision: ") + e.what());
    }
  }
  updateSummary();
  if (!failed)
    startClosure();
}

void ResultsPanel::setDeformation(int percent)
{
  deformationLabel_->setText(QString("%1 %").arg(percent));
  {
    const QSignalBlocker block(prePost_);
    prePost_->setChecked(percent == 100);
    prePost_->setText(percent == 100 ? tr("Post-op") : percent == 0 ? tr("Pre-op") : tr("Pre/post"));
  }
  auto* node = logic_.scene().nodeAs<SurfaceNode>(resultId_);
  if (!node || !result_ || !before_)
    return;
  // In place: the points move, the node says so, the 3D view redraws it.
  ResultsLogic::deform(before_, result_, percent / 100.0);
  node->modified();
}

void ResultsPanel::setColouring(SurfaceNode& node) const
{
  const auto quantity = ResultQuantity(colourBy_->currentData().toInt());
  const QuantityStyle style = quantityStyle(quantity);
  // The range from the plan's arrays (the same at every deformation), so
  // the colours do not change while the skin animates. The four fields in
  // one change (Node::fromJson: one NodeModified, so one redraw, where the
  // four setters would redraw four times).
  nlohmann::json fields = {{"colourArray", style.array},
                           {"scalarRange", ResultsLogic::colourRange(before_, quantity)},
                           {"colourBarTitle", style.barTitle}};
  if (!style.colourMap.empty())
    fields["colourMap"] = style.colourMap;
  node.fromJson(fields);
}

void ResultsPanel::applyColour()
{
  if (auto* node = logic_.scene().nodeAs<SurfaceNode>(resultId_); node && before_)
    setColouring(*node);
}

std::string ResultsPanel::stateWord() const
{
  const int v = deformation_->value();
  return v == 100 ? "after" : v == 0 ? "before" : std::to_string(v) + " % deformed";
}

void ResultsPanel::updateSummary()
{
  computeClosure_->hide();
  if (shown_.plan.empty() || !before_)
  {
    summary_->clear();
    return;
  }
  const auto html = [](const std::string& plain) {
    return QString::fromStdString(plain).toHtmlEscaped().toStdString();
  };
  std::string text = "<b>" + html(shown_.name) + "</b><br>";
  const auto* planNode = logic_.scene().nodeAs<PlanNode>(shown_.plan);
  if (const std::optional<planning::PredictionCheck> check =
        planNode ? ResultsLogic::recordedCheck(*planNode) : std::nullopt)
  {
    // Which model made it and how it checked out; a failed check first, in red.
    if (const std::string warning = planning::checkWarning(*check); !warning.empty())
      text += "<span style=\"color:#b00020\"><b>" + html(warning) + "</b>" +
              (shownAsAFace(*check) ? std::string() : std::string(" The face is shown before the operation.")) +
              "</span><br>";
    text += "Model: " + html(planning::tissueModelDescription(check->model)) + "; " +
            html(planning::checkSummary(*check)) + "<br>";
    if (!check->caveat.empty())
      text += "<span style=\"color:#8a5a00\">Caveat: " + html(check->caveat) + "</span><br>";
  }
  if (shownFailed_)
  { // the numbers of a state short of the closure are not results
    summary_->setText(QString::fromStdString(text));
    return;
  }
  text +=
    "Largest displacement: " + fixed(ResultsLogic::arrayMaximum(before_, "displacement_magnitude_mm"), 2) + " mm<br>";
  text +=
    "Peak von Mises stress on the skin: " + fixed(ResultsLogic::arrayMaximum(before_, "von_mises_kPa"), 1) + " kPa<br>";
  const auto* plan = logic_.scene().nodeAs<PlanNode>(shown_.plan);
  const std::string key = plan ? ResultsLogic::closureKey(*plan) : std::string();
  if (const auto it = closure_.find(key); it != closure_.end())
  {
    const ClosureNumbers& c = it->second;
    if (c.peakTensionPerCentimetre > 0.0)
      text += "Wound tension: " + fixed(c.tensionPerCentimetre, 2) + " N/cm, at most " +
              fixed(c.peakTensionPerCentimetre, 2) + " N/cm on " + html(c.peakTensionLine) + " (" +
              fixed(c.peakForcePerStitch, 2) + " N per stitch every " + fixed(c.stitchSpacing, 0) + " mm)<br>";
    text += "Closure force: " + fixed(c.closureForce, 2) + " N summed over the sutures (largest suture " +
            fixed(c.largestSutureForce, 3) + " N)<br>";
    text += "Peak wound stress: " + fixed(c.peakWoundStress, 1) + " kPa (von Mises, skin within " +
            fixed(c.woundRadius, 0) + " mm of the wound)";
  }
  else if (const auto error = closureError_.find(key); error != closureError_.end())
  {
    text += "Closure force and wound stress: " + html(error->second);
    computeClosure_->show();
  }
  else if (computingKey_ == key)
    text += "Closure force and wound stress: computing...";
  else
  {
    text += "Closure force and wound stress: not computed yet";
    computeClosure_->show();
  }
  summary_->setText(QString::fromStdString(text));
}

void ResultsPanel::startClosure()
{
  auto* plan = logic_.scene().nodeAs<PlanNode>(shown_.plan);
  if (!plan || !isVisible() || !computingKey_.empty())
    return;
  const std::string key = ResultsLogic::closureKey(*plan);
  if (closure_.count(key))
    return;
  if (const std::optional<ClosureNumbers> recorded = ResultsLogic::recordedClosure(*plan))
  { // kept with the prediction: nothing to solve again
    closure_[key] = *recorded;
    updateSummary();
    return;
  }
  closureError_.erase(key);
  std::shared_ptr<ClosureJob> job;
  try
  {
    job = std::make_shared<ClosureJob>(logic_.closureJob(*plan));
  }
  catch (const std::exception& e)
  {
    closureError_[key] = std::string("not available (") + e.what() + ")";
    updateSummary();
    return;
  }
  computingKey_ = key;
  updateSummary();
  auto started = std::make_shared<std::atomic<bool>>(false);
  QPointer<ResultsPanel> self(this);
  host_.runTask("Closure force of " + plan->name(), [job, started, self, key](const TaskProgress& progress) {
    started->store(true);
    std::optional<ClosureNumbers> numbers;
    std::string error;
    try
    {
      numbers = ResultsLogic::computeClosure(*job, progress);
      if (!numbers)
        error = "not computed (cancelled)";
    }
    catch (const std::exception& e)
    {
      error = std::string("not available (") + e.what() + ")";
    }
    // Told through the event loop rather than by the finishing function,
    // which the workstation skips when the user cancelled.
    QMetaObject::invokeMethod(
      self.data(),
      [self, key, numbers, error]() {
        if (!self)
          return;
        self->computingKey_.clear();
        if (numbers)
          self->closure_[key] = *numbers;
        else
          self->closureError_[key] = error;
        self->updateSummary();
        // Another plan may have been chosen meanwhile: its turn once the
        // workstation has closed this task (queued after this call).
        QTimer::singleShot(0, self, [self]() {
          if (self)
            self->startClosure();
        });
      },
      Qt::QueuedConnection);
    return std::function<void()>();
  });
  // runTask refuses (with a message) while other work runs: then the work
  // never starts, and the button offers to try again.
  QTimer::singleShot(1500, this, [this, started, key]() {
    if (!started->load() && computingKey_ == key)
    {
      computingKey_.clear();
      closureError_[key] = "not computed (other work was running)";
      updateSummary();
    }
  });
}

void ResultsPanel::play()
{
  // Forward from where the slider is, unless it is at the end: then back.
  const int value = deformation_->value();
  const bool forward = animation_->isActive() ? animationTo_ == 0 : value < 100;
  animationFrom_ = value;
  animationTo_ = forward ? 100 : 0;
  clock_.start();
  play_->setText(tr("Reverse"));
  animation_->start();
}

void ResultsPanel::tick()
{
  const double span = std::abs(animationTo_ - animationFrom_);
  const double seconds = kPlaySeconds * span / 100.0;
  const double t = seconds > 0.0 ? std::min(1.0, clock_.elapsed() / 1000.0 / seconds) : 1.0;
  deformation_->setValue(int(std::lround(animationFrom_ + t * (animationTo_ - animationFrom_))));
  if (t >= 1.0)
  {
    animation_->stop();
    play_->setText(animationTo_ == 100 ? tr("Play back") : tr("Play"));
  }
}

void ResultsPanel::takeSnapshot()
{
  if (!isVisible())
    return;
  const ViewCapture capture = host_.captureThreeDView();
  if (!capture.image || capture.image->GetNumberOfPoints() == 0)
  {
    host_.showError("Snapshot", "The 3D view could not be captured. Show the 3D view and try again.");
    return;
  }
  std::string caption;
  if (!shown_.plan.empty())
  {
    caption =
      shown_.name + " - " + stateWord() + " - " + quantityStyle(ResultQuantity(colourBy_->currentData().toInt())).label;
  }
  else
    caption = "3D view";
  const SnapshotNode& snapshot = logic_.addSnapshot(caption, capture);
  host_.showStatus("Snapshot taken for the storyboard: " + snapshot.caption());
}

void ResultsPanel::refreshStoryboard()
{
  storyboardPending_ = false;
  const QString selected =
    storyboard_->currentItem() ? storyboard_->currentItem()->data(Qt::UserRole).toString() : QString();
  storyboard_->clear();
  int number = 0;
  for (Node* n : logic_.scene().nodesOfType(NodeType::Snapshot))
  {
    const auto* snapshot = static_cast<const SnapshotNode*>(n);
    const QImage image = toQImage(snapshot->image());
    // Numbered as the report's storyboard prints them (pictures only).
    const QString caption =
      QString::fromStdString(snapshot->caption().empty() ? snapshot->name() : snapshot->caption());
    auto* item = new QListWidgetItem(image.isNull() ? caption : QString("%1. %2").arg(++number).arg(caption));
    if (!image.isNull())
      item->setIcon(QIcon(QPixmap::fromImage(image.scaled(256, 192, Qt::KeepAspectRatio, Qt::SmoothTransformation))));
    item->setToolTip(caption);
    item->setData(Qt::UserRole, QString::fromStdString(snapshot->id()));
    storyboard_->addItem(item);
    if (item->data(Qt::UserRole).toString() == selected)
      storyboard_->setCurrentItem(item);
  }
  deleteSnapshot_->setEnabled(!storyboard_->selectedItems().isEmpty());
}

void ResultsPanel::restoreSnapshotCamera(QListWidgetItem* item)
{
  if (!item)
    return;
  const auto* snapshot = logic_.scene().nodeAs<SnapshotNode>(item->data(Qt::UserRole).toString().toStdString());
  if (snapshot)
    host_.setThreeDViewCamera(snapshot->camera());
}

void ResultsPanel::deleteSnapshots()
{
  std::vector<std::string> ids;
  for (QListWidgetItem* item : storyboard_->selectedItems())
    ids.push_back(item->data(Qt::UserRole).toString().toStdString());
  for (const std::string& id : ids)
    logic_.scene().removeNode(id);
}

} // namespace caps
