#pragma once
/// @file MainWindow.h
/// @brief The workstation window: module selector and panel, a 3D view and
/// three slice views on one scene, window/level presets, HU under the
/// cursor, progress and cancel for long work.

#include <array>
#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <QMainWindow>

#include "modules/core/Module.h"

class QAction;
class QComboBox;
class QLabel;
class QMenu;
class QProgressBar;
class QPushButton;
class QStackedWidget;
class QThread;

namespace caps {

class Session;
class VolumeNode;

namespace ui {
class SliceView;
class ThreeDView;
} // namespace ui

class MainWindow : public QMainWindow, public ModuleHost
{
  Q_OBJECT
public:
  explicit MainWindow(Session& session, QWidget* parent = nullptr);
  ~MainWindow() override;

  /// Opens a DICOM folder, an image file or a scene bundle.
  void openPath(const std::filesystem::path& path);
  /// Saves the scene as the bundle @a bundle (NAME.caps), as File > Save
  /// scene as does after its dialog; false (and the error shown) on failure.
  bool saveSceneTo(const std::filesystem::path& bundle);

  /// Unattended mode (tests, scripts): errors go to stderr instead of
  /// dialogs; once all work is done, the window is saved to @a file and the
  /// application quits (exit code 1 if an error was reported).
  void screenshotWhenIdle(const std::filesystem::path& file);
  /// Errors and warnings go to stderr (and errors to reportedErrors())
  /// instead of dialogs: for tests and scripts, where nobody clicks OK.
  void setUnattended(bool unattended) { unattended_ = unattended; }
  /// Errors shown since the window opened, "title: message".
  const std::vector<std::string>& reportedErrors() const { return reported_errors_; }
  /// Whether long work (runTask) is running.
  bool busy() const { return task_thread_ != nullptr; }

  // ModuleHost
  void runTask(const std::string& title, TaskWork work) override;
  void showError(const std::string& title, const std::string& message) override;
  void showWarning(const std::string& title, const std::string& message) override;
  void showStatus(const std::string& message) override;
  QWidget* window() override { return this; }
  void pickInThreeDView(const std::string& prompt, std::function<void(const SurfacePick&)> picked) override;
  void cancelPick() override;
  void setThreeDViewHandles(const std::vector<std::array<double, 3>>& points,
                            std::function<void(int, const SurfacePick&)> dropped) override;
  ViewCapture captureThreeDView() override;
  void setThreeDViewCamera(const SnapshotNode::Camera& camera) override;
  void setCursorPosition(const std::array<double, 3>& position) override;
  void previewThresholds(const std::optional<std::array<double, 2>>& hu) override;
  void showMeasuredSegment(const std::optional<MeasuredSegment>& segment) override;

  /// The 3D view (tests click on it).
  ui::ThreeDView* threeDView() const { return view3d_; }

protected:
  void dragEnterEvent(QDragEnterEvent* event) override;
  void dropEvent(QDropEvent* event) override;
  void closeEvent(QCloseEvent* event) override;
  void keyPressEvent(QKeyEvent* event) override;

private:
  void buildViews();
  void buildMenus();
  void buildModulePanels();
  void buildStatusBar();
  void observeScene();
  void showVolume(const std::string& id);
  /// The slice views' overlay: the threshold preview while a panel asks for
  /// it, else the current volume's newest label map (View > Segmentation overlay).
  void updateOverlay();
  void applyWindowLevel(double window, double level);
  void moveCursor(const std::array<double, 3>& position);
  /// Patient LPS to the slice views' image space (the volume's axes, origin
  /// kept) when @a toImage, else back.
  std::array<double, 3> rotateAboutOrigin(const std::array<double, 3>& point, bool toImage);
  /// The ruler just finished on @a view, kept in the scene's landmarks.
  void keepRuler(const ui::SliceView& view);
  void showCursorInfo(double x, double y, double z, bool inside);
  void taskFinished(const std::string& title, std::function<void()> finish, const std::string& error, bool cancelled);
  void openScene(const std::filesystem::path& bundle);
  void saveScene(bool askForName);
  void addRecent(const std::filesystem::path& path);
  void updateRecentMenu();
  void maybeTakeScreenshot();

  Session& session_;
  int observer_ = -1;
  std::string volume_id_;
  std::array<ui::SliceView*, 3> slice_views_{};
  ui::ThreeDView* view3d_ = nullptr;
  QComboBox* module_selector_ = nullptr;
  QStackedWidget* panels_ = nullptr;
  QComboBox* presets_ = nullptr;
  QLabel* cursor_info_ = nullptr;
  QProgressBar* progress_ = nullptr;
  QLabel* progress_label_ = nullptr;
  QPushButton* cancel_ = nullptr;
  QMenu* recent_menu_ = nullptr;
  QAction* slices_in_3d_ = nullptr;
  QAction* overlay_action_ = nullptr;
  QAction* ruler_action_ = nullptr;
  std::optional<std::array<double, 2>> threshold_preview_;
  QThread* task_thread_ = nullptr;
  std::atomic<bool> cancel_requested_{false};
  std::filesystem::path scene_path_;
  std::filesystem::path screenshot_file_;
  std::function<void(const SurfacePick&)> pick_handler_;
  std::function<void(int, const SurfacePick&)> handle_handler_;
  bool unattended_ = false;
  bool error_reported_ = false;
  std::vector<std::string> reported_errors_;
};

} // namespace caps
