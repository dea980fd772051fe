#pragma once

#include <array>
#include <functional>
#include <memory>
#include <unordered_map>
#include <utility>
#include <vector>

#include "scene/Node.h"
#include "scene/SceneEvent.h"
#include "scene/UndoStack.h"

namespace caps {

/// @brief The one shared scene: owns every node, gives them stable ids and
/// tells observers about additions, removals and modifications (the MRML
/// scene of CAPS). Modules keep node ids, never pointers into each other.
class Scene
{
public:
  using Observer = std::function<void(SceneEvent, const Node&)>;

  Scene();
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  /// Takes ownership. An empty id becomes TypeN ("Volume1", ...); a duplicate
  /// id or a null node throws SceneError. Fires NodeAdded.
  Node* addNode(std::unique_ptr<Node> node);

  /// Creates a T, adds it and returns it: `auto* v = scene.add<VolumeNode>();`.
  template <class T, class... Args> T* add(Args&&... args)
  {
    return static_cast<T*>(addNode(std::make_unique<T>(std::forward<Args>(args)...)));
  }

  /// nullptr when there is no such node.
  Node* node(const NodeId& id) const;
  /// nullptr when there is no such node or it is not a T.
  template <class T> T* nodeAs(const NodeId& id) const { return dynamic_cast<T*>(node(id)); }

  /// Nodes in insertion order.
  std::vector<Node*> nodes() const;
  std::vector<Node*> nodesOfType(NodeType type) const;
  std::size_t size() const { return nodes_.size(); }

  /// Fires NodeAboutToBeRemoved, drops the node's undo entries, destroys it.
  /// False when there is no such node. The id is taken by value: callers
  /// often pass node.id(), which dies with the node.
  bool removeNode(NodeId id);
  /// Removes every node (last added first) and clears the undo stack.
  void clear();

  /// Replaces every node by @a nodes at once (loading a scene), then clears
  /// the undo stack. All nodes are installed before anyone is told, so an
  /// observer adding nodes cannot make the replacement fail half-way; then
  /// NodeAboutToBeRemoved fires for each old node (last added first; it is
  /// already out of the scene but still alive) and NodeAdded for each new one.
  /// Empty ids get TypeN ids. A null node, a node already in a scene or
  /// duplicate ids throw SceneError and leave the scene unchanged.
  void replaceAll(std::vector<std::unique_ptr<Node>> nodes);

  /// Observers may add or remove observers (themselves included) while called.
  int addObserver(Observer observer);
  void removeObserver(int tag);

  UndoStack& undoStack() { return undo_; }
  const UndoStack& undoStack() const { return undo_; }

private:
  friend class Node;
  friend class UndoStack;
  /// removeNode() without dropping the node's undo entries: undoing its addition.
  void takeOut(const NodeId& id);
  /// A node of @a type with @a id and the state @a json added again: redoing its addition.
  void putBack(NodeType type, const NodeId& id, const nlohmann::json& json);
  bool remove(const NodeId& id, bool dropUndo);
  void notify(SceneEvent event, const Node& node);
  /// True while @a node is the scene's node of that id (not removed since).
  bool holds(const NodeId& id, const Node* node) const;
  NodeId uniqueId(NodeType type);

  std::vector<std::unique_ptr<Node>> nodes_;
  std::unordered_map<NodeId, Node*> byId_;
  // Per NodeType (indexed by its value; room for types yet to come), so ids are not reused soon.
  std::array<int, 32> lastIndex_{};
  std::vector<std::pair<int, std::shared_ptr<Observer>>> observers_;
  int nextObserverTag_ = 1;
  UndoStack undo_{*this};
};

} // namespace caps
