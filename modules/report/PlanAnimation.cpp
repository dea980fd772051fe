#include "modules/report/PlanAnimation.h"

#include "modules/report/PlanFigures.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

#include <vtkPolyData.h>

#include "modules/incision/IncisionLogic.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "planning/SkinChart.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/SurfaceNode.h"
#include "segmentation/Progress.h"

namespace fs = std::filesystem;

// The animation is render/Animation.h's: its types read here unqualified.
using namespace caps::render;

namespace caps::report {
namespace {

const PlanNode& findPlan(const Scene& scene, const std::string& name)
{
  const std::vector<Node*> plans = scene.nodesOfType(NodeType::Plan);
  if (plans.empty())
    throw std::invalid_argument("the scene has no plan to animate: draw one (Incision module, or caps plan) first");
  if (name.empty())
    return *static_cast<const PlanNode*>(plans.front());
  std::string names;
  for (Node* n : plans)
  {
    if (n->name() == name)
      return *static_cast<const PlanNode*>(n);
    names += names.empty() ? "\"" : ", \"";
    names += n->name();
    names += "\"";
  }
  throw std::invalid_argument("the scene has no plan named \"" + name + "\"; its plans are " + names);
}

/// The skin range map the plan is drawn on (RangeMapLogic::mapsOf).
seg::RangeMap skinMapOf(const Scene& scene, const PlanNode& plan)
{
  if (const RangeMapNode* skin = RangeMapLogic::mapsOf(scene, plan).skin)
    return RangeMapLogic::toRangeMap(*skin);
  throw std::invalid_argument("the scene has no skin range map to draw plan \"" + plan.name() +
                              "\" on: make the range maps (RangeMap module, caps rangemap) first");
}

} // namespace

AnimationResult writePlanAnimation(Scene& scene, const std::string& planName, const fs::path& outDir,
                                   const AnimationOptions& options, const TaskProgress& progress)
{
  const auto [width, height] = render::animationFrameSize(options);
  if (options.prePostFrames < 2)
    throw std::invalid_argument("the pre → post animation needs at least 2 frames");
  if (options.turntable && options.turntableFrames < 2)
    throw std::invalid_argument("the turntable needs at least 2 frames");

  const PlanNode& planNode = findPlan(scene, planName);
  AnimationResult result;
  result.planName = planNode.name();
  vtkPolyData* before = surfaceNamed(scene, result.planName + " skin before");
  vtkPolyData* after = surfaceNamed(scene, result.planName + " skin after");
  if (!before || !after)
    throw std::invalid_argument("the scene does not hold the display surfaces of plan \"" + result.planName + "\" (\"" +
                                result.planName + " skin before\" and \"" + result.planName +
                                " skin after\"): predict it (caps plan, or Simulate in the workstation) first");
  if (before->GetNumberOfPoints() != after->GetNumberOfPoints())
    throw std::invalid_argument("plan \"" + result.planName + "\": the skin before has " +
                                std::to_string(before->GetNumberOfPoints()) + " points and the skin after " +
                                std::to_string(after->GetNumberOfPoints()) +
                                ", so one cannot be morphed into the other: predict the plan again (caps plan)");
  // The wound gaping under the skin's pre-tension, when the prediction has it: the middle stage.
  vtkPolyData* gaping = surfaceNamed(scene, result.planName + " skin gaping");
  if (gaping && gaping->GetNumberOfPoints() != before->GetNumberOfPoints())
    gaping = nullptr;
  std::vector<vtkPolyData*> stages{before};
  if (gaping)
    stages.push_back(gaping);
  stages.push_back(after);
  const seg::RangeMap skin = skinMapOf(scene, planNode);
  const seg::CylindricalFrame& frame = skin.frame();
  const planning::IncisionPlan plan = IncisionLogic::readPlan(planNode);
  vtkPolyData* head = options.turntable ? headSkin(scene) : nullptr;
  if (options.turntable && !head)
    throw std::invalid_argument("the scene has no skin surface (\"Skin\") for the turntable: segment the CT "
                                "(Segment module, caps segment) first, or leave the turntable out");

  const int total = options.prePostFrames + (options.turntable ? options.turntableFrames : 0);
  const auto started = std::chrono::steady_clock::now();
  int done = 0;

  // Pre → post: one camera along the radial direction at the plan's centre, framing both surfaces.
  Figure base;
  base.width = width;
  base.height = height;
  base.multiSamples = options.multiSamples;
  result.prePost.folder = fs::absolute(outDir) / "pre-post";
  result.prePost.width = width;
  result.prePost.height = height;
  result.prePost.camera =
    fitCamera(stages, frame.radialDirection(plan.centre().theta), frame.direction(), base.sceneAspect(), 20.0, 1.05);
  renderStagedMorphFrames(stages, base, result.prePost, options.prePostFrames, [&](const char* step) {
    seg::reportProgress(progress, 0.95 * done / total, step);
    ++done;
  });

  // The turntable: the head skin with the incision, once round the axis from the front.
  if (options.turntable)
  {
    FrameSequence turn;
    turn.folder = fs::absolute(outDir) / "turntable";
    turn.width = width;
    turn.height = height;
    Figure figure = base;
    figure.surfaces.push_back(SurfaceLayer::solid(head, {0.90, 0.76, 0.66}));
    LineLayer line = incisionLine(plan, plan.chart(skin), false);
    line.widthPixels = std::max(3.0, height / 240.0);
    figure.lines.push_back(line);
    renderTurntableFrames(figure, head, frame, options.turntableFrames, turn, [&](const char* step) {
      seg::reportProgress(progress, 0.95 * done / total, step);
      ++done;
    });
    result.turntable = turn;
  }
  result.framesRendered = done;
  result.renderSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();

  std::vector<FrameSequence*> sequences{&result.prePost};
  if (result.turntable)
    sequences.push_back(&*result.turntable);
  encodeVideos(sequences, options, progress, result);
  seg::reportProgress(progress, 1.0, "Animation written");
  return result;
}

} // namespace caps::report
