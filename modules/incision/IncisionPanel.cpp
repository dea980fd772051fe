#include "modules/incision/IncisionPanel.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include <QAbstractItemView>
#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QFormLayout>
#include <QGroupBox>
#include <QGridLayout>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QKeySequence>
#include <QLabel>
#include <QListWidget>
#include <QPointer>
#include <QPushButton>
#include <QShortcut>
#include <QSignalBlocker>
#include <QSpinBox>
#include <QTableWidget>
#include <QTimer>
#include <QVBoxLayout>

#include "modules/incision/IncisionLogic.h"
#include "planning/PlanLines.h"
#include "planning/SkinTensionLines.h"
#include "segmentation/LandmarkPlacement.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/ScopedEdit.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"

namespace caps {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
/// §3.3.1: incision lines solid, dark blue so they stand out on the skin.
constexpr std::array<double, 3> kLineColour{0.05, 0.10, 0.45};
constexpr double kLineWidth = 3.0;
// The skin tension lines: a guide, quieter than the plan's own lines.
constexpr std::array<double, 3> kTensionLineColour{0.55, 0.50, 0.20};
constexpr double kTensionLineWidth = 1.5;
constexpr const char* kTensionLinesName = "Skin tension lines";

std::string linesName(const std::string& planName)
{
  std::string name = planName;
  name += " incision";
  return name;
}

Node* nodeNamed(const Scene& scene, const std::string& name, NodeType type)
{
  for (Node* n : scene.nodesOfType(type))
    if (n->name() == name)
      return n;
  return nullptr;
}

/// Whether a plan has nodes of a prediction (IncisionLogic::addPrediction's names).
bool hasPrediction(const Scene& scene, const std::string& planName)
{
  for (Node* n : scene.nodes())
    for (const char* suffix : {" model", " closure", " skin before", " skin after", " skin gaping"})
      if (n->name() == planName + suffix)
        return true;
  return false;
}

/// What the prediction depends on: the plan node without its name.
nlohmann::json planState(const PlanNode& plan)
{
  nlohmann::json j = plan.toJson();
  j.erase("name");
  return j;
}

double toUi(planning::ParameterUnit unit, double value)
{
  return unit == planning::ParameterUnit::Degree ? value / kDegree : value;
}

QString unitSuffix(planning::ParameterUnit unit)
{
  switch (unit)
  {
  case planning::ParameterUnit::Millimetre:
    return " mm";
  case planning::ParameterUnit::Degree:
    return QString::fromUtf8(" °");
  case planning::ParameterUnit::Ratio:
    return "";
  }
  return "";
}

/// "limb_angle" → "Limb angle".
QString readable(const std::string& name)
{
  QString s = QString::fromStdString(name);
  s.replace('_', ' ');
  if (!s.isEmpty())
    s[0] = s[0].toUpper();
  return s;
}

// The normalised cylindrical point (θn, zn) of a picked skin point on a skin map's frame (§4.2.2).
Eigen::Vector2d normalizedOf(const seg::RangeMap& skin, const SurfacePick& pick)
{
  const seg::CylindricalFrame& frame = skin.frame();
  const seg::NormalizedCylindricalPoint n =
    frame.toNormalized(frame.toCylindrical(Eigen::Vector3d(pick.position[0], pick.position[1], pick.position[2])));
  return {n.thetaN, n.zN};
}

} // namespace

IncisionPanel::IncisionPanel(IncisionLogic& logic, ModuleHost& host, QWidget* parent)
  : QWidget(parent), logic_(logic), host_(host)
{
  auto* layout = new QVBoxLayout(this);
  addNewPlanControls(layout);
  addPlanList(layout);
  addPlanEditing(layout);
  addGuidesAndMeasurements(layout);
  connectControls();
  observer_ =
    logic_.scene().addObserver([this](SceneEvent event, const Node& node) { sceneChanged(int(event), node); });

  fillProcedures();
  refresh();
}

/// A new plan: the procedure, its parameters, Place; or a cut drawn point by point.
void IncisionPanel::addNewPlanControls(QVBoxLayout* layout)
{
  auto* newPlan = new QLabel(tr("Procedure:"), this);
  layout->addWidget(newPlan);
  procedure_ = new QComboBox(this);
  procedure_->setObjectName("incision.procedure");
  layout->addWidget(procedure_);

  formBox_ = new QGroupBox(tr("Parameters"), this);
  form_ = new QFormLayout(formBox_);
  layout->addWidget(formBox_);

  place_ = new QPushButton(tr("Place on the skin"), this);
  place_->setObjectName("incision.place");
  place_->setToolTip(tr("Then click on the skin in the 3D view where the centre of the cut goes"));
  layout->addWidget(place_);
  // Or a cut of the surgeon's own, point by point.
  auto* drawRow = new QHBoxLayout();
  draw_ = new QPushButton(tr("Draw a cut point by point"), this);
  draw_->setObjectName("incision.draw");
  draw_->setToolTip(tr("Then click the points of the cut on the skin in order, and Finish"));
  finishDraw_ = new QPushButton(tr("Finish the cut"), this);
  finishDraw_->setObjectName("incision.finishDraw");
  drawRow->addWidget(draw_, 1);
  drawRow->addWidget(finishDraw_);
  layout->addLayout(drawRow);
  drawStatus_ = new QLabel(this);
  drawStatus_->setObjectName("incision.drawStatus");
  drawStatus_->setWordWrap(true);
  layout->addWidget(drawStatus_);
  connect(draw_, &QPushButton::clicked, this, &IncisionPanel::armDraw);
  connect(finishDraw_, &QPushButton::clicked, this, &IncisionPanel::finishDraw);
}

/// The scene's plans and Move, Undo, Redo, Delete.
void IncisionPanel::addPlanList(QVBoxLayout* layout)
{
  layout->addWidget(new QLabel(tr("Plans in the scene:"), this));
  plans_ = new QListWidget(this);
  plans_->setObjectName("incision.plans");
  plans_->setSelectionMode(QAbstractItemView::SingleSelection);
  plans_->setMaximumHeight(110);
  layout->addWidget(plans_);

  auto* buttons = new QHBoxLayout();
  const auto button = [&](const QString& text, const char* name, const QString& tip) {
    auto* b = new QPushButton(text, this);
    b->setObjectName(name);
    b->setToolTip(tip);
    buttons->addWidget(b);
    return b;
  };
  move_ = button(tr("Move"), "incision.move", tr("Click on the skin where the selected plan's centre goes"));
  undo_ = button(tr("Undo"), "incision.undo", tr("Undo the last edit (Ctrl+Z)"));
  redo_ = button(tr("Redo"), "incision.redo", tr("Redo the edit undone (Ctrl+Shift+Z)"));
  delete_ = button(tr("Delete"), "incision.delete", tr("Remove the selected plan and its lines"));
  layout->addLayout(buttons);
}

