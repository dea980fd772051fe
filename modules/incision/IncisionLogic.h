#pragma once
/// @file IncisionLogic.h
/// @brief Logic of the Incision module: the procedure library and plans
/// placed on a skin range map; no widgets (the panel comes later).

#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "modules/core/Module.h"
#include "planning/IncisionPlan.h"
#include "planning/PlanDisplay.h"
#include "planning/PlanSimulation.h"
#include "planning/PlanRecipe.h"
#include "planning/ProcedureTemplate.h"
#include "planning/SkinMeasurements.h"
#include "scene/Node.h"

namespace caps {

class PlanNode;
class RangeMapNode;

/// @class IncisionLogic
/// @brief The procedures of data/procedures/ (§4.1) and plans made from them.
class IncisionLogic : public ModuleLogic
{
public:
  using ModuleLogic::ModuleLogic;

  /// The procedure library, read from planning::defaultProceduresFolder()
  /// the first time it is asked for.
  /// @throws std::runtime_error when the folder does not exist.
  const planning::ProcedureLibrary& procedures();
  /// Reads the library again from folder (a surgeon added a procedure file).
  const planning::ProcedureLibrary& reloadProcedures(const std::filesystem::path& folder);

  /// The plan of procedure `id` centred at a skin point with the given
  /// parameter values (API units; the rest default).
  /// @throws std::invalid_argument for an unknown procedure, bad values, or
  /// a cut that does not fit on the measured skin.
  planning::IncisionPlan placeProcedure(const std::string& id, const seg::RangeMap& skin, const planning::SkinPoint& at,
                                        const std::map<std::string, double>& values = {});

  /// @name The plan in the scene (a PlanNode holds everything a plan is)
  ///@{
  /// Writes @a plan into @a node (procedure, generator, parameters, cut path,
  /// chart centre, excision offsets, sutures as written).
  static void writePlan(const planning::IncisionPlan& plan, PlanNode& node);
  /// The plan a node holds. Its undermined regions come from the node's
  /// recipe (the operations writeRecipe() wrote; PlanNode has no field of its own for them).
  /// @throws std::invalid_argument when its offsets or sutures do not fit its
  /// cut path (a hand-edited scene), or an "undermine" operation cannot be
  /// read, naming what is wrong.
  static planning::IncisionPlan readPlan(const PlanNode& node);
  /// Writes the recipe that made the node's plan (operations, CT hash,
  /// software version) beside what writePlan() wrote.
  static void writeRecipe(const planning::PlanRecipe& recipe, PlanNode& node);
  /// The recipe a node keeps; std::nullopt for a plan saved before plans
  /// kept their recipe (the plan itself still reads with readPlan()).
  /// @throws planning::RecipeError naming the plan and the operation at fault.
  static std::optional<planning::PlanRecipe> readRecipe(const PlanNode& node);

  /// The options a node's prediction was made with, so a replay, a report
  /// or a second look predicts the same thing: planning::SimulationOptions'
  /// defaults, then what the node's simulation() records: elementSize and
  /// cutLayers (as `caps plan` writes them), and regionRadius, layerCount,
  /// underminingWidth and materials when the Simulate panel wrote them.
  /// Values that do not read are left at the default; cutLayers and
  /// underminingWidth, when absent, stay unset: the plan's procedure says.
  /// A plan not predicted yet (no record) gets the large-deformation model,
  /// the prediction; a record without a model was made by the linear one.
  static planning::SimulationOptions simulationOptions(const PlanNode& node);
  /// The simulation() record of a prediction made with @a options:
  /// {"elementSize", "cutLayers"} (the plan file's fields, PlanRecipe) and
  /// "regionRadius", "layerCount", "underminingWidth", "materials" ([{layer,
  /// youngsModulusMPa, poissonRatio}]).
  static nlohmann::json simulationRecord(const planning::SimulationOptions& options);

  /// The scene nodes of a predicted plan.
  struct PredictionNodes
  {
    NodeId plan, mesh, solution, skinBefore, skinAfter;
    NodeId skinGaping; ///< empty without a gape (no pre-tension)
  };
  /// Puts a predicted plan into the scene: a Plan node
  /// (plan and recipe, drawn on @a skinMapId), its FeMesh node, the Solution
  /// node with the displacements, and the display surfaces before and after
  /// the operation (Surface nodes, §4.7), and between them the wound gaping
  /// under the skin's pre-tension when the prediction has one ("<name> skin
  /// gaping", hidden). @a name names them ("Z-plasty 1").
  /// With @a keepPlan (a Plan node of the scene that already holds @a plan)
  /// no Plan node is added: that one takes the recipe and owns the
  /// prediction, keeping its id and so its edits' undo history.
  PredictionNodes addPrediction(const std::string& name, const planning::IncisionPlan& plan,
                                const planning::PlanRecipe& recipe, const planning::PlanPrediction& prediction,
                                const planning::PlanDisplay& display, const NodeId& skinMapId,
                                const NodeId& keepPlan = {});
  ///@}

  /// The plan a recipe makes on @a skin with this logic's procedures
  /// (planning::applyRecipe()).
  planning::IncisionPlan applyRecipe(const planning::PlanRecipe& recipe, const seg::RangeMap& skin);

  /// Why @a plan, drawn on @a skin (the map of @a skinNode), cannot be cut:
  /// its cut runs through skin in the slices that metal's streaks spoil in
  /// the CT the map was made from (planning::cutInMetalStreaks), or over
  /// skin pressed against the head holder (planning::cutAgainstAnObject);
  /// "" when it does not, or when that CT is not in the scene.
  std::string cutOnUnsoundSkin(const planning::IncisionPlan& plan, const seg::RangeMap& skin,
                               const RangeMapNode& skinNode) const;

private:
  std::optional<planning::ProcedureLibrary> library_;
};

} // namespace caps
