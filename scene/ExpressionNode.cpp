#include "scene/ExpressionNode.h"

#include <cmath>

#include "scene/JsonFields.h"
#include "scene/SceneError.h"

namespace caps {

namespace {

/// SceneError unless every id is named and every activation is in [0, 1].
void check(const std::map<std::string, double>& activations, const std::string& expression)
{
  for (const auto& [id, a] : activations)
  {
    if (id.empty())
      throw SceneError("expression '" + expression + "' has a muscle without an id");
    if (!(a >= 0.0 && a <= 1.0))
    {
      std::string message = "the activation of muscle '";
      message += id;
      message += "' in expression '";
      message += expression;
      message += "' must be a number from 0 (at rest) to 1 (full contraction), not ";
      message += std::isnan(a) ? std::string("NaN") : std::to_string(a);
      throw SceneError(message);
    }
  }
}

} // namespace

void ExpressionNode::setMuscleSet(std::string id)
{
  muscleSet_ = std::move(id);
  modified();
}

void ExpressionNode::setDescription(std::string text)
{
  description_ = std::move(text);
  modified();
}

void ExpressionNode::setActivations(std::map<std::string, double> activations)
{
  check(activations, name());
  activations_ = std::move(activations);
  modified();
}

double ExpressionNode::activation(const std::string& muscle) const
{
  const auto it = activations_.find(muscle);
  return it == activations_.end() ? 0.0 : it->second;
}

void ExpressionNode::writeFields(nlohmann::json& j) const
{
  j["muscleSet"] = muscleSet_;
  j["description"] = description_;
  j["activations"] = activations_;
}

void ExpressionNode::readFields(const nlohmann::json& j)
{
  jsonfields::read(j, "muscleSet", muscleSet_);
  jsonfields::read(j, "description", description_);
  const nlohmann::json* a = jsonfields::find(j, "activations");
  if (!a)
    return;
  if (!a->is_object())
    throw SceneError("the activations of expression '" + name() +
                     "' must be an object of muscle id: activation (0 to 1), not " + a->dump());
  std::map<std::string, double> read;
  for (const auto& [id, value] : a->items())
  {
    if (!value.is_number())
      throw SceneError("the activation of muscle '" + id + "' in expression '" + name() +
                       "' must be a number from 0 to 1, not " + value.dump());
    read[id] = value.get<double>();
  }
  check(read, name());
  activations_ = std::move(read);
}

} // namespace caps