void IncisionPanel::addPlanEditing(QVBoxLayout* layout)
{
  // Editing the selected plan point by point (the recipe's operations).
  editBox_ = new QGroupBox(tr("Edit the selected plan"), this);
  auto* edit = new QGridLayout(editBox_);
  point_ = new QSpinBox(editBox_);
  point_->setObjectName("incision.point");
  point_->setPrefix(tr("cut point p"));
  movePoint_ = new QPushButton(tr("Move point"), editBox_);
  movePoint_->setObjectName("incision.movePoint");
  movePoint_->setToolTip(tr("Then click on the skin where the point goes (or drag its white handle in the 3D view)"));
  edit->addWidget(point_, 0, 0);
  edit->addWidget(movePoint_, 0, 1, 1, 3);
  borderPoint_ = new QSpinBox(editBox_);
  borderPoint_->setObjectName("incision.borderPoint");
  borderPoint_->setPrefix(tr("border point "));
  borderPoint_->setToolTip(tr("Hole-loop numbering (thesis Fig. 4.11): a cut point's two sides are two border points"));
  offsetU_ = new QDoubleSpinBox(editBox_);
  offsetU_->setObjectName("incision.offsetU");
  offsetV_ = new QDoubleSpinBox(editBox_);
  offsetV_->setObjectName("incision.offsetV");
  for (QDoubleSpinBox* box : {offsetU_, offsetV_})
  {
    box->setRange(-30.0, 30.0);
    box->setDecimals(1);
    box->setSingleStep(0.5);
    box->setSuffix(" mm");
  }
  offsetU_->setToolTip(tr("Offset across the face (chart u, mm)"));
  offsetV_->setToolTip(tr("Offset up the face (chart v, mm)"));
  offset_ = new QPushButton(tr("Offset"), editBox_);
  offset_->setObjectName("incision.offset");
  offset_->setToolTip(tr("Moves the border point away from its twin: the gap is skin excised (thesis 4.4.4)"));
  edit->addWidget(borderPoint_, 1, 0);
  edit->addWidget(offsetU_, 1, 1);
  edit->addWidget(offsetV_, 1, 2);
  edit->addWidget(offset_, 1, 3);
  undermine_ = new QPushButton(tr("Undermine a region"), editBox_);
  undermine_->setObjectName("incision.undermine");
  undermine_->setToolTip(tr("Click the corners of the region on the skin, then Finish"));
  finishRegion_ = new QPushButton(tr("Finish"), editBox_);
  finishRegion_->setObjectName("incision.finishRegion");
  clearRegions_ = new QPushButton(tr("Clear"), editBox_);
  clearRegions_->setObjectName("incision.clearUndermining");
  clearRegions_->setToolTip(tr("Removes the plan's undermined regions"));
  edit->addWidget(undermine_, 2, 0, 1, 2);
  edit->addWidget(finishRegion_, 2, 2);
  edit->addWidget(clearRegions_, 2, 3);
  regionStatus_ = new QLabel(editBox_);
  regionStatus_->setObjectName("incision.regionStatus");
  regionStatus_->setWordWrap(true);
  edit->addWidget(regionStatus_, 3, 0, 1, 4);
  layout->addWidget(editBox_);
  connect(movePoint_, &QPushButton::clicked, this, &IncisionPanel::armMovePoint);
  connect(offset_, &QPushButton::clicked, this, &IncisionPanel::offsetBorderPoint);
  connect(undermine_, &QPushButton::clicked, this, &IncisionPanel::armUndermine);
  connect(finishRegion_, &QPushButton::clicked, this, &IncisionPanel::finishUndermining);
  connect(clearRegions_, &QPushButton::clicked, this, &IncisionPanel::clearUndermining);
}

/// The tension lines, what the prediction says of the plan, and the
/// measurements on the skin.
void IncisionPanel::addGuidesAndMeasurements(QVBoxLayout* layout)
{
  showTension_ = new QCheckBox(tr("Skin tension lines (guide)"), this);
  showTension_->setObjectName("incision.tensionLines");
  showTension_->setToolTip(tr("Overlay the relaxed skin tension lines of the face (schematic, after Borges 1984),\n"
                              "placed by the facial landmarks of the skin map. Incisions along them heal with\n"
                              "the finest scars; the table gives the angle of the plan's axis to them."));
  layout->addWidget(showTension_);
  connect(showTension_, &QCheckBox::toggled, this, &IncisionPanel::showTensionLines);

  predictionStatus_ = new QLabel(this);
  predictionStatus_->setObjectName("incision.predictionStatus");
  predictionStatus_->setWordWrap(true);
  predictionStatus_->setStyleSheet("color: #a04000;");
  layout->addWidget(predictionStatus_);

  table_ = new QTableWidget(0, 3, this);
  table_->setObjectName("incision.measurements");
  table_->setHorizontalHeaderLabels({tr("On the skin"), tr("Value"), tr("Unit")});
  table_->verticalHeader()->hide();
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  table_->setSelectionMode(QAbstractItemView::NoSelection);
  table_->horizontalHeader()->setSectionResizeMode(0, QHeaderView::Stretch);
  table_->horizontalHeader()->setSectionResizeMode(1, QHeaderView::ResizeToContents);
  table_->horizontalHeader()->setSectionResizeMode(2, QHeaderView::ResizeToContents);
  layout->addWidget(table_, 1);
}

