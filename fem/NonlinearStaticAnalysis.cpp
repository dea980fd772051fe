#include "fem/NonlinearStaticAnalysis.h"

#include "fem/FiniteStrainIntegrator.h"
#include "fem/MixedFiniteStrainIntegrator.h"
#include "fem/VoigtNotation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace caps::fem {

namespace {

struct Cancelled
{};

double secondsSince(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// How one increment ended.
struct IncrementOutcome
{
  bool converged = false;
  int iterations = 0;
  int newTangents = 0; ///< iterations that formed and factored a tangent
  double residual = 0.0;
  std::string rejection;
  int worstElement = -1; ///< an inverted element, when that was the reason
};

/// What one step of a Newton iteration costs, estimated from counts of the
/// model rather than measured: a measured time differs from run to run, and
/// modified Newton's choices with it, so the same plan would stop at a
/// different point inside the tolerance each time (a replayed plan would not
/// reproduce its numbers, and a closed-form test would pass or fail by
/// chance). The rates are those measured on the project's reference
/// machine (2 cores, OpenBLAS; the demo Z-plasty: 27 k integration points,
/// a 9.4 GFlop factorization in 0.12 s, a force evaluation in 15 ms, a
/// tangent in 37 ms, a solve in 7 ms). Only their ratios steer the choice.
struct NewtonStepCosts
{
  double forces = 0.0;        ///< internal forces at a state (seconds)
  double tangent = 0.0;       ///< forces and tangent at a state
  double factorization = 0.0; ///< reducing and factoring the tangent
  double backSolve = 0.0;     ///< one solve with the factor

  static NewtonStepCosts estimate(const Mesh& mesh, double factorFlops, double factorNonZeros)
  {
    constexpr double kForcesPerPoint = 0.53e-6, kTangentPerPoint = 1.35e-6; // s per integration point
    constexpr double kFactorRate = 75e9, kSolveRate = 5e9;                  // flop/s
    double points = 0.0; // a wedge has about two thirds of a brick's points
    for (const Element& el : mesh.elements)
      points += std::pow(integrationPointsOf(el, 3), 3) * (el.kind == ElementKind::Wedge15 ? 2.0 / 3.0 : 1.0);
    return {points * kForcesPerPoint, points * kTangentPerPoint, factorFlops / kFactorRate,
            4.0 * factorNonZeros / kSolveRate};
  }
};

/**
 * Modified Newton's choice (TangentUpdate::WhenSlow) before each iteration:
 * keep the factorization, or form and factor the tangent at the current
 * state, whichever is predicted to reach the residual tolerance sooner in
 * time. Near the solution Newton contracts the residual r by about L r
 * (quadratic convergence), L measured at the last new tangent; a kept
 * factorization contracts it by about as much as the last iteration did
 * (linear convergence). The costs of a force evaluation, a tangent
 * evaluation, a factorization and a solve are estimated from the model's
 * counts (NewtonStepCosts), so the choices depend only on the residuals.
 */
class TangentReusePolicy
{
public:
  NewtonStepCosts costs;

  /// An iteration took the residual from @a before to @a after, with a new
  /// tangent or with a kept one.
  void record(double before, double after, bool newTangent)
  {
    if (!(before > 0.0) || !std::isfinite(after))
    {
      contraction_ = newtonRate_ = kNone;
      return;
    }
    contraction_ = after / before;
    if (newTangent)
      newtonRate_ = contraction_ / before;
  }

  /// Whether the iteration that starts at relative residual @a residual,
  /// with @a iterationsLeft iterations allowed, should form a new tangent.
  bool wantsNewTangent(double residual, double tolerance, int iterationsLeft) const
  {
    // Without a measured contraction, or kept factorizations that barely contract: a new tangent.
    if (!(contraction_ < kSlowestKept) || !(newtonRate_ > 0.0))
      return true;
    if (!(residual > tolerance))
      return false;
    const double digits = std::log(residual / tolerance);
    const int keptIterations = int(std::ceil(digits / -std::log(contraction_)));
    if (keptIterations > iterationsLeft)
      return true;
    int newtonIterations = 0;
    for (double r = residual; r > tolerance && newtonIterations < iterationsLeft; ++newtonIterations)
      r *= std::min(1.0, newtonRate_ * r);
    const double kept = costs.forces + costs.backSolve;
    const double renewed = kept + costs.tangent + costs.factorization;
    return newtonIterations * renewed < keptIterations * kept;
  }

private:
  static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  static constexpr double kSlowestKept = 0.25; ///< a kept factorization must at least quarter the residual
  double contraction_ = kNone;
  double newtonRate_ = kNone;
};

std::string percent(double fraction)
{
  std::ostringstream s;
  s.precision(4);
  s << 100.0 * fraction << " %";
  return s.str();
}

} // namespace

NonlinearStaticAnalysis::NonlinearStaticAnalysis(Mesh mesh, HyperelasticTable materials, Constraints constraints,
                                                 AssemblyOptions options)
  : mesh_(std::move(mesh)), materials_(std::move(materials)), constraints_(std::move(constraints)), options_(options)
{
  for (const auto& [region, material] : materials_)
    linear_[region] = material.smallStrainLimit();
}

void NonlinearStaticAnalysis::validate(const LoadCase& load) const
{
  for (const auto& [region, material] : materials_)
    material.validate("material of region " + std::to_string(region));
  if (options_.volumetric == VolumetricFormulation::MixedPressure) // the mixed element needs the split law
    for (const auto& [region, material] : materials_)
      if (!material.hasVolumetricSplit())
        throw std::invalid_argument("material of region " + std::to_string(region) +
                                    ": the mixed u/p/J formulation needs a deviatoric/volumetric split, which " +
                                    lawName(material.law) + " has not");
  validateMesh(mesh_, linear_);
  for (const Element& el : mesh_.elements)
    integrationRule(el.kind, integrationPointsOf(el, options_.gaussPointsPerDirection));
  if (!load.facePressures.empty())
    throw std::invalid_argument(
      "face pressures are follower loads in large deformation, which the nonlinear analysis does not support; "
      "apply them as nodal forces or solve the linear model");
}

Eigen::VectorXd NonlinearStaticAnalysis::loadVector(const LoadCase& load) const
{
  // Dead loads only (validate() refuses face pressures, which follow the surface).
  LoadCase dead = load;
  dead.facePressures.clear();
  return assembleLoadVector(mesh_, linear_, dead, options_);
}

void NonlinearStaticAnalysis::setInitialStress(InitialStress s0)
{
  s0.validate(mesh_);
  initialStress_ = std::move(s0);
}

DeformationCheck NonlinearStaticAnalysis::evaluate(const Eigen::VectorXd& u, double initialStressScale,
                                                   Eigen::SparseMatrix<double>* k, Eigen::VectorXd* fint) const
{
  if (u.size() != mesh_.dofCount())
    throw std::invalid_argument("the displacement vector has " + std::to_string(u.size()) + " entries for a model of " +
                                std::to_string(mesh_.dofCount()) + " DOFs");
  std::vector<FiniteStrainElementCheck> checks(mesh_.elements.size());
  const ElementKernel kernel = [&](std::size_t e, ElementMatrix* ke, ElementVector* re) {
    const Element& el = mesh_.elements[e];
    ElementDisplacements ue = ElementDisplacements::Zero();
    for (int a = 0; a < kHex20NodeCount; ++a)
      if (el.nodes[std::size_t(a)] >= 0)
        ue.row(a) = u.segment<3>(3 * el.nodes[std::size_t(a)]).transpose();
    ElementVector local;
    // Formulation switch (AssemblyOptions::volumetric): the mixed u/p/J element or the displacement one.
    const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
    const IntegrationRule& rule = integrationRule(el.kind, integrationPointsOf(el, options_.gaussPointsPerDirection));
    const ElementCoordinates x = mesh_.elementCoordinates(e);
    const ReferencePoints reference = reference_.empty() ? referencePoints(shape, x, rule, int(e)) : ReferencePoints{};
    const ReferencePoints& ref = reference_.empty() ? reference : reference_[e];
    Eigen::Matrix3d s0;
    const bool stressed = !initialStress_.empty() && !initialStress_.elementStress[e].isZero(0.0);
    if (stressed)
      s0 = initialStressScale * tensorOf(initialStress_.elementStress[e]);
    if (options_.volumetric == VolumetricFormulation::MixedPressure)
      assembleElementMixedFiniteStrain(shape, x, ref, ue, materials_.at(el.region), rule, int(e), re ? *re : local, ke,
                                       checks[e], nullptr, stressed ? &s0 : nullptr);
    else
      assembleElementFiniteStrain(shape, x, ref, ue, materials_.at(el.region), rule, int(e), re ? *re : local, ke,
                                  checks[e], stressed ? &s0 : nullptr);
  };
  Eigen::VectorXd scratch;
  assembleElements(mesh_, options_.threads, kernel, k, fint ? fint : &scratch);
  DeformationCheck c;
  if (checks.empty())
    return c;
  c.minDetF = c.minStretch = std::numeric_limits<double>::infinity();
  c.maxStretch = 0.0;
  for (std::size_t e = 0; e < checks.size(); ++e)
  {
    if (checks[e].minDetF < c.minDetF)
    {
      c.minDetF = checks[e].minDetF;
      c.minDetFElement = int(e);
    }
    c.maxStretch = std::max(c.maxStretch, checks[e].maxStretch);
    c.minStretch = std::min(c.minStretch, checks[e].minStretch);
    c.strainEnergy += checks[e].energy;
  }
  return c;
}

void NonlinearStaticAnalysis::cacheReferenceGeometry()
{
  // About 13 kB per 27-point brick: 80 MB for a 100k-DOF model.
  constexpr std::size_t kReferenceCacheBytes = std::size_t(2) << 30;
  reference_.clear();
  std::size_t bytes = 0;
  for (const Element& el : mesh_.elements)
    bytes +=
      referencePointsBytes(integrationRule(el.kind, integrationPointsOf(el, options_.gaussPointsPerDirection)).size());
  if (bytes > kReferenceCacheBytes)
    return;
  reference_.reserve(mesh_.elements.size());
  for (std::size_t e = 0; e < mesh_.elements.size(); ++e)
  {
    const Element& el = mesh_.elements[e];
    reference_.push_back(
      referencePoints(ElementShape::fromConnectivity(el.kind, el.nodes), mesh_.elementCoordinates(e),
                      integrationRule(el.kind, integrationPointsOf(el, options_.gaussPointsPerDirection)), int(e)));
  }
}

Eigen::VectorXd NonlinearStaticAnalysis::internalForces(const Eigen::VectorXd& u) const
{
  Eigen::VectorXd f;
  evaluate(u, 1.0, nullptr, &f);
  return f;
}

Eigen::SparseMatrix<double> NonlinearStaticAnalysis::tangentStiffness(const Eigen::VectorXd& u) const
{
  Eigen::SparseMatrix<double> k = stiffnessPattern(mesh_);
  evaluate(u, 1.0, &k, nullptr);
  return k;
}

DeformationCheck NonlinearStaticAnalysis::deformationCheck(const Eigen::VectorXd& u) const
{
  return evaluate(u, 1.0, nullptr, nullptr);
}

namespace {

/**
 * One large-deformation solve: the load increments (run()), each a modified
 * or full Newton iteration (increment()), each iteration the tangent when
 * due, the out-of-balance force, a back-solve, a line search and the
 * convergence test. The forces and tangents come from @a evaluate (the
 * analysis's elements).
 */
class NewtonSolve
{
public:
  /// Forces (and tangent) at a displacement and load fraction.
  using Evaluate =
    std::function<DeformationCheck(const Eigen::VectorXd&, double, Eigen::SparseMatrix<double>*, Eigen::VectorXd*)>;

