#include "modules/expression/ExpressionCommands.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <numbers>
#include <optional>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <variant>

#include <vtkPoints.h>
#include <vtkPolyData.h>

#include "modules/expression/ExpressionLogic.h"
#include "planning/PlanUnderExpression.h"
#include "modules/incision/IncisionLogic.h"
#include "planning/PlanDisplay.h"
#include "modules/report/PlanAnimation.h"
#include "modules/volumes/CommandLine.h"
#include "scene/ExpressionNode.h"
#include "scene/PlanNode.h"
#include "scene/Scene.h"
#include "scene/SceneBundle.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

const char* kExpressionUsage =
  "usage: caps expression SCENE.caps [--expression NAME] [--muscle ID=A ...]\n"
  "                       [--plan NAME] [--push X,Y,Z:DX,DY,DZ[/DX,DY,DZ ...][:R]]\n"
  "                       [--animate DIR] [--frames N] [--size WxH] [--element-size MM]\n"
  "\n"
  "The face of a saved scene under an expression (thesis §5.3): the whole face is\n"
  "meshed from the skin to the bone without a plan, the default muscles\n"
  "(data/muscles/default.muscles) are placed by the facial landmarks, the model is\n"
  "factored once and solved once per muscle, and the expression is the weighted sum\n"
  "of those responses (§3.1.2). Prints each muscle's activation and how far the skin\n"
  "moves.\n"
  "\n"
  "  --expression NAME  a built-in expression (smile, frown, pucker, sneer, fig_5_15 ...\n"
  "                     fig_5_18) or one saved in the scene; default smile\n"
  "  --muscle ID=A      adds activation A (0..1) to a muscle (zygomaticus_major_left,\n"
  "                     or zygomaticus_major for both sides); repeatable\n"
  "  --plan NAME        also the plan's predicted result under the expression (§5.4):\n"
  "                     its model's rim follows the face, the muscles act inside it, and\n"
  "                     the contour bumps within 20 mm of the cut are compared with the\n"
  "                     plan at rest (largest bump, largest change of the skin's height)\n"
  "  --push X,Y,Z:DX,DY,DZ[/DX,DY,DZ ...][:R]  with --plan: a fingertip at X,Y,Z (LPS\n"
  "                     mm, on the skin after the operation) pushes the skin within R mm\n"
  "                     (default 5) along a path: from rest through each DX,DY,DZ (mm of\n"
  "                     travel) in turn; the bumps compared the same way at its end, and\n"
  "                     the largest bump along the way\n"
  "  --animate DIR      writes the expression played and released as DIR/expression-NAME/\n"
  "                     frame-NNNN.png and, with ffmpeg, DIR/expression-NAME.mp4; with\n"
  "                     --plan also the plan's skin under it (DIR/plan-expression-NAME) and\n"
  "                     under the push there and back (DIR/plan-push)\n"
  "  --frames N         frames from rest to the full expression (default 24)\n"
  "  --size WxH         frame size in pixels (default 960x720)\n"
  "  --element-size MM  element size of the face model (default 5)\n"
  "\n"
  "Exit status: 0 done, 1 when the scene has no range maps or landmarks to build the\n"
  "face from (the message says what to do), 2 for a bad argument.\n";

struct ExpressionArgs
{
  fs::path scene;
  std::string expression = "smile";
  std::vector<std::pair<std::string, double>> muscles;
  std::string plan;
  std::optional<expression::PushPath> push;
  fs::path animate;
  int frames = 24;
  int width = 960, height = 720;
  double elementSize = 5.0;
};

bool parseTriple(const std::string& text, Eigen::Vector3d& v)
{
  std::istringstream in(text);
  char c1 = 0, c2 = 0;
  return bool(in >> v.x() >> c1 >> v.y() >> c2 >> v.z()) && c1 == ',' && c2 == ',' && in.peek() == EOF;
}

/// X,Y,Z:DX,DY,DZ[/DX,DY,DZ ...][:R], or nullopt when it is not that.
std::optional<expression::PushPath> parsePush(const std::string& text)
{
  expression::PushPath push;
  const auto colon = text.find(':');
  if (colon == std::string::npos || !parseTriple(text.substr(0, colon), push.centre))
    return std::nullopt;
  const auto second = text.find(':', colon + 1);
  std::string path = text.substr(colon + 1, second == std::string::npos ? std::string::npos : second - colon - 1);
  if (second != std::string::npos && (!cli::parseNumber(text.substr(second + 1), push.radius) || !(push.radius > 0.0)))
    return std::nullopt;
  for (std::size_t begin = 0;;)
  {
    const auto slash = path.find('/', begin);
    Eigen::Vector3d travel;
    if (!parseTriple(path.substr(begin, slash == std::string::npos ? std::string::npos : slash - begin), travel))
      return std::nullopt;
    push.waypoints.push_back(travel);
    if (slash == std::string::npos)
      break;
    begin = slash + 1;
  }
  return push;
}

