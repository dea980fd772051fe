#include "modules/report/Storyboard.h"

#include <cmath>
#include <stdexcept>

#include <vtkImageData.h>

#include "modules/incision/IncisionLogic.h"
#include "modules/report/PlanReport.h"
#include "scene/PlanNode.h"
#include "scene/Scene.h"
#include "scene/SnapshotNode.h"
#include "scene/VolumeNode.h"

namespace caps::report {

PlanView planViewFromName(const std::string& name)
{
  const std::pair<const char*, PlanView> views[] = {{"front", PlanView::Front},     {"oblique", PlanView::Oblique},
                                                    {"profile", PlanView::Profile}, {"before", PlanView::Before},
                                                    {"after", PlanView::After},     {"stress", PlanView::Stress}};
  for (const auto& [word, view] : views)
    if (name == word)
      return view;
  throw std::invalid_argument("no view '" + name + "': give front, oblique, profile, before, after or stress");
}

SnapshotNode& takePlanSnapshot(Scene& scene, const std::string& planName, PlanView view, std::string caption, int width,
                               int height)
{
  const PlanNode* node = nullptr;
  std::string names;
  for (Node* n : scene.nodesOfType(NodeType::Plan))
  {
    names += names.empty() ? "\"" : ", \"";
    names += n->name();
    names += '"';
    if (n->name() == planName)
      node = static_cast<const PlanNode*>(n);
  }
  if (!node)
    throw std::invalid_argument("the scene has no plan \"" + planName +
                                "\"; its plans are: " + (names.empty() ? std::string("none") : names));
  const auto volumes = scene.nodesOfType(NodeType::Volume);
  if (volumes.empty())
    throw std::invalid_argument("the scene has no CT volume");
  if (width < 64 || height < 64)
    throw std::invalid_argument("a snapshot needs at least 64 x 64 pixels");
  PlanFacts plan;
  plan.name = node->name();
  plan.plan = IncisionLogic::readPlan(*node);
  // The figure at the requested pixel size: its print width is what makes
  // width pixels at 150 dpi (text in points scales with it).
  const double dpi = 150.0;
  const PlanFigures figures(scene, *static_cast<const VolumeNode*>(volumes.front()), dpi);
  std::optional<render::Figure> figure = figures.planFigure(plan, view, width / dpi * 25.4, double(height) / width);
  if (!figure)
    throw std::invalid_argument("the scene lacks the surfaces for this view of \"" + planName +
                                "\" (the segmented skin, or the plan's display surfaces from caps plan)");
  figure->width = width;
  figure->height = height;
  vtkSmartPointer<vtkImageData> image = render::renderFigure(*figure);
  auto* snapshot = scene.add<SnapshotNode>();
  const int number = int(scene.nodesOfType(NodeType::Snapshot).size());
  snapshot->setName("Snapshot " + std::to_string(number));
  if (caption.empty())
  {
    caption = planName;
    caption += ": ";
    caption += planViewName(view, std::sin(plan.plan.centre().theta + 1.5707963267948966) > 0.0);
  }
  snapshot->setCaption(caption);
  snapshot->setCamera(figure->camera);
  snapshot->setImage(image);
  return *snapshot;
}

} // namespace caps::report
