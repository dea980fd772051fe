#pragma once
/// @file PlanSimulation.h
/// @brief The simulation pipeline of a plan (thesis §4.5–4.6): plan + skin
/// and bone range maps + materials → surface mesh → skin-to-bone continuum
/// mesh → sutures closed by a linear static solve → the displaced skin.

#include <array>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fem/ContinuumMesher.h"
#include "fem/ElementQuality.h"
#include "fem/HyperelasticMaterial.h"
#include "fem/InteriorNodeOptimization.h"
#include "fem/LinearElasticMaterial.h"
#include "fem/NonlinearStaticAnalysis.h"
#include "fem/Mesh.h"
#include "fem/SurfaceCrossing.h"
#include "fem/SurfaceMesher.h"
#include "planning/IncisionPlan.h"
#include "planning/SkinChart.h"
#include "planning/SkinMeasurements.h"
#include "planning/SkinPreTension.h"
#include "segmentation/Progress.h"
#include "segmentation/RangeMap.h"

namespace caps::planning {

/// Default materials of the facial soft tissue, one per layer from the skin
/// down: region 0 skin (dermis), 1 subcutaneous fat, 2 muscle / SMAS. With
/// fewer layers the first ones are used; with more, the last repeats.
/// See PlanSimulation.cpp for the values and where they come from.
fem::MaterialTable defaultFacialTissueMaterials(int layerCount = 3);

/// What is wrong with a material a user typed (E in MPa); empty when it is
/// usable: E > 0 and finite, 0 < ν < 0.5 (ν = 0.5 is incompressible, which
/// a displacement formulation cannot solve).
std::string materialProblem(double youngsModulusMPa, double poissonRatio);

/// How the tissue from the skin to the bone is layered, measured and made
/// of (§4.5.2, §4.6.1): shared by a plan's model (SimulationOptions) and the
/// whole face's (expression::FaceModelOptions). Lengths in mm.
struct TissueDepthOptions
{
  /// Element layers from the skin to the bone.
  int layerCount = 3;
  /// Fractions of the local depth per layer, skin first (e.g. skin, fat,
  /// muscle: {0.2, 0.4, 0.4}); empty: equal layers.
  std::vector<double> layerFractions;
  /// Soft-tissue depth clamping (mm) and the depth where the bone map has no bone.
  double minDepth = 2.0;
  double maxDepth = 40.0;
  double noBoneDepth = 10.0;
  /// Passes of 3 × 3 box smoothing (eq. 4.2) of the bone surface used for the
  /// depth, after its holes are filled at noBoneDepth under the skin: the raw
  /// map jumps between neighbouring samples (sinus walls, holes), which folds
  /// deep elements; 0 uses the raw map.
  int boneSmoothingPasses = 8;
  /// Materials by layer (region = layer index); empty: defaultFacialTissueMaterials(layerCount).
  fem::MaterialTable materials;

