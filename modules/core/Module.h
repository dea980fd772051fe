#pragma once
/// @file Module.h
/// @brief The plugin interface every workstation module implements.
///
/// A module is a shared library in the app's plugin folder that exports
/// `caps_module_api_version()`, `caps_module_build_stamp()` and
/// `caps_create_module()` (use CAPS_DECLARE_MODULE, and link the
/// caps_build_stamp object library). Like a 3D Slicer loadable module it has metadata,
/// a logic object bound to the scene (no widgets: the command line and the
/// tests drive exactly what the GUI drives), an optional Qt panel, and
/// optional command-line subcommands.

#include <array>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <vtkSmartPointer.h>

#include "modules/core/BuildStamp.h"
#include "scene/Node.h"
#include "scene/SnapshotNode.h"
#include "segmentation/Progress.h"

class QWidget;
class vtkImageData;

namespace caps {

class Scene;
class ModuleHost;

/// Bumped whenever Module, ModuleLogic, ModuleCommand or ModuleHost change
/// in a way that breaks plugins built against the old headers.
inline constexpr int kModuleApiVersion = 6;

/// The module's algorithmic side, bound to the scene. Subclasses add the
/// module's operations; it never includes a widget header.
class ModuleLogic
{
public:
  explicit ModuleLogic(Scene& scene) : scene_(scene) {}
  virtual ~ModuleLogic() = default;
  ModuleLogic(const ModuleLogic&) = delete;
  ModuleLogic& operator=(const ModuleLogic&) = delete;

  Scene& scene() const { return scene_; }

private:
  Scene& scene_;
};

/// A headless subcommand: `caps NAME ARGS...`.
struct ModuleCommand
{
  std::string name;    ///< "info"
  std::string summary; ///< one line for `caps --help`
  std::string usage;   ///< full text for `caps NAME --help`
  /// Runs the command; returns the process exit code (0 = success). Messages
  /// for the user go to err; results to out.
  std::function<int(ModuleLogic& logic, const std::vector<std::string>& args, std::ostream& out, std::ostream& err)>
    run;
};

/// A menu entry a module adds to the workstation (File > Export plan report).
struct ModuleAction
{
  std::string menu;     ///< the menu it goes in: "File"
  std::string title;    ///< "Export plan report as &PDF..."
  std::string shortcut; ///< a QKeySequence text ("Ctrl+P"), or empty
  /// Runs on the GUI thread; long work goes through host.runTask.
  std::function<void(ModuleLogic& logic, ModuleHost& host)> run;
};

/// Progress report of long work: fraction in [0,1] and the current step;
/// returning false asks the work to stop (it then throws seg::Cancelled).
/// The one progress type of the libraries (segmentation/Progress.h).
using TaskProgress = seg::ProgressCallback;

/// Long work split in two: `work` runs on a worker thread and must not touch
/// the scene; the function it returns runs afterwards on the GUI thread and
/// may (to add nodes, for instance).
using TaskWork = std::function<std::function<void()>(const TaskProgress& progress)>;

/// A point the user clicked on a surface in the 3D view.
struct SurfacePick
{
  std::array<double, 3> position{}; ///< patient LPS, mm, on the surface
  NodeId surface;                   ///< the Surface node clicked
};

/// A straight measurement to draw on the slice views: a landmark's depth from
/// the skin to the bone.
struct MeasuredSegment
{
  std::array<double, 3> from{}; ///< patient LPS, mm
  std::array<double, 3> to{};   ///< patient LPS, mm
  std::string label;            ///< "6.2 mm"
};

/// The 3D view as it is on screen: its pixels and the camera that made them.
struct ViewCapture
{
  vtkSmartPointer<vtkImageData> image; ///< RGB, unsigned char, origin bottom left (VTK)
  SnapshotNode::Camera camera;
};

/// What the workstation offers a module's panel.
class ModuleHost
{
public:
  virtual ~ModuleHost() = default;
  /// Runs long work with progress and a Cancel button in the status bar.
  /// Exceptions from either half are shown to the user; nothing else happens.
  virtual void runTask(const std::string& title, TaskWork work) = 0;
  /// Shows an error the user must read (a dialog; stderr when headless).
  virtual void showError(const std::string& title, const std::string& message) = 0;
  /// Shows something the user should know that did not stop the work.
  virtual void showWarning(const std::string& title, const std::string& message) = 0;
  /// Shows a transient message in the status bar.
  virtual void showStatus(const std::string& message) = 0;
  /// The main window, as parent for dialogs.
  virtual QWidget* window() = 0;

