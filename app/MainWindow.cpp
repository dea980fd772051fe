#include "app/MainWindow.h"

#include <algorithm>
#include <iostream>

#include <QAction>
#include <QApplication>
#include <QCloseEvent>
#include <QComboBox>
#include <QDockWidget>
#include <QDragEnterEvent>
#include <QDropEvent>
#include <QKeyEvent>
#include <QFileDialog>
#include <QGridLayout>
#include <QLabel>
#include <QMenuBar>
#include <QMessageBox>
#include <QMimeData>
#include <QProgressBar>
#include <QPushButton>
#include <QScrollArea>
#include <QSettings>
#include <QStackedWidget>
#include <QStatusBar>
#include <QThread>
#include <QTimer>
#include <QToolBar>
#include <QVBoxLayout>

#include <vtkCamera.h>
#include <vtkImageData.h>
#include <vtkLookupTable.h>
#include <vtkMatrix3x3.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkWindowToImageFilter.h>

#include "app/Session.h"
#include "scene/LabelMapNode.h"
#include "scene/LandmarksNode.h"
#include "scene/SceneBundle.h"
#include "scene/ScopedEdit.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"
#include "segmentation/WindowLevel.h"
#include "ui/SliceView.h"
#include "ui/ThreeDView.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

constexpr int kMaxRecent = 8;

bool isSceneBundle(const fs::path& path)
{
  std::error_code ec;
  return fs::is_directory(path, ec) && (path.extension() == ".caps" || fs::exists(path / "scene.json", ec));
}

} // namespace

MainWindow::MainWindow(Session& session, QWidget* parent) : QMainWindow(parent), session_(session)
{
  setWindowTitle("CAPS - Computer-Aided Plastic Surgery");
  setAcceptDrops(true);
  buildViews();
  buildStatusBar();
  buildModulePanels();
  buildMenus();
  observeScene();
  resize(1400, 900);
  // The layout the user left (dock width, toolbars, window size) comes back.
  QSettings settings; // the application's: tests run under their own organisation name
  restoreGeometry(settings.value("window/geometry").toByteArray());
  restoreState(settings.value("window/state").toByteArray());
}

MainWindow::~MainWindow()
{
  if (task_thread_)
  {
    cancel_requested_ = true;
    task_thread_->wait();
  }
  session_.scene().removeObserver(observer_);
  // Panels observe the scene and refer to module logic: they go first.
  delete panels_;
  panels_ = nullptr;
}

void MainWindow::buildViews()
{
  auto* central = new QWidget(this);
  auto* grid = new QGridLayout(central);
  grid->setContentsMargins(2, 2, 2, 2);
  grid->setSpacing(2);
  view3d_ = new ui::ThreeDView(central);
  slice_views_[0] = new ui::SliceView(ui::SliceOrientation::Axial, central);
  slice_views_[1] = new ui::SliceView(ui::SliceOrientation::Coronal, central);
  slice_views_[2] = new ui::SliceView(ui::SliceOrientation::Sagittal, central);
  // 3D top left, then axial, coronal, sagittal (the usual four-up layout).
  grid->addWidget(view3d_, 0, 0);
  grid->addWidget(slice_views_[0], 0, 1);
  grid->addWidget(slice_views_[1], 1, 0);
  grid->addWidget(slice_views_[2], 1, 1);
  setCentralWidget(central);

  for (ui::SliceView* view : slice_views_)
  {
    connect(view, &ui::SliceView::clicked, this, [this](double x, double y, double z) { moveCursor({x, y, z}); });
    connect(view, &ui::SliceView::hovered, this, &MainWindow::showCursorInfo);
    connect(view, &ui::SliceView::windowLevelChanged, this, &MainWindow::applyWindowLevel);
    connect(view, &ui::SliceView::rulerMeasured, this, [this, view](double) { keepRuler(*view); });
    connect(view, &ui::SliceView::sliceChanged, this,
            [this, view](int) { view3d_->setCursorPosition(view->cursorPosition()); });
  }

  connect(view3d_, &ui::ThreeDView::surfaceClicked, this, [this](const QString& key, double x, double y, double z) {
    if (!pick_handler_)
      return;
    // One click, one pick: the handler may arm the next one itself.
    auto handler = std::move(pick_handler_);
    pick_handler_ = nullptr;
    view3d_->setHandlesGrabbable(true);
    view3d_->unsetCursor();
    statusBar()->clearMessage();
    try
    {
      handler(SurfacePick{{x, y, z}, key.toStdString()});
    }
    catch (const std::exception& e)
    {
      showError("Pick", e.what());
    }
  });

  connect(view3d_, &ui::ThreeDView::handleDropped, this,
          [this](int index, const QString& key, double x, double y, double z) {
            if (!handle_handler_)
              return;
            auto handler = handle_handler_; // the handler may replace the handles (and itself)
            try
            {
              handler(index, SurfacePick{{x, y, z}, key.toStdString()});
            }
            catch (const std::exception& e)
            {
              showError("Drag", e.what());
            }
          });

  auto* toolbar = addToolBar(tr("Views"));
  toolbar->setObjectName("ViewsToolBar");
  toolbar->addWidget(new QLabel(tr(" Module: "), this));
  module_selector_ = new QComboBox(this);
  module_selector_->setObjectName("ModuleSelector");
  toolbar->addWidget(module_selector_);
  toolbar->addSeparator();
  toolbar->addWidget(new QLabel(tr(" Window/level: "), this));
  presets_ = new QComboBox(this);
  for (const auto& preset : seg::kWindowPresets)
    presets_->addItem(QString::fromUtf8(preset.name.data(), static_cast<int>(preset.name.size())));
  toolbar->addWidget(presets_);
  connect(presets_, qOverload<int>(&QComboBox::activated), this, [this](int index) {
    const auto& preset = seg::kWindowPresets[static_cast<size_t>(index)];
    applyWindowLevel(preset.window, preset.level);
  });
}