/// The parsed arguments, or the error text.
std::variant<ExpressionArgs, std::string> parseArgs(const std::vector<std::string>& args)
{
  ExpressionArgs parsed;
  for (std::size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    const auto value = [&]() -> std::optional<std::string> {
      if (i + 1 >= args.size())
        return std::nullopt;
      return args[++i];
    };
    if (a == "--expression" || a == "--plan" || a == "--animate" || a == "--muscle" || a == "--push" ||
        a == "--frames" || a == "--size" || a == "--element-size")
    {
      const auto v = value();
      if (!v)
        return a + " needs a value";
      if (a == "--expression")
        parsed.expression = *v;
      else if (a == "--plan")
        parsed.plan = *v;
      else if (a == "--animate")
        parsed.animate = *v;
      else if (a == "--muscle")
      {
        const auto eq = v->find('=');
        double activation = 0.0;
        if (eq == std::string::npos || !cli::parseNumber(v->substr(eq + 1), activation) || activation < 0.0 ||
            activation > 1.0)
          return "--muscle needs ID=A with A between 0 and 1 (got " + *v + ")";
        parsed.muscles.emplace_back(v->substr(0, eq), activation);
      }
      else if (a == "--push")
      {
        if (auto push = parsePush(*v))
          parsed.push = *push;
        else
          return "--push needs X,Y,Z:DX,DY,DZ[/DX,DY,DZ ...][:R] in mm, R above 0 (got " + *v + ")";
      }
      else if (a == "--frames")
      {
        double n = 0.0;
        if (!cli::parseNumber(*v, n) || n < 2 || n > 1000)
          return "--frames needs a number from 2 to 1000";
        parsed.frames = int(n);
      }
      else if (a == "--size")
      {
        if (std::sscanf(v->c_str(), "%dx%d", &parsed.width, &parsed.height) != 2)
          return "--size needs WxH in pixels, e.g. 960x720";
      }
      else if (!cli::parseNumber(*v, parsed.elementSize) || parsed.elementSize < 1.0 || parsed.elementSize > 20.0)
        return "--element-size needs a length from 1 to 20 mm";
    }
    else if (!a.empty() && a[0] == '-')
      return "unknown option " + a;
    else if (parsed.scene.empty())
      parsed.scene = a;
    else
      return "one scene only (got " + parsed.scene.string() + " and " + a + ")";
  }
  if (parsed.scene.empty())
    return "give the scene: caps expression SCENE.caps";
  if (parsed.push && parsed.plan.empty())
    return "--push acts on a plan: give --plan NAME too";
  return parsed;
}

/// The activations of the expression asked for (built-in first, then saved), plus the --muscle additions.
Eigen::VectorXd activationsOf(const ExpressionArgs& args, ExpressionLogic& logic,
                              const std::vector<expression::FittedMuscle>& muscles)
{
  Eigen::VectorXd a;
  const auto& builtIn = expression::builtInExpressions();
  const auto it = std::find_if(builtIn.begin(), builtIn.end(),
                               [&](const expression::ExpressionDefinition& e) { return e.name == args.expression; });
  if (it != builtIn.end())
    a = expression::expressionActivations(*it, muscles);
  else if (const ExpressionNode* saved = logic.savedExpression(args.expression))
    a = expression::expressionActivations(saved->activations(), muscles);
  else
  {
    std::string names;
    for (const auto& e : builtIn)
      names += (names.empty() ? "" : ", ") + e.name;
    for (const ExpressionNode* n : logic.savedExpressions())
      names += ", " + n->name();
    throw std::invalid_argument("there is no expression \"" + args.expression + "\"; there are: " + names);
  }
  for (const auto& [id, value] : args.muscles)
  {
    bool found = false;
    for (std::size_t k = 0; k < muscles.size(); ++k)
      if (muscles[k].id == id || muscles[k].definition == id)
      {
        a[Eigen::Index(k)] = std::clamp(a[Eigen::Index(k)] + value, 0.0, 1.0);
        found = true;
      }
    if (!found)
      throw std::invalid_argument("there is no muscle \"" + id + "\" in the muscle set");
  }
  return a;
}

void printComparison(std::ostream& out, const char* what, const expression::ContourComparison& c)
{
  char line[400];
  std::snprintf(line, sizeof line,
                "%s: %d skin vertices within 20 mm of the cut; largest bump %.2f mm at rest, %.2f mm %s (%+.2f mm, "
                "%s); the skin's height changes by up to %.2f mm at (%.1f, %.1f, %.1f)\n",
                what, c.rest.vertices, c.rest.largest, c.loaded.largest, what, c.bumpChange(),
                c.bumpChange() > 0.05    ? "the bumps get worse"
                : c.bumpChange() < -0.05 ? "the bumps ease"
                                         : "about the same",
                c.largestHeightChange, c.where.x(), c.where.y(), c.where.z());
  out << line;
}