void IncisionPanel::connectControls()
{
  connect(procedure_, QOverload<int>::of(&QComboBox::currentIndexChanged), this, [this] {
    // Another procedure: the form is for a new plan now.
    plans_->blockSignals(true);
    plans_->clearSelection();
    plans_->setCurrentRow(-1);
    plans_->blockSignals(false);
    showSelection();
  });
  connect(place_, &QPushButton::clicked, this, &IncisionPanel::armPlace);
  connect(move_, &QPushButton::clicked, this, &IncisionPanel::armMove);
  connect(undo_, &QPushButton::clicked, this, &IncisionPanel::undo);
  connect(redo_, &QPushButton::clicked, this, &IncisionPanel::redo);
  connect(delete_, &QPushButton::clicked, this, &IncisionPanel::deletePlan);
  connect(plans_, &QListWidget::itemSelectionChanged, this, &IncisionPanel::planSelected);
  auto* undoKey = new QShortcut(QKeySequence::Undo, this);
  undoKey->setContext(Qt::WidgetWithChildrenShortcut);
  connect(undoKey, &QShortcut::activated, this, &IncisionPanel::undo);
  auto* redoKey = new QShortcut(QKeySequence(Qt::CTRL | Qt::SHIFT | Qt::Key_Z), this);
  redoKey->setContext(Qt::WidgetWithChildrenShortcut);
  connect(redoKey, &QShortcut::activated, this, &IncisionPanel::redo);
}

IncisionPanel::~IncisionPanel()
{
  logic_.scene().removeObserver(observer_);
}

// ---------------------------------------------------------------- the form

void IncisionPanel::fillProcedures()
{
  procedure_->blockSignals(true);
  procedure_->clear();
  try
  {
    for (const auto& p : logic_.procedures().procedures())
      procedure_->addItem(QString::fromStdString(p.title()), QString::fromStdString(p.id()));
    if (!logic_.procedures().errors().empty())
    {
      std::string message = "These procedure files were left out:\n";
      for (const auto& e : logic_.procedures().errors())
        message += e + "\n";
      message += "Correct them (data/procedures/README.md describes the format) and restart.";
      host_.showWarning("Procedures", message);
    }
  }
  catch (const std::exception& e)
  {
    host_.showError("Procedures",
                    std::string(e.what()) + "\nSet CAPS_DATA_DIR to the folder holding procedures/ and restart.");
  }
  procedure_->blockSignals(false);
  place_->setEnabled(procedure_->count() > 0);
}

const planning::ProcedureTemplate* IncisionPanel::currentProcedure()
{
  if (procedure_->currentIndex() < 0)
    return nullptr;
  try
  {
    return logic_.procedures().find(procedure_->currentData().toString().toStdString());
  }
  catch (const std::exception&)
  {
    return nullptr;
  }
}

void IncisionPanel::buildForm(const planning::ProcedureTemplate& procedure, const std::map<std::string, double>* values)
{
  while (form_->rowCount() > 0)
    form_->removeRow(0);
  spins_.clear();
  formProcedure_ = procedure.id();
  for (const auto& p : procedure.parameters())
  {
    auto* spin = new QDoubleSpinBox(formBox_);
    spin->setObjectName(QString::fromStdString("incision.param." + p.name));
    spin->setDecimals(p.unit == planning::ParameterUnit::Ratio ? 2 : 1);
    spin->setSingleStep(p.unit == planning::ParameterUnit::Ratio    ? 0.05
                        : p.unit == planning::ParameterUnit::Degree ? 5.0
                                                                    : 1.0);
    spin->setRange(toUi(p.unit, p.minimum), toUi(p.unit, p.maximum));
    spin->setSuffix(unitSuffix(p.unit));
    // One change per edit, not one per key typed.
    spin->setKeyboardTracking(false);
    spin->setToolTip(QString::fromStdString(p.label));
    double value = p.defaultValue;
    if (values)
      if (const auto given = values->find(p.name); given != values->end())
        value = given->second;
    spin->setValue(toUi(p.unit, value));
    const std::string name = p.name;
    connect(spin, QOverload<double>::of(&QDoubleSpinBox::valueChanged), this, [this, name] { parameterChanged(name); });
    auto* label = new QLabel(readable(p.name) + ":", formBox_);
    label->setToolTip(QString::fromStdString(p.label));
    form_->addRow(label, spin);
    spins_[p.name] = spin;
  }
}

std::map<std::string, double> IncisionPanel::formValues(const planning::ProcedureTemplate& procedure) const
{
  std::map<std::string, double> values;
  for (const auto& p : procedure.parameters())
  {
    const auto spin = spins_.find(p.name);
    if (spin == spins_.end())
      continue;
    const double shown = spin->second->value();
    // The default itself where the surgeon left it, so the recipe records
    // what `caps plan` would; else the value, kept inside the file's range
    // against rounding in the conversion from degrees.
    const auto rounded = [&](double v) {
      return std::round(toUi(p.unit, v) * std::pow(10.0, spin->second->decimals()));
    };
    if (rounded(p.defaultValue) == std::round(shown * std::pow(10.0, spin->second->decimals())))
      values[p.name] = p.defaultValue;
    else
      values[p.name] =
        std::clamp(p.unit == planning::ParameterUnit::Degree ? shown * kDegree : shown, p.minimum, p.maximum);
  }
  return procedure.resolveValues(values);
}

// ------------------------------------------------------ placing and editing

void IncisionPanel::armPlace()
{
  const planning::ProcedureTemplate* procedure = currentProcedure();
  if (!procedure)
    return;
  if (!newestSkin())
  {
    host_.showError("Place on the skin", "The scene has no skin range map. Build the range maps in the Range maps "
                                         "module first, then place the procedure.");
    return;
  }
  QPointer<IncisionPanel> self(this);
  host_.pickInThreeDView("Click on the skin where the centre of the " + procedure->title() + " goes",
                         [self](const SurfacePick& pick) {
                           if (self)
                             self->placeAt(pick);
                         });
}