void MainWindow::buildStatusBar()
{
  cursor_info_ = new QLabel(this);
  cursor_info_->setMinimumWidth(420);
  statusBar()->addPermanentWidget(cursor_info_);
  progress_label_ = new QLabel(this);
  progress_ = new QProgressBar(this);
  progress_->setRange(0, 1000);
  progress_->setMaximumWidth(220);
  cancel_ = new QPushButton(tr("Cancel"), this);
  statusBar()->addPermanentWidget(progress_label_);
  statusBar()->addPermanentWidget(progress_);
  statusBar()->addPermanentWidget(cancel_);
  progress_label_->hide();
  progress_->hide();
  cancel_->hide();
  connect(cancel_, &QPushButton::clicked, this, [this]() {
    cancel_requested_ = true;
    cancel_->setEnabled(false);
    progress_label_->setText(progress_label_->text() + tr(" (cancelling)"));
  });
}

void MainWindow::buildModulePanels()
{
  panels_ = new QStackedWidget;
  auto* dock = new QDockWidget(tr("Module"), this);
  dock->setObjectName("ModuleDock");
  dock->setFeatures(QDockWidget::DockWidgetMovable | QDockWidget::DockWidgetFloatable);
  dock->setWidget(panels_);
  addDockWidget(Qt::LeftDockWidgetArea, dock);

  // The selector lists the modules in the order of the work (§5.6: fewer
  // choices, in the order a surgeon makes them); modules not named here follow.
  static const std::vector<std::string> workOrder{"volumes",  "segment", "rangemap",   "incision",
                                                  "simulate", "results", "expression", "report"};
  std::vector<const ModuleManager::Loaded*> ordered;
  for (const auto& loaded : session_.modules().modules())
    ordered.push_back(&loaded);
  auto rank = [](const std::string& name) {
    return std::find(workOrder.begin(), workOrder.end(), name) - workOrder.begin();
  };
  std::stable_sort(ordered.begin(), ordered.end(),
                   [&](const auto* a, const auto* b) { return rank(a->module->name()) < rank(b->module->name()); });
  for (const auto* loaded : ordered)
  {
    const Module& module = *loaded->module;
    QWidget* panel = module.createPanel(session_.logic(module), *this, panels_);
    if (!panel)
    {
      panel = new QLabel(QString::fromStdString(module.help()), panels_);
      static_cast<QLabel*>(panel)->setWordWrap(true);
    }
    // Long panels (the thickness review) scroll instead of squeezing.
    auto* scroll = new QScrollArea(panels_);
    scroll->setWidgetResizable(true);
    scroll->setFrameShape(QFrame::NoFrame);
    scroll->setHorizontalScrollBarPolicy(Qt::ScrollBarAlwaysOff);
    scroll->setWidget(panel);
    panels_->addWidget(scroll);
    module_selector_->addItem(QString::fromStdString(module.title()), QString::fromStdString(module.name()));
  }
  if (session_.modules().modules().empty())
  {
    panels_->addWidget(new QLabel(tr("No module loaded: run caps --list-modules to see why."), panels_));
  }
  connect(module_selector_, qOverload<int>(&QComboBox::currentIndexChanged), this, [this](int index) {
    // A pick or a marker belongs to the panel that asked for it.
    cancelPick();
    setThreeDViewHandles({}, nullptr);
    showMeasuredSegment(std::nullopt);
    view3d_->hideMarker();
    panels_->setCurrentIndex(index);
  });
  // The work starts with loading a CT.
  const int start = module_selector_->findData(QString("volumes"));
  if (start >= 0)
    module_selector_->setCurrentIndex(start);
  dock->setMinimumWidth(380);
}

