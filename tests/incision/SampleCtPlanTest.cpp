// Plans on the embedded sample CT (data/sample-ct): the real face, with its
// uneven tissue, sinus walls and an edentulous jaw. The range maps are made
// once for the suite, as `caps demo` makes them.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "fem/CalculixIO.h"
#include "fem/StaticAnalysis.h"
#include "fem/NonlinearStaticAnalysis.h"
#include "modules/incision/IncisionLogic.h"
#include "planning/PlanSimulation.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "modules/volumes/CommandLine.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"

namespace fs = std::filesystem;

namespace caps::planning {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

class SampleCtPlan : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    scene_ = std::make_unique<Scene>();
    logic_ = std::make_unique<IncisionLogic>(*scene_);
    std::ostringstream messages;
    VolumeNode* volume =
      cli::loadCt(*logic_, fs::path(CAPS_TEST_DATA_DIR) / "sample-ct" / "dicom", seg::CtReadOptions{}, messages);
    maps_ = std::make_unique<RangeMapOutput>();
    RangeMapLogic(*scene_).run(*volume, RangeMapLogic::Parameters{}, {}, maps_.get());
  }
  static void TearDownTestSuite()
  {
    logic_.reset();
    scene_.reset();
    maps_.reset();
  }

  static IncisionPlan place(const std::string& id, double thetaDeg, double z,
                            const std::map<std::string, double>& values = {})
  {
    return logic_->placeProcedure(id, maps_->skin, SkinPoint{thetaDeg * kDegree, z}, values);
  }
  static SimulationOptions options()
  {
    SimulationOptions o; // the defaults `caps plan` uses
    o.threads = 2;
    return o;
  }

  static std::unique_ptr<Scene> scene_;
  static std::unique_ptr<IncisionLogic> logic_;
  static std::unique_ptr<RangeMapOutput> maps_;
};

std::unique_ptr<Scene> SampleCtPlan::scene_;
std::unique_ptr<IncisionLogic> SampleCtPlan::logic_;
std::unique_ptr<RangeMapOutput> SampleCtPlan::maps_;

// The Z-plasty's predicted gain for 30–90° on the sample, next to
// the Fig. 2.2 table: positive and ordered by angle. On the left cheek, where
// `caps demo` puts its Z.
TEST_F(SampleCtPlan, ZPlastyGainOnTheCheekIsPositiveAndOrderedByAngle)
{
  double previous = 0.0;
  for (const double angle : {30.0, 45.0, 60.0, 75.0, 90.0})
  {
    SCOPED_TRACE(angle);
    const IncisionPlan plan = place("z-plasty", -40.0, -47.0, {{"limb_angle", angle * kDegree}});
    const PlanPrediction p = simulatePlan(maps_->skin, maps_->bone, plan, options());
    EXPECT_LT(p.maxSutureGap, 1e-9);
    ASSERT_TRUE(p.zPlasty.has_value());
    const ZPlastyPrediction& z = *p.zPlasty;
    std::printf("[sample cheek Z %.0f deg] %ld DOF; central limb %.2f mm, gain %.2f mm = %.1f %% predicted; "
                "Fig. 2.2 table %.0f %%, geometric %.1f %%; predicted / table %.2f\n",
                angle, long(p.dofCount), z.predicted.before, z.predicted.gain, 100 * z.predicted.fraction,
                100 * z.theoretical, 100 * z.geometric, z.predicted.fraction / z.theoretical);
    EXPECT_GT(z.predicted.fraction, previous);
    EXPECT_LT(z.predicted.fraction, z.geometric) << "a soft-tissue Z cannot gain more than its rigid geometry";
    previous = z.predicted.fraction;
  }
}

