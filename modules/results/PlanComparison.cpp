#include "modules/results/PlanComparison.h"

#include <algorithm>
#include <stdexcept>

#include <QGridLayout>
#include <QLabel>

#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkPolyData.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>

#include "scene/PlanNode.h"
#include "scene/Scene.h"
#include "scene/SurfaceNode.h"
#include "ui/ThreeDView.h"

namespace caps {

PlanComparison::PlanComparison(QWidget* parent) : QWidget(parent, Qt::Window)
{
  setWindowTitle(tr("CAPS - plans side by side"));
  setObjectName("results.comparison");
  auto* grid = new QGridLayout(this);
  grid->setContentsMargins(4, 4, 4, 4);
  for (int side = 0; side < 2; ++side)
  {
    titles_[size_t(side)] = new QLabel(this);
    titles_[size_t(side)]->setWordWrap(true);
    titles_[size_t(side)]->setObjectName(side == 0 ? "results.comparison.leftTitle" : "results.comparison.rightTitle");
    views_[size_t(side)] = new ui::ThreeDView(this);
    views_[size_t(side)]->setObjectName(side == 0 ? "results.comparison.left" : "results.comparison.right");
    grid->addWidget(titles_[size_t(side)], 0, side);
    grid->addWidget(views_[size_t(side)], 1, side);
  }
  grid->setRowStretch(1, 1);
  // One camera for both views: turning one turns the other.
  views_[1]->renderer()->SetActiveCamera(views_[0]->renderer()->GetActiveCamera());
  camera_observer_ = vtkSmartPointer<vtkCallbackCommand>::New();
  camera_observer_->SetClientData(this);
  camera_observer_->SetCallback([](vtkObject*, unsigned long, void* self, void*) {
    auto* comparison = static_cast<PlanComparison*>(self);
    for (ui::ThreeDView* view : comparison->views_)
      view->requestRender();
  });
  observer_tag_ = views_[0]->renderer()->GetActiveCamera()->AddObserver(vtkCommand::ModifiedEvent, camera_observer_);
  resize(1200, 640);
}

PlanComparison::~PlanComparison()
{
  views_[0]->renderer()->GetActiveCamera()->RemoveObserver(observer_tag_);
}

void PlanComparison::show(ResultsLogic& logic, const PredictedPlan& left, const PredictedPlan& right,
                          ResultQuantity quantity, const std::array<QString, 2>& summaries)
{
  Scene& scene = logic.scene();
  const std::array<const PredictedPlan*, 2> plans{&left, &right};
  std::array<vtkPolyData*, 2> before{}, after{};
  for (size_t side = 0; side < 2; ++side)
  {
    auto* b = scene.nodeAs<SurfaceNode>(plans[side]->before);
    auto* a = scene.nodeAs<SurfaceNode>(plans[side]->after);
    if (!b || !a || !b->polyData() || !a->polyData())
      throw std::invalid_argument("plan '" + plans[side]->name + "' has no predicted skin: simulate it first");
    before[side] = b->polyData();
    after[side] = a->polyData();
  }
  // One range over both plans, so equal colours are equal values.
  const QuantityStyle style = quantityStyle(quantity);
  range_ = {0.0, 0.0};
  for (size_t side = 0; side < 2; ++side)
  {
    const auto r = ResultsLogic::colourRange(after[side], quantity);
    range_ = side == 0 ? r : std::array<double, 2>{std::min(range_[0], r[0]), std::max(range_[1], r[1])};
  }
  SurfaceNode* head = logic.headSkin();
  for (size_t side = 0; side < 2; ++side)
  {
    ui::ThreeDView& view = *views_[side];
    view.removeSurface("head");
    view.removeSurface("plan");
    if (head && head->polyData())
    {
      ui::SurfaceStyle headStyle;
      headStyle.colour = head->color();
      view.setSurface("head", ResultsLogic::headWithoutPatch(head->polyData(), before[side]), headStyle);
    }
    ui::SurfaceStyle planStyle;
    planStyle.colour = {0.93, 0.78, 0.69};
    planStyle.colourArray = style.array;
    planStyle.range = range_;
    planStyle.colourMap = style.colourMap.empty() ? "viridis" : style.colourMap;
    planStyle.colourBarTitle = style.barTitle;
    view.setSurface("plan", after[side], planStyle);
    titles_[side]->setText("<b>" + QString::fromStdString(plans[side]->name) + "</b> &nbsp; " + summaries[side]);
  }
  // Framed on the left plan; the right one shares the camera.
  if (const auto* planNode = scene.nodeAs<PlanNode>(left.plan))
    if (const auto camera = logic.planCamera(*planNode, before[0]))
    {
      vtkCamera* c = views_[0]->renderer()->GetActiveCamera();
      c->SetPosition(camera->position.data());
      c->SetFocalPoint(camera->focalPoint.data());
      c->SetViewUp(camera->viewUp.data());
      c->SetViewAngle(camera->viewAngle);
    }
  for (ui::ThreeDView* view : views_)
  {
    view->renderer()->ResetCameraClippingRange();
    view->requestRender();
  }
  QWidget::show();
  raise();
}

} // namespace caps
