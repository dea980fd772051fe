// Skin pre-tension as an initial stress (fem/InitialStress.h): the intact
// pre-stressed body is in equilibrium, a cut releases the traction S0 N and
// the wound gapes by the amount the theory of a crack in a plate under
// tension gives; a cut along the larger tension gapes less than one across
// it; the linear preview (released traction as a load) and the
// large-deformation solve (S0 in the stress) agree at small stress; the
// tangent with S0 is the derivative of the forces.

#include "fem/FacePressure.h"
#include "fem/InitialStress.h"
#include "fem/NonlinearStaticAnalysis.h"
#include "fem/StaticAnalysis.h"

#include "FemTestMeshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace caps::fem {
namespace {

using test::boxMesh;

/// A uniform stress, Voigt.
Vector6d uniformStress(double sxx, double syy, double sxy = 0.0)
{
  Vector6d s = Vector6d::Zero();
  s[0] = sxx;
  s[1] = syy;
  s[3] = sxy;
  return s;
}

/// The quarter of a thin square plate with a central through crack of half
/// length @a a on y = 0 (Griffith's problem), by symmetry: the plate
/// [0, L]^2 x [0, t], the crack face y = 0, x < a; u_x = 0 on x = 0,
/// u_y = 0 on y = 0 beyond the crack, u_z = 0 on the mid-plane (the
/// plate's own symmetry: no bending).
struct CrackedQuarterPlate
{
  Mesh mesh;
  Constraints constraints;
  std::vector<ElementFace> crackFaces;
  int mouthNode = -1; ///< the crack face's node at x = 0 on the mid-plane (z = t/2)
};

CrackedQuarterPlate crackedQuarterPlate(int n, double length, double thickness, double a)
{
  CrackedQuarterPlate p;
  p.mesh = boxMesh(n, n, 1, length, length, thickness);
  const double tol = 1e-9 * length;
  for (Eigen::Index i = 0; i < p.mesh.nodes.cols(); ++i)
  {
    const Eigen::Vector3d x = p.mesh.nodes.col(i);
    if (std::abs(x.x()) < tol)
      p.constraints.fix(int(i), 0);
    if (std::abs(x.y()) < tol && x.x() > a - tol)
      p.constraints.fix(int(i), 1);
    if (std::abs(x.z() - 0.5 * thickness) < tol)
    {
      p.constraints.fix(int(i), 2);
      if (std::abs(x.x()) < tol && std::abs(x.y()) < tol)
        p.mouthNode = int(i);
    }
  }
  // The crack faces: element faces whose every node lies on y = 0, x <= a.
  for (std::size_t e = 0; e < p.mesh.elements.size(); ++e)
  {
    const Element& el = p.mesh.elements[e];
    for (int f = 1; f <= faceCount(el.kind); ++f)
    {
      bool onCrack = true;
      for (int slot : faceNodes(el.kind, f))
      {
        const Eigen::Vector3d x = p.mesh.nodes.col(el.nodes[std::size_t(slot)]);
        onCrack = onCrack && std::abs(x.y()) < tol && x.x() < a + tol;
      }
      if (onCrack)
        p.crackFaces.push_back({int(e), f});
    }
  }
  return p;
}

InitialStress uniformInitialStress(const Mesh& mesh, const Vector6d& s)
{
  InitialStress s0;
  s0.elementStress.assign(mesh.elements.size(), s);
  return s0;
}

/// The linear preview: the released traction -cutFaceTraction() as a load.
Eigen::VectorXd linearGape(const CrackedQuarterPlate& p, const LinearElasticMaterial& m, const InitialStress& s0)
{
  LinearStaticAnalysis analysis(p.mesh, {{0, m}}, p.constraints);
  EXPECT_EQ(analysis.prepare(), SolverStatus::Success) << analysis.message();
  return analysis.solve(nodalLoadCase(-cutFaceTraction(p.mesh, s0, p.crackFaces)));
}

/// The large-deformation solve: S0 in the stress, its balance as a dead load.
NonlinearResult largeDeformationGape(const CrackedQuarterPlate& p, const HyperelasticMaterial& m,
                                     const InitialStress& s0)
{
  NonlinearStaticAnalysis analysis(p.mesh, {{0, m}}, p.constraints);
  analysis.setInitialStress(s0);
  return analysis.solve(nodalLoadCase(initialStressBalance(p.mesh, s0, p.crackFaces)), {0.5, 1e-4, 1.0, false, 100});
}

TEST(InitialStress, IntactPreStressedBodyIsInEquilibriumAtRest)
{
  // A curved, distorted body with a non-uniform stress: with its balance
  // and no cut, nothing moves (the residual at u = 0 is zero).
  test::MeshBuilder b(Eigen::Vector3d(1.0, 1.5, 0.5));
  b.distort([](const Eigen::Vector3d& x) { return test::wobble(x, 0.3); });
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 4; ++i)
      b.addHex(i, j, 0);
  const Mesh mesh = b.build();
  InitialStress s0;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> d(-0.02, 0.05);
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
    s0.elementStress.push_back(uniformStress(d(rng), d(rng), 0.3 * d(rng)));
  NonlinearStaticAnalysis analysis(mesh, {{0, HyperelasticMaterial::neoHookean(0.05, 2.0)}}, {});
  analysis.setInitialStress(s0);
  const Eigen::VectorXd balance = initialStressBalance(mesh, s0, {});
  const Eigen::VectorXd residual = analysis.internalForces(Eigen::VectorXd::Zero(mesh.dofCount())) - balance;
  EXPECT_LT(residual.norm(), 1e-12 * balance.norm());
  EXPECT_GT(balance.norm(), 1e-3); // the stress does load the boundary
}

