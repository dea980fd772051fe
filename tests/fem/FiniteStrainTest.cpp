// The finite-strain path: hyperelastic materials, the Total
// Lagrangian element and the Newton solver, each checked against something
// independent: finite differences of the energy and of the forces, closed
// forms from the strain energy, exact rigid motions, the linear solver.

#include "fem/FiniteStrainIntegrator.h"
#include "fem/HyperelasticMaterial.h"
#include "fem/NonlinearStaticAnalysis.h"
#include "fem/StaticAnalysis.h"

#include "FemTestMeshes.h"
#include "FiniteStrainCases.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace caps::fem {
namespace {

using test::boxMesh;
using test::ElementCase;
using test::elementCases;
using test::wobble;

// Soft tissue scale: E = 0.1 MPa, nu = 0.45.
const LinearElasticMaterial kTissue{0.1, 0.45, 1e-9};

std::vector<std::pair<std::string, HyperelasticMaterial>> allMaterials()
{
  return {{"StVenantKirchhoff", HyperelasticMaterial::fromLinear(HyperelasticLaw::StVenantKirchhoff, kTissue)},
          {"NeoHookean", HyperelasticMaterial::fromLinear(HyperelasticLaw::NeoHookean, kTissue)},
          {"MooneyRivlin", HyperelasticMaterial::mooneyRivlin(0.012, 0.006, 1.2, 1e-9)},
          {"VerondaWestmann", HyperelasticMaterial::fromLinear(HyperelasticLaw::VerondaWestmann, kTissue, 4.0)}};
}

/// A deformation gradient with stretches and shears of tens of percent, det > 0.
Eigen::Matrix3d someDeformation(std::mt19937& rng, double amount = 0.3)
{
  std::uniform_real_distribution<double> d(-amount, amount);
  Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      f(i, j) += d(rng);
  return f;
}

// C = I + 2E with E from Voigt (engineering shears).
Eigen::Matrix3d cauchyGreenOf(const Vector6d& e)
{
  Eigen::Matrix3d m;
  m << 1 + 2 * e[0], e[3], e[5], //
    e[3], 1 + 2 * e[1], e[4],    //
    e[5], e[4], 1 + 2 * e[2];
  return m;
}

Vector6d greenLagrangeOf(const Eigen::Matrix3d& c)
{
  Vector6d e;
  e << 0.5 * (c(0, 0) - 1), 0.5 * (c(1, 1) - 1), 0.5 * (c(2, 2) - 1), c(0, 1), c(1, 2), c(2, 0);
  return e;
}

TEST(HyperelasticMaterial, StressIsTheEnergysDerivativeAndTheTangentTheStresss)
{
  std::mt19937 rng(7);
  for (const auto& [name, m] : allMaterials())
  {
    for (int sample = 0; sample < 5; ++sample)
    {
      const Eigen::Matrix3d f = someDeformation(rng);
      ASSERT_GT(f.determinant(), 0.0);
      const Vector6d e = greenLagrangeOf(f.transpose() * f);
      const MaterialResponse r = m.response(cauchyGreenOf(e), f.determinant());
      const double h = 1e-6;
      Matrix6d fdTangent;
      Vector6d fdStress;
      for (int j = 0; j < 6; ++j)
      {
        Vector6d ep = e, em = e;
        ep[j] += h;
        em[j] -= h;
        const Eigen::Matrix3d cp = cauchyGreenOf(ep), cm = cauchyGreenOf(em);
        const MaterialResponse rp = m.response(cp, std::sqrt(cp.determinant()));
        const MaterialResponse rm = m.response(cm, std::sqrt(cm.determinant()));
        fdStress[j] = (rp.energy - rm.energy) / (2 * h);
        fdTangent.col(j) = (rp.stress - rm.stress) / (2 * h);
      }
      EXPECT_LT((fdStress - r.stress).norm(), 1e-6 * r.stress.norm()) << name;
      EXPECT_LT((fdTangent - r.tangent).norm(), 1e-6 * r.tangent.norm()) << name;
      EXPECT_LT((r.tangent - r.tangent.transpose()).norm(), 1e-12 * r.tangent.norm()) << name;
    }
  }
}

TEST(HyperelasticMaterial, AtSmallStrainEveryLawIsTheLinearMaterial)
{
  const Matrix6d c = kTissue.elasticityMatrix();
  for (const auto& [name, m] : allMaterials())
  {
    if (name == "MooneyRivlin")
      continue; // its own constants
    const MaterialResponse r = m.response(Eigen::Matrix3d::Identity(), 1.0);
    EXPECT_LT(r.stress.norm(), 1e-15) << name;
    EXPECT_LT((r.tangent - c).norm(), 1e-12 * c.norm()) << name;
    const LinearElasticMaterial back = m.smallStrainLimit();
    EXPECT_NEAR(back.youngsModulus, kTissue.youngsModulus, 1e-12) << name;
    EXPECT_NEAR(back.poissonRatio, kTissue.poissonRatio, 1e-12) << name;
  }
  const HyperelasticMaterial mr = HyperelasticMaterial::mooneyRivlin(0.012, 0.006, 1.2);
  EXPECT_NEAR(mr.shearModulus(), 2 * (0.012 + 0.006), 1e-15);
  EXPECT_NEAR(mr.bulkModulus(), 2 / 1.2, 1e-15);
}

TEST(HyperelasticMaterial, BadConstantsAreRefusedWithTheirNames)
{
  EXPECT_THROW(HyperelasticMaterial::neoHookean(0.01, 0.0).validate("skin"), std::invalid_argument);
  EXPECT_THROW(HyperelasticMaterial::neoHookean(-0.01, 1.0).validate("skin"), std::invalid_argument);
  EXPECT_THROW(HyperelasticMaterial::verondaWestmann(0.01, -1.0, 1.0).validate("skin"), std::invalid_argument);
  try
  {
    HyperelasticMaterial::neoHookean(0.01, 0.0).validate("material SKIN");
    FAIL();
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("material SKIN"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("D1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(HyperelasticMaterial::neoHookean(0.01, 1.0).response(Eigen::Matrix3d::Identity(), -0.5),
               std::domain_error);
}

TEST(FiniteStrainElement, TangentIsTheDerivativeOfTheInternalForces)
{
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> d(-0.25, 0.25);
  for (const auto& c : elementCases())
  {
    const Element& el = c.mesh.elements[0];
    const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
    const ElementCoordinates x = c.mesh.elementCoordinates(0);
    for (int points : {2, 3})
    {
      const IntegrationRule& rule = integrationRule(el.kind, points);
      for (const auto& [name, m] : allMaterials())
      {
        // Displacements of tens of percent of the element (mm), the same at repeated slots.
        Eigen::Matrix3Xd nodal(3, c.mesh.nodeCount());
        for (Eigen::Index i = 0; i < nodal.cols(); ++i)
          for (int k = 0; k < 3; ++k)
            nodal(k, i) = d(rng);
        ElementDisplacements u = ElementDisplacements::Zero();
        for (int a = 0; a < kHex20NodeCount; ++a)
          if (el.nodes[std::size_t(a)] >= 0)
            u.row(a) = nodal.col(el.nodes[std::size_t(a)]).transpose();
        ElementVector f;
        ElementMatrix k;
        FiniteStrainElementCheck check;
        assembleElementFiniteStrain(shape, x, u, m, rule, 0, f, &k, check);
        ASSERT_GT(check.minDetF, 0.0);
        // Perturb each node's DOF (all slots of a repeated node together).
        ElementMatrix fd = ElementMatrix::Zero();
        const double h = 1e-6;
        for (Eigen::Index node = 0; node < c.mesh.nodeCount(); ++node)
          for (int dir = 0; dir < 3; ++dir)
          {
            ElementDisplacements up = u, um = u;
            bool used = false;
            for (int a = 0; a < kHex20NodeCount; ++a)
              if (el.nodes[std::size_t(a)] == node)
              {
                up(a, dir) += h;
                um(a, dir) -= h;
                used = true;
              }
            if (!used)
              continue;
            ElementVector fp, fm;
            assembleElementFiniteStrain(shape, x, up, m, rule, 0, fp, nullptr, check);
            assembleElementFiniteStrain(shape, x, um, m, rule, 0, fm, nullptr, check);
            const ElementVector column = (fp - fm) / (2 * h);
            // Column of the first slot holding the node; compare summed over repeated slots.
            for (int a = 0; a < kHex20NodeCount; ++a)
              if (el.nodes[std::size_t(a)] == node)
              {
                fd.col(3 * a + dir) = column;
                break;
              }
          }
        // K summed over the slots of each node equals the FD columns.
        ElementMatrix kNode = ElementMatrix::Zero();
        for (int a = 0; a < kHex20NodeCount; ++a)
        {
          if (el.nodes[std::size_t(a)] < 0)
            continue;
          int first = a;
          for (int b = 0; b < a; ++b)
            if (el.nodes[std::size_t(b)] == el.nodes[std::size_t(a)])
            {
              first = b;
              break;
            }
          kNode.middleCols<3>(3 * first) += k.middleCols<3>(3 * a);
        }
        EXPECT_LT((kNode - fd).norm(), 1e-6 * k.norm()) << c.name << ", " << name << ", " << points << " points";
        EXPECT_LT((k - k.transpose()).norm(), 1e-13 * k.norm()) << c.name << ", " << name;
      }
    }
  }
}

TEST(FiniteStrainElement, AnInvertingDisplacementIsReportedNotEvaluated)
{
  const ElementCase c = elementCases()[0];
  const Element& el = c.mesh.elements[0];
  ElementDisplacements u = ElementDisplacements::Zero();
  const ElementCoordinates x = c.mesh.elementCoordinates(0);
  // Mirror the element through its mid-plane x = 2: det F = -1.
  for (int a = 0; a < kHex20NodeCount; ++a)
    u(a, 0) = 2 * (2.0 - x(a, 0));
  ElementVector f;
  FiniteStrainElementCheck check;
  try
  {
    assembleElementFiniteStrain(ElementShape::fromConnectivity(el.kind, el.nodes), x, u,
                                HyperelasticMaterial::neoHookean(0.02, 1.0), gaussRule(3), 5, f, nullptr, check);
    FAIL() << "no error";
  }
  catch (const InvertedElementError& e)
  {
    EXPECT_EQ(e.element(), 5);
    EXPECT_LT(e.detF(), 0.0);
    EXPECT_NE(std::string(e.what()).find("inside out"), std::string::npos) << e.what();
  }
}

/// Homogeneous uniaxial stretch: W(l1, l2, l3) of the law straight from its
/// definition in the invariants, for the closed forms below.
double energyOfStretches(const HyperelasticMaterial& m, double l1, double l2, double l3)
{
  const double j = l1 * l2 * l3;
  const double i1 = l1 * l1 + l2 * l2 + l3 * l3;
  const double i2 = l1 * l1 * l2 * l2 + l2 * l2 * l3 * l3 + l3 * l3 * l1 * l1;
  const double i1b = std::pow(j, -2.0 / 3.0) * i1, i2b = std::pow(j, -4.0 / 3.0) * i2;
  const double vol = (j - 1) * (j - 1) / m.d1;
  switch (m.law)
  {
  case HyperelasticLaw::NeoHookean:
    return m.c10 * (i1b - 3) + vol;
  case HyperelasticLaw::MooneyRivlin:
    return m.c10 * (i1b - 3) + m.c01 * (i2b - 3) + vol;
  case HyperelasticLaw::VerondaWestmann:
    return m.c10 * (std::exp(m.c2 * (i1b - 3)) - 1) - 0.5 * m.c10 * m.c2 * (i2b - 3) + vol;
  default:
    return NAN;
  }
}

TEST(NonlinearStaticAnalysis, UniaxialStretchToTwiceTheLengthMeetsTheClosedForm)
{
  // A 10 x 4 x 4 mm block, x = 0 held in x (one node fully, one in z), x = 10
  // pulled to x = 20: homogeneous, so the 20-node bricks are exact. Closed
  // form: the lateral stretch l makes dW/dl = 0 at (2, l, l), and the
  // nominal stress is P = dW/dlambda.
  const double length = 10, side = 4, stretch = 2.0;
  for (const HyperelasticMaterial& m :
       {HyperelasticMaterial::neoHookean(0.02, 2.0), HyperelasticMaterial::mooneyRivlin(0.012, 0.006, 1.5),
        HyperelasticMaterial::verondaWestmann(0.01, 3.0, 1.0)})
  {
    Mesh mesh = boxMesh(2, 1, 1, length, side, side);
    const Constraints c = test::uniaxialStretch(mesh, length, side, stretch);
    NonlinearStaticAnalysis analysis(mesh, {{0, m}}, c);
    IncrementControl control;
    control.initial = 0.25;
    // Full Newton: it ends far below the residual tolerance, so the 1e-7 mm
    // below is the closed form's, not where a modified Newton happened to
    // stop inside the tolerance.
    NewtonOptions full;
    full.tangentUpdate = TangentUpdate::EveryIteration;
    const NonlinearResult r = analysis.solve(LoadCase{}, control, full);
    ASSERT_EQ(r.status, NonlinearStatus::Converged) << lawName(m.law) << ": " << r.message;

    // The closed form, by bisection on dW/dl (central differences of W).
    auto dWdl = [&](double l) {
      const double h = 1e-6;
      return (energyOfStretches(m, stretch, l + h, l + h) - energyOfStretches(m, stretch, l - h, l - h)) / (2 * h);
    };
    double lo = 0.3, hi = 1.0;
    for (int i = 0; i < 200; ++i)
      (dWdl(0.5 * (lo + hi)) > 0 ? hi : lo) = 0.5 * (lo + hi);
    const double lateral = 0.5 * (lo + hi);
    const double h = 1e-6;
    const double nominal =
      (energyOfStretches(m, stretch + h, lateral, lateral) - energyOfStretches(m, stretch - h, lateral, lateral)) /
      (2 * h);

    // Lateral stretch at every node: y and z scale by l about the held edge.
    double worst = 0;
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    {
      const Eigen::Vector3d x = mesh.nodes.col(i), u = r.displacements.segment<3>(3 * i);
      worst = std::max({worst, std::abs(u[1] - (lateral - 1) * x[1]), std::abs(u[2] - (lateral - 1) * x[2]),
                        std::abs(u[0] - (stretch - 1) * x[0])});
    }
    EXPECT_LT(worst, 1e-7) << lawName(m.law) << ": lateral stretch " << lateral;
    // The pulling force: the reactions on the x = 10 face.
    const Eigen::VectorXd f = analysis.internalForces(r.displacements);
    double force = 0;
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      if (mesh.nodes(0, i) > length - 1e-9)
        force += f[3 * i];
    EXPECT_NEAR(force / (side * side), nominal, 1e-6 * std::abs(nominal)) << lawName(m.law);
    EXPECT_NEAR(r.check.maxStretch, stretch, 1e-7);
    EXPECT_NEAR(r.check.minDetF, stretch * lateral * lateral, 1e-7);
  }
}

// Modified Newton keeps or renews the tangent by estimated costs, not
// measured times: the same model takes the same path on every run, to the
// bit (a replayed plan reproduces its numbers).
TEST(NonlinearStaticAnalysis, ModifiedNewtonTakesTheSamePathOnEveryRun)
{
  Mesh mesh = boxMesh(2, 1, 1, 10.0, 4.0, 4.0);
  const Constraints c = test::uniaxialStretch(mesh, 10.0, 4.0, 2.0);
  IncrementControl control;
  control.initial = 0.25;
  std::vector<NonlinearResult> runs;
  for (int run = 0; run < 3; ++run)
  {
    NonlinearStaticAnalysis analysis(mesh, {{0, HyperelasticMaterial::neoHookean(0.02, 2.0)}}, c);
    runs.push_back(analysis.solve(LoadCase{}, control, NewtonOptions{}));
    ASSERT_EQ(runs.back().status, NonlinearStatus::Converged) << runs.back().message;
  }
  const auto kept = std::count_if(runs[0].iterations.begin(), runs[0].iterations.end(),
                                  [](const NewtonIteration& it) { return !it.newTangent; });
  EXPECT_GT(kept, 0) << "no factorization was kept: the path had no choice to make";
  for (std::size_t run = 1; run < runs.size(); ++run)
  {
    EXPECT_EQ(runs[run].iterations.size(), runs[0].iterations.size());
    EXPECT_EQ(runs[run].factorizations, runs[0].factorizations);
    EXPECT_EQ(runs[run].displacements, runs[0].displacements) << "run " << run;
  }
}

TEST(NonlinearStaticAnalysis, ABlockTurnedRigidlyBy60DegreesIsStressFree)
{
  // The boundary nodes of a distorted block are prescribed onto its rigid
  // rotation; the interior nodes, free, must follow exactly, with no stress.
  Mesh mesh = boxMesh(2, 2, 2, 6, 5, 4);
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = wobble(mesh.nodes.col(i), 0.2);
  const Eigen::Matrix3d rotation =
    Eigen::AngleAxisd(M_PI / 3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d centre(3, 2.5, 2);
  Constraints c;
  std::vector<int> interior;
  const std::vector<char> outer = test::outerNodes(mesh);
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    const Eigen::Vector3d x = mesh.nodes.col(i);
    const Eigen::Vector3d u = rotation * (x - centre) + centre - x;
    if (outer[std::size_t(i)])
      for (int d = 0; d < 3; ++d)
        c.prescribe(int(i), d, u[d]);
    else
      interior.push_back(int(i));
  }
  ASSERT_FALSE(interior.empty());
  const HyperelasticMaterial m = HyperelasticMaterial::fromLinear(HyperelasticLaw::NeoHookean, kTissue);
  NonlinearStaticAnalysis analysis(mesh, {{0, m}}, c);
  IncrementControl control;
  control.initial = 0.25;
  const NonlinearResult r = analysis.solve(LoadCase{}, control);
  ASSERT_EQ(r.status, NonlinearStatus::Converged) << r.message;
  double positionError = 0;
  for (int i : interior)
  {
    const Eigen::Vector3d x = mesh.nodes.col(i);
    const Eigen::Vector3d expected = rotation * (x - centre) + centre;
    positionError = std::max(positionError, (x + r.displacements.segment<3>(3 * i) - expected).norm());
  }
  EXPECT_LT(positionError, 1e-10 * 6) << "interior nodes off their rigid positions";
  // Stress at every integration point, relative to the shear modulus.
  double worstStress = 0;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Element& el = mesh.elements[e];
    ElementDisplacements ue = ElementDisplacements::Zero();
    for (int a = 0; a < kHex20NodeCount; ++a)
      ue.row(a) = r.displacements.segment<3>(3 * el.nodes[std::size_t(a)]).transpose();
    for (const auto& p : gaussRule(3).points)
    {
      const FiniteStrainPoint q = evaluateFiniteStrainPoint(ElementShape::fromConnectivity(el.kind, el.nodes),
                                                            mesh.elementCoordinates(e), ue, m, p, int(e));
      worstStress = std::max(worstStress, q.cauchy.cwiseAbs().maxCoeff());
      EXPECT_NEAR(q.detF, 1.0, 1e-10);
    }
  }
  EXPECT_LT(worstStress, 1e-10 * m.shearModulus());
}

TEST(NonlinearStaticAnalysis, UnderASmallLoadItIsTheLinearSolution)
{
  // A cantilever 40 x 10 x 10 mm with a tip load small enough that the
  // nonlinear terms are below 1e-6 of the response.
  Mesh mesh = boxMesh(4, 1, 1, 40, 10, 10);
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = wobble(mesh.nodes.col(i));
  Constraints c;
  LoadCase load;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    if (mesh.nodes(0, i) < 0.5)
      c.fixNode(int(i));
    if (mesh.nodes(0, i) > 39.0)
      load.nodalForces.push_back({int(i), Eigen::Vector3d(1e-9, -2e-9, 5e-9)});
  }
  load.gravity = Eigen::Vector3d(0, 0, -1e-3);
  for (const auto& [name, m] : allMaterials())
  {
    LinearStaticAnalysis linear(mesh, {{0, m.smallStrainLimit()}}, c);
    ASSERT_EQ(linear.prepare(), SolverStatus::Success);
    const Eigen::VectorXd ul = linear.solve(load);
    NonlinearStaticAnalysis nonlinear(mesh, {{0, m}}, c);
    const NonlinearResult r = nonlinear.solve(load);
    ASSERT_EQ(r.status, NonlinearStatus::Converged) << name << ": " << r.message;
    EXPECT_LT((r.displacements - ul).cwiseAbs().maxCoeff(), 1e-6 * ul.cwiseAbs().maxCoeff()) << name;
  }
}

/// A 10 mm cube on a fixed base whose top is pushed down by @a fraction of its height.
/// @a sidesHeld: every node held laterally (uniaxial strain), so the cube
/// cannot bulge or fold out of the way.
NonlinearStaticAnalysis compressedCube(double fraction, bool sidesHeld = false)
{
  Mesh mesh = boxMesh(2, 2, 2, 10, 10, 10);
  Constraints c;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    if (sidesHeld && mesh.nodes(2, i) > 1e-9 && mesh.nodes(2, i) < 10 - 1e-9)
    {
      c.fix(int(i), 0);
      c.fix(int(i), 1);
    }
    if (mesh.nodes(2, i) < 1e-9)
      c.fixNode(int(i));
    if (mesh.nodes(2, i) > 10 - 1e-9)
    {
      c.prescribe(int(i), 2, -fraction * 10);
      c.fix(int(i), 0);
      c.fix(int(i), 1);
    }
  }
  return NonlinearStaticAnalysis(mesh, {{0, HyperelasticMaterial::neoHookean(0.02, 2.0)}}, c);
}

