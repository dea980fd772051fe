#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "scene/Node.h"

namespace caps {

class Scene;

/// @brief Records one undoable edit of a node.
///
/// Captures the node's toJson() at construction; at destruction, if the node
/// still exists and its state changed, pushes {label, id, before, after} on
/// the scene's undo stack.
/// @code
///   { ScopedEdit edit(scene, planId, "Move point 3"); plan->setCutPoint(3, p); }
/// @endcode
class ScopedEdit
{
public:
  /// Throws SceneError when the scene has no node @a id.
  ScopedEdit(Scene& scene, NodeId id, std::string label);
  ~ScopedEdit();
  ScopedEdit(const ScopedEdit&) = delete;
  ScopedEdit& operator=(const ScopedEdit&) = delete;

private:
  Scene& scene_;
  NodeId id_;
  std::string label_;
  nlohmann::json before_;
};

} // namespace caps
