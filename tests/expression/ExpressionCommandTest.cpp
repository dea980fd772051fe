// `caps expression` on the demo scene: the smile's muscles and the skin's
// movement printed, the Z-plasty compared under it, the animation written;
// the skin movement printed equals the largest movement of the face model's
// display skin computed here through the library for the same expression;
// bad arguments get a message and exit status 2, an unknown expression the
// list of those there are.

#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <string>

#include "TestPaths.h"
#include "app/RunProcess.h"
#include "modules/expression/ExpressionLogic.h"
#include "report/DemoScene.h"
#include "scene/Scene.h"
#include "scene/SceneBundle.h"

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
  const auto r = runExpression("--expression smile --plan 'Z-plasty 1' --element-size 8 --animate " +
                               test::quoted(out.string()) + " --frames 3 --size 160x120");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  for (const char* expected : {"Zygomaticus major (left)", "100 %", "under the expression: ", "largest bump"})
    EXPECT_NE(r.output.find(expected), std::string::npos) << expected << " in\n" << r.output;
  EXPECT_TRUE(fs::exists(out / "expression-smile" / "frame-0003.png")) << r.output; // 0 1 2 (peak) 3
  EXPECT_FALSE(fs::exists(out / "expression-smile" / "frame-0004.png"));

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
  r = runExpression("--expression grin --element-size 10");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("smile"), std::string::npos) << r.output;
  r = runExpression("--plan 'No such plan' --element-size 10");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("no plan \"No such plan\""), std::string::npos) << r.output;
}

} // namespace
} // namespace caps