TEST(NonlinearStaticAnalysis, AnIncrementThatFailsIsCutBackAndRetried)
{
  // 40 % in one increment: the linear predictor lands where the tangent is
  // no longer positive definite; without the shift of such tangents
  // (NewtonOptions::shiftIndefiniteTangent) smaller increments get there.
  NonlinearStaticAnalysis analysis = compressedCube(0.4);
  NewtonOptions plain;
  plain.shiftIndefiniteTangent = false;
  const NonlinearResult r = analysis.solve(LoadCase{}, {}, plain); // one increment asked for
  ASSERT_EQ(r.status, NonlinearStatus::Converged) << r.message;
  ASSERT_GE(r.increments.size(), 2u);
  EXPECT_FALSE(r.increments.front().accepted);
  EXPECT_FALSE(r.increments.front().rejection.empty());
  for (const IncrementRecord& i : r.increments)
    if (i.accepted)
    {
      EXPECT_TRUE(i.rejection.empty());
    }
  EXPECT_GT(r.check.minDetF, 0.0);
  // The top really is 40 % down.
  const Mesh& mesh = analysis.mesh();
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    if (mesh.nodes(2, i) > 10 - 1e-9)
    {
      EXPECT_NEAR(r.displacements[3 * i + 2], -4.0, 1e-12);
    }

  // Shifted towards its diagonal, the same tangent still gives a descent
  // direction: one increment gets there, to the same equilibrium.
  const NonlinearResult shifted = analysis.solve(LoadCase{});
  ASSERT_EQ(shifted.status, NonlinearStatus::Converged) << shifted.message;
  EXPECT_GT(shifted.shiftedFactorizations, 0);
  EXPECT_LT(shifted.increments.size(), r.increments.size());
  EXPECT_LT((shifted.displacements - r.displacements).norm(), 1e-7 * r.displacements.norm());
}