/// @a surface with its points moved to @a x (its arrays kept).
vtkSmartPointer<vtkPolyData> movedTo(vtkPolyData* surface, const Eigen::Matrix3Xd& x)
{
  auto out = vtkSmartPointer<vtkPolyData>::New();
  out->DeepCopy(surface);
  for (Eigen::Index v = 0; v < x.cols(); ++v)
    out->GetPoints()->SetPoint(v, x.col(v).data());
  out->GetPoints()->Modified();
  return out;
}

void printAnimation(const render::AnimationResult& result, std::ostream& out, std::ostream& err)
{
  out << "Wrote " << result.prePost.frames << " frames to " << result.prePost.folder.string() << "\n";
  if (!result.prePost.video.empty())
    out << "Wrote " << result.prePost.video.string() << "\n";
  if (!result.videoMessage.empty())
    err << result.videoMessage << "\n";
}

/// The plan's skin under the expression, played and released, and under the
/// push along its path and back, from the camera facing the plan.
void writePlanAnimations(const ExpressionArgs& a, const expression::ExpressionModelInput& input,
                         const planning::PlanPrediction& prediction, double planTheta,
                         const expression::PlanExpressionResponses& onPlan, const Eigen::VectorXd& activations,
                         const expression::PushResponses* pushed, std::ostream& out, std::ostream& err)
{
  const planning::SkinShade shade = planning::skinShadeOfCt(input.ct, input.skin);
  if (!shade.note.empty())
    err << "The plan's animation: " << shade.note << "\n";
  const planning::PlanDisplay display = planning::buildPlanDisplay(prediction, input.skin, shade.map());
  const vtkSmartPointer<vtkPolyData> atRest = planning::planDisplayPolyData(display, 1.0);
  const seg::CylindricalFrame& frame = input.skin.frame();
  const Eigen::Vector3d toCamera = frame.radialDirection(planTheta), up = frame.direction();
  render::AnimationOptions options;
  options.width = a.width;
  options.height = a.height;
  const fem::Mesh& mesh = prediction.continuum.mesh;
  Eigen::Matrix3Xd x;
  const expression::ExpressionSurface underMuscles(mesh, display.surface, onPlan.responses(), prediction.displacements);
  underMuscles.positions(activations, display.rangeDetail, x);
  printAnimation(render::writeMorphAnimation(atRest, movedTo(atRest, x), "plan-expression-" + a.expression, toCamera,
                                             up, a.animate, a.frames, true, options, cli::consoleProgress(err)),
                 out, err);
  if (!pushed || !a.push)
    return;
  const expression::ExpressionSurface underPush(mesh, display.surface, pushed->responses(), prediction.displacements);
  std::vector<vtkSmartPointer<vtkPolyData>> frames;
  for (int k = 0; k < 2 * a.frames - 2; ++k)
  {
    const int along = k < a.frames ? k : 2 * (a.frames - 1) - k;
    underPush.positions(a.push->travelAt(double(along) / (a.frames - 1)), display.rangeDetail, x);
    frames.push_back(movedTo(atRest, x));
  }
  printAnimation(
    render::writeSurfaceAnimation(frames, "plan-push", toCamera, up, a.animate, options, cli::consoleProgress(err)),
    out, err);
}