void IncisionPanel::placeAt(const SurfacePick& pick)
{
  const planning::ProcedureTemplate* procedure = currentProcedure();
  const RangeMapNode* skinNode = newestSkin();
  if (!procedure)
    return;
  if (!skinNode)
  {
    host_.showError("Place on the skin", "Build the range maps in the Range maps module first: the plan is drawn "
                                         "on the skin range map.");
    return;
  }
  const NodeId skinId = skinNode->id();
  const seg::RangeMap& skin = rangeMap(*skinNode);
  const seg::CylindricalPoint c =
    skin.frame().toCylindrical(Eigen::Vector3d(pick.position[0], pick.position[1], pick.position[2]));
  const planning::SkinPoint at{c.theta, c.z};
  planning::IncisionPlan plan;
  planning::PlanRecipe recipe;
  try
  {
    const std::map<std::string, double> values = formValues(*procedure);
    plan = logic_.placeProcedure(procedure->id(), skin, at, values);
    recipe.ctSha256 = ctHash(skinId);
    recipe.softwareVersion = planning::softwareVersion();
    recipe.operations.push_back(planning::PlaceProcedure{procedure->id(), at, values});
  }
  catch (const std::exception& e)
  {
    host_.showError("Place on the skin", "The " + procedure->title() + " does not fit there: " + e.what() +
                                           "\nClick nearer the middle of the measured skin, or make the cut smaller.");
    return;
  }
  if (const std::string spoiled = logic_.cutOnUnsoundSkin(plan, skin, *skinNode); !spoiled.empty())
  {
    host_.showError("Place on the skin", "The " + procedure->title() + " cannot be placed there: " + spoiled + ".");
    return;
  }
  const std::string name = addPlan(procedure->title(), plan, recipe, skinId);
  host_.showStatus(name + " placed at θ " + std::to_string(int(std::lround(at.theta / kDegree))) + "°, z " +
                   std::to_string(int(std::lround(at.z))) + " mm");
}

std::string IncisionPanel::addPlan(const std::string& title, const planning::IncisionPlan& plan,
                                   const planning::PlanRecipe& recipe, const NodeId& skinId)
{
  // "<title> <n>", n the first number no node uses.
  std::string name;
  for (int n = 1;; ++n)
  {
    name = title;
    name += " ";
    name += std::to_string(n);
    bool used = false;
    for (Node* node : logic_.scene().nodes())
      used = used || node->name() == name || node->name().rfind(name + " ", 0) == 0;
    if (!used)
      break;
  }
  NodeId planId;
  {
    writing_ = true;
    auto* node = logic_.scene().add<PlanNode>();
    node->setName(name);
    IncisionLogic::writePlan(plan, *node);
    IncisionLogic::writeRecipe(recipe, *node);
    node->setRangeMapId(skinId);
    planId = node->id();
    writing_ = false;
  }
  drawLines(planId, true);
  refreshPlans();
  for (int row = 0; row < plans_->count(); ++row)
    if (plans_->item(row)->data(Qt::UserRole).toString().toStdString() == planId)
      plans_->setCurrentRow(row);
  return name;
}

void IncisionPanel::armDraw()
{
  const RangeMapNode* skinNode = newestSkin();
  if (!skinNode)
  {
    host_.showError("Draw a cut", "Build the range maps in the Range maps module first: the cut is drawn on the "
                                  "skin range map.");
    return;
  }
  const NodeId skinId = skinNode->id();
  if (drawSkin_ != skinId)
    drawn_.clear();
  drawSkin_ = skinId;
  QPointer<IncisionPanel> self(this);
  // One point per click, in scalpel order; each click arms the next until Finish.
  host_.pickInThreeDView("Click the next point of the cut on the skin (Finish in the panel when done)",
                         [self, skinId](const SurfacePick& pick) {
                           if (!self)
                             return;
                           const auto* skin = self->logic_.scene().nodeAs<RangeMapNode>(skinId);
                           if (!skin)
                             return;
                           self->drawn_.push_back(normalizedOf(self->rangeMap(*skin), pick));
                           self->armDraw();
                         });
  drawStatus_->setText(drawn_.empty() ? tr("Click the first point of the cut on the skin.")
                                      : tr("%1 points: click the next, or Finish (at least 2).").arg(drawn_.size()));
}

void IncisionPanel::finishDraw()
{
  host_.cancelPick();
  const std::vector<Eigen::Vector2d> points = std::move(drawn_);
  drawn_.clear();
  const NodeId skinId = drawSkin_;
  drawSkin_.clear();
  const auto* skinNode = logic_.scene().nodeAs<RangeMapNode>(skinId);
  if (!skinNode || points.size() < 2)
  {
    drawStatus_->setText(points.empty() ? QString() : tr("A cut needs at least 2 points: start again."));
    return;
  }
  const seg::RangeMap& skin = rangeMap(*skinNode);
  planning::PlanRecipe recipe;
  planning::IncisionPlan plan;
  try
  {
    const planning::PlanOperation op = planning::DrawCut{points};
    plan = planning::applyOperation(plan, op, 1, skin, logic_.procedures());
    recipe.ctSha256 = ctHash(skinId);
    recipe.softwareVersion = planning::softwareVersion();
    recipe.operations.push_back(op);
  }
  catch (const std::exception& e)
  {
    host_.showError("Draw a cut", std::string(e.what()) + "\nDraw it again with points further apart, and "
                                                          "without crossing itself.");
    drawStatus_->clear();
    return;
  }
  const std::string name = addPlan("Cut", plan, recipe, skinId);
  drawStatus_->setText(tr("%1 drawn with %2 points; its lips are sewn straight back together. Offset border "
                          "points below to make an excision.")
                         .arg(QString::fromStdString(name))
                         .arg(points.size()));
}

void IncisionPanel::armMove()
{
  PlanNode* plan = selectedPlan();
  if (!plan)
    return;
  const NodeId id = plan->id();
  QPointer<IncisionPanel> self(this);
  host_.pickInThreeDView("Click on the skin where the centre of " + plan->name() + " goes",
                         [self, id](const SurfacePick& pick) {
                           if (self)
                             self->moveTo(id, pick);
                         });
}

void IncisionPanel::moveTo(const NodeId& planId, const SurfacePick& pick)
{
  auto* node = logic_.scene().nodeAs<PlanNode>(planId);
  if (!node)
    return;
  recordOperation(planId, "Move " + node->name(), [&](const planning::IncisionPlan& plan, const seg::RangeMap& skin) {
    const seg::CylindricalPoint c =
      skin.frame().toCylindrical(Eigen::Vector3d(pick.position[0], pick.position[1], pick.position[2]));
    // Placed afresh at the new centre with the values it has.
    return planning::PlanOperation(planning::PlaceProcedure{plan.procedure(), {c.theta, c.z}, plan.parameters()});
  });
}