void MainWindow::buildMenus()
{
  QMenu* file = menuBar()->addMenu(tr("&File"));
  file->addAction(tr("Open &DICOM folder..."), this, [this]() {
    const QString folder = QFileDialog::getExistingDirectory(this, tr("Open a DICOM folder"));
    if (!folder.isEmpty())
      openPath(folder.toStdString());
  });
  file->addAction(tr("Open &image file..."), this, [this]() {
    const QString name =
      QFileDialog::getOpenFileName(this, tr("Open a CT image"), QString(),
                                   tr("CT images (*.nii *.nii.gz *.nrrd *.nhdr *.mha *.mhd *.dcm);;All files (*)"));
    if (!name.isEmpty())
      openPath(name.toStdString());
  });
  file->addSeparator();
  file->addAction(
    tr("&Open scene..."), this,
    [this]() {
      const QString folder = QFileDialog::getExistingDirectory(this, tr("Open a scene bundle (NAME.caps)"));
      if (!folder.isEmpty())
        openPath(folder.toStdString());
    },
    QKeySequence::Open);
  file->addAction(
    tr("&Save scene"), this, [this]() { saveScene(false); }, QKeySequence::Save);
  file->addAction(
    tr("Save scene &as..."), this, [this]() { saveScene(true); }, QKeySequence::SaveAs);
  recent_menu_ = file->addMenu(tr("&Recent"));
  updateRecentMenu();
  // What the modules add to the File menu (the report's export and print).
  bool separated = false;
  for (const auto& loaded : session_.modules().modules())
    for (const ModuleAction& action : loaded.module->actions())
    {
      if (action.menu != "File")
        continue;
      if (!separated)
        file->addSeparator();
      separated = true;
      const Module* module = loaded.module.get();
      QAction* entry = file->addAction(QString::fromStdString(action.title), this, [this, module, action]() {
        try
        {
          action.run(session_.logic(*module), *this);
        }
        catch (const std::exception& e)
        {
          showError(action.title, e.what());
        }
      });
      if (!action.shortcut.empty())
        entry->setShortcut(QKeySequence(QString::fromStdString(action.shortcut)));
      entry->setObjectName(QString::fromStdString(module->name() + ":" + action.title));
    }
  file->addSeparator();
  file->addAction(tr("&Quit"), this, &QWidget::close, QKeySequence::Quit);

  QMenu* view = menuBar()->addMenu(tr("&View"));
  slices_in_3d_ = view->addAction(tr("&Slices in the 3D view"));
  slices_in_3d_->setCheckable(true);
  slices_in_3d_->setChecked(true);
  connect(slices_in_3d_, &QAction::toggled, this, [this](bool on) { view3d_->setSlicesVisible(on); });
  overlay_action_ = view->addAction(tr("Segmentation &overlay on the slices"));
  overlay_action_->setCheckable(true);
  overlay_action_->setChecked(true);
  overlay_action_->setShortcut(QKeySequence(tr("Ctrl+L")));
  connect(overlay_action_, &QAction::toggled, this, [this](bool) { updateOverlay(); });
  // A ruler on the slice views, as on a radiology viewer: two clicks, mm.
  ruler_action_ = view->addAction(tr("&Ruler on the slices"));
  ruler_action_->setObjectName("view.ruler");
  ruler_action_->setCheckable(true);
  ruler_action_->setShortcut(QKeySequence(tr("Ctrl+M")));
  ruler_action_->setToolTip(tr("Click two points on a slice to measure between them (mm)"));
  connect(ruler_action_, &QAction::toggled, this, [this](bool on) {
    for (ui::SliceView* view : slice_views_)
      view->setRulerMode(on);
    statusBar()->showMessage(on ? tr("Ruler: click the two ends on a slice") : QString());
  });
  view->addAction(
    tr("&Reset 3D view"), this,
    [this]() {
      view3d_->resetCamera();
      view3d_->renderWindow()->Render();
    },
    QKeySequence(tr("Ctrl+R")));

  // The modules in the order of the work, Ctrl+1 for the first.
  QMenu* modules = menuBar()->addMenu(tr("&Modules"));
  for (int i = 0; i < module_selector_->count(); ++i)
  {
    QAction* entry =
      modules->addAction(module_selector_->itemText(i), this, [this, i]() { module_selector_->setCurrentIndex(i); });
    if (i < 9)
      entry->setShortcut(QKeySequence(QString("Ctrl+%1").arg(i + 1)));
  }

  QMenu* help = menuBar()->addMenu(tr("&Help"));
  help->addAction(tr("&About CAPS"), this, [this]() {
    QMessageBox::about(this, tr("About CAPS"),
                       tr("<b>CAPS %1</b> - Computer-Aided Plastic Surgery.<br>Plans facial plastic surgery on "
                          "a head CT, after S. Pieper's 1991 MIT thesis.<br><br>Sample data: Head and neck CT "
                          "from the Weasis demo archive (N. Roduit), CC BY 4.0.")
                         .arg(CAPS_VERSION));
  });
}

