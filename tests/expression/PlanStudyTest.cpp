// The plan study of the Expressions panel (thesis §5.4) on
// the sample CT: the demo's Z-plasty on the left cheek inside the whole-face
// model. Its real-time skin is checked against the display surface given
// the model's displacement directly (under the muscles and under a
// fingertip moved along a bent path), and the superposed push against a
// push factored afresh.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>

#include <Eigen/Dense>
#include <vtkCellArray.h>
#include <vtkPolyData.h>

#include "SampleFace.h"
#include "modules/expression/PlanStudy.h"
#include "modules/incision/IncisionLogic.h"
#include "planning/PlanDisplay.h"

namespace caps::expression {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

double millisecondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/// The face model (8 mm elements: the test's speed) and the Z-plasty studied in it.
struct Studied
{
  std::shared_ptr<const ExpressionModel> model;
  PlanStudyInput input;
  std::unique_ptr<PlanStudy> study;
};

Studied& studied()
{
  static const std::unique_ptr<Studied> s = [] {
    auto out = std::make_unique<Studied>();
    const auto& face = test::sampleFace();
    ExpressionModelInput in;
    in.skin = face.maps.skin;
    in.bone = face.maps.bone;
    in.landmarks = face.landmarks.landmarks;
    in.face.elementSize = 8.0;
    out->model = buildExpressionModel(in);
    Scene scene;
    IncisionLogic logic(scene);
    out->input.planName = "Z-plasty 1";
    out->input.plan = logic.placeProcedure("z-plasty", face.maps.skin, planning::SkinPoint{-40.0 * kDegree, -47.0}, {});
    out->input.skin = face.maps.skin;
    out->input.bone = face.maps.bone;
    out->input.model = out->model;
    int steps = 0;
    const auto start = std::chrono::steady_clock::now();
    out->study = PlanStudy::build(out->input, [&steps](double, const std::string&) {
      ++steps;
      return true;
    });
    std::printf("[plan study] built in %.2f s (predict %.2f, %ld muscle responses %.2f, display %.2f); %d progress "
                "steps; %ld display vertices\n",
                millisecondsSince(start) / 1e3, out->study->predictSeconds, long(out->study->muscleCount()),
                out->study->responseSeconds, out->study->displaySeconds, steps,
                long(out->study->surface().vertexCount()));
    EXPECT_GT(steps, 3);
    return out;
  }();
  return *s;
}

/// The plan's display surface built independently, with @a u set as its solution.
Eigen::Matrix3Xd displayUnder(const PlanStudy& study, const Eigen::VectorXd& u)
{
  planning::PlanDisplayOptions options;
  options.resolution = 3;
  options.maxRangeDetail = 3.0;
  planning::PlanDisplay display =
    planning::buildPlanDisplay(study.prediction(), test::sampleFace().maps.skin, nullptr, options);
  display.surface.setSolution(u, study.prediction().materials);
  return display.surface.positions(fem::DisplayMapping{1.0, true});
}

Eigen::VectorXd smileOf(const ExpressionModel& model)
{
  Eigen::VectorXd a = Eigen::VectorXd::Zero(Eigen::Index(model.muscles.size()));
  for (std::size_t k = 0; k < model.muscles.size(); ++k)
    if (model.muscles[k].definition == "zygomaticus_major")
      a[Eigen::Index(k)] = 0.8;
    else if (model.muscles[k].definition == "risorius")
      a[Eigen::Index(k)] = 0.4;
  return a;
}

/// A skin node of the plan's model @a below mm below the cut's first point
/// (in the chart), where the closure put it.
Eigen::Vector3d skinPointBelowTheCut(const PlanStudy& study, double below)
{
  const planning::PlanPrediction& p = study.prediction();
  const fem::ChartPoint aim = p.surface.mesh.vertices[0] + fem::ChartPoint(0.0, -below);
  std::size_t nearest = 0;
  for (std::size_t v = 0; v < p.surface.mesh.vertices.size(); ++v)
    if ((p.surface.mesh.vertices[v] - aim).norm() < (p.surface.mesh.vertices[nearest] - aim).norm())
      nearest = v;
  const int node = p.continuum.vertexColumns[nearest].front();
  return p.continuum.mesh.nodes.col(node) + p.displacements.segment<3>(3 * Eigen::Index(node));
}

TEST(PlanStudy, TheSkinUnderTheMusclesIsTheDisplayOfTheirDisplacement)
{
  Studied& s = studied();
  ASSERT_NE(s.study, nullptr);
  const PlanStudy& study = *s.study;
  EXPECT_EQ(study.planName(), "Z-plasty 1");
  EXPECT_EQ(study.muscleCount(), Eigen::Index(s.model->muscles.size()));
  EXPECT_EQ(study.shade().size(), std::size_t(study.surface().vertexCount()));

  // At rest: the plan as predicted (its closure).
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(study.muscleCount());
  Eigen::Matrix3Xd shown;
  study.positions(rest, shown);
  EXPECT_LT((shown - displayUnder(study, study.prediction().displacements)).cwiseAbs().maxCoeff(), 1e-9);

  // Smiling: the display of PlanExpressionResponses::displacement(a).
  const Eigen::VectorXd smile = smileOf(*s.model);
  ASSERT_GT(smile.sum(), 1.0);
  auto start = std::chrono::steady_clock::now();
  constexpr int kRepeats = 50;
  for (int i = 0; i < kRepeats; ++i)
    study.positions(smile, shown);
  const double perUpdate = millisecondsSince(start) / kRepeats;
  const Eigen::Matrix3Xd expected = displayUnder(study, study.responses().displacement(smile));
  const double gap = (shown - expected).cwiseAbs().maxCoeff();
  Eigen::Matrix3Xd atRest;
  study.positions(rest, atRest);
  const double moved = (shown - atRest).colwise().norm().maxCoeff();
  EXPECT_LT(gap, 1e-9);
  EXPECT_GT(moved, 0.3) << "the smile does not reach the plan's skin";

  // The bumps compared: rest as built, loaded as compareContours gives them.
  start = std::chrono::steady_clock::now();
  const ContourComparison c = study.compare(smile);
  const double compareMs = millisecondsSince(start);
  const ContourComparison direct = compareContours(study.prediction(), study.frame(), study.prediction().displacements,
                                                   study.responses().displacement(smile));
  EXPECT_DOUBLE_EQ(c.rest.largest, study.restBumps().largest);
  EXPECT_DOUBLE_EQ(c.loaded.largest, direct.loaded.largest);
  EXPECT_DOUBLE_EQ(c.largestHeightChange, direct.largestHeightChange);
  EXPECT_GT(c.largestHeightChange, 0.1);
  std::printf("[plan study] smile: skin moves up to %.2f mm (%.1e mm from the direct display); %.2f ms per slider "
              "update for %ld vertices; compare %.1f ms: bump %.3f → %.3f mm, height change up to %.2f mm\n",
              moved, gap, perUpdate, long(shown.cols()), compareMs, c.rest.largest, c.loaded.largest,
              c.largestHeightChange);
}

TEST(PlanStudy, TheFingertipAlongABentPathIsTheDisplayOfThePush)
{
  Studied& s = studied();
  ASSERT_NE(s.study, nullptr);
  PlanStudy& study = *s.study;
  PushPath path;
  path.centre = skinPointBelowTheCut(study, 12.0);
  path.radius = 4.0;
  const Eigen::Vector3d up = study.frame().direction().normalized();
  const Eigen::Vector3d in = -study.frame().radialDirection(study.frame().toCylindrical(path.centre).theta);
  path.waypoints = {4.0 * up, 4.0 * up + 2.0 * in}; // up the cheek, then into it
  EXPECT_NEAR(path.length(), 6.0, 1e-12);

  EXPECT_FALSE(study.hasFingertip());
  EXPECT_THROW(study.pushedDisplacement(Eigen::Vector3d::UnitX()), std::logic_error);
  const auto start = std::chrono::steady_clock::now();
  study.setFingertip(path.centre, path.radius);
  const double buildMs = millisecondsSince(start);
  ASSERT_TRUE(study.hasFingertip());
  const Fingertip& tip = study.currentFingertip();
  EXPECT_NEAR(tip.directions.col(0).dot(up), 1.0, 1e-12);
  EXPECT_NEAR(tip.directions.col(2).dot(in), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(tip.directions.determinant()), 1.0, 1e-12);

  Eigen::Matrix3Xd shown;
  for (double at : {0.0, 0.3, 0.8, 1.0})
  {
    const Eigen::Vector3d travel = path.travelAt(at);
    study.pushedPositions(travel, shown);
    const Eigen::Matrix3Xd expected = displayUnder(study, tip.push->displacement(travel));
    EXPECT_LT((shown - expected).cwiseAbs().maxCoeff(), 1e-9) << "at " << at;
  }
  // On the second leg at 0.8: 4 mm up, 0.8 of the way into the 2 mm in.
  EXPECT_LT((path.travelAt(0.8) - (4.0 * up + 0.8 * in)).norm(), 1e-12);

  // The skin under the fingertip goes where the fingertip goes.
  const Eigen::VectorXd full = study.pushedDisplacement(path.travelAt(1.0));
  ASSERT_FALSE(tip.push->pushedNodes().empty());
  for (int node : tip.push->pushedNodes())
    EXPECT_LT((full.segment<3>(3 * Eigen::Index(node)) - study.prediction().displacements.segment<3>(3 * node) -
               path.travelAt(1.0))
                .norm(),
              1e-9);
  const ContourComparison c = study.comparePush(path.travelAt(1.0));
  EXPECT_GT(c.largestHeightChange, 0.5);
  std::printf("[plan study] fingertip of %zu nodes built in %.0f ms; pushed along the path: bump %.3f → %.3f mm, "
              "height change up to %.2f mm\n",
              tip.push->pushedNodes().size(), buildMs, c.rest.largest, c.loaded.largest, c.largestHeightChange);

  // Off the plan's skin: a message, no fingertip change.
  EXPECT_THROW(study.fingertip(path.centre + Eigen::Vector3d(0.0, -200.0, 0.0), 4.0), std::invalid_argument);
  EXPECT_THROW(study.fingertip(path.centre, 0.0), std::invalid_argument);
}

TEST(PlanStudy, TheSuperposedPushEqualsAPushFactoredAfresh)
{
  Studied& s = studied();
  ASSERT_NE(s.study, nullptr);
  const PlanStudy& study = *s.study;
  const Eigen::Vector3d centre = skinPointBelowTheCut(study, 10.0);
  const PushResponses push(study.prediction(), centre, 5.0);
  // An oblique travel: every column of W takes part.
  const Eigen::Vector3d travel(2.5, -1.5, 3.0);
  SkinPush direct;
  direct.centre = centre;
  direct.radius = 5.0;
  direct.displacement = travel;
  const Eigen::VectorXd fresh = pushedDisplacement(study.prediction(), direct);
  const Eigen::VectorXd superposed = push.displacement(travel);
  const double relative = (superposed - fresh).norm() / fresh.norm();
  std::printf("[plan study] push by superposition vs factored afresh: %.1e relative\n", relative);
  EXPECT_LT(relative, 1e-9);
  EXPECT_GT((superposed - study.prediction().displacements).cwiseAbs().maxCoeff(), 1.0);
}

TEST(PlanStudy, TheFaceCellsUnderThePlanCoverTheRegionInsideItsRim)
{
  const Studied& s = studied();
  const PlanStudy& study = *s.study;
  const vtkSmartPointer<vtkPolyData> face = expressionPolyData(*s.model);
  const std::vector<char> under = study.faceCellsUnderPlan(face);
  ASSERT_EQ(under.size(), std::size_t(face->GetNumberOfCells()));

  // Two measures of the same area on the cylinder (arc, z): the rim's
  // polygon (shoelace), and the face cells marked, each by its own polygon.
  // They differ only by the cells the rim cuts: at most a band one cell wide.
  const std::vector<Eigen::Vector2d> rim = study.rimOnSkin();
  ASSERT_GT(rim.size(), 8u);
  const auto shoelace = [](const std::vector<Eigen::Vector2d>& ring) {
    double twice = 0.0;
    for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++)
      twice += ring[j].x() * ring[i].y() - ring[i].x() * ring[j].y();
    return 0.5 * std::abs(twice);
  };
  double perimeter = 0.0;
  for (std::size_t i = 0, j = rim.size() - 1; i < rim.size(); j = i++)
    perimeter += (rim[i] - rim[j]).norm();
  const planning::PlanPrediction& p = study.prediction();
  const seg::CylindricalFrame& frame = test::sampleFace().maps.skin.frame();
  const seg::CylindricalPoint origin = frame.toCylindrical(
    p.continuum.mesh.nodes.col(p.continuum.vertexColumns[std::size_t(p.surface.mesh.outerBorder.front())].front()));
  double marked = 0.0, largestCell = 0.0;
  int count = 0;
  vtkIdType n = 0;
  const vtkIdType* ids = nullptr;
  face->GetPolys()->InitTraversal();
  for (std::size_t cell = 0; face->GetPolys()->GetNextCell(n, ids); ++cell)
  {
    std::vector<Eigen::Vector2d> polygon;
    for (vtkIdType k = 0; k < n; ++k)
    {
      const seg::CylindricalPoint c = frame.toCylindrical(Eigen::Vector3d(face->GetPoint(ids[k])));
      polygon.emplace_back(origin.r * std::remainder(c.theta - origin.theta, 2.0 * std::numbers::pi), c.z);
    }
    const double area = shoelace(polygon);
    if (under[cell])
    {
      marked += area;
      ++count;
      largestCell = std::max(largestCell, area);
    }
  }
  const double rimArea = shoelace(rim);
  std::printf("[face around plan] rim %.0f mm^2 (perimeter %.0f mm); %d face cells under it, %.0f mm^2\n", rimArea,
              perimeter, count, marked);
  EXPECT_GT(rimArea, std::numbers::pi * 20.0 * 20.0) << "the region reaches 25 mm beyond the hole";
  EXPECT_NEAR(marked, rimArea, perimeter * std::sqrt(largestCell));
  EXPECT_LT(count, int(under.size()) / 2) << "most of the face is outside the plan";
}

TEST(PlanStudy, WithoutAFaceModelTheErrorSaysWhatToDo)
{
  PlanStudyInput input = studied().input;
  input.model.reset();
  try
  {
    PlanStudy::build(input);
    FAIL() << "no error without a face model";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("face model"), std::string::npos) << e.what();
  }
}

TEST(PlanStudy, CancelStopsTheBuild)
{
  const PlanStudyInput& input = studied().input;
  int calls = 0;
  const auto stop = PlanStudy::build(input, [&calls](double, const std::string&) { return ++calls < 2; });
  EXPECT_EQ(stop, nullptr);
}

} // namespace
} // namespace caps::expression