  /// @a initialStressForce: the internal force of the whole initial stress
  /// in the reference state (empty: none), for the predictor.
  NewtonSolve(const Mesh& mesh, const HyperelasticTable& materials, const Constraints& constraints,
              const std::function<Eigen::VectorXd()>& loadVector, Evaluate evaluate, Eigen::VectorXd initialStressForce,
              const NewtonOptions& newton, const NewtonMonitor& monitor)
    : map_(resolveConstraints(mesh, constraints)), fext_(loadVector()),
      initialStressForce_(std::move(initialStressForce)), k_(stiffnessPattern(mesh)), kbar_(map_.reduceMatrix(k_)),
      evaluate_(std::move(evaluate)), newton_(newton), monitor_(monitor),
      fullNewton_(newton.tangentUpdate == TangentUpdate::EveryIteration),
      roundoffForce_(roundoffForceOf(mesh, materials))
  {
    // The pattern of K-bar does not change between iterations: analysed once.
    useNodeGroupedOrdering(mesh, map_, solver_);
    if (map_.reducedCount() > 0)
      solver_.analyzePattern(kbar_);
    reuse_.costs = NewtonStepCosts::estimate(mesh, solver_.factorFlops(), solver_.factorNonZeros());
  }

  /// This solve is the strict path's second try (NewtonIteration::strictRetry).
  bool strictRetry = false;

