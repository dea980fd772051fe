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
  double residual = 0.0;
  std::string rejection;
  int worstElement = -1;  ///< an inverted element, when that was the reason
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
    if (options_.volumetric == VolumetricFormulation::MixedPressure)
      assembleElementMixedFiniteStrain(shape, mesh_.elementCoordinates(e), ue, materials_.at(el.region), rule, int(e),
                                       re ? *re : local, ke, checks[e]);
    else
      assembleElementFiniteStrain(shape, mesh_.elementCoordinates(e), ue, materials_.at(el.region), rule, int(e),
                                  re ? *re : local, ke, checks[e]);
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
  };
  // Factor K-bar of the current k; false (with a reason) when it is not positive definite.
  auto factor = [&](std::string& reason) {
    const auto t0 = std::chrono::steady_clock::now();
    map.reduceValues(k, kbar);
    solver.factorize(kbar);
    result.factorSeconds += secondsSince(t0);
    ++result.factorizations;
    if (solver.status() == SolverStatus::Success) return true;
    reason = "the tangent stiffness is not positive definite (the tissue buckles or its material is unstable "
             "at this deformation)";
    return false;
  };

  // 2. One increment from the converged (ubar, lambda0) to lambda1.
  auto runIncrement = [&](int increment, double lambda0, double lambda1, Eigen::VectorXd& state) {
    IncrementOutcome out;
    if (map.reducedCount() == 0) {  // everything prescribed: nothing to solve
      out.converged = true;
      return out;
    }
    Eigen::VectorXd fint;
    // The predictor: the tangent of the converged state, the prescribed
    // increment (lambda1 - lambda0) g as a load.
    timedEvaluate(expand(state, lambda0), &k, &fint);
    const Eigen::VectorXd dg = (lambda1 - lambda0) * map.offset;
    Eigen::VectorXd rbar = map.reduceVector(fint - lambda1 * fext + k.selfadjointView<Eigen::Upper>() * dg).col(0);
    Eigen::VectorXd trial = state;
    double firstEnergy = 0.0;
    bool tangentCurrent = true;  // k holds the tangent at the state rbar belongs to
    for (int it = 1; it <= newton.maxIterations; ++it) {
      out.iterations = it;
      if (!tangentCurrent) {
        try {
          timedEvaluate(expand(trial, lambda1), &k, &fint);
        } catch (const InvertedElementError& e) {  // cannot happen after an accepted line search, but be safe
          out.rejection = e.what();
          out.worstElement = e.element();
          return out;
        }
      }
      if (!factor(out.rejection)) return out;
      const Eigen::VectorXd delta = -solver.solve(rbar);
      const double s0 = delta.dot(rbar);
      const double energy = std::abs(s0);
      if (it == 1) firstEnergy = energy > 0.0 ? energy : 1.0;

      // Line search along delta; an inverting trial halves the step.
      double alpha = 1.0, sPrevAlpha = 0.0, sPrev = s0;
      Eigen::VectorXd next, nextFint, nextR;
      bool accepted = false;
      for (int ls = 0; ls <= newton.maxLineSearchSteps + 6; ++ls) {
        next = trial + alpha * delta;
        try {
          // The first trial also builds the tangent for the next iteration.
          timedEvaluate(expand(next, lambda1), ls == 0 ? &k : nullptr, &nextFint);
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
        nextR = map.reduceVector(nextFint - lambda1 * fext).col(0);
        tangentCurrent = ls == 0;
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
      trial = next;
      fint = nextFint;
      rbar = nextR;

      // Convergence on the residual force and on the energy of the correction.
      const double scale = std::max({(lambda1 * fext).norm(), fint.norm(), roundoffForce});
      const double residual = rbar.norm() <= roundoffForce ? 0.0 : rbar.norm() / scale;
      const double relEnergy = energy / firstEnergy;
      out.residual = residual;
      const NewtonIteration report{increment, lambda1, it, residual, relEnergy, alpha};
      result.iterations.push_back(report);
      if (monitor && !monitor(report)) throw Cancelled{};
      if (!std::isfinite(residual) || residual > 1e8) {
        out.rejection = "the Newton iteration diverged (relative residual " + std::to_string(residual) + ")";
        return out;
      }
      const bool forceSmall = residual <= newton.residualTolerance;
      const bool energySmall = relEnergy <= newton.energyTolerance || residual == 0.0;
      if (forceSmall && energySmall && it > 1) {
        out.converged = true;
        state = trial;
        return out;
      }
      if (it == 1 && residual == 0.0) {  // linear in this increment (e.g. a rigid motion)
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
        if (!control.fixed && o.iterations <= 5) step = std::min(control.maximum, 1.5 * step);
        continue;
      }
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
