#pragma once
/// @file PlanRecipe.h
/// @brief A plan as the list of operations that made it:
/// the procedure placed, its parameters, the points moved and offset, with
/// the content hash of the CT it was made on and the software version, so
/// rerunning it on the same CT gives the same prediction bit for bit.
///
/// An operation applied to a plan gives a new plan or throws RecipeError
/// naming the operation; the plan it was applied to is not touched (the plan
/// is a value). The format of plan.json is documented at recipeToJson().

#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "planning/IncisionPlan.h"
#include "planning/PlanSimulation.h"
#include "planning/ProcedureTemplate.h"
#include "planning/WoundStress.h"
#include "planning/WoundTension.h"

class vtkImageData;

namespace caps::planning {

/// @name Operations a surgeon makes on a plan
///@{
/// Places a procedure centred at a skin point (θ radians, z mm) with
/// parameter values in API units (mm, radians, ratios). It starts the plan
/// afresh: whatever was drawn before is replaced.
struct PlaceProcedure
{
  std::string procedure; ///< "z-plasty"
  SkinPoint at;
  std::map<std::string, double> values;
};

/// Moves cut point `point` (0-based, scalpel order) to (θn, zn).
///
/// Normalised cylindrical coordinates because that is what the plan stores:
/// replaying sets the very same doubles, with no conversion through the
/// chart or the frame that could round differently.
struct MoveCutPoint
{
  int point = 0;
  Eigen::Vector2d thetaZN = Eigen::Vector2d::Zero();
};

/// Moves border point `vertex` (hole-loop numbering, Fig. 4.11) away from
/// its twin by `offset` in the plan's chart (mm) to make an excision (§4.4.4).
struct OffsetBorderPoint
{
  int vertex = 0;
  ChartPoint offset = ChartPoint::Zero();
};

/// Changes one parameter of the placed procedure: the procedure is placed
/// again at the same centre with the other values as they were. The
/// template draws the cut afresh, so moves and offsets made since the last
/// placement are dropped, as they are when the panel's slider moves.
struct SetParameter
{
  std::string name;   ///< "limb_angle"
  double value = 0.0; ///< API units
};

/// Undermines a region of skin (thesis §3.2.4 item 2: the skin freed from
/// what lies beneath): a closed polygon of at least 3 points (θn, zn), the
/// last joined to the first, added to the plan's undermined regions (the
/// skin undermined is their union, with the band of
/// SimulationOptions::underminingWidth). Normalised coordinates as in
/// MoveCutPoint, for the same reason. Checked by checkUnderminedRegion().
/// The regions stay when a parameter is set (SetParameter) and go when a
/// procedure is placed afresh.
struct UndermineRegion
{
  UnderminedRegion region;
};

/// Draws a cut by hand (points clicked one by one on the skin),
/// (θn, zn) in scalpel order, at least 2. It starts the plan afresh like
/// PlaceProcedure, with no procedure: the chart is centred on the middle of
/// the points, and the two lips of the cut are sewn back together edge to
/// edge (straightClosureSutures()); offsetting border points afterwards
/// (OffsetBorderPoint) makes it an excision closed the same way.
struct DrawCut
{
  std::vector<Eigen::Vector2d> points;
};

/// The sutures that close a cut of @a pathPoints points straight: each
/// edge (i, i+1) of the hole loop's first side onto its twin on the other
/// (Fig. 4.11 numbering: vertex i's twin is 2n − 2 − i, the ends are their
/// own), as simple-excision.procedure writes them for 4 points.
std::vector<SutureEdges> straightClosureSutures(int pathPoints);

/// Removes every undermined region of the plan (the band along the sutured
/// edges is a simulation option and stays).
struct ClearUndermining
{};

using PlanOperation = std::variant<PlaceProcedure, MoveCutPoint, OffsetBorderPoint, SetParameter, UndermineRegion,
                                   ClearUndermining, DrawCut>;

/// What an operation does, for messages: "place z-plasty", "move cut point 2",
/// "offset border point 4", "set parameter limb_angle", "undermine a region
/// of 4 points", "clear undermining".
std::string describe(const PlanOperation& operation);
///@}

/// A plan file or an operation that cannot be used. operation() is the
/// 1-based number of the operation at fault, 0 when the recipe as a whole is.
class RecipeError : public std::invalid_argument
{
public:
  RecipeError(int operation, const std::string& message) : std::invalid_argument(message), operation_(operation) {}
  int operation() const { return operation_; }

private:
  int operation_;
};

/// The closure numbers of a prediction that need its solve: the sutures'
/// reactions (ClosureForces) and the skin stress by the wound (WoundStress).
struct ClosureRecord
{
  double force = 0.0;           ///< sum of the sutures' force magnitudes (N)
  double largestSuture = 0.0;   ///< the largest one suture carries (N)
  double peakWoundStress = 0.0; ///< peak von Mises stress of the skin within woundRadius of the wound (MPa)
  double meanWoundStress = 0.0; ///< its mean over that band (MPa)
  double woundRadius = 10.0;    ///< mm
  /// The tension across the wound (WoundTension): over all its lines, the
  /// force across per centimetre of closed line, and the largest on one
  /// sutured piece with the force one stitch carries there; 0 in files from
  /// before it was recorded.
  double tensionPerCentimetre = 0.0;            ///< N/cm
  double peakTensionPerCentimetre = 0.0;        ///< N/cm
  double peakForcePerStitch = 0.0;              ///< N
  double stitchSpacing = kDefaultStitchSpacing; ///< mm
  std::string peakTensionLine;                  ///< the wound line it is on
};

/// The record of @a prediction with the skin stress @a wound by its wound.
/// and the tension along its wound lines.
ClosureRecord closureRecordOf(const PlanPrediction& prediction, const WoundStress& wound, const WoundTension& tension);

/// The operations that made a plan, and what they were applied to.
struct PlanRecipe
{
  /// ctContentHash() of the CT the plan was made on; empty when unknown.
  std::string ctSha256;
  /// softwareVersion() of the CAPS that recorded it.
  std::string softwareVersion;
  std::vector<PlanOperation> operations;
  /// The element size at the wound (mm, SimulationOptions) the prediction
  /// was made with, so a replay meshes the same; 0 when not recorded.
  double elementSize = 0.0;
  /// The incision depth the surgeon chose: tissue layers cut from the skin
  /// (SimulationOptions::cutLayers); 0 = full thickness; unset: the
  /// procedure's own depth, which the replay's placement gives again.
  std::optional<int> cutLayers;
  /// The model of the tissue the prediction was made with (a file without
  /// one was made by the linear model, the only one then).
  TissueModel model = TissueModel::LinearElastic;
  /// The undermining band the surgeon chose (mm, SimulationOptions::
  /// underminingWidth); unset: the procedure's own, which the replay's
  /// placement gives again.
  std::optional<double> underminingWidth;
  /// The skin's pre-tension the prediction carried (SimulationOptions::
  /// preTension): N/mm along and across the relaxed skin tension lines;
  /// unset: none, the slack skin of the thesis (files from before).
  std::optional<std::array<double, 2>> preTension;
  /// How the prediction made from these operations checked out, written
  /// after the solve so anyone can read it from the file; a replay makes
  /// and checks its own.
  std::optional<PredictionCheck> prediction;
  /// What holds the wound closed in that prediction (its solve's reactions
  /// and the skin stress by the wound), kept with it so no view has to solve
  /// the plan again to show them; unset in files from before.
  std::optional<ClosureRecord> closure;
};

/// @brief Applies operation number `number` (1-based, for messages) to @a plan.
///
/// Every result is checked with checkPlan() on @a skin, so a move that makes
/// limbs cross, a point off the scan or too close to its neighbour is refused.
/// @throws RecipeError "operation N (move cut point 2): WHAT IS WRONG ..."
/// naming the operation; @a plan is never changed.
IncisionPlan applyOperation(const IncisionPlan& plan, const PlanOperation& operation, int number,
                            const seg::RangeMap& skin, const ProcedureLibrary& library);

/// The plan the recipe's operations make on @a skin, from nothing.
/// @throws RecipeError for an empty recipe or the first operation refused.
IncisionPlan applyRecipe(const PlanRecipe& recipe, const seg::RangeMap& skin, const ProcedureLibrary& library);

/// @class RecordedPlan
/// @brief A plan and the recipe that made it, edited together: an operation
/// is recorded only when the plan accepts it.
class RecordedPlan
{
public:
  RecordedPlan() = default;
  /// Starts an empty plan on a CT (ctContentHash()) with this software's version.
  explicit RecordedPlan(std::string ctSha256);

