#pragma once

#include "fem/Assembly.h"
#include "fem/Constraints.h"
#include "fem/FiniteStrainIntegrator.h"
#include "fem/HyperelasticMaterial.h"
#include "fem/InitialStress.h"
#include "fem/Mesh.h"
#include "fem/SparseCholeskySolver.h"
#include "fem/StaticAnalysis.h"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <functional>
#include <string>
#include <vector>

namespace caps::fem {

/// When the Newton iteration forms and factors a new tangent.
enum class TangentUpdate
{
  /// Full Newton: a new tangent and one numeric factorization every iteration.
  EveryIteration,
  /// Modified Newton: the last factorization is kept, across iterations and
  /// into the next increment, while keeping it is predicted to reach the
  /// tolerance sooner than a new one (from the measured contraction of the
  /// residual and the costs of a tangent, a factorization, a force
  /// evaluation and a solve, estimated from the model's counts so that the
  /// same model takes the same path on every run); otherwise the iteration
  /// forms the tangent at its state and factors it (the "reformation" of
  /// FEBio's quasi-Newton).
  WhenSlow
};

/**
 * @brief Artificial viscosity through a local instability: a flap that
 *        buckles or wrinkles as it is transposed has no stable quasi-static
 *        path, and Newton fails there at every increment size. After
 *        @a afterFailures increments fail in a row, each increment adds the
 *        viscous force c D (u - u_n) / dt (u_n the increment's start, dt its
 *        size in load fraction, D the diagonal of the reference tangent) and
 *        c D / dt to the tangent; c is set when it starts so that the
 *        predicted increment dissipates @a dissipatedEnergyFraction of the
 *        strain energy (Abaqus's "automatic stabilization", with its default
 *        fraction 2e-4; ANSYS STABILIZE, ENERGY), and grown tenfold when
 *        stabilized increments keep failing. The viscous force is a path, not
 *        a result: at full load the damping is released (relaxation
 *        increments at full load, each twice as long, then Newton without
 *        it), and the solve converges only when that undamped Newton does,
 *        so a converged result is an equilibrium of the tissue alone.
 */
struct StabilizationOptions
{
  bool enabled = true;
  int afterFailures = 2;                  ///< consecutive failed increments before it starts
  double dissipatedEnergyFraction = 2e-4; ///< of the strain energy, per increment, when it starts
  double largestDissipatedFraction = 0.2; ///< c grows at most until this fraction
  int relaxations = 8;                    ///< damped increments at full load before giving up
};

/// Tolerances and safeguards of the Newton-Raphson iteration in one increment.
struct NewtonOptions
{
  /// Converged when |R| <= residualTolerance * the force scale (the larger
  /// of |f_ext| and |f_int|, reactions included) ...
  double residualTolerance = 1e-8;
  /// ... and the energy of the last correction |dU . R| <= energyTolerance
  /// times that of the increment's first.
  double energyTolerance = 1e-14;
  /// The increments before the last (those that end below full load)
  /// converge on this looser residual, and on the energy tolerance loosened
  /// by the square of the same factor (a correction's energy goes as the
  /// residual squared); 0: residualTolerance. Hyperelastic tissue under
  /// dead loads and linear constraints has no memory of its path, so the
  /// states on the way only have to be near enough to equilibrium for
  /// Newton to start the next increment from them (each increment's
  /// residual carries what the last one left over); the state at full load,
  /// the prediction, converges on residualTolerance as always. Not while the
  /// artificial viscosity is on (a damped path depends on its states), and
  /// a solve that fails on the loose path is solved again on the strict one
  /// before it is reported as failed (NonlinearResult::loosePathStoppedAt).
  double pathResidualTolerance = 0.0;
  int maxIterations = 20;
  TangentUpdate tangentUpdate = TangentUpdate::WhenSlow;
  /// Line search along each correction (FEBio's): when the energy along it
  /// has not fallen below lineSearchRatio of its start, the step is cut to
  /// the secant root, at most maxLineSearchSteps times.
  bool lineSearch = true;
  double lineSearchRatio = 0.9;
  int maxLineSearchSteps = 5;
  /// A tangent that is not positive definite is shifted towards its
  /// diagonal until it is (Levenberg-Marquardt), rather than ending the
  /// increment; the increment is still cut back if Newton does not converge.
  bool shiftIndefiniteTangent = true;
  StabilizationOptions stabilization;
};

/// The load increments: fractions of the load, the prescribed displacements
/// and the suture gaps, applied together from 0 to 1.
struct IncrementControl
{
  double initial = 1.0;  ///< first increment
  double minimum = 1e-5; ///< below it, a failing increment ends the solve
  double maximum = 1.0;  ///< the largest increment after growing
  /// Fixed increments of @a initial (CalculiX *STATIC, DIRECT): a failing
  /// increment ends the solve instead of being cut back.
  bool fixed = false;
  int maxIncrements = 1000;
};

/// What one Newton iteration reached (for the log and the progress bar).
struct NewtonIteration
{
  int increment = 0;           ///< 1-based, counting accepted increments
  double loadFraction = 0.0;   ///< the fraction the increment aims at
  int iteration = 0;           ///< 1-based within the increment
  double residual = 0.0;       ///< |R| / force scale after the iteration
  double energy = 0.0;         ///< |dU . R| of the correction / the increment's first
  double lineSearchStep = 1.0; ///< the fraction of the correction taken
  bool newTangent = true;      ///< the correction came from a tangent formed and factored for it
  /// The solve is the strict path's, after the loose one failed
  /// (NewtonOptions::pathResidualTolerance): loadFraction starts again from 0.
  bool strictRetry = false;
};

/// One attempted increment, accepted or cut back.
struct IncrementRecord
{
  int increment = 0;
  double startFraction = 0.0, endFraction = 0.0;
  int iterations = 0;
  double residual = 0.0; ///< the last relative residual
  bool accepted = false;
  bool stabilized = false; ///< with artificial viscosity (StabilizationOptions)
  std::string rejection;   ///< why it was cut back (empty when accepted)
};

enum class NonlinearStatus
{
  Converged,    ///< the whole load reached, every increment converged
  NotConverged, ///< an increment failed at the smallest size: result is the last converged state, NOT a prediction
  Cancelled     ///< stopped by the monitor
};

struct NonlinearResult
{
  NonlinearStatus status = NonlinearStatus::NotConverged;
  std::string message;                     ///< empty when converged; otherwise what happened and what to try
  double loadFraction = 0.0;               ///< the last converged fraction (1 when converged)
  Eigen::VectorXd displacements;           ///< 3N at loadFraction
  DeformationCheck check;                  ///< of the displacements above
  int failedElement = -1;                  ///< the element that inverted in the last failed try, if that was why
  std::vector<IncrementRecord> increments; ///< every attempt, in order
  std::vector<NewtonIteration> iterations; ///< every iteration, in order
  int factorizations = 0;
  /// Factorizations of a tangent shifted to be positive definite
  /// (NewtonOptions::shiftIndefiniteTangent), and the largest relative shift.
  int shiftedFactorizations = 0;
  double largestShift = 0.0;
  /// Accepted increments with artificial viscosity (StabilizationOptions),
  /// the energy it dissipated over the whole solve and that as a fraction
  /// of the final strain energy: 0 when the path needed none.
  int stabilizedIncrements = 0;
  double dissipatedEnergy = 0.0;
  double dissipatedFraction = 0.0;
  /// When a solve on a loose path (NewtonOptions::pathResidualTolerance)
  /// did not converge and this result is the strict path's: where the loose
  /// one stopped (its work is in the counts and times below, its increments
  /// and iterations are not in the lists above). -1: no retry.
  double loosePathStoppedAt = -1.0;
  int assemblies = 0;           ///< evaluations of the forces (with the tangent or, in line searches, without)
  double assembleSeconds = 0.0; ///< in those evaluations
  double factorSeconds = 0.0;   ///< reducing and factoring K-bar
};

/// Called after every Newton iteration; returning false cancels the solve.
using NewtonMonitor = std::function<bool(const NewtonIteration&)>;

/**
 * @brief Quasi-static large-deformation analysis: Total Lagrangian
 *        hyperelastic elements (FiniteStrainIntegrator.h), Newton-Raphson
 *        with line search in load increments that grow when Newton converges
 *        fast and are cut back when it does not or when an element would turn
 *        inside out; a step that fails is never accepted.
 *
 * Constraints are the linear model's master-slave elimination
 * U = T Ubar + lambda g, with g (prescribed values, suture gaps) ramped with
 * the load fraction lambda: a suture is a linear constraint and closes
 * exactly in large deformation too. Each increment starts from the tangent
 * of the last converged state with the prescribed increment as load (the
 * consistent predictor). The pattern of K-bar is analysed once; an
 * iteration either factors a new tangent numerically or, in modified Newton
 * (NewtonOptions::tangentUpdate), keeps the last factorization when that is
 * predicted to converge sooner. Each element's reference geometry is
 * computed once per solve. Loads (nodal forces, gravity,
 * muscles) are dead loads scaled by lambda; face pressures (follower loads
 * in large deformation) are refused.
 */
class NonlinearStaticAnalysis
{
public:
  NonlinearStaticAnalysis(Mesh mesh, HyperelasticTable materials, Constraints constraints,
                          AssemblyOptions options = {});