TEST(InitialStress, UniformStressLoadsOnlyTheBoundaryAsItsTraction)
{
  // div S0 = 0: f0 is the traction S0 N on the outer faces; on a box the
  // face y = L carries sigma_yy times its area in total.
  const Mesh mesh = boxMesh(3, 4, 2, 6.0, 8.0, 2.0);
  const InitialStress s0 = uniformInitialStress(mesh, uniformStress(0.01, 0.03));
  const Eigen::VectorXd f0 = initialStressForces(mesh, s0);
  double fyTop = 0.0, fyInterior = 0.0;
  for (Eigen::Index i = 0; i < mesh.nodes.cols(); ++i)
  {
    const double y = mesh.nodes(1, i), x = mesh.nodes(0, i), z = mesh.nodes(2, i);
    const bool boundary = y < 1e-9 || y > 8.0 - 1e-9 || x < 1e-9 || x > 6.0 - 1e-9 || z < 1e-9 || z > 2.0 - 1e-9;
    if (y > 8.0 - 1e-9)
      fyTop += f0[3 * i + 1];
    if (!boundary)
      fyInterior = std::max(fyInterior, f0.segment<3>(3 * i).norm());
  }
  EXPECT_NEAR(fyTop, 0.03 * 6.0 * 2.0, 1e-12);
  EXPECT_LT(fyInterior, 1e-14);
}

TEST(InitialStress, CrackInPreStressedPlateGapesAsGriffithsCrack)
{
  // A through crack of length 2a in a thin plate under remote tension
  // sigma normal to it opens by 4 sigma a / E at its centre (plane stress;
  // Tada, Paris & Irwin, The Stress Analysis of Cracks Handbook, 3rd ed.
  // 2000, §5.1): the released pre-stress is the same problem by
  // superposition. The plate is 20 crack half-lengths wide (finite-width
  // correction below 1 %) and thin (t = a / 10: plane stress).
  const double a = 3.0, sigma = 0.03;
  const LinearElasticMaterial skin{1.0, 0.3, 0.0};
  const CrackedQuarterPlate p = crackedQuarterPlate(50, 30.0, 0.3, a);
  ASSERT_GE(p.mouthNode, 0);
  ASSERT_EQ(p.crackFaces.size(), 5u); // 0.6 mm elements along 3 mm, the tip on a node
  const Eigen::VectorXd u = linearGape(p, skin, uniformInitialStress(p.mesh, uniformStress(0.0, sigma)));
  const double gape = 2.0 * u[3 * p.mouthNode + 1]; // both faces of the full crack
  const double griffith = 4.0 * sigma * a / skin.youngsModulus;
  EXPECT_GT(gape, 0.0) << "the crack must open, not close";
  EXPECT_NEAR(gape / griffith, 1.0, 0.03) << "gape " << gape << " mm, Griffith " << griffith << " mm";
}

TEST(InitialStress, LargeDeformationGapeMatchesLinearAtSmallStress)
{
  // Two methods: S0 in the large-deformation stress with its balance, and
  // the released traction on the linear model; at sigma = 1e-4 E the
  // geometric terms are of that order.
  const double a = 3.0, sigma = 1e-4;
  const LinearElasticMaterial linear{1.0, 0.3, 0.0};
  const CrackedQuarterPlate p = crackedQuarterPlate(16, 15.0, 0.3, a);
  const InitialStress s0 = uniformInitialStress(p.mesh, uniformStress(0.5 * sigma, sigma));
  const Eigen::VectorXd ul = linearGape(p, linear, s0);
  const NonlinearResult r =
    largeDeformationGape(p, HyperelasticMaterial::fromLinear(HyperelasticLaw::NeoHookean, linear), s0);
  ASSERT_EQ(r.status, NonlinearStatus::Converged) << r.message;
  EXPECT_NEAR(r.displacements[3 * p.mouthNode + 1] / ul[3 * p.mouthNode + 1], 1.0, 2e-3);
  EXPECT_LT((r.displacements - ul).norm(), 2e-3 * ul.norm());
}