  /// 3. The increments: grow after a fast convergence, cut back on failure;
  ///    through an instability with artificial viscosity, released at the end.
  NonlinearResult run(const IncrementControl& control)
  {
    Eigen::VectorXd ubar = Eigen::VectorXd::Zero(map_.reducedCount());
    double lambda = 0.0;
    double step = std::min(control.initial, 1.0);
    int accepted = 0;
    int failuresInARow = 0;
    try
    {
      while (lambda < 1.0 - 1e-12)
      {
        if (int(result_.increments.size()) >= control.maxIncrements)
        {
          lastReason_ = "the solve used its " + std::to_string(control.maxIncrements) + " increments";
          break;
        }
        step = std::min(step, 1.0 - lambda);
        const double target = (1.0 - lambda - step) < 1e-12 ? 1.0 : lambda + step;
        Eigen::VectorXd state = ubar;
        const IncrementOutcome o = increment(accepted + 1, lambda, target, state, target - lambda);
        result_.increments.push_back(
          {accepted + 1, lambda, target, o.iterations, o.residual, o.converged, stabilizing_, o.rejection});
        if (o.converged)
        {
          ++accepted;
          failuresInARow = 0;
          recordDissipation(ubar, lambda, state, target);
          lastStep_ = target - lambda;
          ubar = state;
          lambda = target;
          // Grow after a fast convergence: at most 5 tangents (full Newton: 5
          // iterations), and at most 10 iterations of modified Newton.
          if (!control.fixed && o.newTangents <= 5 && o.iterations <= 10)
            step = std::min(control.maximum, 1.5 * step);
          continue;
        }
        lin_ = {}; // it described the failed trial
        lastReason_ = o.rejection;
        if (o.worstElement >= 0)
          lastWorst_ = o.worstElement;
        if (control.fixed)
          break;
        if (++failuresInARow >= newton_.stabilization.afterFailures && newton_.stabilization.enabled &&
            stabilize(ubar, lambda))
          failuresInARow = 0;
        step *= o.worstElement >= 0 ? 0.25 : 0.5; // an inversion says the step was far too large
        if (step < control.minimum)
          break;
      }
      if (lambda >= 1.0 - 1e-12 && stabilizing_)
        settle(accepted, ubar);
    }
    catch (const Cancelled&)
    {
      result_.status = NonlinearStatus::Cancelled;
      result_.message = "cancelled at load fraction " + percent(lambda) + " (the last converged increment)";
    }
    return finish(ubar, lambda, accepted);
  }

private:
  /// What the solver holds of the current trial state, between iterations
  /// and from one converged increment into the next.
  struct Linearization
  {
    Eigen::VectorXd fint;       ///< internal forces at the trial state
    bool forcesCurrent = false; ///< fint belongs to the trial state
    bool tangentInK = false;    ///< k is the tangent at the trial state
    bool factored = false;      ///< the solver holds a factorization of k (of some earlier state)
  };