// The Z-plasty's gain as the plan pipeline predicts it (large deformation,
// the skin's pre-tension, the procedure's undermining) for 30, 45 and 60°,
// next to Fig. 2.2's table. The clinical measurements the thesis cites with
// the figure (its refs 283-284) spread "from 45 percent less to 25 percent
// more than calculated geometrically": a prediction outside 0.55-1.25 of the
// table would be outside what surgeons measure. Printed with the difference;
// equality with the table is not expected (the table is the rigid
// parallelogram's, the tissue is not).
TEST_F(SampleCtPlan, ZPlastyGainInLargeDeformationLiesInTheClinicallyMeasuredRange)
{
  double previous = 0.0;
  for (const double angle : {30.0, 45.0, 60.0})
  {
    SCOPED_TRACE(angle);
    const IncisionPlan plan = place("z-plasty", -40.0, -47.0, {{"limb_angle", angle * kDegree}});
    SimulationOptions o = options();
    o.model = TissueModel::LargeDeformation;
    o.preTension = SkinPreTension{};
    const PlanPrediction p = simulatePlan(maps_->skin, maps_->bone, plan, o);
    ASSERT_TRUE(p.check.converged) << p.check.problem;
    EXPECT_TRUE(p.check.admissible()) << checkWarning(p.check);
    ASSERT_TRUE(p.zPlasty.has_value());
    const ZPlastyPrediction& z = *p.zPlasty;
    const double ratio = z.predicted.fraction / z.theoretical;
    std::printf("[sample cheek Z %.0f deg, large deformation, pre-tension] gain %.1f %% predicted, Fig. 2.2 %.0f %%, "
                "difference %+.1f points, predicted / table %.2f; %s\n",
                angle, 100 * z.predicted.fraction, 100 * z.theoretical, 100 * (z.predicted.fraction - z.theoretical),
                ratio, checkSummary(p.check).c_str());
    EXPECT_GT(z.predicted.fraction, previous);
    EXPECT_GE(ratio, 0.55);
    EXPECT_LE(ratio, 1.25);
    previous = z.predicted.fraction;
  }
}

