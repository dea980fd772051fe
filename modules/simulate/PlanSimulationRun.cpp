#include "modules/simulate/PlanSimulationRun.h"

#include <algorithm>
#include <memory>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include <vtkCellArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnsignedCharArray.h>

#include "modules/rangemap/RangeMapLogic.h"
#include "scene/FeMeshNode.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/SolutionNode.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"
#include "segmentation/SkinShade.h"

namespace caps::simulate {
namespace {

constexpr double kPi = 3.14159265358979323846;

double secondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

std::string layerName(int layer)
{
  switch (layer)
  {
  case 0:
    return "Skin (dermis)";
  case 1:
    return "Subcutaneous fat";
  case 2:
    return "Muscle / SMAS";
  default:
  {
    std::string name = "Layer ";
    name += std::to_string(layer + 1);
    name += " (as muscle)";
    return name;
  }
  }
}

std::string facialTissueSource()
{
  return "Linear elastic, small strain: assumed orders of magnitude of published finite element models of the "
         "face, not measurements of this patient.\n"
         "Skin (dermis) E = 0.15 MPa, fat 0.01 MPa, muscle / SMAS 0.05 MPa, \u03bd = 0.45 everywhere.\n"
         "Sources: Chabanas, Luboz & Payan, Med. Image Anal. 7(2), 2003; Keeve et al., Comput. Aided Surg. 3, "
         "1998; Barbarino et al., J. Biomech. Eng. 131(4), 2009; Mazza & Barbarino, Facial Plast. Surg. Clin. "
         "N. Am. 19(4), 2011 (see planning/PlanSimulation.cpp).\n"
         "Sutures alone load the model, so the displacements depend only on the ratios of the moduli and on \u03bd; "
         "the forces and stresses scale with E.";
}

PlanRunInput preparePlanRun(const Scene& scene, const NodeId& planId, const planning::SimulationOptions& options)
{
  const auto* node = scene.nodeAs<PlanNode>(planId);
  if (!node)
    throw std::invalid_argument("there is no plan to simulate: place one in the Incision module first");
  const auto [skinNode, boneNode] = RangeMapLogic::mapsOf(scene, *node);
  if (!skinNode || !boneNode)
    throw std::invalid_argument("the scene has no " + std::string(!skinNode ? "skin" : "bone") +
                                " range map for plan \"" + node->name() +
                                "\": build the range maps in the RangeMap module first");
  PlanRunInput in;
  in.planId = node->id();
  in.name = node->name();
  in.plan = IncisionLogic::readPlan(*node);
  if (auto recipe = IncisionLogic::readRecipe(*node))
    in.recipe = std::move(*recipe);
  else
  {
    in.recipe.ctSha256 = node->ctSha256();
    in.recipe.softwareVersion = node->softwareVersion();
  }
  in.skin = RangeMapLogic::toRangeMap(*skinNode);
  in.bone = RangeMapLogic::toRangeMap(*boneNode);
  in.skinMapId = skinNode->id();
  // The CT the maps were built from; maps of older scenes: the first CT.
  const auto volumes = scene.nodesOfType(NodeType::Volume);
  if (const auto* source = scene.nodeAs<VolumeNode>(skinNode->sourceVolumeId()))
    in.ct = source->image();
  else if (!volumes.empty())
    in.ct = static_cast<const VolumeNode*>(volumes.front())->image();
  in.options = options;
  for (const auto& [layer, m] : options.materials)
  {
    const std::string problem = planning::materialProblem(m.youngsModulus, m.poissonRatio);
    if (!problem.empty())
      throw std::invalid_argument("the material of " + layerName(layer) + ": " + problem);
  }
  return in;
}

ModelSize estimateModel(const PlanRunInput& input)
{
  const auto start = std::chrono::steady_clock::now();
  planning::SimulationOptions options = input.options;
  options.progress = nullptr;
  const planning::PlanPrediction meshed = planning::meshPlan(input.skin, input.bone, input.plan, options);
  ModelSize size;
  size.nodes = meshed.continuum.mesh.nodeCount();
  size.elements = Eigen::Index(meshed.continuum.mesh.elements.size());
  size.dofs = meshed.continuum.mesh.dofCount();
  size.seconds = secondsSince(start);
  return size;
}

PlanRunResult runPlan(const PlanRunInput& input, const TaskProgress& progress)
{
  PlanRunResult r;
  // Fractions of the whole run: the simulation takes most of it.
  seg::reportProgress(progress, 0.0, "Skin shade from the CT");
  auto start = std::chrono::steady_clock::now();
  const planning::SkinShade shade = planning::skinShadeOfCt(input.ct, input.skin);
  r.shadeNote = shade.note;
  r.shadeSeconds = secondsSince(start);

  planning::SimulationOptions options = input.options;
  options.progress = [&progress](double fraction, const std::string& step) {
    return !progress || progress(0.05 + 0.8 * fraction, step);
  };
  r.prediction = planning::simulatePlan(input.skin, input.bone, input.plan, options);

  seg::reportProgress(progress, 0.87, "Display surfaces (\u00a74.7)");
  start = std::chrono::steady_clock::now();
  r.display = planning::buildPlanDisplay(r.prediction, input.skin, shade.map());
  r.displaySeconds = secondsSince(start);

  seg::reportProgress(progress, 0.95, "Skin stress near the wound");
  start = std::chrono::steady_clock::now();
  r.woundStress = planning::woundSkinStress(r.prediction, kWoundRadius);
  const seg::CylindricalPoint at = input.skin.frame().toCylindrical(r.woundStress.original);
  r.woundStressTheta = at.theta;
  r.woundStressZ = at.z;
  r.tension = planning::woundTension(r.prediction, input.plan);
  r.stressSeconds = secondsSince(start);

  seg::reportProgress(progress, 0.98, "Model drawing");
  r.modelLines = modelDrawing(r.prediction);
  seg::reportProgress(progress, 1.0, "Adding the prediction to the scene");
  return r;
}

PlanRunNodes addPlanRun(Scene& scene, const PlanRunInput& input, const PlanRunResult& result, bool showModel,
                        bool keepPlanNode)
{
  planning::PlanRecipe recipe = input.recipe;
  recipe.elementSize = input.options.elementSize;
  recipe.cutLayers = input.options.cutLayers;
  recipe.underminingWidth = input.options.underminingWidth;
  recipe.model = input.options.model;
  recipe.preTension.reset();
  if (input.options.preTension)
    recipe.preTension =
      std::array<double, 2>{input.options.preTension->alongLines, input.options.preTension->acrossLines};
  recipe.prediction = result.prediction.check;
  recipe.closure = planning::closureRecordOf(result.prediction, result.woundStress, result.tension);

  // What the old prediction was, found before the new nodes share its names.
  std::vector<NodeId> old;
  const std::string& name = input.name;
  std::vector<NodeId> oldMeshes;
  if (scene.nodeAs<PlanNode>(input.planId) && !keepPlanNode)
    old.push_back(input.planId);
  for (Node* n : scene.nodesOfType(NodeType::FeMesh))
    if (static_cast<FeMeshNode*>(n)->planId() == input.planId || n->name() == name + " model")
      oldMeshes.push_back(n->id());
  old.insert(old.end(), oldMeshes.begin(), oldMeshes.end());
  for (Node* n : scene.nodesOfType(NodeType::Solution))
  {
    const NodeId& mesh = static_cast<SolutionNode*>(n)->meshId();
    if (std::find(oldMeshes.begin(), oldMeshes.end(), mesh) != oldMeshes.end() || n->name() == name + " closure")
      old.push_back(n->id());
  }
  for (Node* n : scene.nodesOfType(NodeType::Surface))
    if (n->name() == name + " skin before" || n->name() == name + " skin after" || n->name() == name + " skin gaping" ||
        n->name() == name + " mesh")
      old.push_back(n->id());

  PlanRunNodes nodes;
  IncisionLogic logic(scene);
  nodes.prediction = logic.addPrediction(name, input.plan, recipe, result.prediction, result.display, input.skinMapId,
                                         keepPlanNode ? input.planId : NodeId());
  std::vector<NodeId> added = {nodes.prediction.mesh, nodes.prediction.solution, nodes.prediction.skinBefore,
                               nodes.prediction.skinAfter};
  if (!keepPlanNode)
    added.push_back(nodes.prediction.plan);
  if (!nodes.prediction.skinGaping.empty())
    added.push_back(nodes.prediction.skinGaping);
  try
  {
    scene.nodeAs<PlanNode>(nodes.prediction.plan)->setSimulation(IncisionLogic::simulationRecord(input.options));
    // Filled before it joins the scene: one event for the views, not one per field.
    auto lines = std::make_unique<SurfaceNode>();
    lines->setName(name + " mesh");
    lines->setPolyData(result.modelLines);
    lines->setColourArray("colour");
    lines->setLineWidth(2.0);
    lines->setVisible(showModel);
    nodes.modelLines = scene.addNode(std::move(lines))->id();
  }
  catch (...)
  {
    // Half a prediction is worse than the old one: take the new nodes out.
    for (const NodeId& id : added)
      scene.removeNode(id);
    throw;
  }
  for (const NodeId& id : old)
    if (scene.removeNode(id))
      nodes.replaced.push_back(id);
  return nodes;
}

bool planUnchangedSince(const Scene& scene, const PlanRunInput& input)
{
  const auto* node = scene.nodeAs<PlanNode>(input.planId);
  if (!node)
    return false;
  // Writing the run's plan into a copy of the node changes nothing when
  // the node still holds it.
  PlanNode probe;
  probe.fromJson(node->toJson());
  IncisionLogic::writePlan(input.plan, probe);
  nlohmann::json written = probe.toJson(), held = node->toJson();
  written.erase("id");
  held.erase("id");
  return written == held;
}

vtkSmartPointer<vtkPolyData> modelDrawing(const planning::PlanPrediction& prediction, int steps, double lift)
{
  if (steps < 1)
    throw std::invalid_argument("modelDrawing: at least one step per element edge");
  const fem::ContinuumMesh& c = prediction.continuum;
  const Eigen::Matrix3Xd& x = c.mesh.nodes;
  const Eigen::Index nodeCount = c.mesh.nodeCount();

  // Outward direction of every node: from the bone end of its column to the skin end.
  Eigen::Matrix3Xd outward = Eigen::Matrix3Xd::Zero(3, nodeCount);
  auto direct = [&](const std::vector<int>& column) {
    int top = -1, bottom = -1;
    for (int n : column)
      if (n >= 0)
      {
        if (top < 0)
          top = n;
        bottom = n;
      }
    if (top < 0 || top == bottom)
      return;
    const Eigen::Vector3d d = (x.col(top) - x.col(bottom)).normalized();
    for (int n : column)
      if (n >= 0)
        outward.col(n) = d;
  };
  for (const auto& column : c.vertexColumns)
    direct(column);
  for (const auto& column : c.edgeColumns)
    direct(column);
  auto at = [&](int n) -> Eigen::Vector3d { return x.col(n) + lift * outward.col(n); };

  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  auto colours = vtkSmartPointer<vtkUnsignedCharArray>::New();
  colours->SetName("colour");
  colours->SetNumberOfComponents(3);
  auto lines = vtkSmartPointer<vtkCellArray>::New();
  auto verts = vtkSmartPointer<vtkCellArray>::New();
  auto addPoint = [&](const Eigen::Vector3d& p, const unsigned char(&rgb)[3]) {
    const vtkIdType id = points->InsertNextPoint(p.x(), p.y(), p.z());
    colours->InsertNextTypedTuple(rgb);
    return id;
  };

  // Skin element edges: surface-mesh edges whose columns reach the skin; the
  // quadratic edge through the two corner nodes and the mid-side node.
  for (std::size_t e = 0; e < c.edges.size() && e < c.edgeColumns.size(); ++e)
  {
    const int a = c.vertexColumns[std::size_t(c.edges[e][0])].front();
    const int b = c.vertexColumns[std::size_t(c.edges[e][1])].front();
    const int m = c.edgeColumns[e].front();
    if (a < 0 || b < 0 || m < 0)
      continue;
    std::vector<vtkIdType> ids;
    for (int k = 0; k <= steps; ++k)
    {
      const double t = -1.0 + 2.0 * k / steps;
      const Eigen::Vector3d p = 0.5 * t * (t - 1.0) * at(a) + (1.0 - t * t) * at(m) + 0.5 * t * (t + 1.0) * at(b);
      ids.push_back(addPoint(p, kEdgeColour));
    }
    lines->InsertNextCell(vtkIdType(ids.size()), ids.data());
  }
  // Fixed nodes (all three directions): points.
  for (int n : c.fixedNodes)
  {
    const vtkIdType id = addPoint(at(n), kFixedColour);
    verts->InsertNextCell(1, &id);
  }
  // Sutures: the node to the node it is sewn onto.
  for (const fem::Suture& s : c.sutures)
  {
    const vtkIdType ids[2] = {addPoint(at(s.node), kSutureColour), addPoint(at(s.target), kSutureColour)};
    lines->InsertNextCell(2, ids);
  }

  auto poly = vtkSmartPointer<vtkPolyData>::New();
  poly->SetPoints(points);
  poly->SetLines(lines);
  poly->SetVerts(verts);
  poly->GetPointData()->AddArray(colours);
  return poly;
}

std::string summaryText(const PlanRunResult& r)
{
  const planning::PlanPrediction& p = r.prediction;
  std::ostringstream out;
  // A failed check comes first: what follows is then not an ordinary result.
  if (const std::string warning = planning::checkWarning(p.check); !warning.empty())
    out << warning << "\n";
  out << "Tissue model: " << planning::tissueModelDescription(p.check.model) << "\n";
  out << "Checks: " << planning::checkSummary(p.check) << "\n";
  if (!p.check.caveat.empty())
    out << "Caveat: " << p.check.caveat << "\n";
  out << "Model: " << p.continuum.mesh.nodeCount() << " nodes, " << p.continuum.mesh.elements.size() << " elements, "
      << p.dofCount << " DOF (" << p.reducedDofCount << " free)\n";
  out << std::fixed << std::setprecision(2) << "Times: skin shade " << r.shadeSeconds << " s, mesh " << p.times.mesh
      << " s, assembly " << p.times.assemble << " s, factorisation " << p.times.factor << " s, solve " << p.times.solve
      << " s, display " << r.displaySeconds << " s, wound stress " << r.stressSeconds << " s\n";
  out << "Wound " << p.maxSutureGapBefore << " mm wide before; largest suture gap after the solve " << std::scientific
      << std::setprecision(2) << p.maxSutureGap << " mm\n";
  out << std::defaultfloat << std::setprecision(4) << "Closure force: " << p.closure.magnitudeSum << " N (sum over "
      << p.closure.sutures.size() << " sutures; largest " << p.closure.largest << " N)\n";
  out << std::fixed << std::setprecision(1) << "Peak skin stress within " << kWoundRadius
      << " mm of the wound: " << 1e3 * r.woundStress.peakVonMises << " kPa von Mises at \u03b8 "
      << r.woundStressTheta * 180.0 / kPi << "\u00b0, z " << r.woundStressZ << " mm (" << r.woundStress.distance
      << " mm from the wound edge)";
  if (!r.shadeNote.empty())
    out << "\nNote: " << r.shadeNote;
  if (!p.surface.message.empty())
    out << "\nNote: " << p.surface.message;
  return out.str();
}

} // namespace caps::simulate