  /// Where a line search ended.
  struct Step
  {
    bool accepted = false;
    double alpha = 1.0;
    Eigen::VectorXd next, fint, rbar; ///< the state, its forces and its reduced residual
    bool tangentInK = false;          ///< k was formed at next (full Newton)
  };

  /// The residual cannot fall below the rounding of stresses that cancel at
  /// small strain (S from C - I): about eps times the force a unit strain
  /// gives, mu L^2 over the model's size L. Below it, a residual is
  /// converged whatever the load (a nearly stress-free state has no force to
  /// compare with).
  static double roundoffForceOf(const Mesh& mesh, const HyperelasticTable& materials)
  {
    double stiffest = 0.0;
    for (const auto& [region, material] : materials)
      stiffest = std::max(stiffest, material.shearModulus());
    const double size =
      mesh.nodeCount() ? (mesh.nodes.rowwise().maxCoeff() - mesh.nodes.rowwise().minCoeff()).norm() : 1.0;
    return 10.0 * std::numeric_limits<double>::epsilon() * stiffest * size * size;
  }

  /// The full displacements of the reduced ones at load fraction @a lambda.
  Eigen::VectorXd expand(const Eigen::VectorXd& reduced, double lambda) const
  {
    return map_.expand(reduced).col(0) + (lambda - 1.0) * map_.offset;
  }

  /// Forces (and tangent) at u, timed.
  void timedEvaluate(const Eigen::VectorXd& u, double lambda, Eigen::SparseMatrix<double>* tangent,
                     Eigen::VectorXd* forces)
  {
    const auto t0 = std::chrono::steady_clock::now();
    struct Tally
    {
      double& total;
      std::chrono::steady_clock::time_point start;
      ~Tally() { total += secondsSince(start); }
    } tally{result_.assembleSeconds, t0};
    evaluate_(u, lambda, tangent, forces);
    if (tangent && viscosity_.size()) // the viscous force's derivative, c D / dt
      for (Eigen::Index j = 0; j < viscosity_.size(); ++j)
        tangent->valuePtr()[diagonalIndex_[std::size_t(j)]] += viscosity_[j];
    ++result_.assemblies;
  }

  /// Factors K-bar of the current k; false (with a reason) when it is not positive definite.
  bool factor(std::string& reason)
  {
    const auto t0 = std::chrono::steady_clock::now();
    map_.reduceValues(k_, kbar_);
    solver_.factorize(kbar_);
    ++result_.factorizations;
    bool factored = solver_.status() == SolverStatus::Success;
    if (!factored && newton_.shiftIndefiniteTangent)
      factored = factorShifted();
    result_.factorSeconds += secondsSince(t0);
    if (factored)
      return true;
    reason = "the tangent stiffness is not positive definite (the tissue buckles or its material is unstable "
             "at this deformation)";
    return false;
  }

  /// A tangent that is not positive definite away from equilibrium (the
  /// trial state of a large step) gives no descent direction. Levenberg and
  /// Marquardt's remedy (Nocedal & Wright, Numerical Optimization, 2006,
  /// §3.4 "Newton's method with Hessian modification"): factor K̄ + mu D, D
  /// its diagonal, with the smallest mu of 1e-3, 1e-2, ... 1 that is
  /// positive definite, starting at the last one that was. The step is then
  /// a descent direction of the energy and the line search finds its
  /// minimum along it; the equilibrium reached is the same (the residual
  /// decides convergence), only the path to it changes. An increment that
  /// needs more than kShiftsPerIncrement shifted tangents is cut back
  /// instead: near a true instability shifting only delays the cut. Each
  /// shift is counted in the result.
  bool factorShifted()
  {
    constexpr int kShiftsPerIncrement = 6;
    if (shiftsThisIncrement_ >= kShiftsPerIncrement)
      return false;
    ++shiftsThisIncrement_;
    const Eigen::VectorXd diagonal = kbar_.diagonal();
    const double floor = diagonal.cwiseAbs().mean();
    for (double mu = std::max(1e-4, 0.1 * lastShift_); mu <= 1.0 + 1e-12; mu *= 10.0)
    {
      for (Eigen::Index i = 0; i < kbar_.rows(); ++i)
        kbar_.coeffRef(i, i) = diagonal[i] + mu * std::max(std::abs(diagonal[i]), 1e-3 * floor);
      solver_.factorize(kbar_);
      ++result_.factorizations;
      if (solver_.status() == SolverStatus::Success)
      {
        lastShift_ = mu;
        ++result_.shiftedFactorizations;
        result_.largestShift = std::max(result_.largestShift, mu);
        return true;
      }
    }
    return false;
  }

