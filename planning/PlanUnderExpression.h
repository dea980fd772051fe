#pragma once
/// @file PlanUnderExpression.h
/// @brief The post-operative face under an expression or a push (thesis
/// §5.4: the surgeon pushes the cheek up to see whether the Z-plasty's
/// bumps get worse when the patient smiles): the plan's model with its
/// sutures closed, loaded by muscles or by a fingertip, and the contour
/// bumps around the incision with and without.

#include <vector>

#include <Eigen/Core>

#include "fem/MuscleLoad.h"
#include "fem/StaticAnalysis.h"
#include "planning/MuscleResponses.h"
#include "planning/PlanSimulation.h"

namespace caps::expression {

/// The plan's finite element model after the operation, factored: its mesh,
/// materials, fixed bone and sutures (PlanPrediction::continuum).
/// @throws std::runtime_error when it cannot be factored.
std::unique_ptr<fem::LinearStaticAnalysis> postOperativeAnalysis(const planning::PlanPrediction& prediction,
                                                                 int threads = 2);

/// @class PlanExpressionResponses
/// @brief The post-operative plan under the muscles of the whole face: a
/// submodel. The plan's model covers a few centimetres around the wound and
/// most muscles attach outside it, so loading it with the muscles alone
/// would miss most of an expression. Here its rim follows the whole-face
/// model (FaceModel.h, §5.3) under each muscle, and the muscle's load acts
/// inside it too; one factorisation of the plan's model with its rim
/// prescribed serves every muscle (LinearStaticAnalysis::solveWithPrescribed).
/// The closure adds to it: U(a) = closure + Σ a_k V_k (§3.1.2).
class PlanExpressionResponses
{
public:
  /// @a faceMesh and @a faceResponses: the whole-face model and its unit
  /// responses to @a muscles (the same list, same order).
  /// @throws std::invalid_argument when the plan's rim lies outside the face
  /// model (a plan beyond the face region); std::runtime_error when the plan's
  /// model cannot be solved.
  PlanExpressionResponses(const planning::PlanPrediction& prediction, const fem::Mesh& faceMesh,
                          const MuscleResponses& faceResponses, const std::vector<std::vector<fem::Muscle>>& muscles,
                          int threads = 2);

  /// V_k: what muscle k at activation 1 adds to the closure (3N × muscles).
  const Eigen::MatrixXd& responses() const { return responses_; }
  /// The rim nodes that follow the face model (not fixed, not sutured).
  const std::vector<int>& rimNodes() const { return rimNodes_; }
  /// Closure + Σ a_k V_k. @throws std::invalid_argument for a wrong count.
  Eigen::VectorXd displacement(const Eigen::VectorXd& activations) const;

private:
  Eigen::VectorXd closure_;
  Eigen::MatrixXd responses_;
  std::vector<int> rimNodes_;
};

/// A fingertip on the skin (§5.4): every skin node within @a radius (mm) of
/// @a centre (world LPS) is moved by @a displacement from where the closure
/// put it, the rest of the tissue follows.
struct SkinPush
{
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 5.0;
  Eigen::Vector3d displacement = Eigen::Vector3d::Zero();
};

/// The displacement (3N) of the post-operative model under @a push at full
/// travel: skin nodes under the fingertip prescribed at closure +
/// displacement (sutured nodes keep their sutures), a new factorisation. The
/// model is linear, so travel s along the push is
/// U(s) = closure + s (U(1) − closure) (the fingertip resting at s = 0
/// holds the skin where the closure put it).
/// @throws std::invalid_argument when no skin node lies under the fingertip;
/// std::runtime_error when the model cannot be solved.
Eigen::VectorXd pushedDisplacement(const planning::PlanPrediction& prediction, const SkinPush& push, int threads = 2);

/// @class PushResponses
/// @brief The post-operative model under a fingertip for any travel, at
/// display rate (§5.4 with §3.1.2). The skin nodes within the fingertip's
/// radius of its centre (where the closure put them; sutured nodes keep their
/// sutures) are prescribed; the model is factored once with them held and
/// solved three times, for a unit travel along x, y and z. The model is
/// linear, so the fingertip moved by d from where the closure put the skin
/// gives U(d) = closure + W d exactly, and a path is a sequence of d.
class PushResponses
{
public:
  /// @throws std::invalid_argument for a radius not above 0, a centre that is
  /// not finite, or no skin node under the fingertip; std::runtime_error when
  /// the model cannot be solved.
  PushResponses(const planning::PlanPrediction& prediction, const Eigen::Vector3d& centre, double radius,
                int threads = 2);

  /// W: 3N × 3, what a unit travel along x, y, z adds to the closure.
  const Eigen::MatrixXd& responses() const { return responses_; }
  /// The closure (3N): the model with the fingertip resting.
  const Eigen::VectorXd& closure() const { return closure_; }
  /// The skin nodes the fingertip holds.
  const std::vector<int>& pushedNodes() const { return pushedNodes_; }
  /// closure + W @a travel.
  Eigen::VectorXd displacement(const Eigen::Vector3d& travel) const;

private:
  Eigen::VectorXd closure_;
  Eigen::MatrixXd responses_;
  std::vector<int> pushedNodes_;
};

/// A fingertip's path (§5.4: a small region of skin displaced along a path):
/// the travel from where the closure put the skin goes from zero through
/// @a waypoints in order, straight between them, at even speed along its length.
struct PushPath
{
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(); ///< the fingertip on the skin after the operation (world LPS)
  double radius = 5.0;                              ///< mm
  std::vector<Eigen::Vector3d> waypoints;           ///< travel (mm) at each corner; the last is the end

  /// The path's length (mm).
  double length() const;
  /// The travel at fraction @a s (clamped to [0, 1]) of the length; zero for an empty or zero-length path.
  Eigen::Vector3d travelAt(double s) const;
};

/// The contour bumps of the skin around an incision: for each skin vertex of
/// the plan's surface mesh within @a window (mm, in the plan's chart) of the
/// cut's points, displaced by @a u, its height r from the head axis above or
/// below the quadratic that fits the displaced skin within 10 mm around it
/// (in arc and z about the axis; moving least squares leaving the vertex
/// out). The cheek's own curve and smooth movement are taken out exactly; a
/// dog-ear or a ridge stands out.
struct ContourBumps
{
  int vertices = 0;                                ///< skin vertices in the window
  double largest = 0.0;                            ///< largest |height − fit| (mm)
  double rms = 0.0;                                ///< root mean square of height − fit (mm)
  Eigen::Vector3d where = Eigen::Vector3d::Zero(); ///< displaced vertex of the largest
};

ContourBumps contourBumps(const planning::PlanPrediction& prediction, const seg::CylindricalFrame& frame,
                          const Eigen::VectorXd& u, double window = 20.0);

/// The plan at rest and under an expression or a push, compared.
struct ContourComparison
{
  ContourBumps rest;
  ContourBumps loaded;
  /// Largest change of a window vertex's height r (mm) between the two.
  double largestHeightChange = 0.0;
  Eigen::Vector3d where = Eigen::Vector3d::Zero();
  /// loaded.largest − rest.largest: > 0 the bumps get worse.
  double bumpChange() const { return loaded.largest - rest.largest; }
};

ContourComparison compareContours(const planning::PlanPrediction& prediction, const seg::CylindricalFrame& frame,
                                  const Eigen::VectorXd& rest, const Eigen::VectorXd& loaded, double window = 20.0);

} // namespace caps::expression