  const IncisionPlan& plan() const { return plan_; }
  const PlanRecipe& recipe() const { return recipe_; }

  /// Applies and records @a operation.
  /// @throws RecipeError (see applyOperation()); plan and recipe stay as they were.
  void apply(const PlanOperation& operation, const seg::RangeMap& skin, const ProcedureLibrary& library);

private:
  IncisionPlan plan_;
  PlanRecipe recipe_;
};

/// The procedure of that id.
/// @throws std::invalid_argument listing the procedures there are and the
/// files left out of the library with their errors (a file with
/// inconsistent sutures is left out, not loaded).
const ProcedureTemplate& findProcedure(const ProcedureLibrary& library, const std::string& id);

/// @name plan.json
///@{
/// The version of the plan file's layout; a file of a later one is refused.
inline constexpr int recipeFormatVersion = 1;

/// @brief The recipe as JSON:
/// @code
/// { "format": "caps-plan", "formatVersion": 1, "softwareVersion": "0.1.0",
///   "ctSha256": "3f2a…(64 hex digits)",
///   "operations": [
///     { "operation": "place", "procedure": "z-plasty", "theta": -1.5707963267948966, "z": 0.0,
///       "values": { "axis_angle": 0.0, "central_length": 20.0, "limb_angle": 1.0471975511965976 } },
///     { "operation": "move", "point": 1, "thetaZN": [-0.49, 0.012] },
///     { "operation": "offset", "vertex": 2, "offset": [0.0, 1.5] },
///     { "operation": "set-parameter", "name": "limb_angle", "value": 0.7853981633974483 },
///     { "operation": "undermine", "region": [[-0.52, 0.01], [-0.46, 0.01], [-0.46, 0.06], [-0.52, 0.06]] },
///     { "operation": "clear-undermining" } ],
///   "simulation": { "elementSize": 2.5, "cutLayers": 1, "model": "large-deformation", "underminingWidth": 8,
///                   "preTension": { "alongLines": 0.01, "acrossLines": 0.005 } },
///   "prediction": { "model": "large-deformation", "converged": true, "closureFraction": 1.0,
///                   "increments": 6, "iterations": 31, "minDetF": 0.42, "maxStretch": 1.61,
///                   "invertedElements": 0, "admissible": true, "problem": "" } }
/// @endcode
/// "simulation" is left out when elementSize is 0; "cutLayers" when the
/// procedure's own depth is used (files from before procedures stated one
/// were cut through every layer: they replay at the procedure's depth now);
/// "model" when it is "linear" (tissueModelId()); "underminingWidth" when
/// the procedure's own band is used; "preTension" (N/mm) when the skin
/// carried none.
/// "prediction" is the check of the prediction made (PredictionCheck),
/// left out until there is one. "undermine" and
/// "clear-undermining" came later within format 1: files without them read
/// as before; a CAPS older than them refuses a file that has them, naming
/// the operation it does not know.
/// Angles in radians, lengths in mm, as the API; doubles are written to the
/// last bit (nlohmann-json writes the shortest text that reads back exactly).
nlohmann::json recipeToJson(const PlanRecipe& recipe);
/// @throws RecipeError naming the field or the operation that is wrong.
PlanRecipe recipeFromJson(const nlohmann::json& json);
nlohmann::json operationToJson(const PlanOperation& operation);
/// @throws RecipeError naming operation `number` (1-based).
PlanOperation operationFromJson(const nlohmann::json& json, int number);

/// Writes plan.json atomically (beside, then renamed).
/// @throws std::runtime_error when it cannot be written.
void writeRecipe(const PlanRecipe& recipe, const std::filesystem::path& file);
/// @throws RecipeError naming the file and what is wrong with it.
PlanRecipe readRecipe(const std::filesystem::path& file);
///@}

/// @brief SHA-256 of a CT's content, as 64 lowercase hex digits.
///
/// Hashes the voxel values (scalar type, components, every voxel as stored,
/// little-endian) and the geometry (dimensions, extent start, spacing,
/// origin, direction matrix) and nothing else: not the file names, their
/// order or the DICOM fields, so the same scan read twice or copied under
/// other names hashes the same and a changed voxel or spacing does not.
/// @throws std::invalid_argument for an image without voxels.
std::string ctContentHash(vtkImageData* image);

/// The CAPS version (CMake's project version, "0.1.0").
std::string softwareVersion();

} // namespace caps::planning