  /// Runs the increments. Throws std::invalid_argument / ElementError on bad
  /// input (mesh, materials, constraints, a face pressure), naming the culprit.
  NonlinearResult solve(const LoadCase& load, const IncrementControl& control = {}, const NewtonOptions& newton = {},
                        const NewtonMonitor& monitor = {});

  /**
   * @brief A stress the tissue carries in its reference state (skin
   *        pre-tension; InitialStress.h), ramped with the load fraction
   *        like every load: at fraction lambda the elements carry
   *        S(C) + lambda S0. The load that balances it on the intact tissue
   *        (initialStressBalance()) is the caller's to add to the load case,
   *        as a dead load it is ramped with S0. Empty: none (the default).
   *        Throws std::invalid_argument as InitialStress::validate().
   */
  void setInitialStress(InitialStress s0);
  const InitialStress& initialStress() const { return initialStress_; }

  /// Full load vector (3N) of @a load at fraction 1.
  Eigen::VectorXd loadVector(const LoadCase& load) const;
  /// Internal forces f_int(u) (3N; at constrained DOFs the reactions), the
  /// whole initial stress included. Throws InvertedElementError where u
  /// turns an element inside out.
  Eigen::VectorXd internalForces(const Eigen::VectorXd& u) const;
  /// Upper triangle of the tangent K_t(u) (3N x 3N).
  Eigen::SparseMatrix<double> tangentStiffness(const Eigen::VectorXd& u) const;
  /// det F, stretches and energy of @a u over every integration point.
  DeformationCheck deformationCheck(const Eigen::VectorXd& u) const;

  const Mesh& mesh() const { return mesh_; }
  const HyperelasticTable& materials() const { return materials_; }
  /// The small-strain limit of each region's material.
  const MaterialTable& smallStrainMaterials() const { return linear_; }

private:
  /// f_int and (if @a k) K_t at @a u, with @a initialStressScale S0, into
  /// @a fint / @a k; returns the checks.
  DeformationCheck evaluate(const Eigen::VectorXd& u, double initialStressScale, Eigen::SparseMatrix<double>* k,
                            Eigen::VectorXd* fint) const;
  void validate(const LoadCase& load) const;
  /// Keeps each element's reference geometry (ReferencePoints) when it fits
  /// kReferenceCacheBytes; evaluations compute it on the fly otherwise.
  void cacheReferenceGeometry();

  Mesh mesh_;
  HyperelasticTable materials_;
  MaterialTable linear_;
  Constraints constraints_;
  AssemblyOptions options_;
  std::vector<ReferencePoints> reference_; ///< per element, or empty
  InitialStress initialStress_;
};

} // namespace caps::fem