int runExpression(ModuleLogic& base, const std::vector<std::string>& args, std::ostream& out, std::ostream& err)
{
  const auto parsed = parseArgs(args);
  if (const auto* problem = std::get_if<std::string>(&parsed))
  {
    err << "caps expression: " << *problem << "\n" << kExpressionUsage;
    return 2;
  }
  const ExpressionArgs& a = std::get<ExpressionArgs>(parsed);
  Scene& scene = base.scene();
  try
  {
    if (!fs::is_directory(a.scene))
      throw std::invalid_argument("there is no scene at " + a.scene.string() +
                                  ": give the NAME.caps folder that the workstation or caps demo saved");
    loadSceneBundle(scene, a.scene);
    ExpressionLogic logic(scene);
    expression::ExpressionModelInput input = logic.modelInput();
    input.face.elementSize = a.elementSize;
    const auto model = expression::buildExpressionModel(input, cli::consoleProgress(err));
    const Eigen::VectorXd activations = activationsOf(a, logic, model->muscles);

    char line[300];
    std::snprintf(line, sizeof line,
                  "Face model: %zu quads, %ld nodes, %ld DOF; built in %.2f s (mesh %.2f, factor %.2f, %ld muscle "
                  "responses %.2f); landmarks: %s\n",
                  model->face.surface.polygons.size(), long(model->face.continuum.mesh.nodeCount()),
                  long(model->face.continuum.mesh.dofCount()), model->totalSeconds, model->meshSeconds,
                  model->factorSeconds, long(model->responses.muscleCount()), model->responseSeconds,
                  model->landmarkSource.c_str());
    out << line;
    out << "Expression \"" << a.expression << "\":\n";
    for (std::size_t k = 0; k < model->muscles.size(); ++k)
      if (activations[Eigen::Index(k)] > 0.0)
      {
        std::snprintf(line, sizeof line, "  %-46s %5.0f %%\n", model->muscles[k].title.c_str(),
                      100.0 * activations[Eigen::Index(k)]);
        out << line;
      }
    vtkSmartPointer<vtkPolyData> rest = expression::expressionPolyData(*model);
    vtkSmartPointer<vtkPolyData> full = expression::expressionPolyData(*model);
    Eigen::Matrix3Xd scratch;
    const double moved = expression::applyActivations(*model, activations, full, scratch);
    std::snprintf(line, sizeof line, "The skin moves by up to %.2f mm.\n", moved);
    out << line;

    if (!a.plan.empty())
    {
      const PlanNode* planNode = nullptr;
      for (Node* n : scene.nodesOfType(NodeType::Plan))
        if (n->name() == a.plan)
          planNode = static_cast<const PlanNode*>(n);
      if (!planNode)
        throw std::invalid_argument("the scene has no plan \"" + a.plan + "\"");
      planning::SimulationOptions options = IncisionLogic::simulationOptions(*planNode);
      options.threads = 2;
      err << "Predicting " << a.plan << "\n";
      const planning::PlanPrediction prediction =
        planning::simulatePlan(input.skin, input.bone, IncisionLogic::readPlan(*planNode), options);
      std::vector<std::vector<fem::Muscle>> functions;
      for (const auto& m : model->muscles)
        functions.push_back(m.functions);
      const expression::PlanExpressionResponses onPlan(prediction, model->face.continuum.mesh, model->responses,
                                                       functions);
      const seg::CylindricalFrame& frame = input.skin.frame();
      printComparison(
        out, "under the expression",
        expression::compareContours(prediction, frame, prediction.displacements, onPlan.displacement(activations)));
      std::optional<expression::PushResponses> pushed;
      if (a.push)
      {
        pushed.emplace(prediction, a.push->centre, a.push->radius);
        printComparison(out, "pushed",
                        expression::compareContours(prediction, frame, prediction.displacements,
                                                    pushed->displacement(a.push->travelAt(1.0))));
        // The bumps may peak part way along a bent path, not at its end.
        double peak = 0.0, peakAt = 0.0;
        constexpr int kStations = 10;
        for (int i = 1; i <= kStations; ++i)
        {
          const double at = double(i) / kStations;
          const double largest =
            expression::contourBumps(prediction, frame, pushed->displacement(a.push->travelAt(at))).largest;
          if (largest > peak)
          {
            peak = largest;
            peakAt = at;
          }
        }
        std::snprintf(line, sizeof line,
                      "Along the push (%.1f mm of path through %zu corner%s, %zu skin nodes under the fingertip): the "
                      "largest bump peaks at %.2f mm, %.0f %% of the way\n",
                      a.push->length(), a.push->waypoints.size(), a.push->waypoints.size() == 1 ? "" : "s",
                      pushed->pushedNodes().size(), peak, 100.0 * peakAt);
        out << line;
      }
      if (!a.animate.empty())
        writePlanAnimations(a, input, prediction, IncisionLogic::readPlan(*planNode).centre().theta, onPlan,
                            activations, pushed ? &*pushed : nullptr, out, err);
    }

    if (!a.animate.empty())
    {
      render::AnimationOptions options;
      options.width = a.width;
      options.height = a.height;
      const seg::CylindricalFrame& frame = input.skin.frame();
      const auto result = render::writeMorphAnimation(rest, full, "expression-" + a.expression,
                                                      frame.radialDirection(-0.5 * std::numbers::pi), frame.direction(),
                                                      a.animate, a.frames, true, options, cli::consoleProgress(err));
      printAnimation(result, out, err);
    }
    return 0;
  }
  catch (const std::exception& e)
  {
    err << "caps expression: " << e.what() << "\n";
    return 1;
  }
}

} // namespace

std::vector<ModuleCommand> expressionCommands()
{
  return {{"expression", "the face under an expression; a plan under it or under a push (§5.3, §5.4)", kExpressionUsage,
           runExpression}};
}

} // namespace caps
