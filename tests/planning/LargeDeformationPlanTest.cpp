// Plans closed in large deformation (thesis §1.4, §6.1.2) on the cylinder
// phantom (skin r = 80 mm, bone r = 70 mm), each prediction checked against
// a second method: the linear model where the closure is small, CalculiX's
// NLGEOM solve of the same model where it is not.

#include <cmath>
#include <cstdio>
#include <filesystem>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "AnalyticSkins.h"
#include "fem/CalculixIO.h"
#include "fem/FiniteStrainStress.h"
#include "fem/NonlinearStaticAnalysis.h"
#include "fem/StaticAnalysis.h"
#include "CcxRunner.h"
#include "planning/PlanSimulation.h"
#include "planning/WoundStress.h"

namespace caps::planning {
namespace {

using Phantom = test::CylinderPhantom;
const Phantom& phantom()
{
  return test::cylinderPhantom();
}

SimulationOptions largeDeformation()
{
  SimulationOptions o = test::phantomSimulationOptions();
  o.model = TissueModel::LargeDeformation;
  return o;
}

IncisionPlan ellipse(double length, double ratio)
{
  return test::shippedProcedure("elliptical-excision")
    .place(phantom().skin, {0.0, 0.0}, {{"length", length}, {"ratio", ratio}, {"axis_angle", 0.0}});
}

double largestDifference(const PlanPrediction& a, const PlanPrediction& b)
{
  return (a.displacements - b.displacements).cwiseAbs().maxCoeff();
}

// The large-deformation model departs from the linear one by the size of
// the strains, so as a closure narrows the two must agree in proportion:
// halving the wound's width halves the relative difference (the first-order
// term of the geometric nonlinearity), and both close their sutures exactly.
TEST(LargeDeformationPlan, NarrowClosuresApproachTheLinearAnswerInProportion)
{
  auto difference = [](double narrowing) {
    IncisionPlan plan = ellipse(24.0, 3.0);
    const std::vector<ChartPoint> offsets = plan.borderOffsets();
    for (int v = 0; v < int(offsets.size()); ++v)
      if (offsets[std::size_t(v)].norm() > 0.0)
        plan.offsetBorderPoint(v, offsets[std::size_t(v)] / narrowing);
    const PlanPrediction linear = simulatePlan(phantom().skin, phantom().bone, plan, test::phantomSimulationOptions());
    const PlanPrediction large = simulatePlan(phantom().skin, phantom().bone, plan, largeDeformation());
    EXPECT_TRUE(large.check.converged) << large.check.problem;
    EXPECT_TRUE(large.check.admissible()) << large.check.problem;
    EXPECT_EQ(large.check.model, TissueModel::LargeDeformation);
    EXPECT_EQ(linear.check.model, TissueModel::LinearElastic);
    EXPECT_LT(large.maxSutureGap, 1e-9);
    const double relative = largestDifference(linear, large) / linear.displacements.cwiseAbs().maxCoeff();
    std::printf("[closure %.2f mm wide] relative difference large - linear %.4f, %d increments, det F min %.4f\n",
                large.maxSutureGapBefore, relative, large.check.increments, large.check.deformation.minDetF);
    return relative;
  };
  const double wide = difference(40.0), narrow = difference(80.0);
  EXPECT_GT(narrow, 0.0) << "the two models cannot agree to the last bit: the large one did not run";
  EXPECT_NEAR(narrow / wide, 0.5, 0.1);
}

// The 24 mm 3:1 excision closes in large deformation to a body: every
// integration point's det F positive and recorded, the sutures met, the
// skin stress the Cauchy stress of the deformed skin; and the same model
// exported to CalculiX (NLGEOM, the same neo-Hookean law, the same
// constraints) gives the same displacements.
TEST(LargeDeformationPlan, AnExcisionClosesToABodyAndAgreesWithCalculix)
{
  const IncisionPlan plan = ellipse(24.0, 3.0);
  SimulationOptions o = largeDeformation();
  o.elementSize = 3.0; // a smaller model: the comparison, not the detail, matters here
  const PlanPrediction p = simulatePlan(phantom().skin, phantom().bone, plan, o);
  const PredictionCheck& c = p.check;
  std::printf("[ellipse 24 mm, large deformation] %ld DOF, %d increments, %d iterations, det F %.3f (element %d), "
              "stretch max %.3f, gap %.2f -> %.2g mm\n",
              long(p.dofCount), c.increments, c.iterations, c.deformation.minDetF, c.deformation.minDetFElement,
              c.deformation.maxStretch, p.maxSutureGapBefore, p.maxSutureGap);
  ASSERT_TRUE(c.converged) << c.problem;
  EXPECT_DOUBLE_EQ(c.closureFraction, 1.0);
  EXPECT_TRUE(c.admissible()) << c.problem;
  EXPECT_TRUE(c.problem.empty()) << c.problem;
  EXPECT_GT(c.deformation.minDetF, 0.0);
  EXPECT_EQ(c.deformation.invertedElements, 0);
  EXPECT_GT(c.deformation.maxStretch, 1.0);
  EXPECT_LT(p.maxSutureGap, 1e-9);
  EXPECT_FALSE(p.hyperelasticMaterials.empty());
  // The closed wound's sides meet point for point and are not a crossing.
  EXPECT_GT(c.skinCrossings.triangles, 0);
  EXPECT_EQ(c.skinCrossings.crossingPairs, 0);
  std::printf("[ellipse 24 mm] deep tissue crossing itself: %d triangle pairs, deepest %.3f mm; mesh: scaled "
              "Jacobian >= %.3f, edge ratio <= %.2f\n",
              c.tissueCrossings.crossingPairs, c.tissueCrossings.deepest, c.mesh.minScaledJacobian,
              c.mesh.maxEdgeRatio);
  EXPECT_EQ(c.mesh.elements, int(p.continuum.mesh.elements.size()));
  // The check recomputed by the solver's own evaluation of its materials.
  const fem::NonlinearStaticAnalysis solver(p.continuum.mesh, p.hyperelasticMaterials, p.continuum.constraints());
  EXPECT_NEAR(solver.deformationCheck(p.displacements).minDetF, c.deformation.minDetF, 1e-12);
  const WoundStress stress = woundSkinStress(p);
  EXPECT_GT(stress.peakVonMises, 0.0);
  EXPECT_TRUE(std::isfinite(stress.meanVonMises));

  if (!fem::test::ccxAvailable())
    GTEST_SKIP() << "ccx (calculix-ccx) is not installed";
  // CalculiX integrates its 15-node wedge with 9 points: the comparison uses
  // the same rules on both sides (2 x 2 x 2 bricks as C3D20R, 9-point wedges).
  const fem::Constraints constraints = p.continuum.constraints();
  fem::AssemblyOptions lower;
  lower.gaussPointsPerDirection = 2;
  fem::NonlinearStaticAnalysis analysis(p.continuum.mesh, p.hyperelasticMaterials, constraints, lower);
  fem::NewtonOptions newton;
  newton.residualTolerance = 1e-10;
  const fem::NonlinearResult ours = analysis.solve(fem::LoadCase{}, o.increments, newton);
  ASSERT_EQ(ours.status, fem::NonlinearStatus::Converged) << ours.message;
  fem::CalculixExportOptions deck;
  deck.defaultIntegrationPoints = 2;
  deck.step.nlgeom = true;
  deck.step.initialIncrement = 0.25;
  deck.step.maximumIncrement = 0.25;
  deck.hyperelastic = p.hyperelasticMaterials;
  deck.tightControls = true;
  const fem::test::CcxResult ccx = fem::test::runCcx(
    "plan-ellipse-nlgeom", fem::calculixInput(p.continuum.mesh, p.materials, constraints, fem::LoadCase{}, deck),
    p.continuum.mesh.nodeCount());
  const double relative = fem::test::relativeDifference(ccx.dat, ours.displacements);
  fem::LinearStaticAnalysis small(p.continuum.mesh, p.materials, constraints, lower);
  ASSERT_EQ(small.prepare(), fem::SolverStatus::Success) << small.message();
  const double linearToCcx = fem::test::relativeDifference(ccx.dat, small.solve(fem::LoadCase{}));
  std::printf("[ellipse 24 mm vs ccx NLGEOM] relative difference %.2e; the linear model's %.2e\n", relative,
              linearToCcx);
  EXPECT_LT(relative, 1e-4);
  EXPECT_GT(linearToCcx, 100 * relative) << "too close to linear to test the large-deformation path";
}

// The check of a deformation against closed form: the plan's own mesh
// (bricks and wedges, curved on the cylinder) moved by a homogeneous
// deformation x -> F x, which its quadratic elements represent exactly, has
// det F = det(F) and the principal stretches of F at every point; a
// reflection (det F < 0) inverts every element.
TEST(LargeDeformationPlan, TheDeformationCheckIsExactForAHomogeneousDeformation)
{
  SimulationOptions heldToTheBone = test::phantomSimulationOptions();
  heldToTheBone.underminingWidth = 0.0;
  const PlanPrediction p = simulatePlan(phantom().skin, phantom().bone, ellipse(24.0, 3.0), heldToTheBone);
  const fem::Mesh& mesh = p.continuum.mesh;
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  auto displacementOf = [&](const Eigen::Matrix3d& f) {
    Eigen::VectorXd u(mesh.dofCount());
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      u.segment<3>(3 * i) = (f - Eigen::Matrix3d::Identity()) * mesh.nodes.col(i);
    return u;
  };
  const Eigen::Matrix3d f = rotation * Eigen::Vector3d(1.3, 0.8, 1.1).asDiagonal();
  const fem::DeformationCheck c = fem::checkDeformation(mesh, displacementOf(f));
  EXPECT_NEAR(c.minDetF, 1.3 * 0.8 * 1.1, 1e-9);
  EXPECT_NEAR(c.maxStretch, 1.3, 1e-9);
  EXPECT_NEAR(c.minStretch, 0.8, 1e-9);
  EXPECT_EQ(c.invertedElements, 0);
  const Eigen::Matrix3d mirror = Eigen::Vector3d(1.0, 1.0, -1.0).asDiagonal();
  const fem::DeformationCheck reflected = fem::checkDeformation(mesh, displacementOf(mirror));
  EXPECT_NEAR(reflected.minDetF, -1.0, 1e-9);
  EXPECT_EQ(reflected.invertedElements, int(mesh.elements.size()));

  // The linear preview of this closure, held to the bone, folds the deep
  // tissue where the large-deformation model of the same mesh does not (the
  // excision test above): its check says so and names the model to trust.
  std::printf("[linear preview] %s\n", checkSummary(p.check).c_str());
  EXPECT_EQ(p.check.model, TissueModel::LinearElastic);
  EXPECT_GT(p.check.deformation.invertedElements, 0);
  EXPECT_FALSE(p.check.admissible());
  EXPECT_NE(checkWarning(p.check).find("large-deformation prediction is the one to trust"), std::string::npos)
    << checkWarning(p.check);
}

TEST(LargeDeformationPlan, TissueModelIdsReadBack)
{
  for (TissueModel m : {TissueModel::LinearElastic, TissueModel::LargeDeformation})
    EXPECT_EQ(tissueModelFromId(tissueModelId(m)), m);
  EXPECT_FALSE(tissueModelFromId("nonlinear"));
  EXPECT_NE(tissueModelDescription(TissueModel::LargeDeformation).find("neo-Hookean"), std::string::npos);
}

} // namespace
} // namespace caps::planning
