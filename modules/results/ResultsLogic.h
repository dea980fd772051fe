#pragma once
/// @file ResultsLogic.h
/// @brief Logic of the Results module: how the surgeon
/// looks at a predicted plan (thesis §4.7 display of the result, §3.3.3
/// documentation). The skin between before and after the operation, its
/// colouring by stress, displacement or strain, the numbers of the closure
/// (re-predicted from the plan's recipe), the profile along the incision
/// and the storyboard's snapshots. No widgets.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include <vtkSmartPointer.h>

#include "modules/core/Module.h"
#include "planning/IncisionPlan.h"
#include "planning/PlanSimulation.h"
#include "planning/WoundTension.h"
#include "scene/SnapshotNode.h"
#include "segmentation/RangeMap.h"

class vtkPolyData;

namespace caps {

class PlanNode;
class SurfaceNode;

/// A plan of the scene that has a prediction (IncisionLogic::addPrediction()).
struct PredictedPlan
{
  std::string name; ///< the Plan node's name ("Z-plasty 1")
  NodeId plan;      ///< the Plan node
  NodeId before;    ///< Surface "NAME skin before"
  NodeId after;     ///< Surface "NAME skin after"
};

/// What the skin can be coloured by.
enum class ResultQuantity
{
  SkinShade,        ///< skin_colour, RGB as it is (undermined skin hatched)
  Displacement,     ///< displacement_magnitude_mm
  VonMises,         ///< von_mises_kPa
  MeanStress,       ///< mean_stress_kPa (signed: tension positive)
  EquivalentStrain, ///< equivalent_strain
};

/// How a quantity is shown: the point array, its colour map, the bar's title.
struct QuantityStyle
{
  std::string label;      ///< "von Mises stress", for menus and captions
  std::string array;      ///< point array of planDisplayPolyData()
  std::string colourMap;  ///< render/ColourMaps.h name; empty for RGB
  std::string barTitle;   ///< "von Mises stress (kPa)"
  bool symmetric = false; ///< range symmetric about 0 (signed quantities)
};

/// Every quantity, in menu order.
std::vector<ResultQuantity> resultQuantities();
QuantityStyle quantityStyle(ResultQuantity quantity);

/// The numbers of a closure that the scene does not keep (they need the
/// solve's reactions): the prediction made again from the plan's recipe.
struct ClosureNumbers
{
  double closureForce = 0.0;       ///< sum of the sutures' force magnitudes (N), ClosureForces::magnitudeSum
  double largestSutureForce = 0.0; ///< N
  double peakWoundStress = 0.0;    ///< largest von Mises stress in the skin within woundRadius of the wound (kPa)
  double woundRadius = 10.0;       ///< mm
  /// The tension across the wound (planning::WoundTension): mean over the
  /// wound and peak per centimetre of line, the force one stitch carries at
  /// the peak, and on which line; 0 when not known.
  double tensionPerCentimetre = 0.0, peakTensionPerCentimetre = 0.0; ///< N/cm
  double peakForcePerStitch = 0.0;                                   ///< N
  double stitchSpacing = planning::kDefaultStitchSpacing;            ///< mm
  std::string peakTensionLine;
};

/// What a re-prediction needs, copied out of the scene so a worker thread
/// can run it without touching the scene.
struct ClosureJob
{
  std::string planName;
  seg::RangeMap skin, bone;
  planning::IncisionPlan plan;
  planning::SimulationOptions options;
};

/// A point along the incision and the skin's values there.
struct IncisionProfile
{
  std::vector<double> arcLength;    ///< mm along the cut path (on the skin before the operation)
  std::vector<double> vonMises;     ///< kPa, after the closure
  std::vector<double> displacement; ///< mm
};

/// @class ResultsLogic
/// @brief The predicted plans of the scene and what is shown of them.
class ResultsLogic : public ModuleLogic
{
public:
  using ModuleLogic::ModuleLogic;

  /// Plans that have a prediction: a Plan node NAME with Surface nodes
  /// "NAME skin before" and "NAME skin after" of the same point count with
  /// a displacement_mm array; in the scene's order.
  std::vector<PredictedPlan> predictedPlans() const;
  std::optional<PredictedPlan> predictedPlan(const std::string& name) const;

