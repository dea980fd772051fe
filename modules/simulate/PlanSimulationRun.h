#pragma once
/// @file PlanSimulationRun.h
/// @brief The headless side of the Simulate panel: a plan
/// of the scene with its options and materials → the prediction nodes
/// `caps plan` makes (thesis §4.5–4.7), a model drawn by the engineering
/// conventions (§3.3.1), and a summary. No widgets: the panel only gathers
/// the options and drives these functions through ModuleHost::runTask.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <vtkImageData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "modules/core/Module.h"
#include "modules/incision/IncisionLogic.h"
#include "planning/PlanDisplay.h"
#include "planning/PlanRecipe.h"
#include "planning/PlanSimulation.h"
#include "planning/WoundStress.h"
#include "scene/Node.h"

namespace caps {

class PlanNode;
class Scene;

namespace simulate {

/// @name Materials
///@{
/// The tissue of layer @a layer from the skin down, as
/// planning::defaultFacialTissueMaterials() assigns it: "Skin (dermis)",
/// "Subcutaneous fat", "Muscle / SMAS", deeper layers "Layer N (as muscle)".
std::string layerName(int layer);
/// Title of the default preset, shown in the panel.
inline constexpr const char* kFacialTissuePreset = "Facial soft tissue (CAPS default)";
/// Where the preset's values come from (PlanSimulation.cpp), for a tooltip.
std::string facialTissueSource();
///@}

/// Everything a run needs, copied out of the scene on the GUI thread so the
/// worker never touches the scene.
struct PlanRunInput
{
  NodeId planId;    ///< the plan node it replaces
  std::string name; ///< its name, kept by the new nodes
  planning::IncisionPlan plan;
  planning::PlanRecipe recipe; ///< the node's recipe (operations only, when it has none: empty)
  seg::RangeMap skin, bone;
  NodeId skinMapId;
  /// The CT the skin's shade is read from (seg::skinShadeFromCt); null: grey.
  vtkSmartPointer<vtkImageData> ct;
  planning::SimulationOptions options;
};

/// @brief Gathers a run of plan @a planId of @a scene with @a options.
/// The skin map is the plan's own (PlanNode::rangeMapId(), else the scene's
/// "skin" map), the bone map the scene's "bone" map, the CT its first volume.
/// @throws std::invalid_argument naming what is missing (no such plan, no
/// skin or bone map: build them in the RangeMap module) or a plan that does
/// not read (IncisionLogic::readPlan(), readRecipe()).
PlanRunInput preparePlanRun(const Scene& scene, const NodeId& planId, const planning::SimulationOptions& options);

/// The size of the model a run will solve, from its meshes alone (planning::meshPlan()).
struct ModelSize
{
  Eigen::Index nodes = 0, elements = 0, dofs = 0;
  double seconds = 0.0; ///< how long the meshing took
};
/// @throws as planning::meshPlan() does.
ModelSize estimateModel(const PlanRunInput& input);

/// What a run computed (worker thread).
struct PlanRunResult
{
  planning::PlanPrediction prediction;
  planning::PlanDisplay display;
  /// The largest skin stress within kWoundRadius of the wound, and where
  /// (θ radians, z mm on the skin map's frame, before the operation).
  planning::WoundStress woundStress;
  double woundStressTheta = 0.0, woundStressZ = 0.0;
  /// The tension across each wound line, per centimetre and per stitch.
  planning::WoundTension tension;
  /// Why the skin is grey, when it is (no CT, or its shade failed); empty otherwise.
  std::string shadeNote;
  double shadeSeconds = 0.0, displaySeconds = 0.0, stressSeconds = 0.0;
  /// The model as drawn (modelDrawing()).
  vtkSmartPointer<vtkPolyData> modelLines;
};

/// The band around the wound in which the peak skin stress is reported (mm).
inline constexpr double kWoundRadius = 10.0;

/// @brief Runs a prediction: the skin's shade from the CT, simulatePlan(),
/// buildPlanDisplay() with that shade, woundSkinStress() and the model
/// drawing, reporting each phase through @a progress (fractions in [0, 1]).
/// @throws seg::Cancelled when @a progress returned false
/// (between phases), and whatever simulatePlan() throws.
PlanRunResult runPlan(const PlanRunInput& input, const TaskProgress& progress);

/// The nodes a run put into the scene.
struct PlanRunNodes
{
  IncisionLogic::PredictionNodes prediction;
  NodeId modelLines;            ///< "<name> mesh"
  std::vector<NodeId> replaced; ///< the old nodes removed
};

/// @brief Puts a run into the scene (GUI thread), as `caps plan` does:
/// IncisionLogic::addPrediction() under the plan's name with the plan's
/// recipe and IncisionLogic::simulationRecord(), plus the Surface node "<name> mesh" of
/// modelLines (visible when @a showModel). Only after all of that was added
/// are the old plan node and its prediction nodes ("<name> model" / the
/// FeMesh of the plan, its Solution, "<name> closure", "<name> skin
/// before", "<name> skin after", "<name> mesh") removed, so a failure never
/// loses the plan.
/// With @a keepPlanNode the plan node input.planId stays (it takes the
/// recipe and the simulation record) and only its prediction nodes are
/// replaced: the live prediction's way, so the edits that led to it can
/// still be undone.
PlanRunNodes addPlanRun(Scene& scene, const PlanRunInput& input, const PlanRunResult& result, bool showModel,
                        bool keepPlanNode = false);

/// Whether plan node @a planId of @a scene still holds the plan of @a input
/// (its cut, parameters, offsets, sutures and undermining as they were read
/// for the run): false once it was edited since, or removed.
bool planUnchangedSince(const Scene& scene, const PlanRunInput& input);

/// @brief The finite element model drawn by the conventions of engineering
/// drawings (thesis §3.3.1), before the operation: the element edges of the
/// skin faces as lines following the quadratic edges (@a steps segments
/// each, through the mid-side node), the nodes fixed in all three directions
/// as points, and the sutures as lines from each sutured node to its target.
/// Point data "colour" (RGB, unsigned char): edges dark blue, fixed nodes
/// red, sutures green (kEdgeColour, kFixedColour, kSutureColour). Lines
/// and points are lifted @a lift mm outwards (from the bone to the skin
/// along each node column) so the skin surface does not hide them.
vtkSmartPointer<vtkPolyData> modelDrawing(const planning::PlanPrediction& prediction, int steps = 4, double lift = 0.3);
inline constexpr unsigned char kEdgeColour[3] = {30, 50, 120};
inline constexpr unsigned char kFixedColour[3] = {220, 30, 30};
inline constexpr unsigned char kSutureColour[3] = {0, 170, 60};

/// Several lines for the panel: model size, phase times, suture gap,
/// closure force (N, 4 significant digits: "Closure force: 0.1234 N") and
/// the peak skin stress near the wound (kPa) and where.
std::string summaryText(const PlanRunResult& result);

} // namespace simulate
} // namespace caps