void IncisionPanel::parameterChanged(const std::string& name)
{
  PlanNode* node = selectedPlan();
  if (!node)
    return; // the form is for the next plan placed
  const planning::ProcedureTemplate* procedure = logic_.procedures().find(node->procedure());
  if (!procedure)
    return;
  const std::map<std::string, double> values = formValues(*procedure);
  const auto value = values.find(name);
  const auto old = node->parameters().find(name);
  if (value == values.end() || (old != node->parameters().end() && old->second == value->second))
    return;
  const bool done = recordOperation(node->id(), "Set " + readable(name).toLower().toStdString() + " of " + node->name(),
                                    [&](const planning::IncisionPlan&, const seg::RangeMap&) {
                                      return planning::PlanOperation(planning::SetParameter{name, value->second});
                                    });
  if (!done)
    showSelection(); // the form shows the plan as it stayed
}

void IncisionPanel::armMovePoint()
{
  PlanNode* plan = selectedPlan();
  if (!plan)
    return;
  const NodeId id = plan->id();
  const int point = point_->value();
  QPointer<IncisionPanel> self(this);
  host_.pickInThreeDView("Click on the skin where cut point p" + std::to_string(point) + " of " + plan->name() +
                           " goes (or drag the point)",
                         [self, id, point](const SurfacePick& pick) {
                           if (self)
                             self->movePointTo(id, point, pick);
                         });
}

void IncisionPanel::movePointTo(const NodeId& planId, int point, const SurfacePick& pick)
{
  auto* node = logic_.scene().nodeAs<PlanNode>(planId);
  if (!node)
    return;
  const bool moved =
    recordOperation(planId, "Move point p" + std::to_string(point) + " of " + node->name(),
                    [&](const planning::IncisionPlan&, const seg::RangeMap& skin) {
                      return planning::PlanOperation(planning::MoveCutPoint{point, normalizedOf(skin, pick)});
                    });
  if (!moved)
    updateHandles(); // refused: the handle goes back to the point
}

void IncisionPanel::updateHandles()
{
  if (!isVisible())
    return; // the handles belong to the panel shown (hideEvent took ours away)
  const PlanNode* node = selectedPlan();
  const RangeMapNode* skinNode = node ? skinOf(*node) : nullptr;
  if (!skinNode)
  {
    host_.setThreeDViewHandles({}, nullptr);
    return;
  }
  const seg::RangeMap& skin = rangeMap(*skinNode);
  const seg::CylindricalFrame& frame = skin.frame();
  std::vector<std::array<double, 3>> points;
  for (const Eigen::Vector2d& p : node->cutPath())
  {
    const seg::CylindricalPoint c = frame.fromNormalized({1.0, p.x(), p.y()});
    const Eigen::Vector3d x = frame.toWorld(skin.sample(c.theta, c.z) + planning::kIncisionLineLift, c.theta, c.z);
    if (!x.allFinite())
    {
      points.clear(); // a point off the skin map: no handles rather than some
      break;
    }
    points.push_back({x.x(), x.y(), x.z()});
  }
  const NodeId id = node->id();
  QPointer<IncisionPanel> self(this);
  host_.setThreeDViewHandles(points, [self, id](int point, const SurfacePick& pick) {
    if (self)
      self->movePointTo(id, point, pick);
  });
}

void IncisionPanel::showEvent(QShowEvent* event)
{
  QWidget::showEvent(event);
  updateHandles();
}

void IncisionPanel::hideEvent(QHideEvent* event)
{
  QWidget::hideEvent(event);
  host_.setThreeDViewHandles({}, nullptr);
}

void IncisionPanel::offsetBorderPoint()
{
  PlanNode* node = selectedPlan();
  if (!node)
    return;
  const int vertex = borderPoint_->value();
  const planning::ChartPoint offset(offsetU_->value(), offsetV_->value());
  recordOperation(node->id(), "Offset border point " + std::to_string(vertex) + " of " + node->name(),
                  [&](const planning::IncisionPlan&, const seg::RangeMap&) {
                    return planning::PlanOperation(planning::OffsetBorderPoint{vertex, offset});
                  });
}

void IncisionPanel::armUndermine()
{
  PlanNode* node = selectedPlan();
  if (!node)
    return;
  const RangeMapNode* skinNode = skinOf(*node);
  if (!skinNode)
  {
    host_.showError("Undermine a region", "Build the range maps in the Range maps module first.");
    return;
  }
  if (regionPlan_ != node->id())
    region_.clear();
  regionPlan_ = node->id();
  const NodeId skinId = skinNode->id();
  QPointer<IncisionPanel> self(this);
  // One corner per click; each click arms the next until Finish.
  std::function<void(const SurfacePick&)> corner;
  corner = [self, skinId](const SurfacePick& pick) {
    if (!self)
      return;
    const auto* skin = self->logic_.scene().nodeAs<RangeMapNode>(skinId);
    if (!skin)
      return;
    const Eigen::Vector2d n = normalizedOf(self->rangeMap(*skin), pick);
    self->region_.push_back({n.x(), n.y()});
    self->regionStatus_->setText(tr("%1 corners: click the next, or Finish (at least 3).").arg(self->region_.size()));
    self->armUndermine();
  };
  regionStatus_->setText(region_.empty()
                           ? tr("Click the first corner of the region on the skin.")
                           : tr("%1 corners: click the next, or Finish (at least 3).").arg(region_.size()));
  host_.pickInThreeDView("Click a corner of the region to undermine (Finish in the panel when done)", corner);
}

void IncisionPanel::finishUndermining()
{
  host_.cancelPick();
  auto* node = logic_.scene().nodeAs<PlanNode>(regionPlan_);
  const std::vector<std::array<double, 2>> corners = std::move(region_);
  region_.clear();
  regionPlan_.clear();
  if (!node || corners.size() < 3)
  {
    regionStatus_->setText(corners.empty() ? QString() : tr("A region needs at least 3 corners: start again."));
    return;
  }
  planning::UnderminedRegion region;
  for (const auto& c : corners)
    region.emplace_back(c[0], c[1]);
  if (recordOperation(node->id(), "Undermine a region of " + node->name(),
                      [&](const planning::IncisionPlan&, const seg::RangeMap&) {
                        return planning::PlanOperation(planning::UndermineRegion{region});
                      }))
    regionStatus_->setText(tr("%1 undermined region(s): simulate the plan again to see their effect.")
                             .arg(IncisionLogic::readPlan(*node).underminedRegions().size()));
}

