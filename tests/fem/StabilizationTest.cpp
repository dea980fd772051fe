// Artificial viscosity through an instability (StabilizationOptions): a
// shallow clamped arch pushed past its limit load snaps through. Under load
// control there is no nearby equilibrium past the limit point, so Newton
// fails at every increment size; damped, the solve crosses to the far branch
// and then releases the damping. Checked against a second method that has no
// instability: the same arch under displacement control, which follows the
// whole path (Crisfield, Non-linear Finite Element Analysis of Solids and
// Structures, vol. 1, 1991, §9.1: limit points under load control).

#include "fem/NonlinearStaticAnalysis.h"

#include "FemTestMeshes.h"

#include <algorithm>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace caps::fem {
namespace {

// Rise 4 mm on 2 mm of thickness: h / r = 6.9 (r the radius of gyration),
// deep enough that Newton cannot jump the limit point on its own.
constexpr double kSpan = 100.0, kThickness = 2.0, kWidth = 4.0, kRise = 4.0;
// About 1.2 times the limit load: the displacement-controlled path's
// largest force is about 0.018 N, near 1.5 mm of apex deflection, and the
// undamped solve stops at 83 % of this load.
constexpr double kLoad = 0.0225;
constexpr double kPi = 3.14159265358979323846;

/// The arch: 20 x 1 x 1 bricks lifted by a half sine of height kRise,
/// pinned at both ends, in plane strain (u_y = 0 everywhere).
struct Arch
{
  Mesh mesh;
  Constraints clamped;
  int apex = -1; ///< the top node at mid-span and mid-width, where the push is
};

Arch shallowArch()
{
  Arch a;
  a.mesh = test::boxMesh(20, 1, 1, kSpan, kWidth, kThickness);
  for (Eigen::Index i = 0; i < a.mesh.nodeCount(); ++i)
  {
    auto x = a.mesh.nodes.col(i);
    x.z() += kRise * std::sin(kPi * x.x() / kSpan);
    // Pinned: the ends' mid-thickness lines held, free to turn about them.
    const bool end = std::abs(x.x()) < 1e-9 || std::abs(x.x() - kSpan) < 1e-9;
    if (end && std::abs(x.z() - kThickness / 2) < 1e-9)
      a.clamped.fixNode(int(i));
    else
      a.clamped.fix(int(i), 1);
    if (std::abs(x.x() - kSpan / 2) < 1e-9 && std::abs(x.y() - kWidth / 2) < 1e-9 && x.z() > kRise + kThickness - 1e-9)
      a.apex = int(i);
  }
  return a;
}

HyperelasticTable rubber()
{
  return {{0, HyperelasticMaterial::fromLinear(HyperelasticLaw::NeoHookean, {10.0, 0.3, 1e-9})}};
}

/// The arch with its apex pushed down by @a w (displacement control): the
/// converged result and the force the push needs.
struct Pushed
{
  NonlinearResult result;
  double force = 0.0;
};

Pushed pushApex(const Arch& arch, double w)
{
  Constraints c = arch.clamped;
  c.prescribe(arch.apex, 2, -w);
  NonlinearStaticAnalysis analysis(arch.mesh, rubber(), c);
  IncrementControl control;
  control.initial = control.maximum = 0.05;
  Pushed p{analysis.solve(LoadCase{}, control), 0.0};
  if (p.result.status == NonlinearStatus::Converged)
    p.force = -analysis.internalForces(p.result.displacements)[3 * arch.apex + 2];
  return p;
}

TEST(Stabilization, AnArchPushedPastItsLimitLoadSnapsThroughToTheEquilibriumDisplacementControlFinds)
{
  const Arch arch = shallowArch();
  ASSERT_GE(arch.apex, 0);

  // 1. A dead load past the limit load, under load control.
  const double load = kLoad;
  LoadCase push;
  push.nodalForces = {{arch.apex, Eigen::Vector3d(0, 0, -load)}};
  IncrementControl control;
  control.initial = 0.1;
  control.minimum = 1e-4;
  NonlinearStaticAnalysis analysis(arch.mesh, rubber(), arch.clamped);

  // Past the limit point no increment converges...
  NewtonOptions undamped;
  undamped.stabilization.enabled = false;
  const NonlinearResult stuck = analysis.solve(push, control, undamped);
  EXPECT_EQ(stuck.status, NonlinearStatus::NotConverged) << "the snap-through did not stop plain Newton";
  // It stops near the limit point (found on a 0.25 mm grid of deflections).
  std::printf("[arch] undamped, the solve stops at %.1f %% of the load\n", 100 * stuck.loadFraction);
  EXPECT_EQ(stuck.stabilizedIncrements, 0);
  EXPECT_EQ(stuck.loosePathStoppedAt, -1.0) << "a strict path is not tried twice";
  // On a loose path (NewtonOptions::pathResidualTolerance) the failed solve
  // is tried again on the strict one, which stops where the plain one does;
  // the monitor is told the second try started over. Full Newton on both,
  // so the two solves differ in the path's tolerance only.
  NewtonOptions undampedFull = undamped;
  undampedFull.tangentUpdate = TangentUpdate::EveryIteration;
  const NonlinearResult stuckFull = analysis.solve(push, control, undampedFull);
  NewtonOptions undampedLoose = undampedFull;
  undampedLoose.pathResidualTolerance = 1e-3;
  int firstTry = 0, secondTry = 0;
  const NonlinearResult stuckTwice = analysis.solve(push, control, undampedLoose, [&](const NewtonIteration& it) {
    ++(it.strictRetry ? secondTry : firstTry);
    return true;
  });
  EXPECT_EQ(stuckTwice.status, NonlinearStatus::NotConverged);
  EXPECT_GE(stuckTwice.loosePathStoppedAt, 0.0);
  EXPECT_EQ(stuckTwice.loadFraction, stuckFull.loadFraction);
  EXPECT_GT(firstTry, 0);
  EXPECT_EQ(std::size_t(secondTry), stuckFull.iterations.size()) << "the second try is the strict path's";
  EXPECT_GT(stuckTwice.factorizations, stuckFull.factorizations) << "the first try's work is counted";
  EXPECT_TRUE(std::all_of(stuckTwice.iterations.begin(), stuckTwice.iterations.end(),
                          [](const NewtonIteration& it) { return it.strictRetry; }));

  // ... and with the viscosity the arch snaps through.
  const NonlinearResult snapped = analysis.solve(push, control);
  ASSERT_EQ(snapped.status, NonlinearStatus::Converged) << snapped.message;
  const double deflection = -snapped.displacements[3 * arch.apex + 2];
  std::printf("[arch] under %.4g N: apex down %.3f mm, %d damped increments, dissipated %.3g of the strain energy, "
              "%zu increments tried\n",
              load, deflection, snapped.stabilizedIncrements, snapped.dissipatedFraction, snapped.increments.size());
  EXPECT_GT(snapped.stabilizedIncrements, 0);
  EXPECT_GT(deflection, 2.0 * kRise); // snapped through: the apex below the chord, as far as it was above
  EXPECT_GT(snapped.check.minDetF, 0.0);
  // The viscosity takes up the energy the snap releases (as a dynamic snap
  // would lose it): a path, not a result, which the checks below confirm.
  EXPECT_GT(snapped.dissipatedEnergy, 0.0);

  // 2. The state is an equilibrium of the arch alone (no viscous force
  //    left): the out-of-balance force at the free DOFs, recomputed here.
  const Eigen::VectorXd f = analysis.internalForces(snapped.displacements) - analysis.loadVector(push);
  std::vector<char> held(std::size_t(arch.mesh.dofCount()), 0);
  for (const PrescribedDof& d : arch.clamped.prescribed)
    held[std::size_t(3 * d.node + d.direction)] = 1;
  double outOfBalance = 0.0;
  for (Eigen::Index i = 0; i < f.size(); ++i)
    if (!held[std::size_t(i)])
      outOfBalance = std::max(outOfBalance, std::abs(f[i]));
  EXPECT_LT(outOfBalance, 1e-6 * load);

  // 3. The second method: the apex pushed to the same deflection needs the
  //    same force, and the whole arch is in the same shape.
  const Pushed same = pushApex(arch, deflection);
  ASSERT_EQ(same.result.status, NonlinearStatus::Converged) << same.result.message;
  std::printf("[arch] displacement control to %.3f mm: force %.6g N (load %.6g N), field difference %.3g\n", deflection,
              same.force, load,
              (same.result.displacements - snapped.displacements).norm() / snapped.displacements.norm());
  EXPECT_NEAR(same.force, load, 1e-6 * load);
  EXPECT_LT((same.result.displacements - snapped.displacements).norm(), 1e-6 * snapped.displacements.norm());

  // 4. With the states before the snap converged to 1e-3 of the forces only
  //    (NewtonOptions::pathResidualTolerance), the arch snaps to the same state.
  NewtonOptions loosePath;
  loosePath.pathResidualTolerance = 1e-3;
  const NonlinearResult loose = analysis.solve(push, control, loosePath);
  ASSERT_EQ(loose.status, NonlinearStatus::Converged) << loose.message;
  std::printf("[arch] loose path: %zu iterations (strict %zu), field difference %.3g, loose path stopped at %.3g\n",
              loose.iterations.size(), snapped.iterations.size(),
              (loose.displacements - snapped.displacements).norm() / snapped.displacements.norm(),
              loose.loosePathStoppedAt);
  EXPECT_GT(loose.stabilizedIncrements, 0);
  EXPECT_LT((loose.displacements - snapped.displacements).norm(), 1e-6 * snapped.displacements.norm());
}

TEST(Stabilization, ASolveThatConvergesWithoutItIsUntouched)
{
  // Below the limit load nothing fails: no damping, the same answer bit for bit.
  const Arch arch = shallowArch();
  LoadCase push;
  push.nodalForces = {{arch.apex, Eigen::Vector3d(0, 0, -0.5 * pushApex(arch, 1.0).force)}};
  NonlinearStaticAnalysis analysis(arch.mesh, rubber(), arch.clamped);
  // Full Newton on both, so the two solves differ in the damping only.
  NewtonOptions undamped, damped;
  undamped.tangentUpdate = damped.tangentUpdate = TangentUpdate::EveryIteration;
  undamped.stabilization.enabled = false;
  const NonlinearResult a = analysis.solve(push, {}, undamped);
  const NonlinearResult b = analysis.solve(push, {}, damped);
  ASSERT_EQ(a.status, NonlinearStatus::Converged) << a.message;
  ASSERT_EQ(b.status, NonlinearStatus::Converged) << b.message;
  EXPECT_EQ(b.stabilizedIncrements, 0);
  EXPECT_EQ(b.dissipatedEnergy, 0.0);
  EXPECT_EQ((a.displacements - b.displacements).norm(), 0.0);
}

} // namespace
} // namespace caps::fem