  /// When an increment ending at load fraction @a lambda1 has converged.
  struct Tolerances
  {
    double residual, energy;
  };
  Tolerances tolerancesOf(double lambda1) const
  {
    const bool onTheWay =
      lambda1 < 1.0 - 1e-12 && !stabilizing_ && newton_.pathResidualTolerance > newton_.residualTolerance;
    if (!onTheWay)
      return {newton_.residualTolerance, newton_.energyTolerance};
    const double loosening = newton_.pathResidualTolerance / newton_.residualTolerance;
    return {newton_.pathResidualTolerance, newton_.energyTolerance * loosening * loosening};
  }

  /// 2. One increment from the converged state (@a state, @a lambda0) to
  ///    @a lambda1; @a state becomes the converged state when it converges.
  ///    @a dt: the increment's length in pseudo-time for the artificial
  ///    viscosity while it is on (0: an increment without it).
  IncrementOutcome increment(int number, double lambda0, double lambda1, Eigen::VectorXd& state, double dt)
  {
    IncrementOutcome out;
    const Tolerances tolerance = tolerancesOf(lambda1);
    shiftsThisIncrement_ = 0;
    if (stabilizing_)
      dampFrom(expand(state, lambda0), dt);
    if (map_.reducedCount() == 0)
    { // everything prescribed: nothing to solve
      out.converged = true;
      return out;
    }
    Eigen::VectorXd trial = state, rbar;
    double firstEnergy = 0.0;
    for (int it = 1; it <= newton_.maxIterations; ++it)
    {
      out.iterations = it;
      bool refresh = false;
      if (!tangentWhenDue(it, it == 1 ? lambda0 : lambda1, trial, tolerance.residual, out, refresh))
        return out;
      // b. The out-of-balance force; the first iteration is the predictor:
      //    the prescribed increment (lambda1 - lambda0) g enters as a load
      //    through the (factored) tangent; the initial stress's increment
      //    by its force in the reference state (its balance is in f_ext:
      //    without it the predictor would push by the balance alone).
      if (it == 1)
      {
        const Eigen::VectorXd dg = (lambda1 - lambda0) * map_.offset;
        Eigen::VectorXd r = lin_.fint - lambda1 * fext_ + k_.selfadjointView<Eigen::Upper>() * dg;
        if (initialStressForce_.size() == r.size())
          r += (lambda1 - lambda0) * initialStressForce_;
        rbar = map_.reduceVector(r).col(0);
      }
      const Eigen::VectorXd delta = -solver_.solve(rbar);
      const double s0 = delta.dot(rbar);
      if (it == 1)
      {
        firstEnergy = s0 != 0.0 ? std::abs(s0) : 1.0;
        // What the increment is predicted to do, which scales the viscosity
        // when it starts (expanded only then).
        if (newton_.stabilization.enabled && !stabilizing_)
          predicted_ = {delta, lambda1 - lambda0, std::abs(s0), std::max(dt, lambda1 - lambda0)};
      }

      Step step = lineSearch(it, lambda1, trial, delta, s0, out);
      if (!step.accepted)
        return out;
      const double energy = std::abs(step.alpha * delta.dot(step.rbar)); // the work the correction leaves undone
      trial = std::move(step.next);
      lin_.fint = std::move(step.fint);
      lin_.forcesCurrent = true;
      lin_.tangentInK = step.tangentInK;
      rbar = std::move(step.rbar);

      // d. Convergence on the residual force and on the energy of the correction.
      const double scale = std::max({(lambda1 * fext_).norm(), lin_.fint.norm(), roundoffForce_});
      const double residual = rbar.norm() <= roundoffForce_ ? 0.0 : rbar.norm() / scale;
      const double relEnergy = energy / firstEnergy;
      if (it > 1)
        reuse_.record(out.residual, residual, refresh);
      out.residual = residual;
      const NewtonIteration report{number, lambda1, it, residual, relEnergy, step.alpha, refresh, strictRetry};
      result_.iterations.push_back(report);
      if (monitor_ && !monitor_(report))
        throw Cancelled{};
      if (!std::isfinite(residual) || residual > 1e8)
      {
        out.rejection = "the Newton iteration diverged (relative residual " + std::to_string(residual) + ")";
        return out;
      }
      const bool forceSmall = residual <= tolerance.residual;
      const bool energySmall = relEnergy <= tolerance.energy || residual == 0.0;
      if ((forceSmall && energySmall && it > 1) || (it == 1 && residual == 0.0))
      {
        // (A zero residual after the first iteration: linear in this increment, e.g. a rigid motion.)
        out.converged = true;
        state = trial;
        return out;
      }
    }
    std::ostringstream m;
    m << "Newton did not converge in " << newton_.maxIterations << " iterations (relative residual " << out.residual
      << ", tolerance " << tolerance.residual << ")";
    out.rejection = m.str();
    return out;
  }

