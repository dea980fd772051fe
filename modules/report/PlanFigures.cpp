#include "modules/report/PlanFigures.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include <vtkDoubleArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>

#include "planning/SkinChart.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "modules/rangemap/RangeMapPreview.h"
#include "render/Figure.h"
#include "modules/report/PlanReport.h"
#include "modules/report/ReportDocument.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/SnapshotNode.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"

// The figures are render/Figure.h's: their types read here unqualified.
using namespace caps::render;

namespace caps::report {
namespace {

/// Pixels for a figure printed widthMm wide at dpi.
int pixels(double widthMm, double dpi)
{
  return int(std::lround(widthMm / 25.4 * dpi));
}

/// A nice upper end for a colour bar: 1, 2 or 5 × 10^k at or above value.
double niceCeiling(double value)
{
  if (!(value > 0.0))
    return 1.0;
  const double power = std::pow(10.0, std::floor(std::log10(value)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * power >= value)
      return m * power;
  return 10.0 * power;
}

} // namespace

vtkPolyData* headSkin(const Scene& scene)
{
  vtkPolyData* fallback = nullptr;
  for (Node* n : scene.nodesOfType(NodeType::Surface))
  {
    const auto* surface = static_cast<const SurfaceNode*>(n);
    if (surface->sourceLabelMapId().empty() || !surface->polyData())
      continue;
    if (surface->name() == "Skin")
      return surface->polyData();
    if (!fallback && surface->name().find("kin") != std::string::npos)
      fallback = surface->polyData();
  }
  return fallback;
}

vtkPolyData* surfaceNamed(const Scene& scene, const std::string& name)
{
  for (Node* n : scene.nodesOfType(NodeType::Surface))
    if (n->name() == name)
      return static_cast<const SurfaceNode*>(n)->polyData();
  return nullptr;
}

LineLayer incisionLine(const planning::IncisionPlan& plan, const planning::SkinChart& chart, bool labelled)
{
  LineLayer line;
  line.markLabelledPoints = labelled;
  const std::vector<planning::ChartPoint> path = plan.chartPath(chart);
  // Every cut point of a short cut; of a long one (an ellipse's 17) the
  // ends and a few between, so the labels do not cover one another.
  const std::size_t every = path.size() <= 6 ? 1 : (path.size() + 3) / 4;
  for (std::size_t i = 0; i < path.size(); ++i)
  {
    line.points.push_back(chart.lift(path[i]));
    std::string label;
    if (labelled && (i % every == 0 || i + 1 == path.size()))
    {
      label = "p";
      label += std::to_string(i);
    }
    line.labels.push_back(label);
    if (i + 1 == path.size())
      break;
    const int steps = std::max(1, int(std::ceil((path[i + 1] - path[i]).norm() / 0.5)));
    for (int k = 1; k < steps; ++k)
    {
      line.points.push_back(chart.lift(path[i] + (path[i + 1] - path[i]) * (double(k) / steps)));
      line.labels.push_back("");
    }
  }
  if (!labelled)
    line.labels.clear();
  return line;
}

PlanFigures::PlanFigures(Scene& scene, const VolumeNode& volume, double dpi) : scene_(scene), volume_(volume), dpi_(dpi)
{}

void PlanFigures::addThicknessViews(ReportDocument& doc, const PlanFacts& plan) const
{
  const RangeMapNode* thickness = mapOfPlan(plan, "thickness");
  if (!thickness)
  {
    doc.paragraph("The scene has no thickness map: make the range maps (RangeMap module) to see the tissue "
                  "thickness here.");
    return;
  }
  doc.heading("Soft-tissue thickness", 2);
  // The unwrapped map at print resolution: 170 mm wide.
  const double widthMm = 170.0;
  PreviewStyle style;
  style.low = 0.0;
  style.high = 30.0;
  style.title = "Soft-tissue thickness, radial (r_skin - r_bone)";
  style.pixelsPerSample =
    std::max(1, int(std::ceil(widthMm / 25.4 * dpi_ / std::max<Eigen::Index>(1, thickness->values().rows()) * 0.8)));
  {
    // Its 13 px labels about 2.5 mm (7 pt) high on paper: the picture is
    // mapW + 180 k pixels wide for text scale k and printed widthMm wide.
    const double mapWidth = double(thickness->values().rows() * style.pixelsPerSample);
    style.textScale = std::max(1.0, 2.5 * mapWidth / (widthMm * 13.0 - 2.5 * 180.0));
  }
  const QImage unwrapped =
    toQImage(renderRangeMapPreview(thickness->values(), thickness->zMin(), thickness->zMax(), style).GetPointer());
  doc.figures({unwrapped}, widthMm,
              {"The thickness map unwrapped around the head axis: the face in the middle, z up (mm); thickness in "
               "mm (0 to 30; thicker regions saturate). Under the incision: " +
               (std::isfinite(plan.thicknessMean) ? std::to_string(int(std::lround(plan.thicknessMin))) + " to " +
                                                      std::to_string(int(std::lround(plan.thicknessMax))) + " mm"
                                                  : std::string("not measured")) +
               "."});
  addThicknessOnFace(doc, plan);
}

void PlanFigures::addStoryboard(ReportDocument& doc) const
{
  std::vector<QImage> images;
  std::vector<std::string> captions;
  int number = 0;
  for (Node* n : scene_.nodesOfType(NodeType::Snapshot))
  {
    const auto* snapshot = static_cast<const SnapshotNode*>(n);
    const QImage image = toQImage(snapshot->image());
    if (image.isNull())
      continue;
    images.push_back(image);
    captions.push_back(std::to_string(++number) + ". " +
                       (snapshot->caption().empty() ? snapshot->name() : snapshot->caption()));
    if (images.size() == 2)
    {
      doc.figures(images, 82.0, captions, false);
      images.clear();
      captions.clear();
    }
  }
  if (!images.empty())
    doc.figures(images, 82.0, captions, false);
  if (number == 0)
    doc.paragraph("No snapshots were taken for this plan. Snapshots taken in the workstation (the views a surgeon "
                  "keeps while planning, §3.3.3) appear here in the order taken, with their captions.");
}

} // namespace caps::report

namespace caps::report {

const RangeMapNode* PlanFigures::mapOfPlan(const PlanFacts& plan, const std::string& role) const
{
  const auto* skin = scene_.nodeAs<RangeMapNode>(plan.skinMapId);
  if (!skin)
    skin = RangeMapLogic::newestMaps(scene_).skin;
  if (!skin)
    return nullptr;
  return role == "skin" ? skin : RangeMapLogic::builtWith(scene_, *skin, role);
}

seg::RangeMap PlanFigures::skinMap(const PlanFacts& plan) const
{
  const RangeMapNode* skin = mapOfPlan(plan, "skin");
  if (!skin)
    throw std::invalid_argument("the scene has no skin range map for the report's figures");
  return RangeMapLogic::toRangeMap(*skin);
}

namespace {
/// Whether the plan lies on the patient's left (towards θ = 0).
bool onTheLeft(const PlanFacts& plan)
{
  return std::sin(plan.plan.centre().theta - viewTheta(View::Front)) > 0.0;
}
} // namespace

std::string planViewName(PlanView view, bool left)
{
  switch (view)
  {
  case PlanView::Front:
    return "front";
  case PlanView::Oblique:
    return left ? "oblique, patient's left" : "oblique, patient's right";
  case PlanView::Profile:
    return left ? "profile, patient's left" : "profile, patient's right";
  case PlanView::Before:
    return "before the operation, the incision drawn";
  case PlanView::After:
    return "predicted after closure (same camera)";
  case PlanView::Stress:
    return "von Mises stress after closure (kPa)";
  }
  return "";
}

std::optional<Figure> PlanFigures::planFigure(const PlanFacts& plan, PlanView view, double printWidthMm,
                                              double heightPerWidth) const
{
  const seg::RangeMap skin = skinMap(plan);
  const seg::CylindricalFrame& frame = skin.frame();
  const planning::SkinChart chart = plan.plan.chart(skin);
  Figure figure;
  figure.printWidthMm = printWidthMm;
  figure.width = pixels(printWidthMm, dpi_);
  figure.height = int(std::lround(figure.width * heightPerWidth));
  LineLayer line = incisionLine(plan.plan, chart);
  line.widthPixels = std::max(3.0, 1.2 * figure.pixelsPerPoint());
  if (view == PlanView::Front || view == PlanView::Oblique || view == PlanView::Profile)
  {
    vtkPolyData* head = headSkin(scene_);
    if (!head)
      return std::nullopt;
    // The oblique and profile views from the side the plan is on.
    const bool left = onTheLeft(plan);
    const View v = view == PlanView::Front     ? View::Front
                   : view == PlanView::Oblique ? (left ? View::ObliqueLeft : View::ObliqueRight)
                                               : (left ? View::ProfileLeft : View::ProfileRight);
    const Eigen::Vector3d target = frame.origin() + frame.direction() * plan.plan.centre().z;
    figure.camera = lookAtCamera(target, frame.radialDirection(viewTheta(v)), frame.direction(), 105.0,
                                 figure.sceneAspect(), 20.0, 1.05);
    figure.surfaces.push_back(SurfaceLayer::solid(head, {0.90, 0.76, 0.66}));
    figure.lines.push_back(line);
    return figure;
  }
  vtkPolyData* before = surfaceNamed(scene_, plan.name + " skin before");
  vtkPolyData* after = surfaceNamed(scene_, plan.name + " skin after");
  if (!before || !after)
    return std::nullopt;
  const std::string shade = before->GetPointData()->GetArray("skin_shade") ? "skin_shade" : "skin_colour";
  if (view == PlanView::Stress)
  {
    double top = 1e3 * plan.woundStress.peakVonMises;
    if (!(top > 0.0))
      if (vtkDataArray* stress = after->GetPointData()->GetArray("von_mises_kPa"))
        top = stress->GetRange()[1];
    top = niceCeiling(top);
    figure.colourBar = ColourBar{"von Mises stress (kPa)", {0.0, top}, ColourMap::Viridis, 6, "%.0f"};
    figure.camera = fitCamera(std::vector<vtkPolyData*>{after}, frame.radialDirection(plan.plan.centre().theta),
                              frame.direction(), figure.sceneAspect(), 20.0, 1.05);
    figure.surfaces.push_back(SurfaceLayer::scalars(after, "von_mises_kPa", 0.0, top, ColourMap::Viridis));
    return figure;
  }
  // One camera for before and after: along the radial direction at the
  // plan's centre, framing both surfaces.
  figure.camera = fitCamera(std::vector<vtkPolyData*>{before, after}, frame.radialDirection(plan.plan.centre().theta),
                            frame.direction(), figure.sceneAspect(), 20.0, 1.05);
  if (view == PlanView::Before)
  {
    figure.surfaces.push_back(SurfaceLayer::pointColours(before, shade));
    figure.lines.push_back(line);
  }
  else
    figure.surfaces.push_back(SurfaceLayer::pointColours(after, shade));
  return figure;
}

void PlanFigures::addIncisionViews(ReportDocument& doc, const PlanFacts& plan) const
{
  std::vector<QImage> images;
  std::vector<std::string> captions;
  for (const PlanView view : {PlanView::Front, PlanView::Oblique, PlanView::Profile})
  {
    const std::optional<Figure> figure = planFigure(plan, view, 56.0, 1.25);
    if (!figure)
    {
      doc.paragraph("The scene has no skin surface to draw the incision on: segment the CT (Segment module).");
      return;
    }
    images.push_back(toQImage(renderFigure(*figure).GetPointer()));
    captions.push_back(planViewName(view, onTheLeft(plan)));
  }
  doc.figures(images, 56.0, captions);
  doc.paragraph("The incision drawn on the patient's skin from the CT (solid line, §3.3.1), its cut points numbered "
                "p0, p1, ... in the scalpel's order as in the measurements below (on a long cut, the ends and a few "
                "between).");
}

void PlanFigures::addPredictionViews(ReportDocument& doc, const PlanFacts& plan) const
{
  const std::optional<Figure> pre = planFigure(plan, PlanView::Before, 82.0, 0.8);
  const std::optional<Figure> post = planFigure(plan, PlanView::After, 82.0, 0.8);
  const std::optional<Figure> stress = planFigure(plan, PlanView::Stress, 120.0, 0.6);
  if (!pre || !post || !stress)
  {
    doc.paragraph("The scene does not hold the display surfaces of this plan (skin before and after): predict it "
                  "again (caps plan) to see them here.");
    return;
  }
  doc.figures({toQImage(renderFigure(*pre).GetPointer()), toQImage(renderFigure(*post).GetPointer())}, 82.0,
              {planViewName(PlanView::Before, false), planViewName(PlanView::After, false)});
  doc.figures({toQImage(renderFigure(*stress).GetPointer())}, 120.0,
              {"von Mises stress on the skin after closure (kPa), nodal averages extrapolated from the Gauss points "
               "(§4.7); largest within 10 mm of the wound " +
               std::to_string(int(std::lround(1e3 * plan.woundStress.peakVonMises))) + " kPa"});
}

void PlanFigures::addThicknessOnFace(ReportDocument& doc, const PlanFacts& plan) const
{
  vtkPolyData* head = headSkin(scene_);
  const RangeMapNode* thicknessNode = mapOfPlan(plan, "thickness");
  if (!head || !thicknessNode)
    return;
  const seg::RangeMap thickness = RangeMapLogic::toRangeMap(*thicknessNode);
  const seg::RangeMap skin = skinMap(plan);
  const seg::CylindricalFrame& frame = thickness.frame();
  // The skin painted with the thickness under each of its points.
  auto painted = vtkSmartPointer<vtkPolyData>::New();
  painted->ShallowCopy(head);
  auto values = vtkSmartPointer<vtkDoubleArray>::New();
  values->SetName("thickness_mm");
  values->SetNumberOfValues(head->GetNumberOfPoints());
  for (vtkIdType i = 0; i < head->GetNumberOfPoints(); ++i)
  {
    double x[3];
    head->GetPoint(i, x);
    const seg::CylindricalPoint c = frame.toCylindrical(Eigen::Vector3d(x[0], x[1], x[2]));
    const double t = thickness.sample(c.theta, c.z);
    values->SetValue(i, t); // NaN (no bone under it) shows grey
  }
  painted->GetPointData()->AddArray(values);
  Figure figure;
  figure.printWidthMm = 100.0;
  figure.width = pixels(figure.printWidthMm, dpi_);
  figure.height = int(std::lround(figure.width * 0.9));
  figure.colourBar = ColourBar{"soft-tissue thickness (mm)", {0.0, 30.0}, ColourMap::Viridis, 7, "%.0f"};
  const Eigen::Vector3d target = frame.origin() + frame.direction() * plan.plan.centre().z;
  figure.camera = lookAtCamera(target, frame.radialDirection(viewTheta(View::Front)), frame.direction(), 105.0,
                               figure.sceneAspect(), 20.0, 1.05);
  figure.surfaces.push_back(SurfaceLayer::scalars(painted, "thickness_mm", 0.0, 30.0, ColourMap::Viridis));
  LineLayer line = incisionLine(plan.plan, plan.plan.chart(skin));
  line.widthPixels = std::max(3.0, 1.0 * figure.pixelsPerPoint());
  line.colour = {0.85, 0.1, 0.1};
  figure.lines.push_back(line);
  doc.figures({toQImage(renderFigure(figure).GetPointer())}, 100.0,
              {"The thickness painted on the face (radial, skin to bone; grey where the ray from the axis meets "
               "no bone), the same colours as the map above, with the incision in red"});
}

} // namespace caps::report
