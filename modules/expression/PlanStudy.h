#pragma once
/// @file PlanStudy.h
/// @brief A predicted plan studied in the whole face (thesis
/// §5.4): its post-operative skin follows the muscles' activations at
/// display rate, its contour bumps around the incision are compared at rest
/// and loaded, and a fingertip pushes its skin along a path. No widgets: the
/// Expressions panel and the tests drive it.
///
/// Everything is superposition (§3.1.2): the plan's model after the
/// operation is factored once with its rim following the face model
/// (PlanExpressionResponses) and once with the fingertip's skin held
/// (PushResponses); a slider move is a matrix-vector product on the display
/// skin (ExpressionSurface).

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <vtkSmartPointer.h>

#include "modules/core/Module.h"
#include "modules/expression/ExpressionLogic.h"
#include "planning/PlanUnderExpression.h"
#include "planning/IncisionPlan.h"
#include "planning/PlanSimulation.h"
#include "segmentation/RangeMap.h"
#include "segmentation/SurfaceScanColourMap.h"

class vtkImageData;
class vtkPolyData;

namespace caps::expression {

/// What a plan study is built from: copies read on the GUI thread, so the
/// build may run on a worker thread while the scene changes.
struct PlanStudyInput
{
  std::string planName;                ///< "Z-plasty 1"
  planning::IncisionPlan plan;         ///< IncisionLogic::readPlan()
  planning::SimulationOptions options; ///< IncisionLogic::simulationOptions(): predicted as it was
  seg::RangeMap skin;                  ///< the plan's skin map
  seg::RangeMap bone;
  /// The CT the skin's shade is read from (seg::skinShadeFromCt); null: grey.
  vtkSmartPointer<vtkImageData> ct;
  /// The whole-face model the plan's rim follows (buildExpressionModel()).
  std::shared_ptr<const ExpressionModel> model;
  /// Display steps per element edge of the plan's skin.
  int resolution = 3;
  /// Longest range detail kept (mm), as planning::PlanDisplayOptions.
  double maxRangeDetail = 3.0;
  /// Window of the contour bumps around the cut (mm, ContourBumps).
  double window = 20.0;
};

/// A fingertip on the plan's skin: its three unit-travel responses and the
/// display skin that follows them (built by PlanStudy::fingertip()).
struct Fingertip
{
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(); ///< on the skin after the operation (world LPS, mm)
  double radius = 5.0;                              ///< mm
  std::shared_ptr<const PushResponses> push;
  /// The display skin: closure + W travel (3 columns: x, y, z of the travel).
  ExpressionSurface surface;
  /// Up the head axis, across (along θ) and into the face (towards the axis)
  /// at the fingertip: the columns of the surgeon's travel frame.
  Eigen::Matrix3d directions = Eigen::Matrix3d::Identity();
  double seconds = 0.0; ///< time to build
};

/// @class PlanStudy
/// @brief One predicted plan after the operation inside the whole-face model.
class PlanStudy
{
public:
  /// @brief Predicts the plan again from @a input (as `caps report` does),
  /// makes its responses to the face model's muscles and its display skin,
  /// and measures its bumps at rest. Runs on a worker thread; @a progress
  /// (may be empty) is told each step and stops the build (returns nullptr)
  /// when it returns false.
  /// @throws std::invalid_argument saying what to do (no face model, a plan
  /// beyond the face model); std::runtime_error when a model cannot be solved.
  static std::unique_ptr<PlanStudy> build(const PlanStudyInput& input, const TaskProgress& progress = {});

  const std::string& planName() const { return planName_; }
  const planning::PlanPrediction& prediction() const { return prediction_; }
  const PlanExpressionResponses& responses() const { return *responses_; }
  /// The plan's display skin under the muscles (base: the closure).
  const ExpressionSurface& surface() const { return surface_; }
  /// Source colour per display vertex (the CT's skin shade; grey without).
  const std::vector<seg::Rgb8>& shade() const { return shade_; }
  const std::string& shadeNote() const { return shadeNote_; }
  const seg::CylindricalFrame& frame() const { return frame_; }
  Eigen::Index muscleCount() const { return responses_->responses().cols(); }
  /// The contour bumps with the muscles at rest (the plan as predicted).
  const ContourBumps& restBumps() const { return restBumps_; }
  double window() const { return window_; }