  /// a. The tangent: reused, or formed at the trial state and factored
  ///    (@a refresh says which). Modified Newton starts an increment on the
  ///    factorization it has and forms a new tangent at its second
  ///    iteration, when the increment's own contraction is not known yet.
  ///    False, with the reason in @a out, when the increment must stop.
  ///    @a tolerance: the residual the increment converges on.
  bool tangentWhenDue(int it, double lambdaAtTrial, const Eigen::VectorXd& trial, double tolerance,
                      IncrementOutcome& out, bool& refresh)
  {
    refresh = !lin_.factored || fullNewton_ || it == 2;
    if (!refresh && it > 2)
      refresh = reuse_.wantsNewTangent(out.residual, tolerance, newton_.maxIterations - it + 1);
    if ((refresh && !lin_.tangentInK) || !lin_.forcesCurrent)
    {
      try
      {
        timedEvaluate(expand(trial, lambdaAtTrial), lambdaAtTrial, refresh ? &k_ : nullptr, &lin_.fint);
      }
      catch (const InvertedElementError& e)
      { // cannot happen at an accepted state, but be safe
        out.rejection = e.what();
        out.worstElement = e.element();
        return false;
      }
      lin_.forcesCurrent = true;
      lin_.tangentInK = lin_.tangentInK || refresh;
    }
    if (refresh)
    {
      ++out.newTangents;
      lin_.factored = false;
      if (!factor(out.rejection))
        return false;
      lin_.factored = true;
    }
    return true;
  }

  /// c. Line search along @a delta (FEBio's energy criterion); an inverting
  ///    trial halves the step. Full Newton builds the next tangent with the
  ///    first trial. Not accepted, with the reason in @a out, when no step is.
  Step lineSearch(int it, double lambda1, const Eigen::VectorXd& trial, const Eigen::VectorXd& delta, double s0,
                  IncrementOutcome& out)
  {
    Step step;
    double sPrevAlpha = 0.0, sPrev = s0;
    double& alpha = step.alpha;
    for (int ls = 0; ls <= newton_.maxLineSearchSteps + 6; ++ls)
    {
      step.next = trial + alpha * delta;
      const bool withTangent = fullNewton_ && ls == 0;
      const Eigen::VectorXd u = expand(step.next, lambda1);
      try
      {
        timedEvaluate(u, lambda1, withTangent ? &k_ : nullptr, &step.fint);
      }
      catch (const InvertedElementError& e)
      {
        if (it == 1 || ls >= newton_.maxLineSearchSteps + 6)
        {
          // The predictor itself inverts an element: the increment is too large.
          out.rejection = e.what();
          out.worstElement = e.element();
          return step;
        }
        alpha *= 0.5;
        continue;
      }
      if (withTangent)
        lin_.factored = false; // k no longer matches the factorization
      step.rbar = outOfBalance(step.fint, u, lambda1);
      step.tangentInK = withTangent;
      if (!newton_.lineSearch || it == 1 || ls >= newton_.maxLineSearchSteps)
      {
        step.accepted = true;
        return step;
      }
      const double s = delta.dot(step.rbar);
      if (!std::isfinite(s))
      {
        alpha *= 0.5;
        continue;
      }
      if (std::abs(s) <= newton_.lineSearchRatio * std::abs(s0))
      {
        step.accepted = true;
        return step;
      }
      // Secant root of s(alpha) through (alphaPrev, sPrev) and (alpha, s).
      double root = (sPrev * alpha - s * sPrevAlpha) / (sPrev - s);
      if (!std::isfinite(root))
        root = 0.5 * alpha;
      sPrevAlpha = alpha;
      sPrev = s;
      alpha = std::clamp(root, 0.1 * alpha, alpha == 1.0 ? 1.0 : 2.0 * alpha);
      if (alpha == sPrevAlpha)
      {
        step.accepted = true;
        return step;
      }
    }
    out.rejection = "the line search found no admissible step";
    return step;
  }

  /// The reduced out-of-balance force at full displacements @a u with
  /// internal forces @a fint: the viscous force included while it is on.
  Eigen::VectorXd outOfBalance(const Eigen::VectorXd& fint, const Eigen::VectorXd& u, double lambda) const
  {
    if (!viscosity_.size())
      return map_.reduceVector(fint - lambda * fext_).col(0);
    return map_.reduceVector(fint - lambda * fext_ + viscosity_.cwiseProduct(u - dampedStart_)).col(0);
  }