void IncisionPanel::clearUndermining()
{
  PlanNode* node = selectedPlan();
  if (!node)
    return;
  recordOperation(node->id(), "Clear the undermining of " + node->name(),
                  [&](const planning::IncisionPlan&, const seg::RangeMap&) {
                    return planning::PlanOperation(planning::ClearUndermining{});
                  });
  regionStatus_->clear();
}

bool IncisionPanel::recordOperation(
  const NodeId& planId, const std::string& label,
  const std::function<planning::PlanOperation(const planning::IncisionPlan&, const seg::RangeMap&)>& operation)
{
  return editPlan(
    planId, label, [&](planning::IncisionPlan& plan, planning::PlanRecipe& recipe, const seg::RangeMap& skin) {
      const planning::PlanOperation op = operation(plan, skin);
      plan = planning::applyOperation(plan, op, int(recipe.operations.size()) + 1, skin, logic_.procedures());
      recipe.operations.push_back(op);
    });
}

bool IncisionPanel::editPlan(
  const NodeId& planId, const std::string& label,
  const std::function<void(planning::IncisionPlan&, planning::PlanRecipe&, const seg::RangeMap&)>& edit)
{
  auto* node = logic_.scene().nodeAs<PlanNode>(planId);
  if (!node)
    return false;
  const RangeMapNode* skinNode = skinOf(*node);
  if (!skinNode)
  {
    host_.showError(label, "The scene has no skin range map for " + node->name() +
                             ". Build the range maps in the Range maps module first.");
    return false;
  }
  try
  {
    const seg::RangeMap& skin = rangeMap(*skinNode);
    planning::IncisionPlan plan = IncisionLogic::readPlan(*node);
    std::optional<planning::PlanRecipe> recipe = IncisionLogic::readRecipe(*node);
    if (!recipe)
    {
      // A plan saved before plans kept their recipe: it starts with the
      // placement it holds (moves made by hand then are not known).
      recipe.emplace();
      recipe->ctSha256 = ctHash(skinNode->id());
      recipe->operations.push_back(planning::PlaceProcedure{plan.procedure(), plan.centre(), plan.parameters()});
    }
    recipe->softwareVersion = planning::softwareVersion();
    edit(plan, *recipe, skin);
    {
      writing_ = true;
      ScopedEdit scoped(logic_.scene(), planId, label);
      IncisionLogic::writePlan(plan, *node);
      IncisionLogic::writeRecipe(*recipe, *node);
      writing_ = false;
    }
  }
  catch (const std::exception& e)
  {
    writing_ = false;
    host_.showError(label, std::string(e.what()) + "\nThe plan is left as it was: try a smaller change, or move "
                                                   "it where there is more skin around it.");
    return false;
  }
  drawLines(planId, true);
  showSelection();
  refreshButtons();
  return true;
}

void IncisionPanel::undo()
{
  UndoStack& stack = logic_.scene().undoStack();
  const std::string label = stack.undoLabel();
  if (stack.undo())
    host_.showStatus("Undone: " + label);
  refresh();
}

void IncisionPanel::redo()
{
  UndoStack& stack = logic_.scene().undoStack();
  const std::string label = stack.redoLabel();
  if (stack.redo())
    host_.showStatus("Redone: " + label);
  refresh();
}

void IncisionPanel::deletePlan()
{
  PlanNode* plan = selectedPlan();
  if (!plan)
    return;
  const std::string name = plan->name();
  const NodeId id = plan->id();
  if (Node* lines = nodeNamed(logic_.scene(), linesName(name), NodeType::Surface))
    logic_.scene().removeNode(lines->id());
  logic_.scene().removeNode(id);
  host_.showStatus(name + " deleted");
  refresh();
}

// --------------------------------------------------------------- the scene

const RangeMapNode* IncisionPanel::newestSkin() const
{
  const RangeMapNode* skin = nullptr;
  for (Node* n : logic_.scene().nodesOfType(NodeType::RangeMap))
    if (static_cast<const RangeMapNode*>(n)->role() == "skin")
      skin = static_cast<const RangeMapNode*>(n);
  return skin;
}

const RangeMapNode* IncisionPanel::skinOf(const PlanNode& plan) const
{
  if (auto* own = logic_.scene().nodeAs<RangeMapNode>(plan.rangeMapId()))
    return own;
  return newestSkin();
}

const seg::RangeMap& IncisionPanel::rangeMap(const RangeMapNode& node)
{
  auto& map = maps_[node.id()];
  if (!map || dirtyMaps_.count(node.id()))
  {
    map = std::make_shared<seg::RangeMap>(RangeMapLogic::toRangeMap(node));
    dirtyMaps_.erase(node.id());
  }
  return *map;
}

std::string IncisionPanel::ctHash(const NodeId& skinId)
{
  // A plan already made on this skin map names its CT.
  for (Node* n : logic_.scene().nodesOfType(NodeType::Plan))
  {
    const auto* plan = static_cast<const PlanNode*>(n);
    if (plan->rangeMapId() == skinId && !plan->ctSha256().empty())
      return plan->ctSha256();
  }
  // Else the CT itself, when the scene holds just one (the maps were made from it).
  const auto volumes = logic_.scene().nodesOfType(NodeType::Volume);
  if (volumes.size() != 1)
    return {};
  auto* volume = static_cast<VolumeNode*>(volumes.front());
  auto known = hashes_.find(volume->id());
  if (known != hashes_.end())
    return known->second;
  try
  {
    if (!volume->image())
      return {};
    return hashes_[volume->id()] = planning::ctContentHash(volume->image());
  }
  catch (const std::exception&)
  {
    return {};
  }
}

PlanNode* IncisionPanel::selectedPlan() const
{
  const auto selected = plans_->selectedItems();
  if (selected.isEmpty())
    return nullptr;
  return logic_.scene().nodeAs<PlanNode>(selected.front()->data(Qt::UserRole).toString().toStdString());
}

