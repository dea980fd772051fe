#pragma once

namespace caps {

/// What happened to a node, as told to scene observers.
enum class SceneEvent
{
  NodeAdded,            ///< the node is in the scene and has its id
  NodeAboutToBeRemoved, ///< the node is still valid; it is destroyed right after
  NodeModified,         ///< a field or the bulk data changed (Node::modified())
};

} // namespace caps