void MainWindow::observeScene()
{
  observer_ = session_.scene().addObserver([this](SceneEvent event, const Node& node) {
    if (node.type() == NodeType::Volume)
    {
      if (event == SceneEvent::NodeAdded)
        showVolume(node.id()); // the newest volume is the one the user wants to see
      else if (event == SceneEvent::NodeAboutToBeRemoved && node.id() == volume_id_)
        showVolume({});
      else if (event == SceneEvent::NodeModified && node.id() == volume_id_)
        showVolume(node.id());
    }
    else if (node.type() == NodeType::LabelMap)
    {
      // After the removal has happened, so the old label map is gone.
      QTimer::singleShot(0, this, [this]() { updateOverlay(); });
    }
    else if (node.type() == NodeType::Surface)
    {
      const auto& surface = static_cast<const SurfaceNode&>(node);
      if (event == SceneEvent::NodeAboutToBeRemoved)
        view3d_->removeSurface(node.id());
      else
      {
        ui::SurfaceStyle style;
        style.colour = surface.color();
        style.opacity = surface.opacity();
        style.visible = surface.visible();
        style.colourArray = surface.colourArray();
        style.range = surface.scalarRange();
        style.colourMap = surface.colourMap();
        style.colourBarTitle = surface.colourBarTitle();
        style.lineWidth = surface.lineWidth();
        view3d_->setSurface(node.id(), surface.polyData(), style);
      }
      // The opaque slice planes would hide the face: a new surface turns them off.
      if (event == SceneEvent::NodeAdded && slices_in_3d_->isChecked())
        slices_in_3d_->setChecked(false);
    }
  });
}

void MainWindow::showVolume(const std::string& id)
{
  volume_id_ = id;
  auto* volume = id.empty() ? nullptr : session_.scene().nodeAs<VolumeNode>(id);
  vtkImageData* image = volume ? volume->image() : nullptr;
  for (ui::SliceView* view : slice_views_)
    view->setImage(image);
  view3d_->setImage(image);
  if (volume)
  {
    applyWindowLevel(volume->window(), volume->level());
    setWindowTitle(QString("CAPS - %1").arg(QString::fromStdString(volume->name())));
  }
  updateOverlay();
}

void MainWindow::applyWindowLevel(double window, double level)
{
  for (ui::SliceView* view : slice_views_)
    if (view->window() != window || view->level() != level)
      view->setWindowLevel(window, level);
  view3d_->setWindowLevel(window, level);
}

void MainWindow::moveCursor(const std::array<double, 3>& position)
{
  for (ui::SliceView* view : slice_views_)
    view->setCursorPosition(position);
  view3d_->setCursorPosition(position);
}