  /// @name Under the muscles
  ///@{
  /// Display positions (3 × V, range detail on) under @a activations: real
  /// time (one matrix-vector product). @throws std::invalid_argument for a wrong count.
  void positions(const Eigen::VectorXd& activations, Eigen::Matrix3Xd& out) const;
  /// The model's displacement (3N) under @a activations.
  Eigen::VectorXd displacement(const Eigen::VectorXd& activations) const;
  /// The bumps at rest and under @a activations (a few milliseconds).
  ContourComparison compare(const Eigen::VectorXd& activations) const;
  ///@}

  /// @name Under a fingertip
  ///@{
  /// @brief The push responses of a fingertip at @a centre (world, mm, on
  /// the skin after the operation) of @a radius: one factorisation, seconds.
  /// Const and thread-safe: run it on a worker thread, then setFingertip().
  /// @throws std::invalid_argument when no skin of the plan's model lies
  /// under the fingertip or the radius is not above 0.
  Fingertip fingertip(const Eigen::Vector3d& centre, double radius) const;
  /// Takes a fingertip made by fingertip().
  void setFingertip(Fingertip fingertip);
  /// fingertip() then setFingertip().
  void setFingertip(const Eigen::Vector3d& centre, double radius) { setFingertip(fingertip(centre, radius)); }
  bool hasFingertip() const { return fingertip_ != nullptr; }
  /// @throws std::logic_error without a fingertip.
  const Fingertip& currentFingertip() const;
  /// Display positions (3 × V, range detail on) with the fingertip moved by
  /// @a travel (world, mm) from where the closure put the skin: real time.
  void pushedPositions(const Eigen::Vector3d& travel, Eigen::Matrix3Xd& out) const;
  /// The model's displacement (3N) under the push.
  Eigen::VectorXd pushedDisplacement(const Eigen::Vector3d& travel) const;
  /// The bumps at rest and with the fingertip moved by @a travel.
  ContourComparison comparePush(const Eigen::Vector3d& travel) const;
  ///@}

  /// The display vertex nearest @a point among @a positions (3 × V); -1 when
  /// none lies within @a tolerance (mm). For a pick on the shown skin.
  static Eigen::Index nearestVertex(const Eigen::Matrix3Xd& positions, const Eigen::Vector3d& point, double tolerance);
  /// Where display vertex @a v lies on the model's skin after the operation
  /// (no range detail, no load): a fingertip's centre.
  Eigen::Vector3d restSkinPoint(Eigen::Index v) const;

  /// The rim of the plan's meshed region (its outer border, counter-clockwise
  /// seen from outside) on the skin before the operation, as (arc mm about
  /// the head axis from the rim's first point, z mm): a closed polygon.
  std::vector<Eigen::Vector2d> rimOnSkin() const;
  /// @brief For each cell of @a face (a display skin at rest, e.g.
  /// expressionPolyData()), whether it lies over the plan's region: every
  /// corner inside rimOnSkin() (the excised hole included). The face drawn
  /// without them frames the plan's skin, whose rim follows the face (§5.4);
  /// the cells the rim cuts stay, so there is no gap between the two.
  std::vector<char> faceCellsUnderPlan(vtkPolyData* face) const;

  /// The display skin as polydata at rest: points, polygons and the RGB
  /// array skin_colour (the shade), as expressionPolyData() makes the face's.
  vtkSmartPointer<vtkPolyData> polyData() const;

  double predictSeconds = 0.0, responseSeconds = 0.0, displaySeconds = 0.0, totalSeconds = 0.0;

private:
  PlanStudy() = default;
  std::string planName_;
  planning::PlanPrediction prediction_;
  std::unique_ptr<PlanExpressionResponses> responses_;
  ExpressionSurface surface_;
  std::vector<seg::Rgb8> shade_;
  std::string shadeNote_;
  seg::CylindricalFrame frame_;
  ContourBumps restBumps_;
  double window_ = 20.0;
  std::unique_ptr<Fingertip> fingertip_;
};

/// Moves the points of @a polyData to @a positions (3 × V); returns the
/// largest distance from @a rest (mm). @throws std::invalid_argument for a
/// polydata of another point count. Calls Modified() on the points.
double setPoints(vtkPolyData* polyData, const Eigen::Matrix3Xd& positions, const Eigen::Matrix3Xd& rest);

} // namespace caps::expression
