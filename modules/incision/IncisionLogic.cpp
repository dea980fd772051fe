#include "modules/incision/IncisionLogic.h"

#include "scene/PlanNode.h"

#include <stdexcept>

namespace caps {

const incision::ProcedureLibrary& IncisionLogic::procedures()
{
  if (!library_)
    library_ = incision::ProcedureLibrary::load(incision::defaultProceduresFolder());
  return *library_;
}

const incision::ProcedureLibrary& IncisionLogic::reloadProcedures(const std::filesystem::path& folder)
{
  library_ = incision::ProcedureLibrary::load(folder);
  return *library_;
}

incision::IncisionPlan IncisionLogic::placeProcedure(const std::string& id, const seg::RangeMap& skin,
                                                     const incision::SkinPoint& at,
                                                     const std::map<std::string, double>& values)
{
  return incision::findProcedure(procedures(), id).place(skin, at, values);
}

incision::IncisionPlan IncisionLogic::applyRecipe(const incision::PlanRecipe& recipe, const seg::RangeMap& skin)
{
  return incision::applyRecipe(recipe, skin, procedures());
}

void IncisionLogic::writePlan(const incision::IncisionPlan& plan, PlanNode& node)
{
  node.setProcedure(plan.procedure());
  node.setGenerator(plan.generator());
  node.setParameters(plan.parameters());
  node.setCutPath(plan.cutPath());
  node.setCentre(Eigen::Vector2d(plan.centre().theta, plan.centre().z));
  const auto offsets = plan.borderOffsets();
  node.setBorderOffsets(plan.isExcision() ? std::vector<Eigen::Vector2d>(offsets.begin(), offsets.end())
                                          : std::vector<Eigen::Vector2d>{});
  std::vector<std::array<int, 4>> sutures;
  for (const auto& s : plan.writtenSutures())
    sutures.push_back({s.a[0], s.a[1], s.b[0], s.b[1]});
  node.setSutures(std::move(sutures));
}

incision::IncisionPlan IncisionLogic::readPlan(const PlanNode& node)
{
  incision::IncisionPlan plan(node.cutPath(), incision::SkinPoint{node.centre().x(), node.centre().y()});
  plan.setProcedure(node.procedure());
  plan.setGenerator(node.generator());
  plan.setParameters(node.parameters());
  const int loop = incision::holeLoopSize(plan.pointCount());
  const auto& offsets = node.borderOffsets();
  if (!offsets.empty() && int(offsets.size()) != loop)
    throw std::invalid_argument("plan '" + node.name() + "' has " + std::to_string(offsets.size()) +
                                " excision offsets but its cut has " + std::to_string(loop) +
                                " border points: the scene was edited by hand; draw the excision again.");
  for (int v = 0; v < int(offsets.size()); ++v)
    if (!offsets[std::size_t(v)].isZero(0.0))
      plan.offsetBorderPoint(v, offsets[std::size_t(v)]);
  std::vector<incision::SutureEdges> written;
  for (const auto& s : node.sutures())
    written.push_back({{s[0], s[1]}, {s[2], s[3]}});
  plan.setSutures(std::move(written));  // throws SutureError (an invalid_argument) naming the pair
  return plan;
}

void IncisionLogic::writeRecipe(const incision::PlanRecipe& recipe, PlanNode& node)
{
  nlohmann::json operations = nlohmann::json::array();
  for (const auto& o : recipe.operations)
    operations.push_back(incision::operationToJson(o));
  node.setOperations(std::move(operations));
  node.setCtSha256(recipe.ctSha256);
  node.setSoftwareVersion(recipe.softwareVersion);
}

std::optional<incision::PlanRecipe> IncisionLogic::readRecipe(const PlanNode& node)
{
  if (node.operations().empty())
    return std::nullopt;
  // Through the plan file's reader, so the scene and plan.json accept the same.
  try
  {
    return incision::recipeFromJson({{"format", "caps-plan"},
                                     {"formatVersion", incision::recipeFormatVersion},
                                     {"softwareVersion", node.softwareVersion()},
                                     {"ctSha256", node.ctSha256()},
                                     {"operations", node.operations()}});
  }
  catch (const incision::RecipeError& e)
  {
    throw incision::RecipeError(e.operation(), "plan '" + node.name() + "': " + e.what());
  }
}

} // namespace caps