void IncisionPanel::drawLines(const NodeId& planId, bool create)
{
  auto* plan = logic_.scene().nodeAs<PlanNode>(planId);
  if (!plan)
    return;
  auto* lines = static_cast<SurfaceNode*>(nodeNamed(logic_.scene(), linesName(plan->name()), NodeType::Surface));
  if (!lines && !create)
    return;
  const RangeMapNode* skinNode = skinOf(*plan);
  if (!skinNode)
    return;
  vtkSmartPointer<vtkPolyData> data;
  try
  {
    data = planning::incisionLinesPolyData(IncisionLogic::readPlan(*plan), rangeMap(*skinNode));
  }
  catch (const std::exception& e)
  {
    host_.showWarning("Incision lines", "The lines of " + plan->name() + " cannot be drawn: " + e.what());
    return;
  }
  writing_ = true;
  if (!lines)
  {
    lines = logic_.scene().add<SurfaceNode>();
    lines->setName(linesName(plan->name()));
    lines->setColor(kLineColour);
    lines->setLineWidth(kLineWidth);
    lines->setColourArray("line_colour"); // the cut blue, undermined regions in their tint
  }
  lines->setPolyData(data);
  writing_ = false;
}

void IncisionPanel::sceneChanged(int eventValue, const Node& node)
{
  const auto event = SceneEvent(eventValue);
  if (node.type() == NodeType::RangeMap)
  {
    dirtyMaps_.insert(node.id());
    if (event == SceneEvent::NodeAboutToBeRemoved)
      maps_.erase(node.id());
  }
  if (node.type() == NodeType::Volume)
    hashes_.erase(node.id());
  if (node.type() == NodeType::Plan && !writing_)
  {
    if (event == SceneEvent::NodeModified)
      redraw_.insert(node.id());
    // Its lines go with it (not when a loaded scene replaces this one: the
    // node is out of the scene already, and the new scene has its own).
    if (event == SceneEvent::NodeAboutToBeRemoved && node.scene())
      if (Node* lines = nodeNamed(*node.scene(), linesName(node.name()), NodeType::Surface))
        dropLines_.insert(lines->id());
  }
  // A prediction made now is a prediction of the plan as it is.
  if (event == SceneEvent::NodeAdded && node.type() != NodeType::Plan && node.scene())
    for (Node* n : node.scene()->nodesOfType(NodeType::Plan))
      if (node.name().rfind(n->name() + " ", 0) == 0 && node.name() != linesName(n->name()))
        predicted_[n->id()] = planState(*static_cast<PlanNode*>(n));
  if (event == SceneEvent::NodeAboutToBeRemoved)
    predicted_.erase(node.id());
  scheduleRefresh();
}

void IncisionPanel::scheduleRefresh()
{
  if (refreshPending_)
    return;
  refreshPending_ = true;
  // After the change is complete (ScopedEdit pushes its entry after the
  // node's events; removals must not happen inside another's notification).
  QTimer::singleShot(0, this, [this] {
    refreshPending_ = false;
    refresh();
  });
}

void IncisionPanel::refresh()
{
  for (const NodeId& id : std::exchange(dropLines_, {}))
    logic_.scene().removeNode(id);
  for (const NodeId& id : std::exchange(redraw_, {}))
    drawLines(id, false);
  // Plans seen with a prediction for the first time: the prediction is of them as they are.
  for (Node* n : logic_.scene().nodesOfType(NodeType::Plan))
    if (!predicted_.count(n->id()) && hasPrediction(logic_.scene(), n->name()))
      predicted_[n->id()] = planState(*static_cast<PlanNode*>(n));
  {
    // The guide is shown when the scene has its lines (a scene saved with them, or undo).
    const QSignalBlocker block(showTension_);
    showTension_->setChecked(nodeNamed(logic_.scene(), kTensionLinesName, NodeType::Surface) != nullptr);
  }
  refreshPlans();
  showSelection();
  refreshButtons();
}

// -------------------------------------------------------- what it shows

void IncisionPanel::refreshPlans()
{
  const PlanNode* selected = selectedPlan();
  const NodeId keep = selected ? selected->id() : NodeId();
  plans_->blockSignals(true);
  plans_->clear();
  for (Node* n : logic_.scene().nodesOfType(NodeType::Plan))
  {
    auto* item = new QListWidgetItem(QString::fromStdString(n->name()), plans_);
    item->setData(Qt::UserRole, QString::fromStdString(n->id()));
    if (n->id() == keep)
      item->setSelected(true), plans_->setCurrentItem(item);
  }
  plans_->blockSignals(false);
}

void IncisionPanel::planSelected()
{
  if (PlanNode* plan = selectedPlan())
  {
    // The plan is shown on the skin while it is being looked at.
    drawLines(plan->id(), true);
    const int index = procedure_->findData(QString::fromStdString(plan->procedure()));
    if (index >= 0)
    {
      procedure_->blockSignals(true);
      procedure_->setCurrentIndex(index);
      procedure_->blockSignals(false);
    }
  }
  showSelection();
  refreshButtons();
}

void IncisionPanel::showSelection()
{
  const PlanNode* plan = selectedPlan();
  const planning::ProcedureTemplate* procedure = nullptr;
  try
  {
    procedure = plan ? logic_.procedures().find(plan->procedure()) : currentProcedure();
  }
  catch (const std::exception&)
  {}
  // Rebuilt only when the procedure changes, else updated in place (a
  // spin box being typed into keeps its focus).
  if (procedure && procedure->id() != formProcedure_)
    buildForm(*procedure, plan ? &plan->parameters() : nullptr);
  else if (procedure && plan)
    for (const auto& p : procedure->parameters())
    {
      const auto value = plan->parameters().find(p.name);
      if (value == plan->parameters().end())
        continue;
      QDoubleSpinBox* spin = spins_[p.name];
      spin->blockSignals(true);
      spin->setValue(toUi(p.unit, value->second));
      spin->blockSignals(false);
    }
  if (!procedure)
  {
    while (form_->rowCount() > 0)
      form_->removeRow(0);
    spins_.clear();
    formProcedure_.clear();
  }
  formBox_->setTitle(plan ? tr("Parameters of %1").arg(QString::fromStdString(plan->name()))
                          : tr("Parameters of the next plan"));

  if (plan && predictionOutOfDate(*plan))
    predictionStatus_->setText(
      tr("The prediction of %1 (its model, closure and skin before/after) was made before these edits: it is out "
         "of date. Re-run it in the Simulate module.")
        .arg(QString::fromStdString(plan->name())));
  else if (!newestSkin())
    predictionStatus_->setText(tr("Build the range maps in the Range maps module first: plans are drawn on the "
                                  "skin range map."));
  else
    predictionStatus_->clear();
  fillMeasurements(plan);
  updateHandles();
}

