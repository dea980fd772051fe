#include "fem/NonlinearStaticAnalysis.h"

#include "fem/FiniteStrainIntegrator.h"
#include "fem/MixedFiniteStrainIntegrator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace caps::fem {

namespace {

struct Cancelled {};

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// How one increment ended.
struct IncrementOutcome {
  bool converged = false;
  int iterations = 0;
  int newTangents = 0;  ///< iterations that formed and factored a tangent
  double residual = 0.0;
  std::string rejection;
  int worstElement = -1;  ///< an inverted element, when that was the reason
};

/// A running mean of measured seconds.
struct MeanTime {
  double total = 0.0;
  int count = 0;
  void add(double s) {
    total += s;
    ++count;
  }
  double mean() const { return count ? total / count : 0.0; }
};

/**
 * Modified Newton's choice (TangentUpdate::WhenSlow) before each iteration:
 * keep the factorization, or form and factor the tangent at the current
 * state, whichever is predicted to reach the residual tolerance sooner in
 * time. Near the solution Newton contracts the residual r by about L r
 * (quadratic convergence), L measured at the last new tangent; a kept
 * factorization contracts it by about as much as the last iteration did
 * (linear convergence). The costs of a force evaluation, a tangent
 * evaluation, a factorization and a solve are measured as the solve goes.
 */
class TangentReusePolicy {
public:
  MeanTime forces, tangent, factorization, backSolve;

  /// An iteration took the residual from @a before to @a after, with a new
  /// tangent or with a kept one.
  void record(double before, double after, bool newTangent) {
    if (!(before > 0.0) || !std::isfinite(after)) {
      contraction_ = newtonRate_ = kNone;
      return;
    }
    contraction_ = after / before;
    if (newTangent) newtonRate_ = contraction_ / before;
  }

  /// Whether the iteration that starts at relative residual @a residual,
  /// with @a iterationsLeft iterations allowed, should form a new tangent.
  bool wantsNewTangent(double residual, double tolerance, int iterationsLeft) const {
    // Without a measured contraction, or kept factorizations that barely contract: a new tangent.
    if (!(contraction_ < kSlowestKept) || !(newtonRate_ > 0.0)) return true;
    if (!(residual > tolerance)) return false;
    const double digits = std::log(residual / tolerance);
    const int keptIterations = int(std::ceil(digits / -std::log(contraction_)));
    if (keptIterations > iterationsLeft) return true;
    int newtonIterations = 0;
    for (double r = residual; r > tolerance && newtonIterations < iterationsLeft; ++newtonIterations)
      r *= std::min(1.0, newtonRate_ * r);
    const double kept = forces.mean() + backSolve.mean();
    const double renewed = kept + tangent.mean() + factorization.mean();
    return newtonIterations * renewed < keptIterations * kept;
  }

private:
  static constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  static constexpr double kSlowestKept = 0.25;  ///< a kept factorization must at least quarter the residual
  double contraction_ = kNone;
  double newtonRate_ = kNone;
};

std::string percent(double fraction) {
  std::ostringstream s;
  s.precision(4);
  s << 100.0 * fraction << " %";
  return s.str();
}

}  // namespace

NonlinearStaticAnalysis::NonlinearStaticAnalysis(Mesh mesh, HyperelasticTable materials, Constraints constraints,
                                                 AssemblyOptions options)
    : mesh_(std::move(mesh)),
      materials_(std::move(materials)),
      constraints_(std::move(constraints)),
      options_(options) {
  for (const auto& [region, material] : materials_) linear_[region] = material.smallStrainLimit();
}

