#include "modules/simulate/SimulatePanel.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <optional>
#include <sstream>

#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QFontDatabase>
#include <QFormLayout>
#include <QGroupBox>
#include <QHeaderView>
#include <QLabel>
#include <QPointer>
#include <QPushButton>
#include <QScopedValueRollback>
#include <QScrollArea>
#include <QSpinBox>
#include <QTableWidget>
#include <QThread>
#include <QTimer>
#include <QVBoxLayout>

#include "modules/incision/IncisionLogic.h"
#include "modules/simulate/LivePrediction.h"
#include "modules/simulate/PlanSimulationRun.h"
#include "modules/simulate/SimulateLogic.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/SurfaceNode.h"

namespace caps {
namespace {

constexpr int kLayerColumn = 0, kModulusColumn = 1, kPoissonColumn = 2;

QString numberText(double value, int decimals)
{
  return QString::number(value, 'f', decimals);
}

} // namespace

SimulatePanel::SimulatePanel(SimulateLogic& logic, ModuleHost& host, QWidget* parent)
  : QWidget(parent), logic_(logic), host_(host)
{
  auto* outer = new QVBoxLayout(this);
  outer->setContentsMargins(0, 0, 0, 0);
  auto* scroll = new QScrollArea(this);
  scroll->setWidgetResizable(true);
  scroll->setFrameShape(QFrame::NoFrame);
  outer->addWidget(scroll);
  auto* content = new QWidget(scroll);
  scroll->setWidget(content);
  auto* layout = new QVBoxLayout(content);

  addPlanChooser(content, layout);
  addMaterials(content, layout);
  addMeshOptions(content, layout);
  addRunAndResults(content, layout);
  setDefaults();
  connectControls();
  observeTheScene();
  updatePlans();
}

/// 1. The plan.
void SimulatePanel::addPlanChooser(QWidget* content, QVBoxLayout* layout)
{
  auto* planBox = new QGroupBox(tr("Plan"), content);
  auto* planLayout = new QVBoxLayout(planBox);
  plan_ = new QComboBox(planBox);
  plan_->setObjectName("simulate.plan");
  plan_->setToolTip(tr("The plan to predict: the scene's plans (Incision module)."));
  planLayout->addWidget(plan_);
  layout->addWidget(planBox);
}

/// 2. Materials: the preset, its source, the table per layer.
void SimulatePanel::addMaterials(QWidget* content, QVBoxLayout* layout)
{
  auto* materialBox = new QGroupBox(tr("Tissue materials (linear elastic)"), content);
  auto* materialLayout = new QVBoxLayout(materialBox);
  preset_ = new QComboBox(materialBox);
  preset_->setObjectName("simulate.preset");
  preset_->addItem(QString::fromUtf8(simulate::kFacialTissuePreset));
  preset_->addItem(tr("Custom (edited below)"));
  preset_->setToolTip(QString::fromStdString(simulate::facialTissueSource()));
  materialLayout->addWidget(preset_);
  source_ = new QLabel(tr("Assumed values from published finite element models of the face "
                          "(Chabanas 2003, Keeve 1998, Barbarino 2009, Mazza 2011), not measured on this "
                          "patient: hover for details."),
                       materialBox);
  source_->setWordWrap(true);
  source_->setToolTip(preset_->toolTip());
  source_->setStyleSheet("color: #555;");
  materialLayout->addWidget(source_);
  materials_ = new QTableWidget(0, 3, materialBox);
  materials_->setObjectName("simulate.materials");
  materials_->setHorizontalHeaderLabels({tr("Layer"), tr("E (kPa)"), QString::fromUtf8("Poisson's \u03bd")});
  materials_->horizontalHeader()->setSectionResizeMode(kLayerColumn, QHeaderView::Stretch);
  materials_->horizontalHeader()->setSectionResizeMode(kModulusColumn, QHeaderView::ResizeToContents);
  materials_->horizontalHeader()->setSectionResizeMode(kPoissonColumn, QHeaderView::ResizeToContents);
  materials_->verticalHeader()->hide();
  materials_->setToolTip(tr("Young's modulus E in kPa (1 MPa = 1000 kPa) and Poisson's ratio \u03bd of each "
                            "layer, skin first. Double-click a value to change it."));
  materialLayout->addWidget(materials_);
  layout->addWidget(materialBox);
}

/// 3. The mesh: layers, region, element size, cut depth, undermining, and
/// the estimate of the model's size.
void SimulatePanel::addMeshOptions(QWidget* content, QVBoxLayout* layout)
{
  auto* meshBox = new QGroupBox(tr("Mesh (thesis \u00a74.5)"), content);
  auto* form = new QFormLayout(meshBox);
  layers_ = new QSpinBox(meshBox);
  layers_->setObjectName("simulate.layers");
  layers_->setRange(1, 8);
  layers_->setToolTip(tr("Element layers from the skin to the bone (3: skin, fat, muscle)."));
  form->addRow(tr("Layers"), layers_);
  regionRadius_ = new QDoubleSpinBox(meshBox);
  regionRadius_->setObjectName("simulate.regionRadius");
  regionRadius_->setRange(5.0, 100.0);
  regionRadius_->setDecimals(1);
  regionRadius_->setSuffix(" mm");
  regionRadius_->setToolTip(tr("How far from the wound the model reaches (its rim is free)."));
  form->addRow(tr("Region radius"), regionRadius_);
  elementSize_ = new QDoubleSpinBox(meshBox);
  elementSize_->setObjectName("simulate.elementSize");
  elementSize_->setRange(0.5, 10.0);
  elementSize_->setDecimals(2);
  elementSize_->setSingleStep(0.5);
  elementSize_->setSuffix(" mm");
  elementSize_->setToolTip(tr("Element size at the wound; larger is faster and coarser."));
  form->addRow(tr("Element size"), elementSize_);
  cutDepth_ = new QSpinBox(meshBox);
  cutDepth_->setObjectName("simulate.cutDepth");
  cutDepth_->setSpecialValueText(tr("full thickness"));
  cutDepth_->setSuffix(tr(" layer(s)"));
  cutDepth_->setToolTip(tr("Layers the incision goes through from the skin (\u00a73.2.2); the tissue below stays "
                           "whole and undermined tissue slides on the plane at the cut's root. 0: through every "
                           "layer. Starts at the depth the procedure states."));
  form->addRow(tr("Cut depth"), cutDepth_);
  model_ = new QComboBox(meshBox);
  model_->setObjectName("simulate.model");
  model_->addItem(tr("Large deformation"), QString(planning::tissueModelId(planning::TissueModel::LargeDeformation)));
  model_->addItem(tr("Linear (preview)"), QString(planning::tissueModelId(planning::TissueModel::LinearElastic)));
  model_->setToolTip(tr("Linear: small strain, one solve, instant, but its mesh can fold where the closure moves "
                        "tissue far (the checks say so). Large deformation: neo-Hookean layers closed over load "
                        "increments, the prediction to trust; slower."));
  form->addRow(tr("Tissue model"), model_);
  undermining_ = new QDoubleSpinBox(meshBox);
  undermining_->setObjectName("simulate.undermining");
  undermining_->setRange(0.0, 50.0);
  undermining_->setDecimals(1);
  undermining_->setSuffix(" mm");
  undermining_->setSpecialValueText(tr("none"));
  undermining_->setToolTip(tr("Skin freed from the tissue beneath within this distance of the sutured edges "
                              "(\u00a73.2.4); it slides on the deep plane. Starts at the band the procedure "
                              "undermines by default."));
  form->addRow(tr("Undermining"), undermining_);
  const planning::SkinPreTension tension;
  tensionAlong_ = new QDoubleSpinBox(meshBox);
  tensionAlong_->setObjectName("simulate.tensionAlong");
  tensionAcross_ = new QDoubleSpinBox(meshBox);
  tensionAcross_->setObjectName("simulate.tensionAcross");
  for (QDoubleSpinBox* box : {tensionAlong_, tensionAcross_})
  {
    box->setRange(0.0, 200.0);
    box->setDecimals(1);
    box->setSuffix(" N/m");
    box->setToolTip(tr("The tension living skin carries before the cut, along and across the relaxed skin "
                       "tension lines (placed from the face's landmarks): the wound gapes under it and the "
                       "sutures close it against it. Default %1 and %2 N/m: in-vivo skin tension (Flynn, "
                       "Taberner and Nielsen 2011). Both 0: slack skin, as the thesis.")
                      .arg(tension.alongLines * 1e3)
                      .arg(tension.acrossLines * 1e3));
  }
  form->addRow(tr("Skin tension along lines"), tensionAlong_);
  form->addRow(tr("Skin tension across lines"), tensionAcross_);
  estimate_ = new QLabel(meshBox);
  estimate_->setObjectName("simulate.estimate");
  estimate_->setWordWrap(true);
  form->addRow(estimate_);
  layout->addWidget(meshBox);
}

/// 4. Run, 5. results, 6. the mesh.
void SimulatePanel::addRunAndResults(QWidget* content, QVBoxLayout* layout)
{
  run_ = new QPushButton(tr("Run simulation (F5)"), content);
  run_->setObjectName("simulate.run");
  run_->setShortcut(QKeySequence(Qt::Key_F5)); // a button's shortcut acts only while it is shown
  run_->setToolTip(tr("Predict the closure of the plan in the background (Cancel in the status bar)."));
  layout->addWidget(run_);
  live_ = new QCheckBox(tr("Predict as the plan is edited"), content);
  live_->setObjectName("simulate.live");
  live_->setToolTip(tr("After each edit of the plan: the linear preview at once, then the large-deformation "
                       "prediction in the background, which replaces it when it is done. The next edit "
                       "stops what is still running."));
  layout->addWidget(live_);
  liveStatus_ = new QLabel(content);
  liveStatus_->setObjectName("simulate.liveStatus");
  liveStatus_->setWordWrap(true);
  liveStatus_->hide();
  layout->addWidget(liveStatus_);
  showMesh_ = new QCheckBox(tr("Show the model: element edges, fixed nodes (red), sutures (green)"), content);
  showMesh_->setObjectName("simulate.showMesh");
  showMesh_->setToolTip(tr("The finite element model before the closure, drawn as engineering drawings do "
                           "(\u00a73.3.1): the skin's element edges (blue), the nodes the bone holds (red "
                           "points), each suture from node to node (green)."));
  layout->addWidget(showMesh_);
  summary_ = new QLabel(content);
  summary_->setObjectName("simulate.summary");
  summary_->setWordWrap(true);
  summary_->setTextInteractionFlags(Qt::TextSelectableByMouse);
  summary_->setText(tr("Run a plan to see its closure force and skin stress here."));
  layout->addWidget(summary_);
  layout->addStretch(1);
}

/// The estimate's timer and the default options (the first plan's own
/// values replace them).
void SimulatePanel::setDefaults()
{
  const planning::SimulationOptions defaults;
  estimateTimer_ = new QTimer(this);
  estimateTimer_->setSingleShot(true);
  estimateTimer_->setInterval(300);
  connect(estimateTimer_, &QTimer::timeout, this, &SimulatePanel::estimate);
  liveTimer_ = new QTimer(this);
  liveTimer_->setSingleShot(true);
  liveTimer_->setInterval(150);
  connect(liveTimer_, &QTimer::timeout, this, &SimulatePanel::predictLive);
  livePrediction_ = new simulate::LivePrediction(
    [this](simulate::LiveStage stage, const auto& input, const auto& result, double seconds) {
      liveReady(stage, input, result, seconds);
    },
    [this](simulate::LiveStage stage, double fraction, const std::string& step) {
      // Under what is shown, so the preview stays named while the prediction runs.
      const QString what = stage == simulate::LiveStage::Preview ? tr("Linear preview") : tr("Prediction");
      QString text = liveShown_.isEmpty() ? QString() : liveShown_ + "\n";
      text += tr("%1: %2 % (%3)").arg(what).arg(int(std::lround(100 * fraction))).arg(QString::fromStdString(step));
      liveStatus_->setText(text);
    },
    [this](simulate::LiveStage stage, const std::string& message) { liveFailed(stage, message); }, this);

  layers_->setValue(defaults.layerCount);
  cutDepth_->setRange(0, defaults.layerCount);
  regionRadius_->setValue(defaults.regionRadius);
  elementSize_->setValue(defaults.elementSize);
  undermining_->setValue(0.0); // until a plan is chosen: loadPlanOptions() shows its band
  tensionAlong_->setValue(planning::SkinPreTension{}.alongLines * 1e3);
  tensionAcross_->setValue(planning::SkinPreTension{}.acrossLines * 1e3);
  resizeMaterials(defaults.layerCount);
}

void SimulatePanel::connectControls()
{
  connect(plan_, qOverload<int>(&QComboBox::currentIndexChanged), this, [this]() {
    if (loading_)
      return;
    loadPlanOptions();
    applyShowMesh();
  });
  connect(preset_, qOverload<int>(&QComboBox::activated), this, [this](int index) {
    if (index == 0)
      fillMaterialsFromPreset();
  });
  connect(materials_, &QTableWidget::itemChanged, this, &SimulatePanel::materialEdited);
  connect(layers_, qOverload<int>(&QSpinBox::valueChanged), this, [this](int layers) {
    cutDepth_->setMaximum(layers);
    resizeMaterials(layers);
    scheduleEstimate();
  });
  for (QDoubleSpinBox* box : {regionRadius_, elementSize_, undermining_, tensionAlong_, tensionAcross_})
    connect(box, qOverload<double>(&QDoubleSpinBox::valueChanged), this, &SimulatePanel::scheduleEstimate);
  connect(cutDepth_, qOverload<int>(&QSpinBox::valueChanged), this, &SimulatePanel::scheduleEstimate);
  connect(run_, &QPushButton::clicked, this, &SimulatePanel::run);
  connect(live_, &QCheckBox::toggled, this, [this](bool on) {
    liveStatus_->setVisible(on);
    if (on)
      predictLive();
    else
    {
      livePrediction_->cancel();
      liveTimer_->stop();
    }
  });
  connect(showMesh_, &QCheckBox::toggled, this, &SimulatePanel::applyShowMesh);
}

/// Plans come and go with the scene; the combo follows (once per burst of events).
void SimulatePanel::observeTheScene()
{
  observer_ = logic_.scene().addObserver([this](SceneEvent event, const Node& node) {
    if (event == SceneEvent::NodeModified && node.type() == NodeType::Plan)
      planEdited(node);
    if (node.type() != NodeType::Plan && node.type() != NodeType::RangeMap && node.type() != NodeType::Surface)
      return;
    if (updatePending_)
      return;
    updatePending_ = true;
    QTimer::singleShot(0, this, [this]() {
      updatePending_ = false;
      updatePlans();
    });
  });
}

SimulatePanel::~SimulatePanel()
{
  logic_.scene().removeObserver(observer_);
  delete livePrediction_; // cancels its run and waits for it, before the widgets it reports to go
  // The estimate's thread posts to this panel: let it end first (meshing only, short).
  if (estimateThread_)
  {
    estimateThread_->wait();
    delete estimateThread_;
  }
}

NodeId SimulatePanel::currentPlan() const
{
  return plan_->currentData().toString().toStdString();
}

void SimulatePanel::updatePlans()
{
  const NodeId chosen = currentPlan();
  const QString chosenName = plan_->currentText();
  loading_ = true;
  plan_->clear();
  int keep = -1, sameName = -1;
  for (Node* n : logic_.scene().nodesOfType(NodeType::Plan))
  {
    const QString name = QString::fromStdString(n->name());
    plan_->addItem(name, QString::fromStdString(n->id()));
    if (n->id() == chosen)
      keep = plan_->count() - 1;
    if (sameName < 0 && name == chosenName)
      sameName = plan_->count() - 1;
  }
  // A run replaces the plan node by one of the same name: stay on it.
  const int index = keep >= 0 ? keep : (sameName >= 0 ? sameName : (plan_->count() > 0 ? 0 : -1));
  plan_->setCurrentIndex(index);
  loading_ = false;
  run_->setEnabled(plan_->count() > 0);
  if (plan_->count() == 0)
    estimate_->setText(tr("No plan in the scene: place one in the Incision module."));
  if (currentPlan() != chosen)
  {
    // A new plan chosen: its own values, unless it is the same plan re-made by a run.
    if (keep < 0 && sameName < 0)
      loadPlanOptions();
    else
      scheduleEstimate();
  }
  showMesh_->setEnabled(plan_->count() > 0);
  applyShowMesh();
}

void SimulatePanel::loadPlanOptions()
{
  const auto* node = logic_.scene().nodeAs<PlanNode>(currentPlan());
  if (!node)
    return;
  const planning::SimulationOptions o = IncisionLogic::simulationOptions(*node);
  loading_ = true;
  layers_->setValue(o.layerCount);
  cutDepth_->setMaximum(o.layerCount);
  cutDepth_->setValue(o.cutLayers.value_or(planning::layersCutTo(
    planning::cutDepthFromId(node->cutDepth()).value_or(planning::CutDepth::Bone), o.layerCount)));
  regionRadius_->setValue(o.regionRadius);
  elementSize_->setValue(o.elementSize);
  undermining_->setValue(o.underminingWidth.value_or(node->underminingBand()));
  tensionAlong_->setValue(o.preTension ? o.preTension->alongLines * 1e3 : 0.0);
  tensionAcross_->setValue(o.preTension ? o.preTension->acrossLines * 1e3 : 0.0);
  model_->setCurrentIndex(std::max(0, model_->findData(QString(planning::tissueModelId(o.model)))));
  loading_ = false;
  if (o.materials.empty())
    fillMaterialsFromPreset();
  else
  {
    const QSignalBlocker block(materials_);
    materials_->setRowCount(0);
    resizeMaterials(o.layerCount);
    for (int layer = 0; layer < o.layerCount; ++layer)
    {
      materials_->item(layer, kModulusColumn)->setText(numberText(o.materials.at(layer).youngsModulus * 1e3, 2));
      materials_->item(layer, kPoissonColumn)->setText(numberText(o.materials.at(layer).poissonRatio, 3));
    }
    bool preset = true;
    for (const auto& [layer, m] : planning::defaultFacialTissueMaterials(o.layerCount))
      preset = preset && o.materials.count(layer) && o.materials.at(layer).youngsModulus == m.youngsModulus &&
               o.materials.at(layer).poissonRatio == m.poissonRatio;
    preset_->setCurrentIndex(preset ? 0 : 1);
  }
  scheduleEstimate();
}

void SimulatePanel::resizeMaterials(int layers)
{
  const QSignalBlocker block(materials_);
  const fem::MaterialTable preset = planning::defaultFacialTissueMaterials(layers);
  const int old = materials_->rowCount();
  materials_->setRowCount(layers);
  for (int layer = old; layer < layers; ++layer)
  {
    auto* name = new QTableWidgetItem(QString::fromStdString(simulate::layerName(layer)));
    name->setFlags(Qt::ItemIsEnabled);
    materials_->setItem(layer, kLayerColumn, name);
    materials_->setItem(layer, kModulusColumn,
                        new QTableWidgetItem(numberText(preset.at(layer).youngsModulus * 1e3, 2)));
    materials_->setItem(layer, kPoissonColumn, new QTableWidgetItem(numberText(preset.at(layer).poissonRatio, 3)));
  }
  // Tall enough for every row without a scroll bar.
  int height = materials_->horizontalHeader()->sizeHint().height() + 2 * materials_->frameWidth();
  for (int row = 0; row < layers; ++row)
    height += materials_->rowHeight(row);
  materials_->setFixedHeight(height);
}

void SimulatePanel::fillMaterialsFromPreset()
{
  {
    const QSignalBlocker block(materials_);
    materials_->setRowCount(0);
  }
  resizeMaterials(layers_->value());
  const QSignalBlocker block(preset_);
  preset_->setCurrentIndex(0);
}

void SimulatePanel::materialEdited(QTableWidgetItem* item)
{
  if (!item || item->column() == kLayerColumn)
    return;
  {
    const QSignalBlocker block(preset_);
    preset_->setCurrentIndex(1);
  }
  const int row = item->row();
  bool okE = false, okNu = false;
  const double e = materials_->item(row, kModulusColumn)->text().trimmed().toDouble(&okE);
  const double nu = materials_->item(row, kPoissonColumn)->text().trimmed().toDouble(&okNu);
  std::string problem;
  if (!okE || !okNu)
    problem = "type a number";
  else
    problem = planning::materialProblem(e / 1e3, nu);
  const QSignalBlocker block(materials_);
  item->setBackground(problem.empty() ? QBrush() : QBrush(QColor(255, 200, 200)));
  if (!problem.empty())
    host_.showError("Material of " + simulate::layerName(row),
                    "\"" + item->text().toStdString() + "\" is refused: " + problem +
                      ". Correct it, or choose the preset again; nothing runs until it is valid.");
}

planning::SimulationOptions SimulatePanel::options(std::string* problem) const
{
  planning::SimulationOptions o;
  o.layerCount = layers_->value();
  o.cutLayers = cutDepth_->value();
  o.regionRadius = regionRadius_->value();
  o.elementSize = elementSize_->value();
  o.underminingWidth = undermining_->value();
  if (tensionAlong_->value() > 0.0 || tensionAcross_->value() > 0.0)
  {
    o.preTension = planning::SkinPreTension{};
    o.preTension->alongLines = tensionAlong_->value() / 1e3;
    o.preTension->acrossLines = tensionAcross_->value() / 1e3;
  }
  o.model = planning::tissueModelFromId(model_->currentData().toString().toStdString()).value_or(o.model);
  o.threads = std::max(1, std::min(2, QThread::idealThreadCount()));
  for (int layer = 0; layer < materials_->rowCount(); ++layer)
  {
    bool okE = false, okNu = false;
    const double e = materials_->item(layer, kModulusColumn)->text().trimmed().toDouble(&okE) / 1e3;
    const double nu = materials_->item(layer, kPoissonColumn)->text().trimmed().toDouble(&okNu);
    const std::string wrong = okE && okNu ? planning::materialProblem(e, nu) : std::string("not a number");
    if (!wrong.empty())
    {
      if (problem && problem->empty())
        *problem = "the material of " + simulate::layerName(layer) + " is refused: " + wrong;
      continue;
    }
    o.materials[layer] = fem::LinearElasticMaterial{e, nu, 1.0e-9};
  }
  return o;
}

void SimulatePanel::scheduleEstimate()
{
  if (loading_)
    return;
  ++estimateGeneration_;
  estimate_->setText(tr("Model size: estimating..."));
  estimateTimer_->start();
}

void SimulatePanel::estimate()
{
  if (estimateThread_)
  {
    estimateAgain_ = true; // one at a time; the newest parameters next
    return;
  }
  if (plan_->count() == 0)
    return;
  std::string problem;
  planning::SimulationOptions o = options(&problem);
  auto input = std::make_shared<simulate::PlanRunInput>();
  try
  {
    *input = simulate::preparePlanRun(logic_.scene(), currentPlan(), o);
  }
  catch (const std::exception& e)
  {
    estimate_->setText(tr("Cannot mesh this plan: %1").arg(QString::fromStdString(e.what())));
    return;
  }
  const int generation = estimateGeneration_;
  estimateThread_ = QThread::create([this, input, generation]() {
    QString text;
    try
    {
      const simulate::ModelSize size = simulate::estimateModel(*input);
      text = tr("Model: %1 nodes, %2 elements, %3 DOF (meshed in %4 s)")
               .arg(size.nodes)
               .arg(size.elements)
               .arg(size.dofs)
               .arg(size.seconds, 0, 'f', 2);
    }
    catch (const std::exception& e)
    {
      text = tr("Cannot mesh this plan: %1").arg(QString::fromStdString(e.what()));
    }
    QMetaObject::invokeMethod(
      this,
      [this, text, generation]() {
        estimateThread_->wait();
        estimateThread_->deleteLater();
        estimateThread_ = nullptr;
        if (generation == estimateGeneration_)
          estimate_->setText(text);
        if (estimateAgain_ || generation != estimateGeneration_)
        {
          estimateAgain_ = false;
          estimate();
        }
      },
      Qt::QueuedConnection);
  });
  estimateThread_->start();
}

void SimulatePanel::run()
{
  if (plan_->count() == 0)
  {
    host_.showError("Simulate", "There is no plan to simulate: place one in the Incision module first.");
    return;
  }
  std::string problem;
  const planning::SimulationOptions o = options(&problem);
  if (!problem.empty())
  {
    host_.showError("Simulate", "Not run: " + problem + ". Correct the value in the material table.");
    return;
  }
  auto input = std::make_shared<simulate::PlanRunInput>();
  try
  {
    *input = simulate::preparePlanRun(logic_.scene(), currentPlan(), o);
  }
  catch (const std::exception& e)
  {
    host_.showError("Simulate", e.what());
    return;
  }
  // A plan saved in a scene (or replayed) before its CT's metal was known:
  // refused here as the Incision panel and `caps plan` refuse it.
  if (const auto* skinNode = logic_.scene().nodeAs<RangeMapNode>(input->skinMapId))
    if (const std::string spoiled = IncisionLogic(logic_.scene()).cutOnUnsoundSkin(input->plan, input->skin, *skinNode);
        !spoiled.empty())
    {
      host_.showError("Simulate", "Not run: " + spoiled);
      return;
    }
  livePrediction_->cancel(); // the run replaces what it would show
  Scene& scene = logic_.scene();
  QPointer<SimulatePanel> panel(this);
  ModuleHost& host = host_;
  host_.runTask("Simulating " + input->name, [input, &scene, panel, &host](const TaskProgress& progress) {
    const auto start = std::chrono::steady_clock::now();
    auto result = std::make_shared<simulate::PlanRunResult>(simulate::runPlan(*input, progress));
    const double workSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return std::function<void()>([input, result, &scene, panel, &host, workSeconds]() {
      const bool show = panel && panel->showMesh_->isChecked();
      {
        std::optional<QScopedValueRollback<bool>> ours; // our own scene writes are not edits
        if (panel)
          ours.emplace(panel->applying_, true);
        simulate::addPlanRun(scene, *input, *result, show);
      }
      if (panel)
      {
        // The predicted skin lies on the head's: the Results module shows it
        // without the head in the way, with the deformation slider.
        panel->summary_->setText(QString::fromStdString(input->name + "\n" + simulate::summaryText(*result)) +
                                 tr("\nSee the predicted face in the Results module."));
      }
      std::ostringstream status;
      status << "Prediction of '" << input->name << "' done (" << std::fixed << std::setprecision(1) << workSeconds
             << " s of computation)";
      host.showStatus(status.str());
    });
  });
}

void SimulatePanel::planEdited(const Node& node)
{
  if (applying_ || !live_->isChecked() || node.name() != plan_->currentText().toStdString())
    return;
  // Whatever runs was made for the state before this edit: its results
  // must not land on the edited plan.
  livePrediction_->cancel();
  liveShown_.clear();
  liveStatus_->setText(tr("The plan changed: predicting it again..."));
  liveTimer_->start();
}

void SimulatePanel::predictLive()
{
  if (!live_->isChecked() || plan_->count() == 0)
    return;
  std::string problem;
  const planning::SimulationOptions o = options(&problem);
  if (!problem.empty())
  {
    liveStatus_->setText(
      tr("Not predicted: %1. Correct the value in the material table.").arg(QString::fromStdString(problem)));
    return;
  }
  try
  {
    livePrediction_->request(simulate::preparePlanRun(logic_.scene(), currentPlan(), o));
  }
  catch (const std::exception& e)
  {
    liveStatus_->setText(tr("Not predicted: %1").arg(QString::fromStdString(e.what())));
    return;
  }
  liveStatus_->setText(o.model == planning::TissueModel::LinearElastic
                         ? tr("Predicting (linear)...")
                         : tr("Linear preview, then the large-deformation prediction..."));
}

void SimulatePanel::liveReady(simulate::LiveStage stage, const std::shared_ptr<const simulate::PlanRunInput>& input,
                              const std::shared_ptr<const simulate::PlanRunResult>& result, double seconds)
{
  // The plan may have been edited, renamed or removed since: then this is
  // not its prediction (the edit has cancelled the run, and starts its own).
  if (!simulate::planUnchangedSince(logic_.scene(), *input))
    return;
  try
  {
    const QScopedValueRollback<bool> ours(applying_, true); // our own scene writes are not edits
    simulate::addPlanRun(logic_.scene(), *input, *result, showMesh_->isChecked(), true);
  }
  catch (const std::exception& e)
  {
    livePrediction_->cancel();
    liveStatus_->setText(
      tr("The prediction could not be put into the scene: %1").arg(QString::fromStdString(e.what())));
    return;
  }
  const bool preview = stage == simulate::LiveStage::Preview;
  const planning::PredictionCheck& check = result->prediction.check;
  QString text = preview ? tr("Linear preview shown (%1 s); the large-deformation prediction is running...")
                 : check.model == planning::TissueModel::LargeDeformation
                   ? tr("Large-deformation prediction shown (%1 s).")
                   : tr("Linear prediction shown (%1 s).");
  text = text.arg(seconds, 0, 'f', 1);
  if (!preview && !check.admissible())
    text += "\n" + QString::fromStdString(planning::checkWarning(check));
  liveShown_ = preview ? tr("Linear preview shown (%1 s).").arg(seconds, 0, 'f', 1) : QString();
  liveStatus_->setText(text);
  summary_->setText(QString::fromStdString(input->name + "\n" + simulate::summaryText(*result)) +
                    tr("\nSee the predicted face in the Results module."));
}

void SimulatePanel::liveFailed(simulate::LiveStage stage, const std::string& message)
{
  const QString why = QString::fromStdString(message);
  liveStatus_->setText(
    stage == simulate::LiveStage::Preview
      ? tr("Cannot predict this plan: %1").arg(why)
      : tr("The large-deformation prediction failed: %1\nThe linear preview shown is not the "
           "prediction: change the plan (more undermining, a larger element size) and it is predicted again.")
          .arg(why));
}

void SimulatePanel::applyShowMesh()
{
  const auto* plan = logic_.scene().nodeAs<PlanNode>(currentPlan());
  if (!plan)
    return;
  const std::string name = plan->name() + " mesh";
  for (Node* n : logic_.scene().nodesOfType(NodeType::Surface))
    if (n->name() == name)
    {
      auto* surface = static_cast<SurfaceNode*>(n);
      if (surface->visible() != showMesh_->isChecked())
        surface->setVisible(showMesh_->isChecked());
    }
}

} // namespace caps
