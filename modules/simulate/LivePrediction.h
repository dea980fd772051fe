#pragma once
/// @file LivePrediction.h
/// @brief The prediction that follows the surgeon's edits (issue 21 item 8):
/// each edit of a plan gets the linear preview at once and then, in the
/// background, the large-deformation prediction that replaces it; the next
/// edit cancels whatever is still running. No widgets: the Simulate panel
/// feeds it the runs and puts what comes back into the scene.

#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include <QObject>

#include "modules/simulate/PlanSimulationRun.h"

class QThread;

namespace caps::simulate {

/// One stage of a live prediction: the quick linear preview, or the final
/// prediction in the model the surgeon chose.
enum class LiveStage
{
  Preview,
  Final,
};

/// @class LivePrediction
/// @brief Runs PlanRunInput after PlanRunInput on one worker thread, the
/// newest only. request() starts the linear preview of a plan's state and,
/// when the plan's own model is large deformation, the large-deformation
/// prediction after it (the same mesh is made again from the same plan).
/// A request while a run is in progress cancels it (between Newton
/// iterations: runPlan()'s progress returns false) and drops its results;
/// the new run starts as soon as the old thread has ended.
///
/// The callbacks run on the thread that owns the object (the GUI's), each
/// for the newest request only.
class LivePrediction : public QObject
{
  Q_OBJECT
public:
  /// A stage done: its input (the model it was solved with in
  /// input.options.model) and result, and how long it took.
  using Ready = std::function<void(LiveStage stage, const std::shared_ptr<const PlanRunInput>& input,
                                   const std::shared_ptr<const PlanRunResult>& result, double seconds)>;
  /// Progress of the running stage, fraction in [0, 1] of that stage.
  using Progress = std::function<void(LiveStage stage, double fraction, const std::string& step)>;
  /// A stage that threw (what simulatePlan() throws: a plan that cannot
  /// be meshed, a solver failure); the stages after it do not run.
  using Failed = std::function<void(LiveStage stage, const std::string& message)>;

  LivePrediction(Ready ready, Progress progress, Failed failed, QObject* parent = nullptr);
  /// Cancels the run in progress and waits for its thread.
  ~LivePrediction() override;

  /// Predicts @a input (its options.model says whether a final
  /// large-deformation stage follows the linear preview).
  void request(const PlanRunInput& input);
  /// Stops the run in progress; its results are dropped.
  void cancel();
  /// Whether a run is in progress or waiting for the old one to end.
  bool busy() const { return worker_ != nullptr || pending_ != nullptr; }

private:
  void startPending();
  void workerEnded();

  Ready ready_;
  Progress progress_;
  Failed failed_;
  QThread* worker_ = nullptr;
  std::shared_ptr<PlanRunInput> pending_;
  /// The newest request's number: a run whose number is not this one is
  /// cancelled and its results are dropped.
  std::atomic<int> generation_{0};
};

} // namespace caps::simulate