// The whole model of a real plan (uneven depth, distorted wedges at the
// wound, suture equations with offsets) solved by CalculiX gives the same
// displacements. CalculiX integrates its 15-node wedge with 9 points and our
// full rule has 18, so the comparison uses the same rules on both sides:
// our level 2 (2×2×2 bricks, 9-point wedges) against C3D20R and C3D15.
TEST_F(SampleCtPlan, CheekZPlastyModelAgreesWithCalculix)
{
  if (std::system("command -v ccx > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "ccx (calculix-ccx) is not installed";
  const IncisionPlan plan = place("z-plasty", -40.0, -47.0);
  SimulationOptions o = options();
  o.elementSize = 3.0; // a smaller model: the comparison, not the detail, matters here
  const PlanPrediction p = simulatePlan(maps_->skin, maps_->bone, plan, o);
  const fem::Mesh& mesh = p.continuum.mesh;
  const fem::Constraints constraints = p.continuum.constraints();
  fem::AssemblyOptions lower;
  lower.gaussPointsPerDirection = 2;
  fem::LinearStaticAnalysis analysis(mesh, p.materials, constraints, lower);
  ASSERT_EQ(analysis.prepare(), fem::SolverStatus::Success) << analysis.message();
  const Eigen::VectorXd u = analysis.solve(fem::LoadCase{});

  const fs::path dir = fs::path(CAPS_TEST_ARTIFACTS_DIR) / "sample-cheek-z-ccx";
  fs::create_directories(dir);
  std::string deck = fem::calculixInput(mesh, p.materials, constraints, fem::LoadCase{});
  int bricks = 0;
  for (std::size_t at = deck.find("TYPE=C3D20,"); at != std::string::npos; at = deck.find("TYPE=C3D20,", at), ++bricks)
    deck.replace(at, 11, "TYPE=C3D20R,");
  ASSERT_GT(bricks, 0);
  ASSERT_NE(deck.find("TYPE=C3D15,"), std::string::npos) << "the Z's corners are wedges";
  std::ofstream(dir / "job.inp") << deck;
  ASSERT_EQ(std::system(("cd '" + dir.string() + "' && ccx -i job > ccx.log 2>&1").c_str()), 0)
    << "see " << (dir / "ccx.log");
  const Eigen::Matrix3Xd theirs = fem::readDatDisplacements((dir / "job.dat").string(), mesh.nodeCount());
  const Eigen::Map<const Eigen::Matrix3Xd> ours(u.data(), 3, mesh.nodeCount());
  const double relative = (ours - theirs).norm() / ours.norm();
  std::printf("[sample cheek Z vs ccx] %ld DOF, largest displacement %.2f mm, largest difference %.2e mm, "
              "relative %.2e\n",
              long(p.dofCount), ours.colwise().norm().maxCoeff(), (ours - theirs).colwise().norm().maxCoeff(),
              relative);
  EXPECT_LT(relative, 1e-5); // ccx's .dat keeps 7 significant digits
}

// The demo's cheek Z-plasty as its procedure states it: cut through the
// skin and the fat, both flaps and a 12 mm band around them raised on the
// fascia, where they slide. The linear preview's deformed mesh is not a body
// (its check finds the inverted elements and says so); the large-deformation
// closure converges to a body. Transposed instead while held to the bone
// through all three layers, which no surgeon does, the large-deformation
// solve stops short of the closure and says it is not a prediction, rather
// than throwing or returning a folded face.
TEST_F(SampleCtPlan, TheCheekZPlastyIsCheckedAndClosesInLargeDeformationAsTheProcedureStatesIt)
{
  const IncisionPlan plan = place("z-plasty", -40.0, -47.0);
  EXPECT_EQ(plan.cutDepth(), CutDepth::Fascia);
  EXPECT_DOUBLE_EQ(plan.underminingBand(), 12.0);
  SimulationOptions o = options();
  const PlanPrediction linear = simulatePlan(maps_->skin, maps_->bone, plan, o);
  std::printf("[cheek Z, linear] %s\n", checkSummary(linear.check).c_str());
  EXPECT_EQ(linear.cutLayers, 2);
  EXPECT_GT(linear.check.deformation.invertedElements, 0);
  EXPECT_FALSE(linear.check.admissible());
  EXPECT_NE(checkWarning(linear.check).find("linear preview"), std::string::npos) << checkWarning(linear.check);

  o.model = TissueModel::LargeDeformation;
  const PlanPrediction raised = simulatePlan(maps_->skin, maps_->bone, plan, o);
  std::printf("[cheek Z, large deformation, raised on the fascia] %s; closure force %.2f N, largest suture %.3f N; "
              "%zu nodes slide\n",
              checkSummary(raised.check).c_str(), raised.closure.magnitudeSum, raised.closure.largest,
              raised.continuum.slidingNodes.size());
  ASSERT_TRUE(raised.check.converged) << raised.check.problem;
  EXPECT_TRUE(raised.check.admissible()) << raised.check.problem;
  EXPECT_EQ(raised.check.deformation.invertedElements, 0);
  EXPECT_LT(raised.maxSutureGap, 1e-6);
  EXPECT_TRUE(checkWarning(raised.check).empty());
  EXPECT_FALSE(raised.continuum.slidingNodes.empty());

  o.cutLayers = 0;          // through every layer ...
  o.underminingWidth = 0.0; // ... and nothing undermined
  const PlanPrediction held = simulatePlan(maps_->skin, maps_->bone, plan, o);
  std::printf("[cheek Z, large deformation, held to the bone] %s; closure reached %.1f %%\n",
              checkSummary(held.check).c_str(), 100 * held.check.closureFraction);
  if (!held.check.converged)
  {
    EXPECT_LT(held.check.closureFraction, 1.0);
    EXPECT_NE(checkWarning(held.check).find("NOT A PREDICTION"), std::string::npos);
    EXPECT_GT(held.check.deformation.minDetF, 0.0) << "the last converged state is still a body";
  }
}

// Newton's iteration on the demo's Z-plasty meets tangents that are not
// positive definite away from equilibrium (trial states of large steps).
// Shifted towards their diagonal (Levenberg-Marquardt) they still give a
// descent direction; the closure reached is the same equilibrium as plain
// Newton's, which the hyperelastic model makes path-independent, and at a
// finer mesh the shifted iteration closes where plain Newton stops short.
TEST_F(SampleCtPlan, ShiftedNewtonReachesTheSameClosureAndClosesWherePlainNewtonStops)
{
  const IncisionPlan plan = place("z-plasty", -40.0, -47.0);
  auto solve = [&](double elementSize, bool shift) {
    SimulationOptions o = options();
    o.elementSize = elementSize;
    const PlanPrediction p = meshPlan(maps_->skin, maps_->bone, plan, o);
    fem::HyperelasticTable neoHookean;
    for (const auto& [layer, m] : o.layerMaterials())
      neoHookean[layer] = fem::HyperelasticMaterial::fromLinear(fem::HyperelasticLaw::NeoHookean, m);
    fem::AssemblyOptions assembly;
    assembly.threads = 2;
    fem::NonlinearStaticAnalysis analysis(p.continuum.mesh, neoHookean, p.continuum.constraints(), assembly);
    fem::NewtonOptions newton;
    newton.shiftIndefiniteTangent = shift;
    newton.stabilization.enabled = false; // Newton's own safeguards only
    fem::NonlinearResult r = analysis.solve(fem::LoadCase{}, o.increments, newton);
    std::printf("[cheek Z, %.1f mm, %s Newton] %s at %.1f %% of the closure; %zu increments tried, %zu iterations, "
                "%d factorizations (%d shifted, largest shift %.0e)\n",
                elementSize, shift ? "shifted" : "plain",
                r.status == fem::NonlinearStatus::Converged ? "converged" : "stopped", 100 * r.loadFraction,
                r.increments.size(), r.iterations.size(), r.factorizations, r.shiftedFactorizations, r.largestShift);
    return r;
  };
  const fem::NonlinearResult plain = solve(3.0, false), shifted = solve(3.0, true);
  ASSERT_EQ(plain.status, fem::NonlinearStatus::Converged) << plain.message;
  ASSERT_EQ(shifted.status, fem::NonlinearStatus::Converged) << shifted.message;
  EXPECT_GT(shifted.shiftedFactorizations, 0);
  const double relative = (shifted.displacements - plain.displacements).norm() / plain.displacements.norm();
  std::printf("[cheek Z, 3 mm] shifted and plain Newton differ by %.2e relative\n", relative);
  EXPECT_LT(relative, 1e-6);

  const fem::NonlinearResult finer = solve(2.5, true);
  EXPECT_EQ(finer.status, fem::NonlinearStatus::Converged) << finer.message;
  EXPECT_EQ(solve(2.5, false).status, fem::NonlinearStatus::NotConverged)
    << "plain Newton now closes this one too: find a harder case for the shift";
}

// The scan's awkward places: across the θ = ±π seam at the back of the head,
// and close to the top of the scan, which cuts the sample's head at z ≈ 70 mm
// (the frame's last row, z = 74.9, has no skin): the region stops at the last
// measured row. Each plan closes.
TEST_F(SampleCtPlan, PlansAcrossTheSeamAndNearTheTopOfTheScanClose)
{
  const seg::CylindricalFrame& frame = maps_->skin.frame();
  struct Where
  {
    const char* name;
    double thetaDeg, z;
  };
  for (const Where w :
       {Where{"occiput across the seam", 180.0, 40.0}, Where{"near the top of the scan", -90.0, frame.zMax() - 25.0}})
  {
    SCOPED_TRACE(w.name);
    const IncisionPlan plan = place("elliptical-excision", w.thetaDeg, w.z, {{"length", 20.0}});
    const PlanPrediction p = simulatePlan(maps_->skin, maps_->bone, plan, options());
    double vMax = -1e300;
    for (const auto& v : p.surface.mesh.vertices)
      vMax = std::max(vMax, v.y());
    std::printf("[sample %s] %ld DOF, wound %.2f mm -> %.2e mm; region reaches z %.1f of the scan's %.1f mm\n", w.name,
                long(p.dofCount), p.maxSutureGapBefore, p.maxSutureGap, plan.centre().z + vMax, frame.zMax());
    EXPECT_GT(p.maxSutureGapBefore, 2.0);
    EXPECT_LT(p.maxSutureGap, 1e-9);
    EXPECT_LE(plan.centre().z + vMax, frame.zMax() + 1e-9);
    EXPECT_TRUE(p.surface.reachedChartBound) << "the region reaches the top of the measured skin";
  }
}

} // namespace
} // namespace caps::planning