void MainWindow::showCursorInfo(double x, double y, double z, bool inside)
{
  auto* volume = session_.scene().nodeAs<VolumeNode>(volume_id_);
  if (!volume || !volume->image() || !inside)
  {
    cursor_info_->clear();
    return;
  }
  vtkImageData* image = volume->image();
  const double* origin = image->GetOrigin();
  const double* spacing = image->GetSpacing();
  const double p[3] = {x, y, z};
  int index[3];
  double offset[3];
  for (int a = 0; a < 3; ++a)
  {
    index[a] = static_cast<int>(std::lround((p[a] - origin[a]) / spacing[a]));
    offset[a] = p[a] - origin[a];
  }
  // Image space to patient space through the direction matrix.
  double patient[3];
  image->GetDirectionMatrix()->MultiplyPoint(offset, patient);
  for (int a = 0; a < 3; ++a)
    patient[a] += origin[a];
  const double hu = image->GetScalarComponentAsDouble(index[0], index[1], index[2], 0);
  cursor_info_->setText(QString("LPS (%1, %2, %3) mm   voxel (%4, %5, %6)   %7 HU")
                          .arg(patient[0], 0, 'f', 1)
                          .arg(patient[1], 0, 'f', 1)
                          .arg(patient[2], 0, 'f', 1)
                          .arg(index[0])
                          .arg(index[1])
                          .arg(index[2])
                          .arg(hu, 0, 'f', 0));
}

void MainWindow::runTask(const std::string& title, TaskWork work)
{
  if (task_thread_)
  {
    showError("Busy", "Wait for '" + progress_label_->text().toStdString() +
                        "' to finish, or cancel it, before starting '" + title + "'.");
    return;
  }
  cancel_requested_ = false;
  progress_label_->setText(QString::fromStdString(title));
  progress_->setValue(0);
  progress_label_->show();
  progress_->show();
  cancel_->setEnabled(true);
  cancel_->show();

  TaskProgress progress = [this](double fraction, const std::string& step) {
    QMetaObject::invokeMethod(
      this,
      [this, fraction, step]() {
        progress_->setValue(static_cast<int>(fraction * 1000));
        if (!cancel_requested_)
          progress_label_->setText(QString::fromStdString(step));
      },
      Qt::QueuedConnection);
    return !cancel_requested_.load();
  };
  task_thread_ = QThread::create([this, title, work, progress]() {
    std::function<void()> finish;
    std::string error;
    try
    {
      finish = work(progress);
    }
    catch (const std::exception& e)
    {
      error = e.what();
    }
    const bool cancelled = cancel_requested_.load();
    QMetaObject::invokeMethod(
      this, [this, title, finish, error, cancelled]() { taskFinished(title, finish, error, cancelled); },
      Qt::QueuedConnection);
  });
  connect(task_thread_, &QThread::finished, task_thread_, &QObject::deleteLater);
  task_thread_->start();
}

void MainWindow::taskFinished(const std::string& title, std::function<void()> finish, const std::string& error,
                              bool cancelled)
{
  task_thread_->wait();
  task_thread_ = nullptr;
  progress_label_->hide();
  progress_->hide();
  cancel_->hide();
  if (cancelled)
    showStatus(title + ": cancelled.");
  else if (!error.empty())
    showError(title, error);
  else if (finish)
  {
    try
    {
      finish();
    }
    catch (const std::exception& e)
    {
      showError(title, e.what());
    }
  }
  maybeTakeScreenshot();
}

void MainWindow::showError(const std::string& title, const std::string& message)
{
  error_reported_ = true;
  reported_errors_.push_back(title + ": " + message);
  if (unattended_)
  {
    std::cerr << "caps: " << title << ": " << message << "\n";
    return;
  }
  QMessageBox::warning(this, QString::fromStdString(title), QString::fromStdString(message));
}

void MainWindow::showWarning(const std::string& title, const std::string& message)
{
  if (unattended_)
  {
    std::cerr << "caps: warning: " << title << ": " << message << "\n";
    return;
  }
  QMessageBox::information(this, QString::fromStdString(title), QString::fromStdString(message));
}

void MainWindow::showStatus(const std::string& message)
{
  statusBar()->showMessage(QString::fromStdString(message), 8000);
  if (unattended_)
    std::cerr << "caps: " << message << "\n";
}

void MainWindow::openPath(const fs::path& path)
{
  std::error_code ec;
  if (!fs::exists(path, ec))
  {
    showError("Cannot open", "No such file or folder: " + path.string() + ".");
    return;
  }
  if (isSceneBundle(path))
  {
    openScene(path);
    return;
  }
  for (const auto& loaded : session_.modules().modules())
    if (loaded.module->canOpen(path))
    {
      loaded.module->open(session_.logic(*loaded.module), *this, path);
      addRecent(path);
      return;
    }
  showError("Cannot open", path.string() + " is neither a DICOM folder, a CT image file (NIfTI, NRRD, "
                                           "MetaImage) nor a CAPS scene (NAME.caps).");
}

