// A plan under expression or a push (thesis §5.4) on the sample CT: a
// Z-plasty on the left cheek closed by its sutures, then loaded by the
// default muscles or pushed by a fingertip. Checked against independent
// answers: the closed model loaded directly equals closure + weighted unit
// responses; the contour measure ignores a uniform lift and sees a bump of
// known height; a push of half the travel, solved again, is half way.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "SampleFace.h"
#include "planning/FaceModel.h"
#include "planning/MuscleSet.h"
#include "planning/PlanUnderExpression.h"
#include "modules/incision/IncisionLogic.h"

namespace caps::expression {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

struct ClosedPlan
{
  planning::PlanPrediction prediction;
  std::unique_ptr<fem::LinearStaticAnalysis> analysis;
  std::vector<FittedMuscle> muscles;
};

/// The demo's Z-plasty (left cheek, θ = -40°, z = -47 mm), closed.
const ClosedPlan& closedPlan()
{
  static const std::unique_ptr<ClosedPlan> plan = [] {
    auto out = std::make_unique<ClosedPlan>();
    const auto& face = test::sampleFace();
    Scene scene;
    IncisionLogic logic(scene);
    const planning::IncisionPlan z =
      logic.placeProcedure("z-plasty", face.maps.skin, planning::SkinPoint{-40.0 * kDegree, -47.0}, {});
    planning::SimulationOptions options;
    options.threads = 2;
    out->prediction = planning::simulatePlan(face.maps.skin, face.maps.bone, z, options);
    out->analysis = postOperativeAnalysis(out->prediction);
    out->muscles =
      fitMuscleSet(readMuscleSet(defaultMuscleSetPath()), face.landmarks.landmarks, face.maps.skin, face.maps.bone);
    return out;
  }();
  return *plan;
}

/// The skin node 12 mm below the cut's first point (in the chart): where the fingertip goes.
int fingertipNode(const planning::PlanPrediction& p)
{
  const fem::ChartPoint below = p.surface.mesh.vertices[0] + fem::ChartPoint(0.0, -12.0);
  std::size_t nearest = 0;
  for (std::size_t v = 0; v < p.surface.mesh.vertices.size(); ++v)
    if ((p.surface.mesh.vertices[v] - below).norm() < (p.surface.mesh.vertices[nearest] - below).norm())
      nearest = v;
  return p.continuum.vertexColumns[nearest].front();
}

Eigen::VectorXd activationsOf(const std::vector<FittedMuscle>& muscles,
                              const std::vector<std::pair<std::string, double>>& mix)
{
  Eigen::VectorXd a = Eigen::VectorXd::Zero(Eigen::Index(muscles.size()));
  for (const auto& [id, value] : mix)
    for (std::size_t k = 0; k < muscles.size(); ++k)
      if (muscles[k].id == id)
        a[Eigen::Index(k)] = value;
  return a;
}

const std::vector<std::pair<std::string, double>> kSmile = {
  {"zygomaticus_major_left", 0.6}, {"zygomaticus_major_right", 0.6}, {"risorius_left", 0.3}, {"risorius_right", 0.3}};

TEST(PlanUnderExpression, MusclesOnTheClosedPlanAddToItsClosure)
{
  const ClosedPlan& plan = closedPlan();
  std::vector<std::vector<fem::Muscle>> functions;
  for (const auto& m : plan.muscles)
    functions.push_back(m.functions);
  const MuscleResponses responses(*plan.analysis, functions);
  // Without load the model is closed as the prediction closed it.
  const Eigen::VectorXd closure = plan.analysis->solve(fem::LoadCase{});
  EXPECT_LT((closure - plan.prediction.displacements).norm() / plan.prediction.displacements.norm(), 1e-9);

  const Eigen::VectorXd a = activationsOf(plan.muscles, kSmile);
  fem::LoadCase smile;
  for (std::size_t k = 0; k < functions.size(); ++k)
    for (fem::Muscle m : functions[k])
    {
      m.load *= a[Eigen::Index(k)];
      if (m.load > 0.0)
        smile.muscles.push_back(m);
    }
  const Eigen::VectorXd direct = plan.analysis->solve(smile);
  const Eigen::VectorXd summed = plan.prediction.displacements + responses.combined(a);
  const double relative = (summed - direct).norm() / direct.norm();
  std::printf("[plan under smile] %ld DOF; closure + weighted responses vs direct solve: %.2e relative; the smile "
              "adds up to %.2f mm\n",
              long(direct.size()), relative, (direct - closure).cwiseAbs().maxCoeff());
  EXPECT_LT(relative, 1e-9);
  EXPECT_GT((direct - closure).cwiseAbs().maxCoeff(), 0.1) << "the smile does not reach the plan's model";

  // The §5.4 question, printed: do the contour bumps get worse under the smile?
  const seg::CylindricalFrame& frame = test::sampleFace().maps.skin.frame();
  const ContourComparison c = compareContours(plan.prediction, frame, closure, summed);
  std::printf("[plan under smile] %d skin vertices within 20 mm of the cut: largest bump %.3f mm at rest, %.3f mm "
              "smiling (change %+.3f mm); height changes by up to %.2f mm\n",
              c.rest.vertices, c.rest.largest, c.loaded.largest, c.bumpChange(), c.largestHeightChange);
  EXPECT_TRUE(std::isfinite(c.bumpChange()));
}

TEST(PlanUnderExpression, TheContourMeasureIgnoresALiftAndSeesABump)
{
  const ClosedPlan& plan = closedPlan();
  const planning::PlanPrediction& p = plan.prediction;
  const seg::CylindricalFrame& frame = test::sampleFace().maps.skin.frame();
  const Eigen::VectorXd& rest = p.displacements;
  const ContourBumps before = contourBumps(p, frame, rest);

  // Every node moved 1.5 mm straight out from the axis: each height grows
  // by exactly 1.5 mm, the fit absorbs it, the bumps stay.
  Eigen::VectorXd lifted = rest, bumped = rest;
  const auto& x = p.continuum.mesh.nodes;
  for (Eigen::Index i = 0; i < x.cols(); ++i)
  {
    const Eigen::Vector3d at = x.col(i) + rest.segment<3>(3 * i);
    lifted.segment<3>(3 * i) += 1.5 * frame.radialDirection(frame.toCylindrical(at).theta);
  }
  const ContourComparison lift = compareContours(p, frame, rest, lifted);
  EXPECT_NEAR(lift.largestHeightChange, 1.5, 1e-9);
  EXPECT_NEAR(lift.loaded.largest, before.largest, 1e-9);

  // A bump of 2 mm (Gaussian, 2 mm wide) on the skin about 8 mm from the
  // cut's first point, centred on a vertex: the largest bump is there, most
  // of its 2 mm (the fit to the skin around it, 10 mm, takes some of it).
  const fem::ChartPoint aim = p.surface.mesh.vertices[0] + fem::ChartPoint(0.0, 8.0);
  std::size_t peak = 0;
  for (std::size_t v = 0; v < p.surface.mesh.vertices.size(); ++v)
    if ((p.surface.mesh.vertices[v] - aim).norm() < (p.surface.mesh.vertices[peak] - aim).norm())
      peak = v;
  const fem::ChartPoint centre = p.surface.mesh.vertices[peak];
  for (std::size_t v = 0; v < p.surface.mesh.vertices.size(); ++v)
  {
    const double d = (p.surface.mesh.vertices[v] - centre).norm();
    const int node = p.continuum.vertexColumns[v].front();
    const Eigen::Vector3d at = x.col(node) + rest.segment<3>(3 * Eigen::Index(node));
    bumped.segment<3>(3 * Eigen::Index(node)) +=
      2.0 * std::exp(-d * d / (2.0 * 2.0 * 2.0)) * frame.radialDirection(frame.toCylindrical(at).theta);
  }
  const ContourBumps after = contourBumps(p, frame, bumped);
  const int top = p.continuum.vertexColumns[peak].front();
  const Eigen::Vector3d bumpTop = x.col(top) + bumped.segment<3>(3 * Eigen::Index(top));
  std::printf("[contour] %d vertices; largest bump %.3f mm, with a 2 mm bump added %.3f mm, %.2f mm from its top\n",
              before.vertices, before.largest, after.largest, (after.where - bumpTop).norm());
  EXPECT_GT(after.largest, 1.0);
  EXPECT_LT(after.largest, 2.05);
  EXPECT_LT((after.where - bumpTop).norm(), 1e-9) << "the largest bump is not where it was added";
}

TEST(PlanUnderExpression, APushOfHalfTheTravelIsHalfWay)
{
  const ClosedPlan& plan = closedPlan();
  const planning::PlanPrediction& p = plan.prediction;
  const seg::CylindricalFrame& frame = test::sampleFace().maps.skin.frame();
  // The fingertip below the cut, pushing the cheek up 6 mm along the head
  // axis (§5.4: "pushed her cheek up about a half inch").
  const int tip = fingertipNode(p);
  SkinPush push;
  push.centre = p.continuum.mesh.nodes.col(tip) + p.displacements.segment<3>(3 * Eigen::Index(tip));
  push.radius = 4.0;
  push.displacement = 6.0 * frame.direction().normalized();
  const Eigen::VectorXd full = pushedDisplacement(p, push);
  // The fingertip's skin went where it was pushed.
  EXPECT_LT(
    (full.segment<3>(3 * Eigen::Index(tip)) - p.displacements.segment<3>(3 * Eigen::Index(tip)) - push.displacement)
      .norm(),
    1e-9);
  // Half the travel, solved again: half way between closure and full travel.
  SkinPush half = push;
  half.displacement *= 0.5;
  const Eigen::VectorXd halfway = pushedDisplacement(p, half);
  const Eigen::VectorXd expected = p.displacements + 0.5 * (full - p.displacements);
  EXPECT_LT((halfway - expected).norm() / expected.norm(), 1e-9);

  const ContourComparison c = compareContours(p, frame, p.displacements, full);
  std::printf("[plan pushed] cheek pushed up 6 mm 12 mm below the Z: largest bump %.3f mm at rest, %.3f mm pushed "
              "(change %+.3f mm); height changes by up to %.2f mm\n",
              c.rest.largest, c.loaded.largest, c.bumpChange(), c.largestHeightChange);
  EXPECT_GT(c.largestHeightChange, 0.5);

  SkinPush away = push;
  away.centre += Eigen::Vector3d(0.0, -200.0, 0.0);
  EXPECT_THROW(pushedDisplacement(p, away), std::invalid_argument);
}

TEST(PlanUnderExpression, ThePushPathGoesThroughItsCornersAtEvenSpeed)
{
  PushPath path;
  EXPECT_EQ(path.travelAt(0.5), Eigen::Vector3d::Zero()) << "an empty path stays at rest";
  // Up 6 mm, then 3 mm sideways: 9 mm in all.
  path.waypoints = {Eigen::Vector3d(0.0, 0.0, 6.0), Eigen::Vector3d(3.0, 0.0, 6.0)};
  EXPECT_DOUBLE_EQ(path.length(), 9.0);
  EXPECT_LT((path.travelAt(0.0) - Eigen::Vector3d::Zero()).norm(), 1e-12);
  EXPECT_LT((path.travelAt(1.0 / 3.0) - Eigen::Vector3d(0.0, 0.0, 3.0)).norm(), 1e-12);
  EXPECT_LT((path.travelAt(2.0 / 3.0) - Eigen::Vector3d(0.0, 0.0, 6.0)).norm(), 1e-12);
  EXPECT_LT((path.travelAt(0.75) - Eigen::Vector3d(0.75, 0.0, 6.0)).norm(), 1e-12);
  EXPECT_LT((path.travelAt(1.0) - Eigen::Vector3d(3.0, 0.0, 6.0)).norm(), 1e-12);
  EXPECT_LT((path.travelAt(7.0) - Eigen::Vector3d(3.0, 0.0, 6.0)).norm(), 1e-12) << "s is clamped";
  // A corner repeated (a zero-length leg) changes nothing.
  path.waypoints.insert(path.waypoints.begin() + 1, Eigen::Vector3d(0.0, 0.0, 6.0));
  EXPECT_LT((path.travelAt(0.75) - Eigen::Vector3d(0.75, 0.0, 6.0)).norm(), 1e-12);
}

TEST(PlanUnderExpression, ThreeUnitPushesGiveAnyTravelAsAFreshSolveDoes)
{
  const ClosedPlan& plan = closedPlan();
  const planning::PlanPrediction& p = plan.prediction;
  const int tip = fingertipNode(p);
  const Eigen::Vector3d centre = p.continuum.mesh.nodes.col(tip) + p.displacements.segment<3>(3 * Eigen::Index(tip));
  const PushResponses responses(p, centre, 4.0);
  EXPECT_FALSE(responses.pushedNodes().empty());
  EXPECT_LT((responses.displacement(Eigen::Vector3d::Zero()) - p.displacements).norm(), 1e-9 * p.displacements.norm())
    << "the fingertip at rest holds the skin where the closure put it";

  // A bent path: up the cheek 6 mm, then 3 mm forward and 1 mm in. At
  // three quarters of it the superposed model must equal the model factored
  // afresh with the fingertip there (pushedDisplacement: a new factorisation).
  PushPath path;
  path.centre = centre;
  path.radius = 4.0;
  path.waypoints = {Eigen::Vector3d(0.0, 0.0, 6.0), Eigen::Vector3d(3.0, -1.0, 6.0)};
  for (double s : {0.3, 0.75, 1.0})
  {
    SkinPush push;
    push.centre = centre;
    push.radius = 4.0;
    push.displacement = path.travelAt(s);
    const Eigen::VectorXd fresh = pushedDisplacement(p, push);
    const Eigen::VectorXd superposed = responses.displacement(path.travelAt(s));
    EXPECT_LT((superposed - fresh).norm() / fresh.norm(), 1e-9) << "at s = " << s;
    // The fingertip's skin is where the path put it.
    EXPECT_LT((superposed.segment<3>(3 * Eigen::Index(tip)) - p.displacements.segment<3>(3 * Eigen::Index(tip)) -
               path.travelAt(s))
                .norm(),
              1e-9);
  }
  EXPECT_THROW(PushResponses(p, centre + Eigen::Vector3d(0.0, -200.0, 0.0), 4.0), std::invalid_argument);
  EXPECT_THROW(PushResponses(p, centre, 0.0), std::invalid_argument);
}

TEST(PlanUnderExpression, TheWholeFaceSmileDrivesThePlanAtItsRim)
{
  const ClosedPlan& plan = closedPlan();
  const planning::PlanPrediction& p = plan.prediction;
  const auto& sample = test::sampleFace();
  FaceModelOptions options;
  options.elementSize = 8.0;
  const FaceMesh face = meshFace(sample.maps.skin, sample.maps.bone, sample.landmarks.landmarks, options);
  fem::AssemblyOptions assembly;
  assembly.threads = 2;
  fem::LinearStaticAnalysis faceAnalysis(face.continuum.mesh, face.materials, face.continuum.constraints(), assembly);
  ASSERT_EQ(faceAnalysis.prepare(), fem::SolverStatus::Success) << faceAnalysis.message();
  std::vector<std::vector<fem::Muscle>> functions;
  for (const auto& m : plan.muscles)
    functions.push_back(m.functions);
  const MuscleResponses faceResponses(faceAnalysis, functions);
  const PlanExpressionResponses onPlan(p, face.continuum.mesh, faceResponses, functions);
  ASSERT_FALSE(onPlan.rimNodes().empty());

  // No activation: the closure as predicted.
  const Eigen::VectorXd rest = onPlan.displacement(Eigen::VectorXd::Zero(Eigen::Index(functions.size())));
  EXPECT_LT((rest - p.displacements).norm() / p.displacements.norm(), 1e-12);

  // The left zygomaticus alone, checked by a model factored afresh with its
  // rim where the response put it and the muscle's load: the reused
  // factorisation (new prescribed values) gives the same answer.
  std::size_t zygomaticus = 0;
  while (zygomaticus < plan.muscles.size() && plan.muscles[zygomaticus].id != "zygomaticus_major_left")
    ++zygomaticus;
  ASSERT_LT(zygomaticus, plan.muscles.size());
  Eigen::VectorXd a = Eigen::VectorXd::Zero(Eigen::Index(functions.size()));
  a[Eigen::Index(zygomaticus)] = 1.0;
  const Eigen::VectorXd pulled = onPlan.displacement(a);
  fem::Constraints fresh = p.continuum.constraints();
  for (int node : onPlan.rimNodes())
    for (int d = 0; d < 3; ++d)
      fresh.prescribe(node, d, pulled[3 * Eigen::Index(node) + d]);
  fem::LinearStaticAnalysis check(p.continuum.mesh, p.materials, fresh, assembly);
  ASSERT_EQ(check.prepare(), fem::SolverStatus::Success) << check.message();
  fem::LoadCase load;
  load.muscles = functions[zygomaticus];
  const Eigen::VectorXd direct = check.solve(load);
  EXPECT_LT((direct - pulled).norm() / pulled.norm(), 1e-9);
  // The plan's region moves with the face: its rim by the face model's
  // movement there (the largest rim movement is the face's, not zero).
  double rimMoves = 0.0;
  for (int node : onPlan.rimNodes())
    rimMoves = std::max(rimMoves, (pulled - rest).segment<3>(3 * Eigen::Index(node)).norm());
  EXPECT_GT(rimMoves, 0.5);

  // The §5.4 question for a smile, printed.
  const Eigen::VectorXd smiling = onPlan.displacement(activationsOf(plan.muscles, kSmile));
  const ContourComparison c = compareContours(p, sample.maps.skin.frame(), rest, smiling);
  std::printf("[plan in a smiling face] rim of %zu nodes follows the face; the left zygomaticus moves the rim up to "
              "%.2f mm; smiling: largest bump %.3f mm at rest, %.3f mm smiling (change %+.3f mm), height changes by "
              "up to %.2f mm\n",
              onPlan.rimNodes().size(), rimMoves, c.rest.largest, c.loaded.largest, c.bumpChange(),
              c.largestHeightChange);
  EXPECT_GT(c.largestHeightChange, 0.5);
}

} // namespace
} // namespace caps::expression
