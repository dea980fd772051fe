#include "modules/results/ResultsLogic.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkIdList.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkStaticPointLocator.h>

#include "modules/incision/IncisionLogic.h"
#include "planning/SkinChart.h"
#include "planning/WoundStress.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/SnapshotNode.h"
#include "scene/SurfaceNode.h"

namespace caps {
namespace {

/// The wound band of the peak stress, as caps plan and the report use it.
constexpr double kWoundStressRadius = 10.0; // mm

SurfaceNode* surfaceNamed(const Scene& scene, const std::string& name)
{
  for (Node* n : scene.nodesOfType(NodeType::Surface))
    if (n->name() == name)
      return static_cast<SurfaceNode*>(n);
  return nullptr;
}

} // namespace

std::vector<ResultQuantity> resultQuantities()
{
  return {ResultQuantity::SkinShade, ResultQuantity::Displacement, ResultQuantity::VonMises, ResultQuantity::MeanStress,
          ResultQuantity::EquivalentStrain};
}

QuantityStyle quantityStyle(ResultQuantity quantity)
{
  switch (quantity)
  {
  case ResultQuantity::SkinShade:
    return {"skin shade", "skin_colour", "", "", false};
  case ResultQuantity::Displacement:
    return {"displacement", "displacement_magnitude_mm", "viridis", "displacement (mm)", false};
  case ResultQuantity::VonMises:
    return {"von Mises stress", "von_mises_kPa", "viridis", "von Mises stress (kPa)", false};
  // Signed: compression blue, tension red, zero grey.
  case ResultQuantity::MeanStress:
    return {"mean stress", "mean_stress_kPa", "cool-warm", "mean stress (kPa)", true};
  case ResultQuantity::EquivalentStrain:
    return {"equivalent strain", "equivalent_strain", "viridis", "equivalent strain (von Mises)", false};
  }
  return {};
}

std::vector<PredictedPlan> ResultsLogic::predictedPlans() const
{
  std::vector<PredictedPlan> plans;
  for (Node* n : scene().nodesOfType(NodeType::Plan))
  {
    const SurfaceNode* before = surfaceNamed(scene(), n->name() + " skin before");
    const SurfaceNode* after = surfaceNamed(scene(), n->name() + " skin after");
    if (!before || !after || !before->polyData() || !after->polyData())
      continue;
    vtkPolyData* b = before->polyData();
    if (b->GetNumberOfPoints() == 0 || b->GetNumberOfPoints() != after->polyData()->GetNumberOfPoints())
      continue;
    vtkDataArray* u = b->GetPointData()->GetArray("displacement_mm");
    if (!u || u->GetNumberOfComponents() != 3 || u->GetNumberOfTuples() != b->GetNumberOfPoints())
      continue;
    plans.push_back({n->name(), n->id(), before->id(), after->id()});
  }
  return plans;
}

std::optional<PredictedPlan> ResultsLogic::predictedPlan(const std::string& name) const
{
  for (const PredictedPlan& p : predictedPlans())
    if (p.name == name)
      return p;
  return std::nullopt;
}

vtkSmartPointer<vtkPolyData> ResultsLogic::makeResultSurface(vtkPolyData* before)
{
  if (!before)
    throw std::invalid_argument("no surface to show");
  auto result = vtkSmartPointer<vtkPolyData>::New();
  result->ShallowCopy(before); // cells and arrays shared: they do not change with s
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  points->DeepCopy(before->GetPoints());
  result->SetPoints(points);
  return result;
}

void ResultsLogic::deform(vtkPolyData* before, vtkPolyData* result, double s)
{
  if (!before || !result || !result->GetPoints())
    throw std::invalid_argument("no surface to deform");
  const vtkIdType n = before->GetNumberOfPoints();
  vtkDataArray* u = before->GetPointData()->GetArray("displacement_mm");
  if (!u || u->GetNumberOfComponents() != 3 || u->GetNumberOfTuples() != n || result->GetNumberOfPoints() != n)
    throw std::invalid_argument("the plan's skin surface has no displacement_mm array of its size: predict the plan "
                                "again (Incision module)");
  vtkPoints* from = before->GetPoints();
  vtkPoints* to = result->GetPoints();
  double x[3], d[3];
  for (vtkIdType i = 0; i < n; ++i)
  {
    from->GetPoint(i, x);
    u->GetTuple(i, d);
    // The same expression as fem::DisplaySurface::positions: s = 1 gives the after surface.
    to->SetPoint(i, x[0] + s * d[0], x[1] + s * d[1], x[2] + s * d[2]);
  }
  to->Modified();
  result->Modified();
}

double ResultsLogic::arrayMaximum(vtkPolyData* surface, const std::string& array)
{
  vtkDataArray* a = surface ? surface->GetPointData()->GetArray(array.c_str()) : nullptr;
  if (!a || a->GetNumberOfTuples() == 0)
    return 0.0;
  double top = -INFINITY;
  for (vtkIdType i = 0; i < a->GetNumberOfTuples(); ++i)
  {
    const double v = a->GetComponent(i, 0);
    if (std::isfinite(v))
      top = std::max(top, v);
  }
  return std::isfinite(top) ? top : 0.0;
}

std::array<double, 2> ResultsLogic::colourRange(vtkPolyData* surface, ResultQuantity quantity)
{
  const QuantityStyle style = quantityStyle(quantity);
  if (style.colourMap.empty())
    return {0.0, 0.0};
  vtkDataArray* a = surface ? surface->GetPointData()->GetArray(style.array.c_str()) : nullptr;
  if (!a)
    return {0.0, 0.0};
  double lo = INFINITY, hi = -INFINITY;
  for (vtkIdType i = 0; i < a->GetNumberOfTuples(); ++i)
  {
    const double v = a->GetComponent(i, 0);
    if (!std::isfinite(v))
      continue;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  if (!std::isfinite(lo))
    return {0.0, 1.0};
  if (style.symmetric)
  {
    const double m = std::max(std::abs(lo), std::abs(hi));
    return m > 0.0 ? std::array<double, 2>{-m, m} : std::array<double, 2>{-1.0, 1.0};
  }
  return {0.0, hi > 0.0 ? hi : 1.0};
}

std::string ResultsLogic::closureKey(const PlanNode& plan)
{
  return plan.id() + "|" + plan.operations().dump() + "|" + plan.simulation().dump() + "|" + plan.procedure();
}

ClosureJob ResultsLogic::closureJob(const PlanNode& node)
{
  const auto [skinNode, boneNode] = RangeMapLogic::mapsOf(scene(), node);
  if (!skinNode || !boneNode)
    throw std::invalid_argument("the scene has no skin and bone range maps for plan \"" + node.name() +
                                "\": make them in the RangeMap module first");
  ClosureJob job;
  job.planName = node.name();
  job.skin = RangeMapLogic::toRangeMap(*skinNode);
  job.bone = RangeMapLogic::toRangeMap(*boneNode);
  // As the report's planFacts: the plan rebuilt from its recipe, meshed
  // and solved with the options it was predicted with.
  IncisionLogic incision(scene());
  const std::optional<planning::PlanRecipe> recipe = IncisionLogic::readRecipe(node);
  job.plan = recipe ? incision.applyRecipe(*recipe, job.skin) : IncisionLogic::readPlan(node);
  job.options = IncisionLogic::simulationOptions(node);
  job.options.threads = 2;
  return job;
}

namespace {

ClosureNumbers numbersOf(const planning::ClosureRecord& c)
{
  ClosureNumbers numbers;
  numbers.closureForce = c.force;
  numbers.largestSutureForce = c.largestSuture;
  numbers.peakWoundStress = 1e3 * c.peakWoundStress;
  numbers.woundRadius = c.woundRadius;
  numbers.tensionPerCentimetre = c.tensionPerCentimetre;
  numbers.peakTensionPerCentimetre = c.peakTensionPerCentimetre;
  numbers.peakForcePerStitch = c.peakForcePerStitch;
  numbers.stitchSpacing = c.stitchSpacing;
  numbers.peakTensionLine = c.peakTensionLine;
  return numbers;
}

} // namespace

std::optional<ClosureNumbers> ResultsLogic::computeClosure(const ClosureJob& job, const TaskProgress& progress)
{
  if (progress && !progress(0.05, "Predicting " + job.planName + " again for its closure force"))
    return std::nullopt;
  const planning::PlanPrediction prediction = planning::simulatePlan(job.skin, job.bone, job.plan, job.options);
  if (progress && !progress(0.95, "Wound stress of " + job.planName))
    return std::nullopt;
  const planning::WoundStress wound = planning::woundSkinStress(prediction, kWoundStressRadius);
  return numbersOf(planning::closureRecordOf(prediction, wound, planning::woundTension(prediction, job.plan)));
}

namespace {

/// The plan's recipe, or nothing when it has none or it does not read (the
/// callers then fall back to solving again, which names the problem).
std::optional<planning::PlanRecipe> recipeOf(const PlanNode& plan)
{
  try
  {
    return IncisionLogic::readRecipe(plan);
  }
  catch (const std::exception&)
  {
    return std::nullopt;
  }
}

} // namespace

std::optional<ClosureNumbers> ResultsLogic::recordedClosure(const PlanNode& plan)
{
  const std::optional<planning::PlanRecipe> recipe = recipeOf(plan);
  if (!recipe || !recipe->closure)
    return std::nullopt;
  return numbersOf(*recipe->closure);
}

std::optional<planning::PredictionCheck> ResultsLogic::recordedCheck(const PlanNode& plan)
{
  const std::optional<planning::PlanRecipe> recipe = recipeOf(plan);
  return recipe ? recipe->prediction : std::nullopt;
}

IncisionProfile ResultsLogic::incisionProfile(const PlanNode& node, vtkPolyData* before) const
{
  const RangeMapNode* skinNode = RangeMapLogic::mapsOf(scene(), node).skin;
  if (!skinNode)
    throw std::invalid_argument("the scene has no skin range map for plan \"" + node.name() + "\"");
  IncisionProfile profile;
  if (!before || before->GetNumberOfPoints() == 0)
    return profile;
  vtkDataArray* stress = before->GetPointData()->GetArray("von_mises_kPa");
  vtkDataArray* moved = before->GetPointData()->GetArray("displacement_magnitude_mm");
  if (!stress || !moved)
    return profile;
  const seg::RangeMap skin = RangeMapLogic::toRangeMap(*skinNode);
  const planning::IncisionPlan plan = IncisionLogic::readPlan(node);
  const planning::SkinChart chart = plan.chart(skin);
  const std::vector<planning::ChartPoint> path = plan.chartPath(chart);

  auto locator = vtkSmartPointer<vtkStaticPointLocator>::New();
  locator->SetDataSet(before);
  locator->BuildLocator();
  double length = 0.0;
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  const auto sample = [&](const planning::ChartPoint& c) {
    const Eigen::Vector3d p = chart.lift(c);
    if (!p.allFinite())
      return;
    if (!profile.arcLength.empty())
      length += (p - previous).norm();
    previous = p;
    const vtkIdType v = locator->FindClosestPoint(p.data());
    if (v < 0)
      return;
    profile.arcLength.push_back(length);
    profile.vonMises.push_back(stress->GetComponent(v, 0));
    profile.displacement.push_back(moved->GetComponent(v, 0));
  };
  // Every 0.5 mm along each segment of the cut, as the report draws it.
  for (std::size_t i = 0; i + 1 < path.size(); ++i)
  {
    const int steps = std::max(1, int(std::ceil((path[i + 1] - path[i]).norm() / 0.5)));
    for (int k = 0; k < steps; ++k)
      sample(path[i] + (path[i + 1] - path[i]) * (double(k) / steps));
  }
  if (!path.empty())
    sample(path.back());
  return profile;
}

SurfaceNode* ResultsLogic::headSkin() const
{
  SurfaceNode* fallback = nullptr;
  for (Node* n : scene().nodesOfType(NodeType::Surface))
  {
    auto* surface = static_cast<SurfaceNode*>(n);
    if (surface->sourceLabelMapId().empty() || !surface->polyData())
      continue;
    if (surface->name() == "Skin")
      return surface;
    if (!fallback && surface->name().find("kin") != std::string::npos)
      fallback = surface;
  }
  return fallback;
}

vtkSmartPointer<vtkPolyData> ResultsLogic::headWithoutPatch(vtkPolyData* head, vtkPolyData* before, double reach)
{
  auto out = vtkSmartPointer<vtkPolyData>::New();
  if (!head)
    return out;
  out->SetPoints(head->GetPoints());
  out->GetPointData()->ShallowCopy(head->GetPointData());
  if (!before || before->GetNumberOfPoints() == 0)
  {
    out->SetPolys(head->GetPolys());
    return out;
  }
  // The patch's boundary: edges only one polygon uses. Its longest loop is
  // the rim of the meshed region; the others are the wound (the cut's lips,
  // an excision's hole), whose inside is no skin after the operation.
  std::vector<char> rim(std::size_t(before->GetNumberOfPoints()), 0), wound(rim.size(), 0);
  std::vector<vtkIdType> loopOf(rim.size(), -1);
  std::map<vtkIdType, double> woundReach;
  {
    std::map<std::pair<vtkIdType, vtkIdType>, int> edges;
    vtkCellArray* polys = before->GetPolys();
    auto ids = vtkSmartPointer<vtkIdList>::New();
    polys->InitTraversal();
    while (polys->GetNextCell(ids))
      for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k)
      {
        vtkIdType a = ids->GetId(k), b = ids->GetId((k + 1) % ids->GetNumberOfIds());
        ++edges[{std::min(a, b), std::max(a, b)}];
      }
    // Loops of boundary edges by union-find, and each loop's length.
    std::vector<vtkIdType> parent(rim.size());
    for (std::size_t i = 0; i < parent.size(); ++i)
      parent[i] = vtkIdType(i);
    auto find = [&parent](vtkIdType i) {
      while (parent[std::size_t(i)] != i)
        i = parent[std::size_t(i)] = parent[std::size_t(parent[std::size_t(i)])];
      return i;
    };
    std::vector<std::pair<vtkIdType, vtkIdType>> boundary;
    for (const auto& [edge, count] : edges)
      if (count == 1)
      {
        boundary.push_back(edge);
        parent[std::size_t(find(edge.first))] = find(edge.second);
      }
    std::map<vtkIdType, double> loopLength;
    double a[3], b[3];
    for (const auto& [p, q] : boundary)
    {
      before->GetPoint(p, a);
      before->GetPoint(q, b);
      loopLength[find(p)] += std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    }
    vtkIdType outer = -1;
    for (const auto& [loop, length] : loopLength)
      if (outer < 0 || length > loopLength[outer])
        outer = loop;
    for (const auto& [p, q] : boundary)
      for (vtkIdType v : {p, q})
        (find(v) == outer ? rim : wound)[std::size_t(v)] = 1;
    // How far each wound reaches from its centre: nothing farther from its
    // edge can be inside it.
    std::map<vtkIdType, Eigen::Vector3d> centre;
    std::map<vtkIdType, int> count;
    for (std::size_t v = 0; v < wound.size(); ++v)
      if (wound[v])
      {
        before->GetPoint(vtkIdType(v), a);
        const vtkIdType loop = find(vtkIdType(v));
        centre.try_emplace(loop, Eigen::Vector3d::Zero()).first->second += Eigen::Vector3d(a[0], a[1], a[2]);
        ++count[loop];
      }
    for (auto& [loop, c] : centre)
      c /= count[loop];
    for (std::size_t v = 0; v < wound.size(); ++v)
      if (wound[v])
      {
        before->GetPoint(vtkIdType(v), a);
        const vtkIdType loop = find(vtkIdType(v));
        woundReach[loop] = std::max(woundReach[loop], (Eigen::Vector3d(a[0], a[1], a[2]) - centre[loop]).norm());
      }
    for (std::size_t v = 0; v < wound.size(); ++v)
      if (wound[v])
        loopOf[v] = find(vtkIdType(v));
  }
  auto locator = vtkSmartPointer<vtkStaticPointLocator>::New();
  locator->SetDataSet(before);
  locator->BuildLocator();
  const vtkIdType n = head->GetNumberOfPoints();
  std::vector<char> under(std::size_t(n), 0);
  double x[3], y[3];
  for (vtkIdType i = 0; i < n; ++i)
  {
    head->GetPoint(i, x);
    const vtkIdType v = locator->FindClosestPoint(x);
    if (v < 0 || rim[std::size_t(v)])
      continue;
    before->GetPoint(v, y);
    // Nearest to the wound's edge means inside the wound (the patch
    // surrounds it): that skin is cut away or sewn over, however wide the
    // excision, as far as the wound reaches from its centre.
    const double d = std::hypot(x[0] - y[0], x[1] - y[1], x[2] - y[2]);
    under[std::size_t(i)] = wound[std::size_t(v)] ? d <= woundReach[loopOf[std::size_t(v)]] : d <= reach;
  }
  auto kept = vtkSmartPointer<vtkCellArray>::New();
  vtkCellArray* polys = head->GetPolys();
  auto ids = vtkSmartPointer<vtkIdList>::New();
  polys->InitTraversal();
  while (polys->GetNextCell(ids))
  {
    bool covered = true;
    for (vtkIdType k = 0; k < ids->GetNumberOfIds() && covered; ++k)
      covered = under[std::size_t(ids->GetId(k))] != 0;
    if (!covered)
      kept->InsertNextCell(ids);
  }
  out->SetPolys(kept);
  return out;
}

std::optional<SnapshotNode::Camera> ResultsLogic::planCamera(const PlanNode& node, vtkPolyData* before) const
{
  const RangeMapNode* skinNode = RangeMapLogic::mapsOf(scene(), node).skin;
  if (!skinNode || !before || before->GetNumberOfPoints() == 0)
    return std::nullopt;
  const seg::RangeMap skin = RangeMapLogic::toRangeMap(*skinNode);
  const seg::CylindricalFrame& frame = skin.frame();
  double b[6];
  before->GetBounds(b);
  const Eigen::Vector3d centre(0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 0.5 * (b[4] + b[5]));
  const double radius = 0.5 * std::hypot(b[1] - b[0], b[3] - b[2], b[5] - b[4]);
  // Along the radial direction at the plan's centre, turned a little
  // towards the front so the face is seen and not only the cheek.
  const double theta = IncisionLogic::readPlan(node).centre().theta;
  const double front = -1.5707963267948966;
  const double diff = std::remainder(theta - front, 2.0 * 3.141592653589793);
  const Eigen::Vector3d toCamera = frame.radialDirection(front + 0.6 * diff);
  SnapshotNode::Camera camera;
  camera.viewAngle = 30.0;
  // The patch and some face around it fill the view.
  const double distance = 1.4 * radius / std::tan(0.5 * camera.viewAngle * 3.141592653589793 / 180.0);
  const Eigen::Vector3d eye = centre + distance * toCamera.normalized();
  camera.focalPoint = {centre.x(), centre.y(), centre.z()};
  camera.position = {eye.x(), eye.y(), eye.z()};
  const Eigen::Vector3d up = frame.direction();
  camera.viewUp = {up.x(), up.y(), up.z()};
  return camera;
}

SnapshotNode& ResultsLogic::addSnapshot(const std::string& caption, const ViewCapture& capture)
{
  auto* snapshot = scene().add<SnapshotNode>();
  // Named as the report's takePlanSnapshot names them.
  snapshot->setName("Snapshot " + std::to_string(scene().nodesOfType(NodeType::Snapshot).size()));
  snapshot->setCaption(caption);
  snapshot->setCamera(capture.camera);
  snapshot->setImage(capture.image);
  return *snapshot;
}

} // namespace caps