  /// Starts the artificial viscosity at the converged state (@a ubar,
  /// @a lambda), or makes it ten times stronger if it is on already; false
  /// when it cannot (nothing to scale it by, or at its strongest).
  bool stabilize(const Eigen::VectorXd& ubar, double lambda)
  {
    const StabilizationOptions& o = newton_.stabilization;
    if (stabilizing_)
    {
      if (10.0 * dissipationFraction_ > o.largestDissipatedFraction)
        return false;
      dissipationFraction_ *= 10.0;
      viscosityFactor_ *= 10.0;
      return true;
    }
    if (!predicted_.reduced.size())
      return false;
    // D: the diagonal of the reference tangent (the tissue's own stiffness
    // scale at every DOF, positive), into k_'s pattern positions.
    diagonalIndex_.assign(std::size_t(k_.cols()), 0);
    for (Eigen::Index j = 0; j < k_.cols(); ++j)
      for (Eigen::SparseMatrix<double>::InnerIterator e(k_, j); e; ++e)
        if (e.row() == j)
          diagonalIndex_[std::size_t(j)] = std::size_t(&e.value() - k_.valuePtr());
    timedEvaluate(Eigen::VectorXd::Zero(k_.cols()), 0.0, &k_, nullptr);
    lin_ = {};
    dampingShape_.resize(k_.cols());
    for (Eigen::Index j = 0; j < k_.cols(); ++j)
      dampingShape_[j] = std::abs(k_.valuePtr()[diagonalIndex_[std::size_t(j)]]);
    const double floor = 1e-3 * dampingShape_.mean();
    dampingShape_ = dampingShape_.cwiseMax(floor);
    // c: the predicted increment dissipates the stated fraction of the strain energy.
    const Eigen::VectorXd du = map_.expand(predicted_.reduced).col(0) + predicted_.loadStep * map_.offset;
    const double strain =
      std::max(evaluate_(expand(ubar, lambda), lambda, nullptr, nullptr).strainEnergy, 0.5 * predicted_.work);
    const double quadratic = du.dot(dampingShape_.cwiseProduct(du));
    if (!(strain > 0.0) || !(quadratic > 0.0))
      return false;
    dissipationFraction_ = o.dissipatedEnergyFraction;
    viscosityFactor_ = dissipationFraction_ * strain * predicted_.dt / quadratic;
    stabilizing_ = true;
    return true;
  }

  /// The viscosity of an increment of length @a dt from full displacements
  /// @a start (dt = 0: none); the tangent in k_ no longer matches it. The
  /// factorization is kept: modified Newton may start the increment on it,
  /// as on any earlier state's, and the residual (which has the new
  /// viscosity) decides whether that converges.
  void dampFrom(const Eigen::VectorXd& start, double dt)
  {
    lin_.tangentInK = false;
    if (dt <= 0.0)
    {
      viscosity_.resize(0);
      return;
    }
    viscosity_ = (viscosityFactor_ / dt) * dampingShape_;
    dampedStart_ = start;
  }

  /// Counts a damped increment from (@a ubar0, @a lambda0) to (@a ubar1,
  /// @a lambda1) and the energy its viscosity dissipated.
  void recordDissipation(const Eigen::VectorXd& ubar0, double lambda0, const Eigen::VectorXd& ubar1, double lambda1)
  {
    if (!viscosity_.size())
      return;
    const Eigen::VectorXd du = expand(ubar1, lambda1) - expand(ubar0, lambda0);
    result_.dissipatedEnergy += du.dot(viscosity_.cwiseProduct(du));
    ++result_.stabilizedIncrements;
  }

  /// 3'. At full load after a damped path: Newton without the viscosity,
  ///     and while it fails, damped increments at full load, each twice as
  ///     long (the viscous force relaxes), before trying again.
  void settle(int& accepted, Eigen::VectorXd& ubar)
  {
    double dt = lastStep_;
    for (int round = 0;; ++round)
    {
      Eigen::VectorXd state = ubar;
      IncrementOutcome o = increment(accepted + 1, 1.0, 1.0, state, 0.0);
      result_.increments.push_back({accepted + 1, 1.0, 1.0, o.iterations, o.residual, o.converged, false, o.rejection});
      if (o.converged)
      {
        ++accepted;
        ubar = state;
        viscosity_.resize(0);
        return;
      }
      lin_ = {};
      if (round >= newton_.stabilization.relaxations)
      {
        unsettled_ =
          "without the artificial viscosity Newton does not reach equilibrium at full load (" + o.rejection + ")";
        return;
      }
      dt *= 2.0;
      state = ubar;
      o = increment(accepted + 1, 1.0, 1.0, state, dt);
      result_.increments.push_back({accepted + 1, 1.0, 1.0, o.iterations, o.residual, o.converged, true, o.rejection});
      if (!o.converged)
      {
        unsettled_ = "a damped relaxation at full load failed (" + o.rejection + ")";
        viscosity_.resize(0);
        return;
      }
      ++accepted;
      recordDissipation(ubar, 1.0, state, 1.0);
      ubar = state;
    }
  }

  /// 4. The result: the last converged state, its checks, and when the
  ///    loads were not all applied the message saying how far it got, what
  ///    failed, and what to try.
  NonlinearResult finish(const Eigen::VectorXd& ubar, double lambda, int accepted)
  {
    NonlinearResult& result = result_;
    result.loadFraction = lambda;
    result.displacements = expand(ubar, lambda);
    result.check = evaluate_(result.displacements, lambda, nullptr, nullptr);
    if (result.status == NonlinearStatus::Cancelled)
      return std::move(result_);
    if (result.check.strainEnergy > 0.0)
      result.dissipatedFraction = result.dissipatedEnergy / result.check.strainEnergy;
    if (lambda >= 1.0 - 1e-12 && !unsettled_.empty())
    {
      result.status = NonlinearStatus::NotConverged;
      std::ostringstream m;
      m << "the large-deformation solve reached full load only with artificial viscosity through an instability ("
        << result.stabilizedIncrements << " damped increments, " << 100.0 * result.dissipatedFraction
        << " % of the strain energy dissipated), and " << unsettled_
        << ": the state shown is not an equilibrium of the tissue and not a prediction. Try undermining the tissue "
           "around the wound, or a finer mesh there";
      result.message = m.str();
      return std::move(result_);
    }
    if (lambda >= 1.0 - 1e-12)
    {
      result.status = NonlinearStatus::Converged;
      result.loadFraction = 1.0;
      return std::move(result_);
    }
    result.status = NonlinearStatus::NotConverged;
    result.failedElement = lastWorst_;
    std::ostringstream m;
    m << "the large-deformation solve did not converge: increment " << accepted + 1 << ", from load fraction "
      << percent(lambda) << ", failed at the smallest allowed size";
    if (!lastReason_.empty())
      m << " (" << lastReason_ << ")";
    m << "; the last converged state is " << percent(lambda) << " of the loads, prescribed displacements and suture "
      << "closure, which is not a prediction";
    if (lastWorst_ >= 0)
      m << "; the element that failed is " << lastWorst_;
    else if (result.check.minDetFElement >= 0)
      m << "; the most compressed element is " << result.check.minDetFElement << " (det F = " << result.check.minDetF
        << ")";
    m << ". Try smaller increments, undermining the tissue around the wound, or a finer mesh there";
    result.message = m.str();
    return std::move(result_);
  }

