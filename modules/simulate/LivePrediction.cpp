#include "modules/simulate/LivePrediction.h"

#include <chrono>
#include <exception>
#include <utility>
#include <vector>

#include <QThread>

#include "segmentation/Progress.h"

namespace caps::simulate {

LivePrediction::LivePrediction(Ready ready, Progress progress, Failed failed, QObject* parent)
  : QObject(parent), ready_(std::move(ready)), progress_(std::move(progress)), failed_(std::move(failed))
{}

LivePrediction::~LivePrediction()
{
  cancel();
  if (worker_)
  {
    worker_->wait();
    delete worker_;
  }
}

void LivePrediction::request(const PlanRunInput& input)
{
  pending_ = std::make_shared<PlanRunInput>(input);
  ++generation_; // the run in progress, if any, stops at its next progress report
  if (!worker_)
    startPending();
}

void LivePrediction::cancel()
{
  pending_.reset();
  ++generation_;
}

void LivePrediction::startPending()
{
  const std::shared_ptr<const PlanRunInput> input = std::move(pending_);
  pending_.reset();
  const int generation = generation_.load();
  worker_ = QThread::create([this, input, generation]() {
    const auto current = [this, generation]() { return generation_.load() == generation; };
    // Posted to the owner's thread, and dropped there if a newer request came.
    const auto post = [this, current](std::function<void()> call) {
      QMetaObject::invokeMethod(
        this,
        [current, call = std::move(call)]() {
          if (current())
            call();
        },
        Qt::QueuedConnection);
    };
    // The linear preview first when the plan's model is large deformation.
    std::vector<std::pair<LiveStage, std::shared_ptr<PlanRunInput>>> stages;
    if (input->options.model != planning::TissueModel::LinearElastic)
    {
      auto preview = std::make_shared<PlanRunInput>(*input);
      preview->options.model = planning::TissueModel::LinearElastic;
      stages.emplace_back(LiveStage::Preview, preview);
    }
    stages.emplace_back(LiveStage::Final, std::make_shared<PlanRunInput>(*input));
    for (const auto& [stage, stageInput] : stages)
    {
      const LiveStage s = stage;
      const TaskProgress progress = [this, s, current, post](double fraction, const std::string& step) {
        if (!current())
          return false;
        post([this, s, fraction, step]() { progress_(s, fraction, step); });
        return true;
      };
      const auto start = std::chrono::steady_clock::now();
      try
      {
        auto result = std::make_shared<const PlanRunResult>(runPlan(*stageInput, progress));
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::shared_ptr<const PlanRunInput> ran = stageInput;
        post([this, s, ran, result, seconds]() { ready_(s, ran, result, seconds); });
      }
      catch (const seg::Cancelled&)
      {
        return;
      }
      catch (const std::exception& e)
      {
        const std::string message = e.what();
        post([this, s, message]() { failed_(s, message); });
        return;
      }
      if (!current())
        return;
    }
  });
  connect(worker_, &QThread::finished, this, &LivePrediction::workerEnded);
  worker_->start();
}

void LivePrediction::workerEnded()
{
  if (!worker_)
    return;
  worker_->wait();
  worker_->deleteLater();
  worker_ = nullptr;
  if (pending_)
    startPending();
}

} // namespace caps::simulate