TEST(NonlinearStaticAnalysis, AnImpossibleLoadEndsWithAMessageNotAResult)
{
  // The top pushed 120 % of the way through the base, the cube held at its
  // sides: no body can do that. (With free sides it can: the cube folds
  // over into a C whose ends face each other, every det F positive, which
  // the damped path through the fold finds; StabilizationOptions.)
  NonlinearStaticAnalysis analysis = compressedCube(1.2, true);
  IncrementControl control; // the whole push at first
  control.minimum = 1e-3;
  const NonlinearResult r = analysis.solve(LoadCase{}, control);
  ASSERT_EQ(r.status, NonlinearStatus::NotConverged);
  EXPECT_LT(r.loadFraction, 1.0 / 1.2); // it cannot pass the base
  EXPECT_GT(r.loadFraction, 0.0);
  EXPECT_NE(r.message.find("did not converge"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("increment"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("element"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("not a prediction"), std::string::npos) << r.message;
  EXPECT_GT(r.check.minDetF, 0.0); // the state kept is a converged one
  // The first try, the whole push at once, turned an element inside out.
  ASSERT_FALSE(r.increments.empty());
  EXPECT_NE(r.increments.front().rejection.find("inside out"), std::string::npos) << r.increments.front().rejection;
}

TEST(NonlinearStaticAnalysis, TheMonitorSeesEveryIterationAndCanCancel)
{
  NonlinearStaticAnalysis analysis = compressedCube(0.3);
  IncrementControl control;
  control.initial = 0.1;
  int seen = 0;
  const NonlinearResult r = analysis.solve(LoadCase{}, control, {}, [&seen](const NewtonIteration& it) {
    EXPECT_GE(it.iteration, 1);
    return ++seen < 7;
  });
  EXPECT_EQ(r.status, NonlinearStatus::Cancelled);
  EXPECT_EQ(seen, 7);
  EXPECT_EQ(int(r.iterations.size()), 7);
  EXPECT_LT(r.loadFraction, 1.0);
  EXPECT_NE(r.message.find("cancelled"), std::string::npos);
}

TEST(NonlinearStaticAnalysis, FacePressuresAreRefusedWithAMessage)
{
  NonlinearStaticAnalysis analysis = compressedCube(0.1);
  LoadCase load;
  load.facePressures.push_back({0, 1, 0.01});
  try
  {
    analysis.solve(load);
    FAIL();
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("follower"), std::string::npos) << e.what();
  }
}

} // namespace
} // namespace caps::fem
