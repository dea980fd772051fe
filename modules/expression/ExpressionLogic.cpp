#include "modules/expression/ExpressionLogic.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include <vtkCellArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkUnsignedCharArray.h>

#include "fem/StaticAnalysis.h"
#include "planning/PlanDisplay.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "scene/ExpressionNode.h"
#include "scene/LandmarksNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/ScopedEdit.h"
#include "scene/VolumeNode.h"
#include "segmentation/LandmarkPlacement.h"
#include "segmentation/SkinShade.h"

namespace caps {
namespace expression {

const std::vector<ExpressionDefinition>& builtInExpressions()
{
  // Muscle ids of data/muscles/default.muscles; a definition id means both
  // sides. Activations: 1 is the file's strong contraction.
  static const std::vector<ExpressionDefinition> expressions{
    {"smile",
     "Smile",
     "Zygomaticus major and risorius pull the mouth corners up and out; levator labii lifts the upper lip a little",
     {{"zygomaticus_major", 1.0}, {"risorius", 0.6}, {"levator_labii_superioris", 0.3}}},
    {"frown",
     "Frown",
     "Corrugator draws the brows together and down; depressor labii pulls the lower lip down",
     {{"corrugator_supercilii", 1.0}, {"depressor_labii_inferioris", 0.8}}},
    {"pucker",
     "Pucker",
     "Orbicularis oris, upper and lower lip, purses the mouth",
     {{"orbicularis_oris_upper", 1.0}, {"orbicularis_oris_lower", 1.0}}},
    {"sneer",
     "Sneer",
     "Levator labii superioris alaeque nasi lifts the upper lip and the nose's wing",
     {{"levator_labii_superioris_alaeque_nasi", 1.0}}},
    {"fig_5_15",
     "Fig. 5.15",
     "Thesis Fig. 5.15: levator labii and temporalis",
     {{"levator_labii_superioris", 1.0}, {"temporalis", 1.0}}},
    {"fig_5_16",
     "Fig. 5.16",
     "Thesis Fig. 5.16: risorius, alaeque nasi and corrugator",
     {{"risorius", 1.0}, {"levator_labii_superioris_alaeque_nasi", 1.0}, {"corrugator_supercilii", 1.0}}},
    {"fig_5_17", "Fig. 5.17", "Thesis Fig. 5.17: depressor labii", {{"depressor_labii_inferioris", 1.0}}},
    {"fig_5_18",
     "Fig. 5.18",
     "Thesis Fig. 5.18: orbicularis oris",
     {{"orbicularis_oris_upper", 1.0}, {"orbicularis_oris_lower", 1.0}}},
  };
  return expressions;
}

Eigen::VectorXd expressionActivations(const ExpressionDefinition& expression, const std::vector<FittedMuscle>& muscles)
{
  Eigen::VectorXd a = Eigen::VectorXd::Zero(Eigen::Index(muscles.size()));
  for (const auto& [id, activation] : expression.muscles)
    for (std::size_t k = 0; k < muscles.size(); ++k)
      if (muscles[k].definition == id || muscles[k].id == id)
        a[Eigen::Index(k)] = activation;
  return a;
}

Eigen::VectorXd expressionActivations(const std::map<std::string, double>& activations,
                                      const std::vector<FittedMuscle>& muscles, std::vector<std::string>* unknown)
{
  Eigen::VectorXd a = Eigen::VectorXd::Zero(Eigen::Index(muscles.size()));
  for (const auto& [id, activation] : activations)
  {
    const auto it = std::find_if(muscles.begin(), muscles.end(), [&](const FittedMuscle& m) { return m.id == id; });
    if (it != muscles.end())
      a[it - muscles.begin()] = activation;
    else if (unknown)
      unknown->push_back(id);
  }
  return a;
}

Eigen::VectorXd mixActivations(const std::vector<Eigen::VectorXd>& expressions, const std::vector<double>& weights,
                               const Eigen::VectorXd& offsets)
{
  if (expressions.size() != weights.size())
    throw std::invalid_argument("mixing expressions needs one weight per expression");
  Eigen::VectorXd a = offsets;
  for (std::size_t e = 0; e < expressions.size(); ++e)
  {
    if (expressions[e].size() != offsets.size())
      throw std::invalid_argument("an expression has activations for another number of muscles than the model");
    a += weights[e] * expressions[e];
  }
  return a.cwiseMax(0.0).cwiseMin(1.0);
}

int ExpressionModel::muscleIndex(const std::string& id) const
{
  for (std::size_t k = 0; k < muscles.size(); ++k)
    if (muscles[k].id == id)
      return int(k);
  return -1;
}

namespace {

double secondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

std::unique_ptr<ExpressionModel> buildExpressionModel(const ExpressionModelInput& input, const TaskProgress& progress)
{
  const auto start = std::chrono::steady_clock::now();
  const auto step = [&progress](double fraction, const std::string& what) {
    return !progress || progress(fraction, what);
  };
  auto model = std::make_unique<ExpressionModel>();
  model->landmarkSource = input.landmarkSource;
  model->frame = input.skin.frame();

  if (!step(0.0, "Fitting the muscles to the landmarks"))
    return nullptr;
  const MuscleSet set = readMuscleSet(input.muscleSet.empty() ? defaultMuscleSetPath() : input.muscleSet);
  model->muscleSetId = set.id;
  model->muscles = fitMuscleSet(set, input.landmarks, input.skin, input.bone);
  if (model->muscles.empty())
    throw std::invalid_argument("the muscle set " + set.file.string() + " has no muscles");

  if (!step(0.05, "Meshing the face (no plan, thesis 5.3)"))
    return nullptr;
  auto t = std::chrono::steady_clock::now();
  model->face = meshFace(input.skin, input.bone, input.landmarks, input.face);
  model->meshSeconds = secondsSince(t);

  if (!step(0.2, "Factoring the stiffness matrix"))
    return nullptr;
  t = std::chrono::steady_clock::now();
  fem::AssemblyOptions assembly;
  assembly.threads = 2;
  fem::LinearStaticAnalysis analysis(model->face.continuum.mesh, model->face.materials,
                                     model->face.continuum.constraints(), assembly);
  if (analysis.prepare() != fem::SolverStatus::Success)
    throw std::invalid_argument("the face model cannot be solved: " + analysis.message());
  model->factorSeconds = secondsSince(t);

  if (!step(0.7, "Solving once per muscle (superposition, thesis 3.1.2)"))
    return nullptr;
  t = std::chrono::steady_clock::now();
  std::vector<std::vector<fem::Muscle>> functions;
  for (const FittedMuscle& m : model->muscles)
    functions.push_back(m.functions);
  model->responses = MuscleResponses(analysis, functions);
  model->responseSeconds = secondsSince(t);

  if (!step(0.85, "The skin's shade and detail"))
    return nullptr;
  const fem::Mesh& mesh = model->face.continuum.mesh;
  fem::DisplaySurface display(mesh, fem::skinFaces(model->face.continuum), input.resolution);
  // Table 4.9's range displacement and source colour at each vertex's
  // undeformed (θ, z), by planning::buildPlanDisplay's rules: the face shows
  // the scanned skin, not the quadratic element faces.
  planning::setRangeDetail(display, input.skin, input.maxRangeDetail);
  const planning::SkinShade shade = planning::skinShadeOfCt(input.ct, input.skin);
  model->shadeNote = shade.note;
  const Eigen::Matrix3Xd& x = display.undeformedPositions();
  model->shade.assign(std::size_t(x.cols()), seg::kNoSourceColour);
  if (shade.colour)
    for (Eigen::Index v = 0; v < x.cols(); ++v)
    {
      const seg::CylindricalPoint c = input.skin.frame().toCylindrical(x.col(v));
      model->shade[std::size_t(v)] = seg::sampleColour(*shade.colour, c.theta, c.z);
    }
  model->surface = ExpressionSurface(mesh, std::move(display), model->responses);
  model->totalSeconds = secondsSince(start);
  step(1.0, "Face model ready");
  return model;
}

vtkSmartPointer<vtkPolyData> shadedSkinPolyData(const ExpressionSurface& surface, const std::vector<seg::Rgb8>& shade)
{
  const fem::DisplaySurface& s = surface.surface();
  auto pd = vtkSmartPointer<vtkPolyData>::New();
  Eigen::Matrix3Xd rest;
  surface.positions(Eigen::VectorXd::Zero(surface.muscleCount()), true, rest);
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(vtkIdType(rest.cols()));
  for (Eigen::Index v = 0; v < rest.cols(); ++v)
    points->SetPoint(vtkIdType(v), rest.col(v).data());
  pd->SetPoints(points);
  auto polys = vtkSmartPointer<vtkCellArray>::New();
  for (const std::vector<int>& polygon : s.polygons())
  {
    polys->InsertNextCell(vtkIdType(polygon.size()));
    for (int v : polygon)
      polys->InsertCellPoint(v);
  }
  pd->SetPolys(polys);
  auto colour = vtkSmartPointer<vtkUnsignedCharArray>::New();
  colour->SetName("skin_colour");
  colour->SetNumberOfComponents(3);
  colour->SetNumberOfTuples(vtkIdType(rest.cols()));
  for (vtkIdType v = 0; v < vtkIdType(rest.cols()); ++v)
  {
    const seg::Rgb8 c = std::size_t(v) < shade.size() ? shade[std::size_t(v)] : seg::kNoSourceColour;
    for (int k = 0; k < 3; ++k)
      colour->SetTypedComponent(v, k, c[std::size_t(k)]);
  }
  pd->GetPointData()->AddArray(colour);
  pd->GetPointData()->SetScalars(colour);
  return pd;
}

vtkSmartPointer<vtkPolyData> expressionPolyData(const ExpressionModel& model)
{
  return shadedSkinPolyData(model.surface, model.shade);
}

double applyActivations(const ExpressionModel& model, const Eigen::VectorXd& activations, vtkPolyData* polyData,
                        Eigen::Matrix3Xd& scratch)
{
  model.positions(activations, scratch);
  vtkPoints* points = polyData->GetPoints();
  if (!points || points->GetNumberOfPoints() != vtkIdType(scratch.cols()))
    throw std::invalid_argument("the expression surface does not belong to this face model");
  double largest = 0.0;
  const Eigen::Matrix3Xd& rest = model.surface.surface().undeformedPositions();
  const Eigen::Matrix3Xd& detail = model.surface.surface().rangeDetail();
  for (Eigen::Index v = 0; v < scratch.cols(); ++v)
  {
    points->SetPoint(vtkIdType(v), scratch(0, v), scratch(1, v), scratch(2, v));
    largest = std::max(largest, (scratch.col(v) - rest.col(v) - detail.col(v)).squaredNorm());
  }
  points->Modified();
  return std::sqrt(largest);
}

} // namespace expression

namespace {} // namespace

expression::ExpressionModelInput ExpressionLogic::modelInput() const
{
  const auto [skinNode, boneNode] = RangeMapLogic::newestMaps(scene());
  if (!skinNode || !boneNode)
    throw std::invalid_argument(std::string("the scene has no ") + (!skinNode ? "skin" : "bone") +
                                " range map: build the range maps in the Range maps module first (open a CT, "
                                "segment it, then build the maps)");
  expression::ExpressionModelInput in;
  in.skin = RangeMapLogic::toRangeMap(*skinNode);
  in.bone = RangeMapLogic::toRangeMap(*boneNode);
  if (in.bone.frame() != in.skin.frame())
    in.bone = seg::RangeMap();
  const seg::LandmarkPlacement placed = seg::placeLandmarks(in.skin, in.bone);
  in.landmarks = placed.landmarks;
  in.landmarkSource = "placed automatically";
  // The user's landmarks (the thickness review) in place of the automatic
  // ones of the same standard name.
  int own = 0;
  const auto nodes = scene().nodesOfType(NodeType::Landmarks);
  if (!nodes.empty())
    for (const LandmarksNode::Landmark& l : static_cast<const LandmarksNode*>(nodes.back())->landmarks())
    {
      if (seg::landmarkDescription(l.name).empty())
        continue;
      const seg::CylindricalPoint c =
        in.skin.frame().toCylindrical(Eigen::Vector3d(l.position[0], l.position[1], l.position[2]));
      const seg::Landmark mark{l.name, c.theta, c.z};
      auto it = std::find_if(in.landmarks.begin(), in.landmarks.end(),
                             [&](const seg::Landmark& m) { return m.name == l.name; });
      if (it != in.landmarks.end())
        *it = mark;
      else
        in.landmarks.push_back(mark);
      ++own;
    }
  if (own > 0)
    in.landmarkSource = std::to_string(own) + " placed by you, the others automatically";
  std::string missing;
  for (const char* name : {"nasion", "subnasale", "menton", "forehead", "zygion_left", "zygion_right"})
    if (std::none_of(in.landmarks.begin(), in.landmarks.end(), [&](const seg::Landmark& m) { return m.name == name; }))
      missing += missing.empty() ? name : std::string(", ") + name;
  if (!missing.empty())
    throw std::invalid_argument("the face model needs the landmarks " + missing +
                                ", which could not be found on the skin: place them in the Range maps module "
                                "(Landmarks, 'Add on the face', named as the standard landmarks)");
  const auto volumes = scene().nodesOfType(NodeType::Volume);
  if (!volumes.empty())
    in.ct = static_cast<const VolumeNode*>(volumes.front())->image();
  return in;
}

std::vector<ExpressionNode*> ExpressionLogic::savedExpressions() const
{
  std::vector<ExpressionNode*> out;
  for (Node* n : scene().nodesOfType(NodeType::Expression))
    out.push_back(static_cast<ExpressionNode*>(n));
  return out;
}

ExpressionNode* ExpressionLogic::savedExpression(const std::string& name) const
{
  for (ExpressionNode* n : savedExpressions())
    if (n->name() == name)
      return n;
  return nullptr;
}

ExpressionNode& ExpressionLogic::saveExpression(const std::string& name, const std::string& muscleSet,
                                                const std::map<std::string, double>& activations,
                                                const std::string& description)
{
  if (name.empty())
    throw std::invalid_argument("give the expression a name first");
  std::map<std::string, double> kept;
  for (const auto& [id, a] : activations)
    if (std::isfinite(a) && a > 0.0)
      kept[id] = std::min(a, 1.0);
  const nlohmann::json fields{
    {"name", name}, {"muscleSet", muscleSet}, {"description", description}, {"activations", kept}};
  if (ExpressionNode* existing = savedExpression(name))
  {
    // One undoable edit for all three fields.
    ScopedEdit edit(scene(), existing->id(), "Change expression " + name);
    existing->fromJson(fields);
    return *existing;
  }
  auto* node = scene().add<ExpressionNode>();
  node->fromJson(fields);
  scene().undoStack().pushAddition(*node, "Save expression " + name);
  return *node;
}

} // namespace caps
