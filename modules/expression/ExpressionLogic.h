#pragma once
/// @file ExpressionLogic.h
/// @brief Expressions as named activation sets (thesis §5.3,
/// Fig. 5.14–5.18) and the face model that shows them in real time by
/// superposition (§3.1.2). No widgets: the panel and the tests drive it.
///
/// How sliders mix (mixActivations()): each expression e has an activation
/// A_e[k] per fitted muscle k and a weight w_e in [0, 1] (its slider); each
/// muscle has an offset o_k in [0, 1] (its slider). The muscles' activations
/// are
///
///     a_k = clamp(Σ_e w_e A_e[k] + o_k, 0, 1),
///
/// so a single expression slider at 100 % gives that expression exactly,
/// two expressions add (a smile with a sneer), a muscle slider adds its own
/// contraction on top, and no muscle goes beyond the muscle file's full
/// contraction (activation 1). The skin is linear in a (§4.6), so the face
/// is Σ a_k D_k on the display skin: no finite-element work per slider move.

#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <vtkSmartPointer.h>

#include "modules/core/Module.h"
#include "planning/FaceModel.h"
#include "planning/MuscleResponses.h"
#include "planning/MuscleSet.h"
#include "segmentation/Landmarks.h"
#include "segmentation/RangeMap.h"
#include "segmentation/SurfaceScanColourMap.h"

class vtkImageData;
class vtkPolyData;

namespace caps {

class ExpressionNode;

namespace expression {

/// A built-in expression: activations per muscle of the default set. A
/// muscle is named by its definition id ("zygomaticus_major": both sides of
/// a bilateral muscle) or by a fitted id ("zygomaticus_major_left").
struct ExpressionDefinition
{
  std::string name;        ///< "smile": also the slider's object name suffix
  std::string title;       ///< "Smile"
  std::string description; ///< which muscles, and where it comes from
  std::vector<std::pair<std::string, double>> muscles;
};

/// The built-in expressions: smile, frown, pucker, sneer, and the thesis's
/// expressions of Fig. 5.15–5.18 (fig_5_15 levator labii + temporalis;
/// fig_5_16 risorius + alaeque nasi + corrugator; fig_5_17 depressor labii;
/// fig_5_18 orbicularis oris).
const std::vector<ExpressionDefinition>& builtInExpressions();

/// The activation of every fitted muscle (in @a muscles' order) under
/// @a expression: a muscle named by its definition id applies to every
/// fitted muscle of that definition, a fitted id to that muscle only (the
/// later entry wins). Names no fitted muscle matches are ignored.
Eigen::VectorXd expressionActivations(const ExpressionDefinition& expression, const std::vector<FittedMuscle>& muscles);

/// The same for a saved expression (muscle id → activation); ids the model
/// does not have are returned in @a unknown when given.
Eigen::VectorXd expressionActivations(const std::map<std::string, double>& activations,
                                      const std::vector<FittedMuscle>& muscles,
                                      std::vector<std::string>* unknown = nullptr);

/// a_k = clamp(Σ_e weights[e] expressions[e][k] + offsets[k], 0, 1) (see the
/// file comment). @throws std::invalid_argument for mismatched sizes.
Eigen::VectorXd mixActivations(const std::vector<Eigen::VectorXd>& expressions, const std::vector<double>& weights,
                               const Eigen::VectorXd& offsets);

/// What the face model is built from: copies, so the build may run on a
/// worker thread while the scene changes.
struct ExpressionModelInput
{
  seg::RangeMap skin;
  seg::RangeMap bone;
  std::vector<seg::Landmark> landmarks;
  /// Where the landmarks came from, for the status line.
  std::string landmarkSource;
  /// The CT the skin's shade is read from (seg::skinShadeFromCt); null: grey.
  vtkSmartPointer<vtkImageData> ct;
  std::filesystem::path muscleSet; ///< defaultMuscleSetPath() unless set
  FaceModelOptions face;
  /// Display steps per element edge (fem::DisplaySurface).
  int resolution = 3;
  /// Longest range detail kept (mm), as planning::PlanDisplayOptions.
  double maxRangeDetail = 3.0;
};

/// The face model of one patient, ready for sliders.
struct ExpressionModel
{
  std::string muscleSetId;     ///< "default"
  seg::CylindricalFrame frame; ///< the skin map's (the camera faces θ = -π/2)
  FaceMesh face;
  std::vector<FittedMuscle> muscles;
  MuscleResponses responses;
  /// The skin faces with the scan's range detail set (PlanDisplay's rule).
  ExpressionSurface surface;
  /// Source colour per display vertex (the CT's skin shade, grey without).
  std::vector<seg::Rgb8> shade;
  std::string shadeNote; ///< why the skin is grey, when it is
  std::string landmarkSource;
  double meshSeconds = 0.0, factorSeconds = 0.0, responseSeconds = 0.0, totalSeconds = 0.0;

