#pragma once

#include <map>
#include <string>

#include "scene/Node.h"

namespace caps {

/// @brief A named facial expression (thesis §5.3, Fig.
/// 5.15–5.18): how strongly each muscle of a muscle set contracts.
///
/// Activations are per fitted muscle id ("zygomaticus_major_left"), 0 at
/// rest to 1 the muscle file's strong contraction; muscles not listed are at
/// rest. The face model of the Expression module turns them into a skin
/// shape by superposition (§3.1.2). Small fields only.
class ExpressionNode : public Node
{
public:
  NodeType type() const override { return NodeType::Expression; }

  /// The muscle set the ids belong to ("default": data/muscles/default.muscles).
  const std::string& muscleSet() const { return muscleSet_; }
  void setMuscleSet(std::string id);

  const std::string& description() const { return description_; }
  void setDescription(std::string text);

  /// Muscle id → activation in [0, 1].
  const std::map<std::string, double>& activations() const { return activations_; }
  /// Throws SceneError for an empty id or an activation outside [0, 1] (or NaN).
  void setActivations(std::map<std::string, double> activations);
  /// The activation of @a muscle, 0 when not listed.
  double activation(const std::string& muscle) const;

protected:
  void writeFields(nlohmann::json& j) const override;
  void readFields(const nlohmann::json& j) override;

private:
  std::string muscleSet_ = "default";
  std::string description_;
  std::map<std::string, double> activations_;
};

} // namespace caps
