#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace caps {

/// The kinds of node the scene holds. The string form is what scene.json
/// stores, so existing names must never change.
enum class NodeType
{
  Volume,
  LabelMap,
  Surface,
  RangeMap,
  Plan,
  FeMesh,
  Solution,
  Snapshot,
  Landmarks,
  Expression
};

/// "Volume", "LabelMap", ... (also the prefix of generated node ids).
std::string nodeTypeToString(NodeType type);

/// Inverse of nodeTypeToString; std::nullopt for a name this build does not know.
std::optional<NodeType> nodeTypeFromString(std::string_view name);

} // namespace caps