  /// The continuum mesher's options for these layers and depths (the rim,
  /// cut depth and undermining left at the mesher's defaults).
  fem::ContinuumMeshOptions continuumMeshOptions() const;
  /// materials, or the default ones for layerCount when empty.
  fem::MaterialTable layerMaterials() const;
};

/// Which model of the tissue makes a prediction (thesis §1.4 and §6.1.2: the
/// linear model's limits).
enum class TissueModel
{
  /// Small-strain linear elasticity, one solve: the instant preview. Its
  /// deformed mesh need not be a body when the closure moves tissue by more
  /// than a few per cent of the element size; the check says so.
  LinearElastic,
  /// Compressible neo-Hookean layers with the same small-strain moduli
  /// (fem::HyperelasticMaterial::fromLinear()), Total Lagrangian, the
  /// sutures' gaps closed over load increments
  /// (fem::NonlinearStaticAnalysis): the final prediction.
  LargeDeformation
};

/// "linear" or "large-deformation": the name in plan.json and on the command line.
const char* tissueModelId(TissueModel model);
/// What the model is, in words, for every output that shows a prediction.
std::string tissueModelDescription(TissueModel model);
/// The model of an id of tissueModelId(); empty for any other text.
std::optional<TissueModel> tissueModelFromId(const std::string& id);

/// The smallest det F below which a deformation is not shown as a body of
/// tissue: an element folded (det F <= 0) or crushed to a hundredth of its
/// volume. Living soft tissue is nearly incompressible (det F ~ 1).
constexpr double kAdmissibleDetF = 0.01;

/// How far to trust a prediction (thesis §5.5): which model made it, whether
/// its solve reached the full closure, and whether the deformation it gives
/// is a body (every integration point's det F above kAdmissibleDetF).
struct PredictionCheck
{
  TissueModel model = TissueModel::LinearElastic;
  /// The large-deformation solve reached the full closure (always true for
  /// the linear model, which has one solve).
  bool converged = true;
  /// The fraction of the closure the displacements are at (1 when converged).
  double closureFraction = 1.0;
  int increments = 0; ///< accepted load increments (1 for the linear model)
  int iterations = 0; ///< Newton iterations in all, cut-back attempts included
  /// Increments solved with artificial viscosity through an instability (a
  /// flap that buckles as it is transposed; fem::StabilizationOptions), and
  /// the energy it took up as a fraction of the final strain energy: 0 when
  /// the path needed none. A converged result is an undamped equilibrium
  /// either way; a damped path is one the tissue may reach by another way
  /// (wrinkling, a snap) than the increments suggest.
  int dampedIncrements = 0;
  double dissipatedFraction = 0.0;
  /// The solve with the states on the way converged loosely (the faster
  /// path, fem::NewtonOptions::pathResidualTolerance) stopped at this
  /// fraction of the closure, and the prediction is that of a second solve
  /// with every increment converged fully; -1 when there was no second solve.
  double loosePathStoppedAt = -1.0;
  /// det F and the principal stretches over every integration point of the
  /// displacements (for the linear model: of its displacement field taken as
  /// a deformation x + u).
  fem::DeformationCheck deformation;
  /// Whether the deformed skin passes through itself (a flap folded back
  /// into the skin beside it), which det F > 0 does not rule out: the model
  /// has no contact between parts of the tissue. A skin that does is not a
  /// prediction.
  fem::SurfaceCrossingCheck skinCrossings;
  /// The same over the body's whole boundary (wound walls, the undermined
  /// plane, the deep face): where deep tissue is squeezed through the tissue
  /// beside it (wound walls bunching at a Z's corners). Stated as a caveat
  /// (on the stresses there), not a failure, when the skin stays clear.
  fem::SurfaceCrossingCheck tissueCrossings;
  /// What holds only with a reservation (e.g. the deep tissue crossing
  /// itself), for a person; empty when nothing.
  std::string caveat;
  /// The shape of the undeformed elements (scaled Jacobian at nodes and
  /// integration points, edge ratio), against fem::ElementQualityLimits.
  fem::MeshQualityCheck mesh;
  /// What the interior nodes' optimisation did before that check (zero
  /// movable nodes when it was switched off).
  fem::InteriorNodeOptimization nodeOptimization;
  /// Empty when admissible; otherwise what failed, where, and what to try.
  std::string problem;

