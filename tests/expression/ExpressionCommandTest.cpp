// `caps expression` on the demo scene: the smile's muscles and the skin's
// movement printed, the Z-plasty compared under it, the animation written;
// the skin movement printed equals the largest movement of the face model's
// display skin computed here through the library for the same expression;
// bad arguments get a message and exit status 2, an unknown expression the
// list of those there are.

#include <gtest/gtest.h>

#include <vtkPolyData.h>

#include <cstdio>
#include <filesystem>
#include <regex>
#include <string>

#include "TestPaths.h"
#include "app/RunProcess.h"
#include "modules/expression/ExpressionLogic.h"
#include "report/DemoScene.h"
#include "scene/Scene.h"
#include "scene/SceneBundle.h"
#include "scene/SurfaceNode.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

test::ProcessResult runExpression(const std::string& args)
{
  return test::runProcess(test::quoted(CAPS_EXECUTABLE) + " expression " +
                          test::quoted((test::reportDemoFolder() / "sample.caps").string()) + " " + args);
}

TEST(ExpressionCommand, TheSmileThePlanUnderItAndItsAnimation)
{
  const fs::path out = test::scratchFolder();
  // The fingertip: the point of the Z-plasty's predicted skin nearest its middle.
  Scene saved;
  loadSceneBundle(saved, test::reportDemoFolder() / "sample.caps");
  const SurfaceNode* after = nullptr;
  for (Node* n : saved.nodesOfType(NodeType::Surface))
    if (n->name() == "Z-plasty 1 skin after")
      after = static_cast<const SurfaceNode*>(n);
  ASSERT_TRUE(after && after->polyData());
  vtkPolyData* skin = after->polyData();
  Eigen::Vector3d middle = Eigen::Vector3d::Zero();
  for (vtkIdType i = 0; i < skin->GetNumberOfPoints(); ++i)
    middle += Eigen::Vector3d(skin->GetPoint(i));
  middle /= double(skin->GetNumberOfPoints());
  Eigen::Vector3d tip = Eigen::Vector3d(skin->GetPoint(0));
  for (vtkIdType i = 0; i < skin->GetNumberOfPoints(); ++i)
    if ((Eigen::Vector3d(skin->GetPoint(i)) - middle).norm() < (tip - middle).norm())
      tip = Eigen::Vector3d(skin->GetPoint(i));
  char push[200];
  std::snprintf(push, sizeof push, "%.3f,%.3f,%.3f:0,0,4/2,0,4:6", tip.x(), tip.y(), tip.z());
  std::printf("[push] --push %s\n", push);

  const auto r = runExpression("--expression smile --plan 'Z-plasty 1' --element-size 8 --animate " +
                               test::quoted(out.string()) + " --frames 3 --size 160x120 --push " + push);
  ASSERT_EQ(r.exitCode, 0) << r.output;
  for (const char* expected : {"Zygomaticus major (left)", "100 %", "under the expression: ", "largest bump",
                               "pushed: ", "Along the push (6.0 mm of path through 2 corners"})
    EXPECT_NE(r.output.find(expected), std::string::npos) << expected << " in\n" << r.output;
  // Each played there and back: 0 1 2 (peak) 3.
  for (const char* animation : {"expression-smile", "plan-expression-smile", "plan-push"})
  {
    EXPECT_TRUE(fs::exists(out / animation / "frame-0003.png")) << animation << "\n" << r.output;
    EXPECT_FALSE(fs::exists(out / animation / "frame-0004.png")) << animation;
  }
  // The bumps along the path peak no lower than at its end (the end is one of the stations).
  std::smatch pushed, along;
  ASSERT_TRUE(std::regex_search(r.output, pushed, std::regex("pushed: .* ([0-9.]+) mm pushed"))) << r.output;
  ASSERT_TRUE(std::regex_search(r.output, along, std::regex("peaks at ([0-9.]+) mm"))) << r.output;
  EXPECT_GE(std::stod(along[1].str()) + 0.005, std::stod(pushed[1].str()));

  // The movement printed, against the library on the same scene.
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("The skin moves by up to ([0-9.]+) mm"))) << r.output;
  Scene scene;
  loadSceneBundle(scene, test::reportDemoFolder() / "sample.caps");
  ExpressionLogic logic(scene);
  expression::ExpressionModelInput input = logic.modelInput();
  input.face.elementSize = 8.0;
  const auto model = expression::buildExpressionModel(input);
  ASSERT_TRUE(model);
  const auto& smile = expression::builtInExpressions();
  const auto it = std::find_if(smile.begin(), smile.end(), [](const auto& e) { return e.name == "smile"; });
  ASSERT_NE(it, smile.end());
  Eigen::Matrix3Xd x;
  model->positions(expression::expressionActivations(*it, model->muscles), x);
  Eigen::Matrix3Xd rest;
  model->positions(Eigen::VectorXd::Zero(model->responses.muscleCount()), rest);
  EXPECT_NEAR(std::stod(m[1].str()), (x - rest).colwise().norm().maxCoeff(), 0.006);
}

TEST(ExpressionCommand, BadArgumentsGetAMessage)
{
  auto r = runExpression("--muscle zygomaticus_major=2");
  EXPECT_EQ(r.exitCode, 2) << r.output;
  EXPECT_NE(r.output.find("between 0 and 1"), std::string::npos) << r.output;
  r = runExpression("--push 1,2,3:0,0,5");
  EXPECT_EQ(r.exitCode, 2) << r.output;
  EXPECT_NE(r.output.find("--plan"), std::string::npos) << r.output;
  r = runExpression("--plan 'Z-plasty 1' --push 1,2,3:0,0,5/0,0:4");
  EXPECT_EQ(r.exitCode, 2) << r.output;
  EXPECT_NE(r.output.find("X,Y,Z:DX,DY,DZ[/DX,DY,DZ ...][:R]"), std::string::npos) << r.output;
  r = runExpression("--plan 'Z-plasty 1' --push 1,2,3:0,0,5:-1");
  EXPECT_EQ(r.exitCode, 2) << r.output;
  r = runExpression("--expression grin --element-size 10");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("smile"), std::string::npos) << r.output;
  r = runExpression("--plan 'No such plan' --element-size 10");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("no plan \"No such plan\""), std::string::npos) << r.output;
}

} // namespace
} // namespace caps