bool IncisionPanel::predictionOutOfDate(const PlanNode& plan) const
{
  const auto state = predicted_.find(plan.id());
  return state != predicted_.end() && hasPrediction(logic_.scene(), plan.name()) && state->second != planState(plan);
}

void IncisionPanel::fillMeasurements(const PlanNode* node)
{
  table_->setRowCount(0);
  if (!node)
    return;
  const RangeMapNode* skinNode = skinOf(*node);
  if (!skinNode)
    return;
  const auto row = [this](const QString& what, double value, int decimals, const QString& unit) {
    const int r = table_->rowCount();
    table_->insertRow(r);
    table_->setItem(r, 0, new QTableWidgetItem(what));
    auto* number = new QTableWidgetItem(QString::number(value, 'f', decimals));
    number->setData(Qt::UserRole, value);
    number->setTextAlignment(Qt::AlignRight | Qt::AlignVCenter);
    table_->setItem(r, 1, number);
    table_->setItem(r, 2, new QTableWidgetItem(unit));
  };
  try
  {
    const planning::IncisionPlan plan = IncisionLogic::readPlan(*node);
    const planning::PlanMeasurements m = planning::measurePlan(plan, rangeMap(*skinNode));
    for (const auto& l : m.limbs)
      row(tr("Limb p%1–p%2").arg(l.from).arg(l.to), l.skin, 2, "mm");
    for (const auto& a : m.limbAngles)
      row(tr("Angle at p%1").arg(a.point), a.skin / kDegree, 1, QString::fromUtf8("°"));
    row(tr("Excised area"), m.excisedArea, 1, QString::fromUtf8("mm²"));
    const planning::SkinTensionLines* guide = showTension_->isChecked() ? tensionLines(*skinNode) : nullptr;
    if (guide)
    {
      try
      {
        const planning::AxisToTensionLines axis = planning::axisToTensionLines(plan, *guide);
        row(tr("Axis %1 to skin tension lines").arg(QString::fromStdString(axis.axis)), axis.degrees, 0,
            QString::fromUtf8("°"));
      }
      catch (const std::invalid_argument&)
      {
        // off the part of the face the guide covers: no row
      }
    }
    const auto angle = plan.parameters().find("limb_angle");
    if ((plan.generator() == "z" || plan.generator() == "multiple-z") && angle != plan.parameters().end())
    {
      try
      {
        row(tr("Theoretical gain in length (Fig. 2.2)"), 100.0 * planning::zPlastyTheoreticalGain(angle->second), 0,
            "%");
      }
      catch (const std::invalid_argument&)
      {}
      row(tr("Geometric gain in length"), 100.0 * planning::zPlastyGeometricGain(angle->second), 0, "%");
    }
  }
  catch (const std::exception& e)
  {
    const int r = table_->rowCount();
    table_->insertRow(r);
    table_->setItem(r, 0, new QTableWidgetItem(tr("Cannot measure: %1").arg(e.what())));
  }
}

const planning::SkinTensionLines* IncisionPanel::tensionLines(const RangeMapNode& skinNode, std::string* why)
{
  const seg::RangeMap& skin = rangeMap(skinNode);
  TensionLinesOnMap& entry = tension_[skinNode.id()];
  const std::shared_ptr<seg::RangeMap>& map = maps_[skinNode.id()];
  if (entry.map != map)
  {
    entry = {map, nullptr, {}};
    try
    {
      const seg::LandmarkPlacement found = seg::placeLandmarks(skin);
      entry.lines =
        std::make_unique<planning::SkinTensionLines>(skin, planning::FaceLayout::fromLandmarks(found.landmarks, skin));
    }
    catch (const std::exception& e)
    {
      entry.why = e.what();
    }
  }
  if (why)
    *why = entry.why;
  return entry.lines.get();
}

void IncisionPanel::showTensionLines(bool show)
{
  Node* existing = nodeNamed(logic_.scene(), kTensionLinesName, NodeType::Surface);
  if (!show)
  {
    if (existing)
      logic_.scene().removeNode(existing->id());
    fillMeasurements(selectedPlan());
    return;
  }
  const RangeMapNode* skinNode = newestSkin();
  std::string why = "there is no skin range map yet: make one in the Range maps module first.";
  const planning::SkinTensionLines* guide = skinNode ? tensionLines(*skinNode, &why) : nullptr;
  if (!guide)
  {
    host_.showWarning("Skin tension lines", "The skin tension lines cannot be shown: " + why);
    const QSignalBlocker block(showTension_);
    showTension_->setChecked(false);
    return;
  }
  auto* node = static_cast<SurfaceNode*>(existing);
  if (!node)
  {
    node = logic_.scene().add<SurfaceNode>();
    node->setName(kTensionLinesName);
    node->setColor(kTensionLineColour);
    node->setLineWidth(kTensionLineWidth);
  }
  node->setPolyData(planning::skinTensionLinesPolyData(*guide));
  host_.showStatus("Skin tension lines shown (a schematic guide placed by the facial landmarks)");
  fillMeasurements(selectedPlan());
}

void IncisionPanel::refreshButtons()
{
  PlanNode* node = selectedPlan();
  const bool selected = node != nullptr;
  // Move places the procedure afresh: a cut drawn by hand has none (move its points instead).
  move_->setEnabled(selected && !node->procedure().empty());
  delete_->setEnabled(selected);
  editBox_->setEnabled(selected);
  if (node)
  {
    // The points the plan has: p0 .. p(n-1) on the cut, 0 .. loop size - 1 on the border.
    const int points = int(node->cutPath().size());
    point_->setRange(0, std::max(0, points - 1));
    borderPoint_->setRange(0, std::max(0, planning::holeLoopSize(points) - 1));
  }
  const UndoStack& stack = logic_.scene().undoStack();
  undo_->setEnabled(stack.canUndo());
  redo_->setEnabled(stack.canRedo());
  undo_->setToolTip(stack.canUndo() ? tr("Undo %1 (Ctrl+Z)").arg(QString::fromStdString(stack.undoLabel()))
                                    : tr("Nothing to undo"));
  redo_->setToolTip(stack.canRedo() ? tr("Redo %1 (Ctrl+Shift+Z)").arg(QString::fromStdString(stack.redoLabel()))
                                    : tr("Nothing to redo"));
}

} // namespace caps
