#include "modules/incision/IncisionLogic.h"

#include "modules/rangemap/RangeMapLogic.h"
#include "planning/CutOnSoundSkin.h"
#include "scene/RangeMapNode.h"
#include "scene/VolumeNode.h"

#include "fem/VtuWriter.h"
#include "scene/FeMeshNode.h"
#include "scene/PlanNode.h"
#include "scene/Scene.h"
#include "scene/SolutionNode.h"
#include "scene/SurfaceNode.h"

#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <cmath>
#include <stdexcept>

namespace caps {

const planning::ProcedureLibrary& IncisionLogic::procedures()
{
  if (!library_)
    library_ = planning::ProcedureLibrary::load(planning::defaultProceduresFolder());
  return *library_;
}

const planning::ProcedureLibrary& IncisionLogic::reloadProcedures(const std::filesystem::path& folder)
{
  library_ = planning::ProcedureLibrary::load(folder);
  return *library_;
}

planning::IncisionPlan IncisionLogic::placeProcedure(const std::string& id, const seg::RangeMap& skin,
                                                     const planning::SkinPoint& at,
                                                     const std::map<std::string, double>& values)
{
  return planning::findProcedure(procedures(), id).place(skin, at, values);
}

planning::IncisionPlan IncisionLogic::applyRecipe(const planning::PlanRecipe& recipe, const seg::RangeMap& skin)
{
  return planning::applyRecipe(recipe, skin, procedures());
}

std::string IncisionLogic::cutOnUnsoundSkin(const planning::IncisionPlan& plan, const seg::RangeMap& skin,
                                            const RangeMapNode& skinNode) const
{
  const auto* volume = scene().nodeAs<VolumeNode>(skinNode.sourceVolumeId());
  if (!volume || !volume->image())
    return {};
  const RangeMapLogic rangeMaps(scene());
  const std::string metal = planning::cutInMetalStreaks(plan, skin, rangeMaps.metalOf(*volume), volume->image());
  return !metal.empty() ? metal
                        : planning::cutAgainstAnObject(plan, skin, rangeMaps.againstAnObject(*volume, skin.frame()));
}

void IncisionLogic::writePlan(const planning::IncisionPlan& plan, PlanNode& node)
{
  node.setProcedure(plan.procedure());
  node.setGenerator(plan.generator());
  node.setParameters(plan.parameters());
  node.setUnderminingBand(plan.underminingBand());
  node.setCutDepth(planning::cutDepthId(plan.cutDepth()));
  node.setCutPath(plan.cutPath());
  node.setCentre(Eigen::Vector2d(plan.centre().theta, plan.centre().z));
  const auto offsets = plan.borderOffsets();
  node.setBorderOffsets(plan.isExcision() ? std::vector<Eigen::Vector2d>(offsets.begin(), offsets.end())
                                          : std::vector<Eigen::Vector2d>{});
  std::vector<std::array<int, 4>> sutures;
  for (const auto& s : plan.writtenSutures())
    sutures.push_back({s.a[0], s.a[1], s.b[0], s.b[1]});
  node.setSutures(std::move(sutures));
  node.setWoundLineNames(plan.woundLineNames());
}

planning::IncisionPlan IncisionLogic::readPlan(const PlanNode& node)
{
  planning::IncisionPlan plan(node.cutPath(), planning::SkinPoint{node.centre().x(), node.centre().y()});
  plan.setProcedure(node.procedure());
  plan.setGenerator(node.generator());
  plan.setParameters(node.parameters());
  plan.setUnderminingBand(node.underminingBand());
  plan.setCutDepth(planning::cutDepthFromId(node.cutDepth()).value_or(planning::CutDepth::Bone));
  const int loop = planning::holeLoopSize(plan.pointCount());
  const auto& offsets = node.borderOffsets();
  if (!offsets.empty() && int(offsets.size()) != loop)
    throw std::invalid_argument("plan '" + node.name() + "' has " + std::to_string(offsets.size()) +
                                " excision offsets but its cut has " + std::to_string(loop) +
                                " border points: the scene was edited by hand; draw the excision again.");
  for (int v = 0; v < int(offsets.size()); ++v)
    if (!offsets[std::size_t(v)].isZero(0.0))
      plan.offsetBorderPoint(v, offsets[std::size_t(v)]);
  std::vector<planning::SutureEdges> written;
  for (const auto& s : node.sutures())
    written.push_back({{s[0], s[1]}, {s[2], s[3]}});
  // throws SutureError (an invalid_argument) naming the pair
  plan.setSutures(std::move(written), node.woundLineNames());
  // The undermined regions as the node's recipe leaves them (placing a
  // procedure starts afresh, "clear-undermining" empties them).
  const nlohmann::json& operations = node.operations();
  for (std::size_t k = 0; operations.is_array() && k < operations.size(); ++k)
  {
    const nlohmann::json& o = operations[k];
    const auto kind = o.is_object() ? o.find("operation") : o.end();
    if (!o.is_object() || kind == o.end() || !kind->is_string())
      continue; // readRecipe() names it
    if (*kind == "place" || *kind == "clear-undermining")
      plan.clearUnderminedRegions();
    else if (*kind == "undermine")
      try
      {
        const auto operation = planning::operationFromJson(o, int(k + 1));
        plan.addUnderminedRegion(std::get<planning::UndermineRegion>(operation).region);
      }
      catch (const planning::RecipeError& e)
      {
        throw planning::RecipeError(e.operation(), "plan '" + node.name() + "': " + e.what());
      }
  }
  return plan;
}

void IncisionLogic::writeRecipe(const planning::PlanRecipe& recipe, PlanNode& node)
{
  nlohmann::json operations = nlohmann::json::array();
  for (const auto& o : recipe.operations)
    operations.push_back(planning::operationToJson(o));
  node.setOperations(std::move(operations));
  node.setCtSha256(recipe.ctSha256);
  node.setSoftwareVersion(recipe.softwareVersion);
  const nlohmann::json written = planning::recipeToJson(recipe);
  node.setSimulation(written.contains("simulation") ? written["simulation"] : nlohmann::json());
  node.setPredictionCheck(written.contains("prediction") ? written["prediction"] : nlohmann::json());
  node.setClosure(written.contains("closure") ? written["closure"] : nlohmann::json());
}

std::optional<planning::PlanRecipe> IncisionLogic::readRecipe(const PlanNode& node)
{
  if (node.operations().empty())
    return std::nullopt;
  // Through the plan file's reader, so the scene and plan.json accept the same.
  try
  {
    return planning::recipeFromJson({{"format", "caps-plan"},
                                     {"formatVersion", planning::recipeFormatVersion},
                                     {"softwareVersion", node.softwareVersion()},
                                     {"ctSha256", node.ctSha256()},
                                     {"operations", node.operations()},
                                     {"simulation", node.simulation()},
                                     {"prediction", node.predictionCheck()},
                                     {"closure", node.closure()}});
  }
  catch (const planning::RecipeError& e)
  {
    throw planning::RecipeError(e.operation(), "plan '" + node.name() + "': " + e.what());
  }
}

namespace {

/// The FE mesh (and point arrays) as a VTK grid, through the VTU document
/// the model files are written as, so scene and files hold the same thing.
vtkSmartPointer<vtkUnstructuredGrid> gridOf(const fem::Mesh& mesh, const std::vector<fem::VtuArray>& pointData)
{
  auto reader = vtkSmartPointer<vtkXMLUnstructuredGridReader>::New();
  reader->ReadFromInputStringOn();
  reader->SetInputString(fem::vtuDocument(mesh, pointData));
  reader->Update();
  vtkSmartPointer<vtkUnstructuredGrid> grid = reader->GetOutput();
  if (!grid || grid->GetNumberOfPoints() != mesh.nodeCount())
    throw std::runtime_error("the finite element model could not be put into the scene (VTU conversion failed)");
  return grid;
}

} // namespace

IncisionLogic::PredictionNodes IncisionLogic::addPrediction(const std::string& name, const planning::IncisionPlan& plan,
                                                            const planning::PlanRecipe& recipe,
                                                            const planning::PlanPrediction& prediction,
                                                            const planning::PlanDisplay& display,
                                                            const NodeId& skinMapId, const NodeId& keepPlan)
{
  // Everything built first, so a failure leaves the scene as it was.
  const Eigen::Map<const Eigen::Matrix3Xd> u(prediction.displacements.data(), 3, prediction.displacements.size() / 3);
  vtkSmartPointer<vtkUnstructuredGrid> meshGrid = gridOf(prediction.continuum.mesh, {});
  vtkSmartPointer<vtkUnstructuredGrid> resultGrid =
    gridOf(prediction.continuum.mesh, {{"displacement_mm", Eigen::MatrixXd(u)}});
  vtkSmartPointer<vtkPolyData> before = planning::planDisplayPolyData(display, 0.0);
  vtkSmartPointer<vtkPolyData> after = planning::planDisplayPolyData(display, 1.0);
  vtkSmartPointer<vtkPolyData> gaping = planning::gapingSkinPolyData(display, prediction);

  PredictionNodes ids;
  if (!keepPlan.empty())
  {
    auto* kept = scene().nodeAs<PlanNode>(keepPlan);
    if (!kept)
      throw std::invalid_argument("the plan node " + keepPlan +
                                  " the prediction was made for is no longer in the scene");
    writeRecipe(recipe, *kept);
    ids.plan = keepPlan;
  }
  else
  {
    auto* planNode = scene().add<PlanNode>();
    planNode->setName(name);
    writePlan(plan, *planNode);
    writeRecipe(recipe, *planNode);
    planNode->setRangeMapId(skinMapId);
    ids.plan = planNode->id();
  }

  auto* meshNode = scene().add<FeMeshNode>();
  meshNode->setName(name + " model");
  meshNode->setMesh(meshGrid);
  meshNode->setPlanId(ids.plan);
  ids.mesh = meshNode->id();

  auto* solution = scene().add<SolutionNode>();
  solution->setName(name + " closure");
  solution->setMeshId(ids.mesh);
  solution->setLoadCase("sutures closed");
  solution->setResult(resultGrid);
  ids.solution = solution->id();

  const auto surface = [&](vtkSmartPointer<vtkPolyData> data, const std::string& when, bool visible) {
    auto* node = scene().add<SurfaceNode>();
    node->setName(name + " skin " + when);
    node->setPolyData(data);
    node->setColor({0.93, 0.78, 0.69});
    node->setVisible(visible);
    return node->id();
  };
  ids.skinBefore = surface(before, "before", false);
  ids.skinAfter = surface(after, "after", true);
  if (gaping)
    ids.skinGaping = surface(gaping, "gaping", false);
  return ids;
}

planning::SimulationOptions IncisionLogic::simulationOptions(const PlanNode& node)
{
  planning::SimulationOptions options;
  const nlohmann::json& s = node.simulation();
  if (!s.is_object() || s.empty())
  { // not predicted yet: the prediction is the large-deformation one
    options.model = planning::TissueModel::LargeDeformation;
    options.preTension = planning::SkinPreTension{}; // living skin is tense
    return options;
  }
  auto number = [&s](const char* key, double& out, double lowest) {
    const auto it = s.find(key);
    if (it != s.end() && it->is_number() && std::isfinite(it->get<double>()) && it->get<double>() >= lowest)
      out = it->get<double>();
  };
  auto integer = [&s](const char* key, int& out, int lowest, int highest) {
    const auto it = s.find(key);
    if (it != s.end() && it->is_number_integer() && it->get<long long>() >= lowest && it->get<long long>() <= highest)
      out = int(it->get<long long>());
  };
  number("elementSize", options.elementSize, 1e-3);
  number("regionRadius", options.regionRadius, 1e-3);
  double width = -1.0; // absent: the procedure's band (planning::underminingWidthFor())
  number("underminingWidth", width, 0.0);
  if (width >= 0.0)
    options.underminingWidth = width;
  integer("layerCount", options.layerCount, 1, 16);
  int cut = -1; // absent: the procedure's depth (planning::cutLayersFor())
  integer("cutLayers", cut, 0, options.layerCount);
  if (cut >= 0)
    options.cutLayers = cut;
  if (const auto model = s.find("model"); model != s.end() && model->is_string())
    options.model = planning::tissueModelFromId(model->get<std::string>()).value_or(options.model);
  // A record without one was predicted on slack skin (before pre-tension).
  if (const auto tension = s.find("preTension"); tension != s.end() && tension->is_object())
  {
    const auto along = tension->find("alongLines"), across = tension->find("acrossLines");
    if (along != tension->end() && across != tension->end() && along->is_number() && across->is_number())
    {
      planning::SkinPreTension t;
      t.alongLines = along->get<double>();
      t.acrossLines = across->get<double>();
      if (t.alongLines >= 0.0 && t.acrossLines >= 0.0 && t.alongLines <= 1.0 && t.acrossLines <= 1.0)
        options.preTension = t;
    }
  }
  if (const auto materials = s.find("materials"); materials != s.end() && materials->is_array())
  {
    fem::MaterialTable table;
    bool complete = true;
    for (const auto& m : *materials)
    {
      complete = complete && m.is_object() && m.contains("layer") && m["layer"].is_number_integer() &&
                 m.contains("youngsModulusMPa") && m["youngsModulusMPa"].is_number() && m.contains("poissonRatio") &&
                 m["poissonRatio"].is_number();
      if (!complete)
        break;
      const double e = m["youngsModulusMPa"].get<double>(), nu = m["poissonRatio"].get<double>();
      complete = planning::materialProblem(e, nu).empty();
      table[int(m["layer"].get<long long>())] = fem::LinearElasticMaterial{e, nu, 1.0e-9};
    }
    for (int layer = 0; layer < options.layerCount; ++layer)
      complete = complete && table.count(layer);
    if (complete)
      options.materials = table;
  }
  return options;
}

nlohmann::json IncisionLogic::simulationRecord(const planning::SimulationOptions& options)
{
  nlohmann::json j = {{"elementSize", options.elementSize},
                      {"regionRadius", options.regionRadius},
                      {"layerCount", options.layerCount},
                      {"model", planning::tissueModelId(options.model)}};
  if (options.underminingWidth)
    j["underminingWidth"] = *options.underminingWidth;
  if (options.cutLayers)
    j["cutLayers"] = *options.cutLayers;
  if (options.preTension)
    j["preTension"] = {{"alongLines", options.preTension->alongLines},
                       {"acrossLines", options.preTension->acrossLines}};
  const fem::MaterialTable materials =
    options.materials.empty() ? planning::defaultFacialTissueMaterials(options.layerCount) : options.materials;
  nlohmann::json list = nlohmann::json::array();
  for (const auto& [layer, m] : materials)
    list.push_back({{"layer", layer}, {"youngsModulusMPa", m.youngsModulus}, {"poissonRatio", m.poissonRatio}});
  j["materials"] = std::move(list);
  return j;
}

} // namespace caps