  bool admissible() const
  {
    return converged && deformation.minDetF > kAdmissibleDetF && skinCrossings.crossingPairs == 0;
  }
};

/// The check in one line for a person: "smallest det F 0.639, largest
/// stretch 2.83, 0 inverted elements, 5 increments (41 Newton iterations),
/// converged at full closure".
std::string checkSummary(const PredictionCheck& check);
/// The label every view of a prediction starts with when the check failed:
/// "NOT A PREDICTION: ..." (large deformation) or "WARNING (linear preview):
/// ..." with the problem; empty when the check passed.
std::string checkWarning(const PredictionCheck& check);

/// Options of simulatePlan(). Lengths in mm.
struct SimulationOptions : TissueDepthOptions
{
  /// The model of the tissue; materials (TissueDepthOptions) are the
  /// small-strain moduli of either.
  TissueModel model = TissueModel::LinearElastic;
  /// Load increments of the large-deformation solve: the first is a quarter
  /// of the closure, grown when Newton converges fast, cut back (down to
  /// 1e-4 of the closure) when it does not or an element would turn inside
  /// out.
  fem::IncrementControl increments = {0.25, 1e-4, 0.5, false, 200};
  /// Newton's tolerances of the large-deformation solve: the prediction at
  /// full closure converges on the solver's residual (1e-8 of the forces);
  /// the states on the way, which only lead there, on a looser one
  /// (fem::NewtonOptions::pathResidualTolerance).
  fem::NewtonOptions newton = [] {
    fem::NewtonOptions n;
    n.pathResidualTolerance = 1e-3;
    return n;
  }();
  /// Element size at the wound: cut-path segments are split so every hole
  /// border edge is at most this long (sutured edges into equal numbers of
  /// pieces on both sides), and it is the first quad layer's thickness.
  double elementSize = 2.0;
  /// Distance from the hole to the rim of the meshed region.
  double regionRadius = 25.0;
  /// Growth of the quad layers' thickness away from the wound (SurfaceMesherOptions).
  double layerGrowth = 1.25;
  fem::RimCondition rim = fem::RimCondition::Free;
  /// Move the nodes between the skin and the bone so the elements stand
  /// upright where the bone is steep against the columns
  /// (fem::optimizeInteriorNodes()); the skin, the bone, the wound and the
  /// rim stay where the mesher put them.
  bool optimizeInteriorNodes = true;
  /// Undermining (thesis §3.2.2, §3.2.4 item 2, default form): the skin
  /// within this distance (mm, measured on the skin chart) of the sutured
  /// hole border edges is freed from what lies beneath, so the bone nodes
  /// under it are not fixed (fem::underminingBand()). 0: no undermining.
  /// Unset: the band the plan's procedure undermines by default
  /// (IncisionPlan::underminingBand(); underminingWidthFor()).
  std::optional<double> underminingWidth;
  /// What holds the undermined tissue on the deep plane: it slides on it
  /// (u . n = 0, the default: the surgeon frees the tissue in a plane, over
  /// the fascia or periosteum, and it glides there) or nothing does.
  fem::UnderminedBase underminedBase = fem::UnderminedBase::Sliding;
  /// Incision depth (thesis §3.2.2: cutting to a depth): the layers, from
  /// the skin, the cut goes through; 0 = all (full thickness down to the
  /// deep layer). Below a cut of partial depth the tissue stays whole, the
  /// sutures sew only the layers cut and undermined tissue is raised in the
  /// plane at the cut's root (fem::ContinuumMeshOptions::cutLayers). With
  /// the default three layers: 1 = through the skin, 2 = through the fat as
  /// well. Unset: the depth the plan's procedure states
  /// (IncisionPlan::cutDepth(); cutLayersFor()).
  std::optional<int> cutLayers;
  /// The tension the living skin carries before the cut (SkinPreTension):
  /// the wound gapes under it (PlanPrediction::gape) and the sutures close
  /// it against it. Unset: the skin is slack, as in the thesis.
  std::optional<SkinPreTension> preTension;
  /// Threads of the assembly.
  int threads = 1;
  /// Called by simulatePlan() between its phases (surface mesh, continuum
  /// mesh, assembly and factorisation, solve, closure forces) with the
  /// fraction of the work done and the phase starting; returning false stops
  /// it with seg::Cancelled. A phase once started runs to its end (the
  /// assembly and factorisation are one call of fem::LinearStaticAnalysis).
  /// Empty: not called.
  seg::ProgressCallback progress;
};

/// The undermining band a prediction of @a plan uses (mm):
/// options.underminingWidth if set, else the plan's procedure default.
double underminingWidthFor(const SimulationOptions& options, const IncisionPlan& plan);
/// The layers a prediction of @a plan cuts through (1..layerCount):
/// options.cutLayers if set (0: all), else the plan's procedure depth.
int cutLayersFor(const SimulationOptions& options, const IncisionPlan& plan);

/// The skin surface after the operation, for a display: one entry per
/// surface-mesh vertex (its skin node), and the surface polygons.
struct DisplacedSkin
{
  std::vector<ChartPoint> chart;          ///< chart position (mm) before the operation
  std::vector<Eigen::Vector3d> original;  ///< world (LPS mm) before
  std::vector<Eigen::Vector3d> displaced; ///< world after the solve
  std::vector<int> nodes;                 ///< FE node of each vertex (the skin node of its column)
  std::vector<std::vector<int>> polygons; ///< surface-mesh polygons (counter-clockwise seen from outside)
  int holeVertexCount = 0;                ///< leading vertices that are the hole loop
};

/// Wall-clock seconds of the pipeline's phases.
struct SimulationTimes
{
  double mesh = 0.0;     ///< surface and continuum meshing
  double assemble = 0.0; ///< stiffness assembly and constraint reduction
  /// Ordering, symbolic and numeric factorisation: the wall time they add
  /// after the assembly (the ordering runs on its own thread beside it).
  double factor = 0.0;
  double solve = 0.0; ///< substitution and expansion
};

/// Z-plasty gain predicted by the simulation next to the Fig. 2.2 table.
struct ZPlastyPrediction
{
  double limbAngle = 0.0; ///< radians (plan parameter)
  /// From the displaced pivot corners at the ends of the central limb (the
  /// copies the sutures do not carry; see simulatePlan()).
  ZPlastyGain predicted;
  double theoretical = 0.0; ///< zPlastyTheoreticalGain(limbAngle), fraction
  double geometric = 0.0;   ///< zPlastyGeometricGain(limbAngle), fraction
};

/// The force one suture carries after the closure: the reaction of its
/// constraint (thesis eq. 4.43), i.e. the internal force K U at the sutured
/// node, where no load acts.
struct SutureForce
{
  int node = -1;   ///< the sutured node (fem::Suture::node)
  int target = -1; ///< the node it is sewn onto
  /// On node (N); the target gets the opposite.
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
};

/// The closure force along one sutured edge pair of the plan.
struct SuturedEdgeForce
{
  fem::SutureEdgePair edges; ///< the plan's pair (the plan's own loop vertices)
  /// Node sutures along it: every layer of the columns of its refined edges.
  /// A suture at a cut point shared by two pairs counts in both.
  int sutureCount = 0;
  Eigen::Vector3d resultant = Eigen::Vector3d::Zero(); ///< sum of the forces on the sutured nodes (N)
  double resultantMagnitude = 0.0;                     ///< |resultant| (N)
  double magnitudeSum = 0.0;                           ///< sum of the sutures' force magnitudes (N)
};

/// What holds the wound closed (issue: how far to undermine).
struct ClosureForces
{
  std::vector<SutureForce> sutures;    ///< one per continuum suture, in the same order
  std::vector<SuturedEdgeForce> edges; ///< one per suture pair of the plan, in the plan's order
  double magnitudeSum = 0.0;           ///< sum of every suture's force magnitude (N)
  double largest = 0.0;                ///< the largest force one suture carries (N)
  /// Sum of the reactions of the fixed nodes (the bone, a clamped rim), N.
  Eigen::Vector3d supportReaction = Eigen::Vector3d::Zero();
};

/// The wound as cut, before any suture, opened by the skin's pre-tension
/// (issue 21 item 4): the middle step of intact, incised and gaping, closed.
struct WoundGape
{
  /// 3N, with the same model as the prediction, held as
  /// ContinuumMesh::openWoundConstraints() says.
  Eigen::VectorXd displacements;
  /// World position of each skin vertex (DisplacedSkin order) gaping.
  std::vector<Eigen::Vector3d> skin;
  /// The widest the wound is across (mm): the largest distance between the
  /// two sides a suture will join, as cut and gaping.
  double widestAsCut = 0.0;
  double widestGaping = 0.0;
  /// The same on the skin surface only, along the wound: the mean over the
  /// sutured skin nodes of how far the sides move apart (mm).
  double meanOpening = 0.0;
  /// The wound's open area on the skin (mm²): the area the hole loop
  /// encloses, through its vertices and edge midpoints, projected on its
  /// own best plane; as cut and gaping. A Z-plasty's or a flap's limbs
  /// enclose almost none as cut, so this is the gape of any incision.
  double openAreaAsCut = 0.0;
  double openAreaGaping = 0.0;
  /// Empty when the gaping solve converged, is a body (det F above
  /// kAdmissibleDetF) and its skin does not pass through itself; otherwise
  /// why not (the gape is then not shown as one).
  std::string problem;
};

/// Everything simulatePlan() computed.
struct PlanPrediction
{
  fem::SurfaceMesherResult surface;         ///< the surface mesh of the refined hole (chart mm)
  fem::HoleLoop hole;                       ///< the refined hole loop the mesh was grown from
  std::vector<fem::SutureEdgePair> sutures; ///< the plan's sutures on the refined loop
  /// For each loop vertex of the plan's own hole loop, its vertex in the refined loop.
  std::vector<int> refinedVertexOf;
  fem::ContinuumMesh continuum;  ///< FE mesh, constraints, node columns
  Eigen::VectorXd displacements; ///< 3N: (x, y, z) of node i at 3i..3i+2 (mm)
  /// Internal nodal forces K U (N), 3N like displacements: zero to round-off
  /// at free nodes, the reactions at fixed and sutured ones.
  Eigen::VectorXd nodalForces;
  /// Per surface-mesh vertex, non-zero where the skin is undermined: the
  /// band of SimulationOptions::underminingWidth and the plan's own regions
  /// (IncisionPlan::underminedRegions()); the bone nodes released are
  /// continuum.underminedNodes.
  std::vector<char> underminedVertices;
  /// The band along the sutured edges undermined (mm; underminingWidthFor()).
  double underminingWidth = 0.0;
  ClosureForces closure;
  /// The tissue the excision removes (§3.1.3): wedges over the hole's floor
  /// through the layers cut (fem::meshExcisedTissue()), with the depths of
  /// the model; empty without excision.
  fem::ContinuumMesh excisedTissue;
  /// Its volume (mm³), from the elements (fem::meshVolume()).
  double excisedVolume = 0.0;
  int layerCount = 0; ///< tissue layers of the model
  int cutLayers = 0;  ///< of which the cut goes through (layerCount for full thickness)
  DisplacedSkin skin;
  /// Largest distance between the two nodes of a suture after the solve (mm).
  double maxSutureGap = 0.0;
  /// The same before the solve: how wide the wound was.
  double maxSutureGapBefore = 0.0;
  Eigen::Index dofCount = 0;        ///< 3 × nodes
  Eigen::Index reducedDofCount = 0; ///< unknowns after constraints
  SimulationTimes times;
  std::optional<ZPlastyPrediction> zPlasty; ///< for plans of a Z generator
  fem::MaterialTable materials;             ///< what was used (small-strain moduli)
  /// The large-deformation materials (empty for the linear model).
  fem::HyperelasticTable hyperelasticMaterials;
  PredictionCheck check;
  /// The pre-tension the model carries (SkinPreTension::describe()), or
  /// empty: none (the thesis's slack skin).
  std::string preTension;
  /// How the wound gapes before it is sutured; set with a pre-tension.
  std::optional<WoundGape> gape;

