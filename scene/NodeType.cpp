#include "scene/NodeType.h"

#include <array>
#include <utility>

namespace caps {

namespace {
constexpr std::array<std::pair<NodeType, std::string_view>, 10> kNames{{
  {NodeType::Volume, "Volume"},
  {NodeType::LabelMap, "LabelMap"},
  {NodeType::Surface, "Surface"},
  {NodeType::RangeMap, "RangeMap"},
  {NodeType::Plan, "Plan"},
  {NodeType::FeMesh, "FeMesh"},
  {NodeType::Solution, "Solution"},
  {NodeType::Snapshot, "Snapshot"},
  {NodeType::Landmarks, "Landmarks"},
  {NodeType::Expression, "Expression"},
}};
} // namespace

std::string nodeTypeToString(NodeType type)
{
  for (const auto& [t, name] : kNames)
    if (t == type)
      return std::string(name);
  return "Unknown";
}

std::optional<NodeType> nodeTypeFromString(std::string_view name)
{
  for (const auto& [t, n] : kNames)
    if (n == name)
      return t;
  return std::nullopt;
}

} // namespace caps