void MainWindow::openScene(const fs::path& bundle)
{
  QApplication::setOverrideCursor(Qt::WaitCursor);
  try
  {
    loadSceneBundle(session_.scene(), bundle);
    scene_path_ = bundle;
    addRecent(bundle);
    showStatus("Opened scene " + bundle.string());
  }
  catch (const std::exception& e)
  {
    showError("Cannot open the scene", e.what());
  }
  QApplication::restoreOverrideCursor();
  maybeTakeScreenshot();
}

void MainWindow::saveScene(bool askForName)
{
  // The save reads the scene while it runs; work that would change it must
  // finish first.
  if (task_thread_)
  {
    showError("Not saved yet",
              "Wait for '" + progress_label_->text().toStdString() + "' to finish, or cancel it, then save again.");
    return;
  }
  fs::path target = scene_path_;
  if (askForName || target.empty())
  {
    const QString name =
      QFileDialog::getSaveFileName(this, tr("Save the scene as"), QString(), tr("CAPS scene (*.caps)"));
    if (name.isEmpty())
      return;
    target = name.toStdString();
    if (target.extension() != ".caps")
      target += ".caps";
  }
  saveSceneTo(target);
}

bool MainWindow::saveSceneTo(const fs::path& bundle)
{
  if (task_thread_)
  {
    showError("Not saved yet",
              "Wait for '" + progress_label_->text().toStdString() + "' to finish, or cancel it, then save again.");
    return false;
  }
  QApplication::setOverrideCursor(Qt::WaitCursor);
  progress_label_->setText(tr("Saving scene"));
  progress_label_->show();
  progress_->show();
  bool saved = false;
  try
  {
    saveSceneBundle(session_.scene(), bundle, [this](double fraction, const std::string&) {
      progress_->setValue(static_cast<int>(fraction * 1000));
      QApplication::processEvents(QEventLoop::ExcludeUserInputEvents);
    });
    scene_path_ = bundle;
    addRecent(bundle);
    showStatus("Saved scene " + bundle.string());
    saved = true;
  }
  catch (const std::exception& e)
  {
    showError("The scene was not saved", std::string(e.what()) + "\nThe previous copy on disk, if any, is unchanged.");
  }
  progress_label_->hide();
  progress_->hide();
  QApplication::restoreOverrideCursor();
  return saved;
}

void MainWindow::addRecent(const fs::path& path)
{
  QSettings settings;
  QStringList recent = settings.value("recentFiles").toStringList();
  const QString entry = QString::fromStdString(fs::absolute(path).lexically_normal().string());
  recent.removeAll(entry);
  recent.prepend(entry);
  while (recent.size() > kMaxRecent)
    recent.removeLast();
  settings.setValue("recentFiles", recent);
  updateRecentMenu();
}

void MainWindow::updateRecentMenu()
{
  recent_menu_->clear();
  QSettings settings;
  const QStringList recent = settings.value("recentFiles").toStringList();
  for (const QString& entry : recent)
    recent_menu_->addAction(entry, this, [this, entry]() { openPath(entry.toStdString()); });
  recent_menu_->setEnabled(!recent.isEmpty());
}

void MainWindow::dragEnterEvent(QDragEnterEvent* event)
{
  if (event->mimeData()->hasUrls())
    event->acceptProposedAction();
}

void MainWindow::dropEvent(QDropEvent* event)
{
  for (const QUrl& url : event->mimeData()->urls())
    if (url.isLocalFile())
    {
      openPath(url.toLocalFile().toStdString());
      event->acceptProposedAction();
      return;
    }
}

void MainWindow::pickInThreeDView(const std::string& prompt, std::function<void(const SurfacePick&)> picked)
{
  pick_handler_ = std::move(picked);
  view3d_->setHandlesGrabbable(false); // the click asked for, even on a handle
  statusBar()->showMessage(QString::fromStdString(prompt + "  (Esc cancels)"));
  view3d_->setCursor(Qt::CrossCursor);
  view3d_->setFocus();
}