TEST(InitialStress, CutAlongTheGreaterTensionGapesLess)
{
  // Skin tension is greater along the tension lines than across them
  // (about 2.3 : 1 on the face): a cut along the lines opens under the
  // smaller tension across it and gapes less (the surgeon's rule of
  // placing incisions along the lines). Large deformation, skin-like
  // stress of a few per cent of E.
  const double a = 3.0, along = 0.03, across = 0.013;
  const HyperelasticMaterial skin = HyperelasticMaterial::fromLinear(HyperelasticLaw::NeoHookean, {0.6, 0.45, 0.0});
  const CrackedQuarterPlate p = crackedQuarterPlate(16, 15.0, 0.3, a); // the crack runs along x
  const NonlinearResult alongLines =
    largeDeformationGape(p, skin, uniformInitialStress(p.mesh, uniformStress(along, across)));
  const NonlinearResult acrossLines =
    largeDeformationGape(p, skin, uniformInitialStress(p.mesh, uniformStress(across, along)));
  ASSERT_EQ(alongLines.status, NonlinearStatus::Converged) << alongLines.message;
  ASSERT_EQ(acrossLines.status, NonlinearStatus::Converged) << acrossLines.message;
  const double gapeAlong = alongLines.displacements[3 * p.mouthNode + 1];
  const double gapeAcross = acrossLines.displacements[3 * p.mouthNode + 1];
  EXPECT_GT(gapeAlong, 0.0);
  EXPECT_LT(gapeAlong, gapeAcross);
  // In the linear limit the gape is proportional to the tension across the
  // cut alone; large deformation moves the ratio by a few per cent.
  EXPECT_NEAR(gapeAlong / gapeAcross, across / along, 0.05 * across / along);
  EXPECT_GT(alongLines.check.minDetF, 0.5);
}

TEST(InitialStress, TangentWithInitialStressIsTheDerivativeOfTheForces)
{
  // Central differences of f_int(u) against K_t(u), S0 included (its
  // geometric stiffness), at a deformed state.
  const Mesh mesh = boxMesh(2, 1, 1, 2.0, 1.0, 1.0);
  InitialStress s0;
  s0.elementStress = {uniformStress(0.02, -0.01, 0.005), uniformStress(0.04, 0.01, 0.0)};
  s0.elementStress[1][2] = 0.01;
  s0.elementStress[1][4] = -0.003;
  NonlinearStaticAnalysis analysis(mesh, {{0, HyperelasticMaterial::neoHookean(0.03, 1.0)}}, {});
  analysis.setInitialStress(s0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> d(-0.05, 0.05);
  Eigen::VectorXd u(mesh.dofCount());
  for (Eigen::Index i = 0; i < u.size(); ++i)
    u[i] = d(rng);
  const Eigen::MatrixXd k = Eigen::MatrixXd(analysis.tangentStiffness(u)).selfadjointView<Eigen::Upper>();
  const double h = 1e-6;
  double worst = 0.0;
  for (Eigen::Index j = 0; j < u.size(); ++j)
  {
    Eigen::VectorXd up = u, um = u;
    up[j] += h;
    um[j] -= h;
    const Eigen::VectorXd column = (analysis.internalForces(up) - analysis.internalForces(um)) / (2 * h);
    worst = std::max(worst, (column - k.col(j)).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-6 * k.cwiseAbs().maxCoeff());
}

TEST(InitialStress, BadFieldsAreRefused)
{
  const Mesh mesh = boxMesh(2, 1, 1, 2.0, 1.0, 1.0);
  NonlinearStaticAnalysis analysis(mesh, {{0, HyperelasticMaterial::neoHookean(0.03, 1.0)}}, {});
  InitialStress tooFew;
  tooFew.elementStress = {Vector6d::Zero()};
  EXPECT_THROW(analysis.setInitialStress(tooFew), std::invalid_argument);
  InitialStress notFinite = uniformInitialStress(mesh, uniformStress(std::nan(""), 0.0));
  EXPECT_THROW(analysis.setInitialStress(notFinite), std::invalid_argument);
  EXPECT_THROW(cutFaceTraction(mesh, uniformInitialStress(mesh, uniformStress(0.01, 0.0)), {{5, 1}}),
               std::invalid_argument);
}

} // namespace
} // namespace caps::fem
