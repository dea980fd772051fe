#pragma once

#include <cstddef>
#include <deque>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>

#include "scene/Node.h"

namespace caps {

class Scene;

/// @brief Undo/redo of node edits by memento: each entry keeps the node's
/// toJson() before and after the edit (small fields only, e.g. plan edits).
///
/// Entries are pushed by ScopedEdit. undo()/redo() apply fromJson, which fires
/// NodeModified. A new entry clears the redo tail; the oldest entries are
/// dropped beyond depthLimit(); removing a node drops its entries.
class UndoStack
{
public:
  struct Entry
  {
    std::string label; ///< shown in the Edit menu: "Undo Move point 3"
    NodeId nodeId;
    nlohmann::json before;
    nlohmann::json after;
    /// Set when the entry is the node's addition (pushAddition()): undo
    /// takes the node out of the scene, redo puts it back with the same id
    /// and the state @a after.
    std::optional<NodeType> added;
  };

  static constexpr std::size_t kDefaultDepthLimit = 100;

  explicit UndoStack(Scene& scene) : scene_(scene) {}
  UndoStack(const UndoStack&) = delete;
  UndoStack& operator=(const UndoStack&) = delete;

  void push(Entry entry);
  /// Records that @a node was just added to the scene, as one undoable
  /// step. Only for nodes whose whole state is in toJson() (plans,
  /// landmarks, expressions): a node with bulk data (an image, a mesh)
  /// could not be put back, so it throws SceneError, as it does for a node
  /// not in this stack's scene.
  void pushAddition(const Node& node, std::string label);

  bool canUndo() const { return applied_ > 0; }
  bool canRedo() const { return applied_ < entries_.size(); }
  /// Label of the edit undo()/redo() would apply, "" if none.
  std::string undoLabel() const;
  std::string redoLabel() const;
  /// Returns false when there is nothing to undo/redo.
  bool undo();
  bool redo();

  std::size_t size() const { return entries_.size(); }
  std::size_t depthLimit() const { return depthLimit_; }
  void setDepthLimit(std::size_t limit);

  void clear();
  /// Drops every entry of @a id (called by Scene::removeNode).
  void removeEntriesFor(const NodeId& id);

private:
  Scene& scene_;
  std::deque<Entry> entries_;
  std::size_t applied_ = 0; // entries_[0, applied_) are done, the rest can be redone
  std::size_t depthLimit_ = kDefaultDepthLimit;
};

} // namespace caps
