#pragma once
// The real workstation in the test process: the plugins of the build, one
// Session and its MainWindow, shown on the X display the test runs under
// (ctest runs these tests inside xvfb-run). Tests drive it as a user does:
// they pick modules, press the panels' buttons (found by object name), click
// on the 3D view, and wait for background work; screenshots of each step go
// to build/test-artifacts/workstation/.

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include <QApplication>
#include <QComboBox>
#include <QTest>
#include <QThread>
#include <gtest/gtest.h>

#include <vtkCamera.h>
#include <vtkCommand.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>

#include "app/MainWindow.h"
#include "app/ModuleManager.h"
#include "app/Session.h"
#include "scene/Scene.h"
#include "ui/ThreeDView.h"

namespace caps::test {

/// Folder of this suite's screenshots.
/// The first node of @a scene named @a name that is a @a T (SurfaceNode,
/// PlanNode, ..., or Node for any); nullptr when there is none.
template <class T = Node> T* nodeNamed(Scene& scene, const std::string& name)
{
  for (Node* node : scene.nodes())
    if (node->name() == name)
      if (auto* t = dynamic_cast<T*>(node))
        return t;
  return nullptr;
}

inline std::filesystem::path workstationArtifacts()
{
  const std::filesystem::path folder = std::filesystem::path(CAPS_TEST_ARTIFACTS_DIR) / "workstation";
  std::filesystem::create_directories(folder);
  return folder;
}

class Workstation
{
public:
  Workstation()
  {
    modules_.loadFolder(CAPS_MODULE_DIR);
    session_ = std::make_unique<Session>(modules_);
    window_ = std::make_unique<MainWindow>(*session_);
    window_->setUnattended(true);
    window_->resize(1500, 950);
    window_->show();
    render_observer_ = threeDView().renderWindow()->AddObserver(vtkCommand::StartEvent, this, &Workstation::rendering);
    settle(200);
  }
  ~Workstation()
  {
    threeDView().renderWindow()->RemoveObserver(render_observer_);
    window_.reset();
    session_.reset();
  }

  MainWindow& window() { return *window_; }
  Session& session() { return *session_; }
  Scene& scene() { return session_->scene(); }
  ui::ThreeDView& threeDView() { return *window_->threeDView(); }

  /// Processes events for @a ms milliseconds.
  void settle(int ms = 300)
  {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
    while (std::chrono::steady_clock::now() < end)
    {
      QApplication::processEvents(QEventLoop::AllEvents, 20);
      QThread::msleep(5);
    }
  }

  /// Processes events until @a done or @a seconds pass; false on timeout.
  bool waitUntil(const std::function<bool()>& done, double seconds)
  {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (!done())
    {
      if (std::chrono::steady_clock::now() > end)
        return false;
      QApplication::processEvents(QEventLoop::AllEvents, 20);
      QThread::msleep(10);
    }
    settle(100);
    return true;
  }

  /// Waits until no background work runs (runTask); false on timeout.
  bool waitUntilIdle(double seconds)
  {
    return waitUntil([this] { return !window_->busy(); }, seconds);
  }

  /// Shows module @a name's panel, as choosing it in the selector does.
  void selectModule(const std::string& name)
  {
    auto* selector = widget<QComboBox>("ModuleSelector");
    ASSERT_NE(selector, nullptr);
    const int index = selector->findData(QString::fromStdString(name));
    ASSERT_GE(index, 0) << "no module " << name;
    selector->setCurrentIndex(index);
    settle(100);
  }

  /// The window's child widget of that object name and type; nullptr (and a
  /// test failure) when there is none.
  template <class T> T* widget(const std::string& objectName)
  {
    T* found = window_->findChild<T*>(QString::fromStdString(objectName));
    if (!found)
      ADD_FAILURE() << "no widget '" << objectName << "' in the workstation";
    return found;
  }

  /// Where world point @a p (LPS mm) is in the 3D view, in widget pixels.
  QPoint threeDViewPointOf(const std::array<double, 3>& p)
  {
    // The camera and the view's size make the projection: no redraw needed.
    vtkRenderer* renderer = threeDView().renderer();
    renderer->SetWorldPoint(p[0], p[1], p[2], 1.0);
    renderer->WorldToDisplay();
    double display[3];
    renderer->GetDisplayPoint(display);
    const double ratio = threeDView().devicePixelRatioF();
    const int height = threeDView().renderWindow()->GetSize()[1];
    return QPoint(static_cast<int>(display[0] / ratio), static_cast<int>((height - 1 - display[1]) / ratio));
  }

  /// A left click at @a at on the 3D view, as the mouse makes it.
  void clickThreeDView(const QPoint& at)
  {
    QTest::mouseClick(&threeDView(), Qt::LeftButton, Qt::NoModifier, at);
    settle(100);
  }

  /// A left-button drag on the 3D view from @a from to @a to, moving the
  /// mouse through @a steps points on the way, as a hand makes it.
  void dragThreeDView(const QPoint& from, const QPoint& to, int steps = 8)
  {
    QWidget* view = &threeDView();
    auto send = [view](QEvent::Type type, const QPoint& at, Qt::MouseButton button, Qt::MouseButtons buttons) {
      QMouseEvent event(type, QPointF(at), QPointF(view->mapToGlobal(at)), button, buttons, Qt::NoModifier);
      QApplication::sendEvent(view, &event);
    };
    send(QEvent::MouseButtonPress, from, Qt::LeftButton, Qt::LeftButton);
    for (int k = 1; k <= steps; ++k)
    {
      send(QEvent::MouseMove, from + (to - from) * k / steps, Qt::NoButton, Qt::LeftButton);
      settle(20);
    }
    send(QEvent::MouseButtonRelease, to, Qt::LeftButton, Qt::NoButton);
    settle(100);
  }

  /// Saves the window as build/test-artifacts/workstation/NAME.png.
  std::filesystem::path screenshot(const std::string& name)
  {
    settle(300);
    // What the workstation changes asks the view for a render of its own
    // (done by now); only a camera a test turned directly is not drawn yet.
    vtkCamera* camera = threeDView().renderer()->GetActiveCamera();
    if (camera != rendered_camera_ || camera->GetMTime() > rendered_camera_time_)
      threeDView().renderWindow()->Render();
    const std::filesystem::path file = workstationArtifacts() / (name + ".png");
    EXPECT_TRUE(window_->grab().save(QString::fromStdString(file.string()))) << file;
    return file;
  }

  /// What the workstation reported as errors, one per line (for messages).
  std::string errors() const
  {
    std::string all;
    for (const auto& e : window_->reportedErrors())
      all += e + "\n";
    return all;
  }

private:
  /// The 3D view starts a render: the camera it draws with.
  void rendering()
  {
    rendered_camera_ = threeDView().renderer()->GetActiveCamera();
    rendered_camera_time_ = rendered_camera_->GetMTime();
  }

  unsigned long render_observer_ = 0;
  vtkCamera* rendered_camera_ = nullptr;
  vtkMTimeType rendered_camera_time_ = 0;
  ModuleManager modules_;
  std::unique_ptr<Session> session_;
  std::unique_ptr<MainWindow> window_;
};

} // namespace caps::test