  /// @name The skin between before and after
  ///@{
  /// A copy of @a before to deform: its own points (double), the cells and
  /// point arrays shared with @a before (they are the same before and after).
  static vtkSmartPointer<vtkPolyData> makeResultSurface(vtkPolyData* before);
  /// Moves @a result's points in place to before + s · displacement_mm
  /// (s = 0 before the operation, 1 after; the after surface is exactly
  /// before + displacement, planDisplayPolyData()) and marks them modified.
  /// @throws std::invalid_argument when the surfaces do not match.
  static void deform(vtkPolyData* before, vtkPolyData* result, double s);
  ///@}

  /// The colour range of @a quantity on @a surface: [0, max] or, for a
  /// signed quantity, [-m, m] with m the largest magnitude; fixed per plan so
  /// it does not change while the skin animates. {0, 0} for RGB.
  static std::array<double, 2> colourRange(vtkPolyData* surface, ResultQuantity quantity);
  /// Largest value of a one-component point array (0 when absent).
  static double arrayMaximum(vtkPolyData* surface, const std::string& array);

  /// @name The closure force and wound stress (re-predicted)
  ///@{
  /// Copies what re-predicting @a plan needs out of the scene: its skin and
  /// bone maps, the plan its recipe makes (IncisionLogic::readRecipe,
  /// applyRecipe; readPlan for a plan without a recipe) and the options
  /// it was predicted with, as the report's planFacts does.
  /// @throws std::invalid_argument naming what is missing.
  ClosureJob closureJob(const PlanNode& plan);
  /// Runs the prediction (slow; any thread). Returns std::nullopt when
  /// @a progress asks to stop.
  static std::optional<ClosureNumbers> computeClosure(const ClosureJob& job, const TaskProgress& progress = {});
  /// A key that changes when the plan or its prediction settings change.
  static std::string closureKey(const PlanNode& plan);
  /// The numbers the prediction kept with it (planning::ClosureRecord in
  /// the plan's recipe, written by caps plan and the Simulate module), so
  /// nothing is solved again; std::nullopt for a plan predicted before
  /// predictions kept them.
  static std::optional<ClosureNumbers> recordedClosure(const PlanNode& plan);
  ///@}

  /// How the plan's prediction checked out (planning::PredictionCheck, kept
  /// in its recipe): which model made it, whether it converged and whether
  /// its deformation is a body; std::nullopt for a plan predicted before
  /// predictions kept their check.
  static std::optional<planning::PredictionCheck> recordedCheck(const PlanNode& plan);

  /// The skin's values along the cut path: the path in the plan's chart,
  /// sampled every 0.5 mm, each sample lifted onto the skin before the
  /// operation and given the arrays of the display vertex of @a before
  /// nearest to it (@a after's arrays are the same; the cut's two lips are
  /// twin vertices at one place, the nearest of them is taken).
  /// @throws std::invalid_argument when the scene has no skin map for the plan.
  IncisionProfile incisionProfile(const PlanNode& plan, vtkPolyData* before) const;

  /// The head's skin (the segmented Surface node "Skin"), nullptr when none.
  SurfaceNode* headSkin() const;
  /// @a head without the cells the plan's skin patch @a before lies on, so the
  /// two do not fight for the same pixels: a head vertex is under the patch
  /// when its nearest patch vertex is within @a reach mm and not on the
  /// patch's rim (its longest boundary loop), or when its nearest patch
  /// vertex is on the wound (the other boundary loops: the cut's lips, an
  /// excision's hole, whose skin is gone after the operation); a cell goes
  /// when all its vertices are under it.
  static vtkSmartPointer<vtkPolyData> headWithoutPatch(vtkPolyData* head, vtkPolyData* before, double reach = 4.0);

  /// A camera looking at the plan's skin from outside along the radial
  /// direction at its centre, framing the patch with some face around it.
  std::optional<SnapshotNode::Camera> planCamera(const PlanNode& plan, vtkPolyData* before) const;

  /// Adds a Snapshot node ("Snapshot N", after the others: the report's
  /// storyboard prints them in the scene's order) with @a caption.
  SnapshotNode& addSnapshot(const std::string& caption, const ViewCapture& capture);
};

} // namespace caps