void NonlinearStaticAnalysis::validate(const LoadCase& load) const {
  for (const auto& [region, material] : materials_) material.validate("material of region " + std::to_string(region));
  if (options_.volumetric == VolumetricFormulation::MixedPressure)  // the mixed element needs the split law
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

Eigen::VectorXd NonlinearStaticAnalysis::loadVector(const LoadCase& load) const {
  // Dead loads only (validate() refuses face pressures, which follow the surface).
  LoadCase dead = load;
  dead.facePressures.clear();
  return assembleLoadVector(mesh_, linear_, dead, options_);
}

DeformationCheck NonlinearStaticAnalysis::evaluate(const Eigen::VectorXd& u, Eigen::SparseMatrix<double>* k,
                                                   Eigen::VectorXd* fint) const {
  if (u.size() != mesh_.dofCount())
    throw std::invalid_argument("the displacement vector has " + std::to_string(u.size()) + " entries for a model of " +
                                std::to_string(mesh_.dofCount()) + " DOFs");
  std::vector<FiniteStrainElementCheck> checks(mesh_.elements.size());
  const ElementKernel kernel = [&](std::size_t e, ElementMatrix* ke, ElementVector* re) {
    const Element& el = mesh_.elements[e];
    ElementDisplacements ue = ElementDisplacements::Zero();
    for (int a = 0; a < kHex20NodeCount; ++a)
      if (el.nodes[std::size_t(a)] >= 0) ue.row(a) = u.segment<3>(3 * el.nodes[std::size_t(a)]).transpose();
    ElementVector local;
    // Formulation switch (AssemblyOptions::volumetric): the mixed u/p/J element or the displacement one.
    const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
    const IntegrationRule& rule = integrationRule(el.kind, integrationPointsOf(el, options_.gaussPointsPerDirection));
    const ElementCoordinates x = mesh_.elementCoordinates(e);
    const ReferencePoints reference = reference_.empty() ? referencePoints(shape, x, rule, int(e)) : ReferencePoints{};
    const ReferencePoints& ref = reference_.empty() ? reference : reference_[e];
    if (options_.volumetric == VolumetricFormulation::MixedPressure)
      assembleElementMixedFiniteStrain(shape, x, ref, ue, materials_.at(el.region), rule, int(e), re ? *re : local, ke,
                                       checks[e]);
    else
      assembleElementFiniteStrain(shape, x, ref, ue, materials_.at(el.region), rule, int(e), re ? *re : local, ke,
                                  checks[e]);
  };
  Eigen::VectorXd scratch;
  assembleElements(mesh_, options_.threads, kernel, k, fint ? fint : &scratch);
  DeformationCheck c;
  if (checks.empty()) return c;
  c.minDetF = c.minStretch = std::numeric_limits<double>::infinity();
  c.maxStretch = 0.0;
  for (std::size_t e = 0; e < checks.size(); ++e) {
    if (checks[e].minDetF < c.minDetF) {
      c.minDetF = checks[e].minDetF;
      c.minDetFElement = int(e);
    }
    c.maxStretch = std::max(c.maxStretch, checks[e].maxStretch);
    c.minStretch = std::min(c.minStretch, checks[e].minStretch);
    c.strainEnergy += checks[e].energy;
  }
  return c;
}

void NonlinearStaticAnalysis::cacheReferenceGeometry() {
  // About 13 kB per 27-point brick: 80 MB for a 100k-DOF model.
  constexpr std::size_t kReferenceCacheBytes = std::size_t(2) << 30;
  reference_.clear();
  std::size_t bytes = 0;
  for (const Element& el : mesh_.elements)
    bytes += referencePointsBytes(integrationRule(el.kind, integrationPointsOf(el, options_.gaussPointsPerDirection)).size());
  if (bytes > kReferenceCacheBytes) return;
  reference_.reserve(mesh_.elements.size());
  for (std::size_t e = 0; e < mesh_.elements.size(); ++e) {
    const Element& el = mesh_.elements[e];
    reference_.push_back(referencePoints(ElementShape::fromConnectivity(el.kind, el.nodes), mesh_.elementCoordinates(e),
                                         integrationRule(el.kind, integrationPointsOf(el, options_.gaussPointsPerDirection)),
                                         int(e)));
  }
}

Eigen::VectorXd NonlinearStaticAnalysis::internalForces(const Eigen::VectorXd& u) const {
  Eigen::VectorXd f;
  evaluate(u, nullptr, &f);
  return f;
}

Eigen::SparseMatrix<double> NonlinearStaticAnalysis::tangentStiffness(const Eigen::VectorXd& u) const {
  Eigen::SparseMatrix<double> k = stiffnessPattern(mesh_);
  evaluate(u, &k, nullptr);
  return k;
}

DeformationCheck NonlinearStaticAnalysis::deformationCheck(const Eigen::VectorXd& u) const {
  return evaluate(u, nullptr, nullptr);
}

NonlinearResult NonlinearStaticAnalysis::solve(const LoadCase& load, const IncrementControl& control,
                                               const NewtonOptions& newton, const NewtonMonitor& monitor) {
  // 1. Check the input and set up the constrained system once: the pattern
  //    of K-bar does not change between iterations, so it is analysed once.
  validate(load);
  cacheReferenceGeometry();
  if (!(control.initial > 0.0 && control.initial <= 1.0 && control.minimum > 0.0 &&
        control.minimum <= control.initial && control.maximum >= control.initial))
    throw std::invalid_argument("the load increments need 0 < minimum <= initial <= maximum and initial <= 1");
  const ConstraintMap map = resolveConstraints(mesh_, constraints_);
  const Eigen::VectorXd fext = loadVector(load);
  Eigen::SparseMatrix<double> k = stiffnessPattern(mesh_);
  Eigen::SparseMatrix<double> kbar = map.reduceMatrix(k);
  SparseCholeskySolver solver;
  useNodeGroupedOrdering(mesh_, map, solver);
  if (map.reducedCount() > 0) solver.analyzePattern(kbar);

  // The residual cannot fall below the rounding of stresses that cancel at
  // small strain (S from C - I): about eps times the force a unit strain
  // gives, mu L^2 over the model's size L. Below it, a residual is converged
  // whatever the load (a nearly stress-free state has no force to compare with).
  double stiffest = 0.0;
  for (const auto& [region, material] : materials_) stiffest = std::max(stiffest, material.shearModulus());
  const double size = mesh_.nodeCount() ? (mesh_.nodes.rowwise().maxCoeff() - mesh_.nodes.rowwise().minCoeff()).norm() : 1.0;
  const double roundoffForce = 10.0 * std::numeric_limits<double>::epsilon() * stiffest * size * size;

  NonlinearResult result;
  Eigen::VectorXd ubar = Eigen::VectorXd::Zero(map.reducedCount());
  auto expand = [&map](const Eigen::VectorXd& reduced, double lambda) -> Eigen::VectorXd {
    return map.expand(reduced).col(0) + (lambda - 1.0) * map.offset;
  };

  TangentReusePolicy reuse;  // measures the costs it weighs
  // Forces (and tangent) at u, timed.
  auto timedEvaluate = [&](const Eigen::VectorXd& u, Eigen::SparseMatrix<double>* tangent, Eigen::VectorXd* forces) {
    const auto t0 = std::chrono::steady_clock::now();
    struct Tally {
      double& total;
      std::chrono::steady_clock::time_point start;
      ~Tally() { total += secondsSince(start); }
    } tally{result.assembleSeconds, t0};
    evaluate(u, tangent, forces);
    ++result.assemblies;
    (tangent ? reuse.tangent : reuse.forces).add(secondsSince(t0));
  };
  // Factor K-bar of the current k; false (with a reason) when it is not positive definite.
  auto factor = [&](std::string& reason) {
    const auto t0 = std::chrono::steady_clock::now();
    map.reduceValues(k, kbar);
    solver.factorize(kbar);
    result.factorSeconds += secondsSince(t0);
    reuse.factorization.add(secondsSince(t0));
    ++result.factorizations;
    if (solver.status() == SolverStatus::Success) return true;
    reason = "the tangent stiffness is not positive definite (the tissue buckles or its material is unstable "
             "at this deformation)";
    return false;
  };

  // What the solver holds of the current trial state, between iterations
  // and from one converged increment into the next.
  struct Linearization {
    Eigen::VectorXd fint;        ///< internal forces at the trial state
    bool forcesCurrent = false;  ///< fint belongs to the trial state
    bool tangentInK = false;     ///< k is the tangent at the trial state
    bool factored = false;       ///< the solver holds a factorization of k (of some earlier state)
  } lin;
  const bool fullNewton = newton.tangentUpdate == TangentUpdate::EveryIteration;

  // 2. One increment from the converged (ubar, lambda0) to lambda1.
  auto runIncrement = [&](int increment, double lambda0, double lambda1, Eigen::VectorXd& state) {
    IncrementOutcome out;
    if (map.reducedCount() == 0) {  // everything prescribed: nothing to solve
      out.converged = true;
      return out;
    }
    Eigen::VectorXd trial = state, rbar;
    double firstEnergy = 0.0;
    for (int it = 1; it <= newton.maxIterations; ++it) {
      out.iterations = it;
      const double lambdaAtTrial = it == 1 ? lambda0 : lambda1;
      // a. The tangent: reused, or formed at the trial state and factored.
      //    Modified Newton starts an increment on the factorization it has
      //    and forms a new tangent at its second iteration, when the
      //    increment's own contraction is not known yet.
      bool refresh = !lin.factored || fullNewton || it == 2;
      if (!refresh && it > 2)
        refresh = reuse.wantsNewTangent(out.residual, newton.residualTolerance, newton.maxIterations - it + 1);
      if ((refresh && !lin.tangentInK) || !lin.forcesCurrent) {
        try {
          timedEvaluate(expand(trial, lambdaAtTrial), refresh ? &k : nullptr, &lin.fint);
        } catch (const InvertedElementError& e) {  // cannot happen at an accepted state, but be safe
          out.rejection = e.what();
          out.worstElement = e.element();
          return out;
        }
        lin.forcesCurrent = true;
        lin.tangentInK = lin.tangentInK || refresh;
      }
      if (refresh) {
        ++out.newTangents;
        lin.factored = false;
        if (!factor(out.rejection)) return out;
        lin.factored = true;
      }
      // b. The out-of-balance force; the first iteration is the predictor:
      //    the prescribed increment (lambda1 - lambda0) g enters as a load
      //    through the (factored) tangent.
      if (it == 1) {
        const Eigen::VectorXd dg = (lambda1 - lambda0) * map.offset;
        rbar = map.reduceVector(lin.fint - lambda1 * fext + k.selfadjointView<Eigen::Upper>() * dg).col(0);
      }
      const auto solveStart = std::chrono::steady_clock::now();
      const Eigen::VectorXd delta = -solver.solve(rbar);
      reuse.backSolve.add(secondsSince(solveStart));
      const double s0 = delta.dot(rbar);
      if (it == 1) firstEnergy = s0 != 0.0 ? std::abs(s0) : 1.0;

      // c. Line search along delta; an inverting trial halves the step.
      //    Full Newton builds the next tangent with the first trial.
      double alpha = 1.0, sPrevAlpha = 0.0, sPrev = s0;
      Eigen::VectorXd next, nextFint, nextR;
      bool accepted = false, nextTangent = false;
      for (int ls = 0; ls <= newton.maxLineSearchSteps + 6; ++ls) {
        next = trial + alpha * delta;
        const bool withTangent = fullNewton && ls == 0;
        try {
          timedEvaluate(expand(next, lambda1), withTangent ? &k : nullptr, &nextFint);
        } catch (const InvertedElementError& e) {
          if (it == 1 || ls >= newton.maxLineSearchSteps + 6) {
            // The predictor itself inverts an element: the increment is too large.
            out.rejection = e.what();
            out.worstElement = e.element();
            return out;
          }
          alpha *= 0.5;
          continue;
        }
        if (withTangent) lin.factored = false;  // k no longer matches the factorization
        nextR = map.reduceVector(nextFint - lambda1 * fext).col(0);
        nextTangent = withTangent;
        if (!newton.lineSearch || it == 1 || ls >= newton.maxLineSearchSteps) {
          accepted = true;
          break;
        }
        const double s = delta.dot(nextR);
        if (!std::isfinite(s)) {
          alpha *= 0.5;
          continue;
        }
        if (std::abs(s) <= newton.lineSearchRatio * std::abs(s0)) {
          accepted = true;
          break;
        }
        // Secant root of s(alpha) through (alphaPrev, sPrev) and (alpha, s).
        double root = (sPrev * alpha - s * sPrevAlpha) / (sPrev - s);
        if (!std::isfinite(root)) root = 0.5 * alpha;
        sPrevAlpha = alpha;
        sPrev = s;
        alpha = std::clamp(root, 0.1 * alpha, alpha == 1.0 ? 1.0 : 2.0 * alpha);
        if (alpha == sPrevAlpha) {
          accepted = true;
          break;
        }
      }
      if (!accepted) {
        out.rejection = "the line search found no admissible step";
        return out;
      }
      const double energy = std::abs(alpha * delta.dot(nextR));  // the work the correction leaves undone
      trial = next;
      lin.fint = nextFint;
      lin.forcesCurrent = true;
      lin.tangentInK = nextTangent;
      rbar = nextR;

      // d. Convergence on the residual force and on the energy of the correction.
      const double scale = std::max({(lambda1 * fext).norm(), lin.fint.norm(), roundoffForce});
      const double residual = rbar.norm() <= roundoffForce ? 0.0 : rbar.norm() / scale;
      const double relEnergy = energy / firstEnergy;
      if (it > 1) reuse.record(out.residual, residual, refresh);
      out.residual = residual;
      const NewtonIteration report{increment, lambda1, it, residual, relEnergy, alpha, refresh};
      result.iterations.push_back(report);
      if (monitor && !monitor(report)) throw Cancelled{};
      if (!std::isfinite(residual) || residual > 1e8) {
        out.rejection = "the Newton iteration diverged (relative residual " + std::to_string(residual) + ")";
        return out;
      }
      const bool forceSmall = residual <= newton.residualTolerance;
      const bool energySmall = relEnergy <= newton.energyTolerance || residual == 0.0;
      if ((forceSmall && energySmall && it > 1) || (it == 1 && residual == 0.0)) {
        // (A zero residual after the first iteration: linear in this increment, e.g. a rigid motion.)
        out.converged = true;
        state = trial;
        return out;
      }
    }
    std::ostringstream m;
    m << "Newton did not converge in " << newton.maxIterations << " iterations (relative residual " << out.residual
      << ", tolerance " << newton.residualTolerance << ")";
    out.rejection = m.str();
    return out;
  };

  // 3. The increments: grow after a fast convergence, cut back on failure.
  double lambda = 0.0;
  double step = std::min(control.initial, 1.0);
  int accepted = 0;
  int lastWorst = -1;
  std::string lastReason;
  try {
    while (lambda < 1.0 - 1e-12) {
      if (int(result.increments.size()) >= control.maxIncrements) {
        lastReason = "the solve used its " + std::to_string(control.maxIncrements) + " increments";
        break;
      }
      step = std::min(step, 1.0 - lambda);
      const double target = (1.0 - lambda - step) < 1e-12 ? 1.0 : lambda + step;
      Eigen::VectorXd state = ubar;
      const IncrementOutcome o = runIncrement(accepted + 1, lambda, target, state);
      IncrementRecord record{accepted + 1, lambda, target, o.iterations, o.residual, o.converged, o.rejection};
      result.increments.push_back(record);
      if (o.converged) {
        ++accepted;
        ubar = state;
        lambda = target;
        // Grow after a fast convergence: at most 5 tangents (full Newton: 5
        // iterations), and at most 10 iterations of modified Newton.
        if (!control.fixed && o.newTangents <= 5 && o.iterations <= 10) step = std::min(control.maximum, 1.5 * step);
        continue;
      }
      lin = {};  // it described the failed trial
      lastReason = o.rejection;
      if (o.worstElement >= 0) lastWorst = o.worstElement;
      if (control.fixed) break;
      step *= o.worstElement >= 0 ? 0.25 : 0.5;  // an inversion says the step was far too large
      if (step < control.minimum) break;
    }
  } catch (const Cancelled&) {
    result.status = NonlinearStatus::Cancelled;
    result.message = "cancelled at load fraction " + percent(lambda) + " (the last converged increment)";
  }

  result.loadFraction = lambda;
  result.displacements = expand(ubar, lambda);
  result.check = evaluate(result.displacements, nullptr, nullptr);
  if (result.status == NonlinearStatus::Cancelled) return result;
  if (lambda >= 1.0 - 1e-12) {
    result.status = NonlinearStatus::Converged;
    result.loadFraction = 1.0;
    return result;
  }
  result.status = NonlinearStatus::NotConverged;
  result.failedElement = lastWorst;
  std::ostringstream m;
  m << "the large-deformation solve did not converge: increment " << accepted + 1 << ", from load fraction "
    << percent(lambda) << ", failed at the smallest allowed size";
  if (!lastReason.empty()) m << " (" << lastReason << ")";
  m << "; the last converged state is " << percent(lambda) << " of the loads, prescribed displacements and suture "
    << "closure, which is not a prediction";
  if (lastWorst >= 0) m << "; the element that failed is " << lastWorst;
  else if (result.check.minDetFElement >= 0)
    m << "; the most compressed element is " << result.check.minDetFElement << " (det F = " << result.check.minDetF
      << ")";
  m << ". Try smaller increments, undermining the tissue around the wound, or a finer mesh there";
  result.message = m.str();
  return result;
}

}  // namespace caps::fem