  const ConstraintMap map_;
  const Eigen::VectorXd fext_;
  const Eigen::VectorXd initialStressForce_;
  Eigen::SparseMatrix<double> k_;
  Eigen::SparseMatrix<double> kbar_;
  SparseCholeskySolver solver_;
  Evaluate evaluate_;
  const NewtonOptions& newton_;
  const NewtonMonitor& monitor_;
  const bool fullNewton_;
  const double roundoffForce_;
  TangentReusePolicy reuse_;
  Linearization lin_;
  NonlinearResult result_;
  int lastWorst_ = -1;
  std::string lastReason_;
  double lastShift_ = 0.0;      ///< the last shift that made K̄ + mu D positive definite
  int shiftsThisIncrement_ = 0; ///< shifted tangents in the current increment
  double lastStep_ = 0.0;       ///< the size of the last accepted increment

  /// The artificial viscosity (StabilizationOptions), off until needed.
  struct Prediction
  {
    Eigen::VectorXd reduced; ///< the predictor's correction of the free DOFs
    double loadStep = 0.0;   ///< with this increment of the prescribed values
    double work = 0.0;       ///< |dU . R| of the predictor
    double dt = 0.0;         ///< the increment's length
  } predicted_;              ///< of the last increment tried
  bool stabilizing_ = false;
  double viscosityFactor_ = 0.0;           ///< c
  double dissipationFraction_ = 0.0;       ///< the fraction c was set (or grown) for
  Eigen::VectorXd dampingShape_;           ///< D (3N)
  Eigen::VectorXd viscosity_;              ///< c D / dt of the current increment (3N; empty: off)
  Eigen::VectorXd dampedStart_;            ///< u_n, the full displacements the increment starts from
  std::vector<std::size_t> diagonalIndex_; ///< where each DOF's diagonal lies in k_'s values
  std::string unsettled_;                  ///< why the undamped equilibrium at full load failed (empty: it did not)
};

} // namespace

NonlinearResult NonlinearStaticAnalysis::solve(const LoadCase& load, const IncrementControl& control,
                                               const NewtonOptions& newton, const NewtonMonitor& monitor)
{
  // 1. Check the input and set up the constrained system once.
  validate(load);
  cacheReferenceGeometry();
  if (!(control.initial > 0.0 && control.initial <= 1.0 && control.minimum > 0.0 &&
        control.minimum <= control.initial && control.maximum >= control.initial))
    throw std::invalid_argument("the load increments need 0 < minimum <= initial <= maximum and initial <= 1");
  const Eigen::VectorXd initialStressForce =
    initialStress_.empty() ? Eigen::VectorXd() : initialStressForces(mesh_, initialStress_, options_);
  auto run = [&](const NewtonOptions& options, bool strictRetry) {
    NewtonSolve newtonSolve(
      mesh_, materials_, constraints_, [&] { return loadVector(load); },
      [this](const Eigen::VectorXd& u, double lambda, Eigen::SparseMatrix<double>* k, Eigen::VectorXd* fint) {
        return evaluate(u, lambda, k, fint);
      },
      initialStressForce, options, monitor);
    newtonSolve.strictRetry = strictRetry;
    return newtonSolve.run(control);
  };
  NonlinearResult result = run(newton, false);
  if (result.status != NonlinearStatus::NotConverged || !(newton.pathResidualTolerance > newton.residualTolerance))
    return result;
  // 2. Near an instability the path decides which way the tissue goes, and
  //    a loose one can end where the strict one passes: the solve fails only
  //    when the strict path fails too. Its cost is counted.
  NewtonOptions strict = newton;
  strict.pathResidualTolerance = 0.0;
  NonlinearResult again = run(strict, true);
  again.loosePathStoppedAt = result.loadFraction;
  again.factorizations += result.factorizations;
  again.shiftedFactorizations += result.shiftedFactorizations;
  again.assemblies += result.assemblies;
  again.assembleSeconds += result.assembleSeconds;
  again.factorSeconds += result.factorSeconds;
  return again;
}

} // namespace caps::fem