void MainWindow::setThreeDViewHandles(const std::vector<std::array<double, 3>>& points,
                                      std::function<void(int, const SurfacePick&)> dropped)
{
  handle_handler_ = points.empty() ? nullptr : std::move(dropped);
  view3d_->setHandles(points);
}

void MainWindow::cancelPick()
{
  pick_handler_ = nullptr;
  view3d_->setHandlesGrabbable(true);
  view3d_->unsetCursor();
  statusBar()->clearMessage();
}

ViewCapture MainWindow::captureThreeDView()
{
  ViewCapture capture;
  vtkRenderWindow* window = view3d_->renderWindow();
  // The grabber renders the view itself before it reads it (ShouldRerender).
  auto grabber = vtkSmartPointer<vtkWindowToImageFilter>::New();
  grabber->SetInput(window);
  grabber->SetInputBufferTypeToRGB();
  grabber->ReadFrontBufferOff();
  grabber->Update();
  capture.image = vtkSmartPointer<vtkImageData>::New();
  capture.image->DeepCopy(grabber->GetOutput());
  vtkCamera* camera = view3d_->renderer()->GetActiveCamera();
  camera->GetPosition(capture.camera.position.data());
  camera->GetFocalPoint(capture.camera.focalPoint.data());
  camera->GetViewUp(capture.camera.viewUp.data());
  capture.camera.viewAngle = camera->GetViewAngle();
  return capture;
}

void MainWindow::setThreeDViewCamera(const SnapshotNode::Camera& c)
{
  vtkCamera* camera = view3d_->renderer()->GetActiveCamera();
  camera->SetPosition(c.position.data());
  camera->SetFocalPoint(c.focalPoint.data());
  camera->SetViewUp(c.viewUp.data());
  camera->SetViewAngle(c.viewAngle);
  view3d_->renderer()->ResetCameraClippingRange();
  view3d_->renderWindow()->Render();
}

void MainWindow::setCursorPosition(const std::array<double, 3>& position)
{
  moveCursor(rotateAboutOrigin(position, true));
  view3d_->setMarker(position);
}

void MainWindow::showMeasuredSegment(const std::optional<MeasuredSegment>& segment)
{
  std::optional<ui::SliceSegment> onSlices;
  if (segment)
    onSlices =
      ui::SliceSegment{rotateAboutOrigin(segment->from, true), rotateAboutOrigin(segment->to, true), segment->label};
  for (ui::SliceView* view : slice_views_)
    view->setMeasuredSegment(onSlices);
}

void MainWindow::keepRuler(const ui::SliceView& view)
{
  const std::optional<ui::SliceSegment> ruler = view.ruler();
  if (!ruler)
    return;
  // Saved with the scene's landmarks, as a radiology viewer keeps its
  // measurements with the study; undoable like any edit.
  Scene& scene = session_.scene();
  const auto nodes = scene.nodesOfType(NodeType::Landmarks);
  auto* landmarks = nodes.empty() ? scene.add<LandmarksNode>() : static_cast<LandmarksNode*>(nodes.back());
  if (nodes.empty())
    landmarks->setName("Landmarks");
  const LandmarksNode::Distance distance{"Ruler " + std::to_string(landmarks->distances().size() + 1),
                                         rotateAboutOrigin(ruler->from, false), rotateAboutOrigin(ruler->to, false)};
  {
    ScopedEdit edit(scene, landmarks->id(), "Measure " + distance.name);
    landmarks->addDistance(distance);
  }
  statusBar()->showMessage(tr("%1: %2 mm, kept in the scene's landmarks (click again for another; Ctrl+M ends the "
                              "ruler)")
                             .arg(QString::fromStdString(distance.name))
                             .arg(distance.length(), 0, 'f', 1));
}

std::array<double, 3> MainWindow::rotateAboutOrigin(const std::array<double, 3>& point, bool toImage)
{
  // The views' image space keeps the volume's origin and axes: patient LPS
  // is origin + D (p - origin), image space origin + Dᵀ (x - origin).
  std::array<double, 3> rotated = point;
  auto* volume = session_.scene().nodeAs<VolumeNode>(volume_id_);
  if (!volume || !volume->image())
    return rotated;
  vtkImageData* image = volume->image();
  const double* origin = image->GetOrigin();
  vtkMatrix3x3* direction = image->GetDirectionMatrix();
  for (int a = 0; a < 3; ++a)
  {
    rotated[static_cast<size_t>(a)] = origin[a];
    for (int b = 0; b < 3; ++b)
      rotated[static_cast<size_t>(a)] += (toImage ? direction->GetElement(b, a) : direction->GetElement(a, b)) *
                                         (point[static_cast<size_t>(b)] - origin[b]);
  }
  return rotated;
}