  /// The index of fitted muscle @a id, -1 when none.
  int muscleIndex(const std::string& id) const;
  /// Display positions under @a activations, range detail on.
  void positions(const Eigen::VectorXd& activations, Eigen::Matrix3Xd& out) const
  {
    surface.positions(activations, true, out);
  }
};

/// @brief Builds the face model (thesis §5.3 and §3.1.2): reads and fits the
/// muscle set, meshes the face without a plan, factors it once, solves once
/// per muscle, and interpolates the responses to the display skin. Runs on a
/// worker thread; @a progress (may be empty) is told each step and stops the
/// build (returns nullptr) when it returns false.
/// @throws std::invalid_argument (or MuscleSetFileError) saying what is missing.
std::unique_ptr<ExpressionModel> buildExpressionModel(const ExpressionModelInput& input,
                                                      const TaskProgress& progress = {});

/// A display skin as polydata with every activation 0 (the base only, range
/// detail on): points, the display polygons (triangles and quadrilaterals,
/// outward) and the RGB array skin_colour (the active scalars) from
/// @a shade, one per vertex (grey where it has none).
vtkSmartPointer<vtkPolyData> shadedSkinPolyData(const ExpressionSurface& surface, const std::vector<seg::Rgb8>& shade);

/// The face's display skin as polydata at rest (shadedSkinPolyData()).
vtkSmartPointer<vtkPolyData> expressionPolyData(const ExpressionModel& model);

/// Moves the points of @a polyData (made by expressionPolyData()) to the
/// skin under @a activations; @a scratch is reused. Returns the largest
/// vertex movement from rest (mm). Does not call Modified().
double applyActivations(const ExpressionModel& model, const Eigen::VectorXd& activations, vtkPolyData* polyData,
                        Eigen::Matrix3Xd& scratch);

} // namespace expression

/// The Expression module's logic: the scene's side of expressions.
class ExpressionLogic : public ModuleLogic
{
public:
  using ModuleLogic::ModuleLogic;

  /// The inputs of the face model from the scene: the newest skin and bone
  /// range maps, the landmarks placed automatically on them with the
  /// user's (a Landmarks node, by standard name) in their place, and the CT.
  /// @throws std::invalid_argument saying what to do when a map or a
  ///         landmark the model needs is missing.
  expression::ExpressionModelInput modelInput() const;

  /// The expressions saved in the scene, in scene order.
  std::vector<ExpressionNode*> savedExpressions() const;
  ExpressionNode* savedExpression(const std::string& name) const;

  /// Saves @a activations (fitted id → activation, clamped to [0, 1]; zeros
  /// left out) as expression @a name, as one undoable edit either way: the
  /// one of that name changed, or a new ExpressionNode (undo takes it out
  /// of the scene, redo puts it back with the same id).
  /// @throws std::invalid_argument for an empty name.
  ExpressionNode& saveExpression(const std::string& name, const std::string& muscleSet,
                                 const std::map<std::string, double>& activations, const std::string& description);
};

} // namespace caps