  /// Displaced world position of FE node i.
  Eigen::Vector3d displacedNode(int i) const;
};

/// @brief Simulates a plan: meshes the skin around its hole down to the bone
/// and closes its sutures (thesis §4.5–4.6) with the model of
/// options.model: a linear static solve or a large-deformation one.
///
/// The chart is the plan's (centre()). The cut path is refined to
/// options.elementSize consistently with the sutures; offsets (excisions)
/// are interpolated along each side. The chart bounds are the skin map's z
/// range. The tissue under chart point c runs along the ray towards the
/// axis from the skin point lift(c); its depth is skin r − bone r, clamped to
/// [minDepth, maxDepth], noBoneDepth where the bone map has no bone. Bone
/// nodes are fixed except under the undermined band and the plan's
/// undermined regions, the rim as options.rim
/// says. After the solve, the reaction of every suture is the closure force.
/// Every prediction carries its check (PlanPrediction::check): a
/// large-deformation solve that stops short of the full closure returns its
/// last converged state with check.converged false and check.problem
/// saying what to try; it is not a prediction and must not be shown as one.
///
/// @throws std::invalid_argument for a bad plan (checkPlan()), a plan off the
/// skin, holes in the skin map under the meshed region, a bone map on another
/// axis, bad options; std::runtime_error when the model cannot be solved
/// (the message says why).
PlanPrediction simulatePlan(const seg::RangeMap& skin, const seg::RangeMap& bone, const IncisionPlan& plan,
                            const SimulationOptions& options = {});

/// How far apart two predictions of one plan on one mesh put the skin (mm):
/// the largest and the mean distance between a skin vertex's two displaced
/// positions, e.g. the linear preview against the large-deformation
/// prediction (the report's "Model and assumptions").
struct SkinDifference
{
  double largest = 0.0;
  double mean = 0.0;
};
/// @throws std::invalid_argument when the two do not share the skin's vertices.
SkinDifference skinDifference(const PlanPrediction& a, const PlanPrediction& b);

/// @brief The meshes simulatePlan() would solve, without solving: the
/// fields up to the continuum mesh (surface, hole, sutures,
/// refinedVertexOf, underminedVertices, continuum, excisedTissue,
/// excisedVolume, layerCount, cutLayers, times.mesh) are what simulatePlan()
/// sets with the same arguments; the rest stay empty. For the size of a
/// model before it is run: continuum.mesh.nodeCount(), elements,
/// continuum.mesh.dofCount() (= simulatePlan()'s dofCount).
/// @throws as simulatePlan() does for its checks and meshing.
PlanPrediction meshPlan(const seg::RangeMap& skin, const seg::RangeMap& bone, const IncisionPlan& plan,
                        const SimulationOptions& options = {});

/// @brief The bone surface the soft-tissue depth is measured to: @a bone with
/// its holes filled @a noBoneDepth under the skin, then box-smoothed
/// (eq. 4.2) @a smoothingPasses times (SimulationOptions::boneSmoothingPasses).
/// An empty @a bone gives an empty map; 0 passes the bone as it is.
seg::RangeMap boneForTissueDepth(const seg::RangeMap& skin, const seg::RangeMap& bone, double noBoneDepth,
                                 int smoothingPasses);

/// @brief Where the tissue lies under the chart (§4.5.2): the skin lifted from
/// @a chart, the depth to @a boneForDepth (from boneForTissueDepth(); empty:
/// NaN, no bone) along the ray towards the axis.
/// @warning Keeps references to all three: they must outlive the geometry.
fem::TissueGeometry skinToBoneGeometry(const SkinChart& chart, const seg::RangeMap& skin,
                                       const seg::RangeMap& boneForDepth);

/// @name Pieces of the pipeline, exposed for tests
///@{
/// The cut path refined so no hole border edge is longer than maxSpacing,
/// with every group of suture-connected segments split into the same number
/// of pieces; returns the refined hole loop (offsets interpolated along each
/// side) and the sutures on it. refinedVertexOf maps old loop vertices to new.
struct RefinedHole
{
  fem::HoleLoop hole;
  std::vector<fem::SutureEdgePair> sutures;
  std::vector<int> refinedVertexOf;
  std::vector<int> piecesPerSegment;
};
RefinedHole refineHole(const std::vector<ChartPoint>& path, const std::vector<ChartPoint>& offsets,
                       const std::vector<fem::SutureEdgePair>& sutures, double maxSpacing);
///@}

} // namespace caps::planning