void MainWindow::previewThresholds(const std::optional<std::array<double, 2>>& hu)
{
  threshold_preview_ = hu;
  updateOverlay();
}

void MainWindow::updateOverlay()
{
  auto* volume = session_.scene().nodeAs<VolumeNode>(volume_id_);
  vtkSmartPointer<vtkImageData> overlay;
  auto colours = vtkSmartPointer<vtkLookupTable>::New();
  // Soft tissue a warm tint, bone a pale yellow, both see-through.
  const double tissue[4] = {0.95, 0.45, 0.30, 0.35};
  const double bone[4] = {1.0, 0.95, 0.45, 0.55};
  if (volume && volume->image() && threshold_preview_)
  {
    // The CT itself through a table by HU: what the thresholds would label.
    overlay = volume->image();
    constexpr double low = -1024.0, high = 3071.0;
    const int n = static_cast<int>(high - low) + 1;
    colours->SetNumberOfTableValues(n);
    colours->SetTableRange(low, high);
    for (int i = 0; i < n; ++i)
    {
      const double hu = low + i;
      if (hu >= (*threshold_preview_)[1])
        colours->SetTableValue(i, bone);
      else if (hu >= (*threshold_preview_)[0])
        colours->SetTableValue(i, tissue);
      else
        colours->SetTableValue(i, 0, 0, 0, 0);
    }
    colours->SetUseBelowRangeColor(true);
    colours->SetBelowRangeColor(0, 0, 0, 0);
    colours->SetUseAboveRangeColor(true);
    colours->SetAboveRangeColor(bone);
  }
  else if (volume && volume->image() && overlay_action_->isChecked())
  {
    LabelMapNode* labels = nullptr;
    for (Node* node : session_.scene().nodesOfType(NodeType::LabelMap))
      if (static_cast<LabelMapNode*>(node)->referenceVolumeId() == volume_id_)
        labels = static_cast<LabelMapNode*>(node);
    if (labels && labels->image())
    {
      overlay = labels->image();
      colours->SetNumberOfTableValues(3);
      colours->SetTableRange(0, 2);
      colours->SetTableValue(0, 0, 0, 0, 0);
      colours->SetTableValue(1, tissue);
      colours->SetTableValue(2, bone);
    }
  }
  for (ui::SliceView* view : slice_views_)
    view->setOverlay(overlay, overlay ? colours.GetPointer() : nullptr);
}

void MainWindow::keyPressEvent(QKeyEvent* event)
{
  if (event->key() == Qt::Key_Escape && pick_handler_)
  {
    cancelPick();
    showStatus("Pick cancelled.");
    return;
  }
  QMainWindow::keyPressEvent(event);
}

void MainWindow::closeEvent(QCloseEvent* event)
{
  QSettings settings;
  settings.setValue("window/geometry", saveGeometry());
  settings.setValue("window/state", saveState());
  if (task_thread_)
  {
    cancel_requested_ = true;
    task_thread_->wait();
  }
  event->accept();
}

void MainWindow::screenshotWhenIdle(const fs::path& file)
{
  screenshot_file_ = file;
  unattended_ = true;
  // Nothing to wait for when no work was started.
  QTimer::singleShot(0, this, [this]() { maybeTakeScreenshot(); });
}

void MainWindow::maybeTakeScreenshot()
{
  if (screenshot_file_.empty() || task_thread_)
    return;
  // Let the views render the last changes first.
  QTimer::singleShot(800, this, [this]() {
    if (screenshot_file_.empty() || task_thread_)
      return;
    for (ui::SliceView* view : slice_views_)
      view->renderWindow()->Render();
    view3d_->renderWindow()->Render();
    std::error_code ec;
    if (screenshot_file_.has_parent_path())
      fs::create_directories(screenshot_file_.parent_path(), ec);
    const bool saved = grab().save(QString::fromStdString(screenshot_file_.string()));
    if (!saved)
      std::cerr << "caps: could not write the screenshot " << screenshot_file_.string() << "\n";
    else
      std::cerr << "caps: screenshot saved to " << screenshot_file_.string() << "\n";
    screenshot_file_.clear();
    QApplication::exit(saved && !error_reported_ ? 0 : 1);
  });
}

} // namespace caps