  /// @name The 3D view
  ///@{
  /// Arms a pick: the next left click (a click, not a drag that turns the
  /// view) on a visible surface in the 3D view calls @a picked on the GUI
  /// thread; @a prompt goes in the status bar meanwhile. The view still
  /// turns and zooms while armed (§5.6: a changeable viewpoint while
  /// drawing). A new request replaces an armed one; Esc cancels it.
  virtual void pickInThreeDView(const std::string& prompt, std::function<void(const SurfacePick&)> picked) = 0;
  /// Disarms a pick requested with pickInThreeDView(); nothing if none.
  virtual void cancelPick() = 0;
  /// Shows points the user can drag along the surfaces in the 3D view (a
  /// plan's cut points); @a dropped gets the handle's index and where on a
  /// surface it was let go. Replaces the handles shown before; an empty list
  /// (or choosing another module) takes them away.
  virtual void setThreeDViewHandles(const std::vector<std::array<double, 3>>& points,
                                    std::function<void(int, const SurfacePick&)> dropped) = 0;
  /// The 3D view as shown now, at its size on screen.
  virtual ViewCapture captureThreeDView() = 0;
  /// Moves the 3D view's camera.
  virtual void setThreeDViewCamera(const SnapshotNode::Camera& camera) = 0;
  /// Moves the cursor (the crosshair of the slice views and the slices of
  /// the 3D view) to @a position (patient LPS, mm) and marks it in the 3D view.
  virtual void setCursorPosition(const std::array<double, 3>& position) = 0;
  ///@}

  /// @name The slice views
  ///@{
  /// Colours the CT on the slice views by thresholds while the user sets
  /// them (§4.2: the skin and bone thresholds): soft tissue from hu[0] (HU),
  /// bone from hu[1]; std::nullopt goes back to the segmentation's own
  /// overlay (its label map), if any.
  virtual void previewThresholds(const std::optional<std::array<double, 2>>& hu) = 0;
  /// Draws @a segment on the slice views, projected onto the slice each
  /// shows, its label at the @a segment.to end; std::nullopt (or choosing
  /// another module) takes it away.
  virtual void showMeasuredSegment(const std::optional<MeasuredSegment>& segment) = 0;
  ///@}
};

/// A workstation module: metadata and factories only.
class Module
{
public:
  virtual ~Module() = default;
  virtual std::string name() const = 0;  ///< short id: "volumes"
  virtual std::string title() const = 0; ///< shown in the module selector: "Volumes"
  virtual std::string help() const = 0;  ///< a paragraph for the user
  virtual std::unique_ptr<ModuleLogic> createLogic(Scene& scene) const = 0;
  /// The module's panel, or nullptr for modules without one.
  virtual QWidget* createPanel(ModuleLogic& logic, ModuleHost& host, QWidget* parent) const
  {
    (void)logic, (void)host, (void)parent;
    return nullptr;
  }
  virtual std::vector<ModuleCommand> commands() const { return {}; }
  /// Menu entries of the module in the workstation.
  virtual std::vector<ModuleAction> actions() const { return {}; }
  /// Whether the module opens this path (a dropped folder, a recent file).
  virtual bool canOpen(const std::filesystem::path& path) const
  {
    (void)path;
    return false;
  }
  /// Opens the path in the workstation (through host.runTask for slow reads).
  virtual void open(ModuleLogic& logic, ModuleHost& host, const std::filesystem::path& path) const
  {
    (void)logic, (void)host, (void)path;
  }
};

} // namespace caps

/// Exports a module class from its plugin library.
#define CAPS_DECLARE_MODULE(ModuleClass)                                                                               \
  extern "C" __attribute__((visibility("default"))) int caps_module_api_version()                                      \
  {                                                                                                                    \
    return ::caps::kModuleApiVersion;                                                                                  \
  }                                                                                                                    \
  extern "C" __attribute__((visibility("default"))) const char* caps_module_build_stamp()                              \
  {                                                                                                                    \
    return ::caps::buildStamp();                                                                                       \
  }                                                                                                                    \
  extern "C" __attribute__((visibility("default"))) ::caps::Module* caps_create_module()                               \
  {                                                                                                                    \
    return new ModuleClass();                                                                                          \
  }
