#include "scene/Scene.h"

#include <algorithm>
#include <set>

#include "scene/SceneError.h"

namespace caps {

Scene::Scene() = default;

Scene::~Scene()
{
  for (auto& n : nodes_)
    n->scene_ = nullptr;
}

NodeId Scene::uniqueId(NodeType type)
{
  int& last = lastIndex_.at(static_cast<std::size_t>(type));
  const std::string prefix = nodeTypeToString(type);
  NodeId id;
  do
  {
    id = prefix + std::to_string(++last);
  } while (byId_.count(id));
  return id;
}

Node* Scene::addNode(std::unique_ptr<Node> node)
{
  if (!node)
    throw SceneError("cannot add an empty node to the scene");
  if (node->scene_)
    throw SceneError("node '" + node->id() + "' is already in a scene");
  if (node->id_.empty())
    node->id_ = uniqueId(node->type());
  if (byId_.count(node->id_))
    throw SceneError("the scene already has a node with id '" + node->id_ + "'; ids must be unique");
  Node* raw = node.get();
  raw->scene_ = this;
  byId_[raw->id_] = raw;
  nodes_.push_back(std::move(node));
  const NodeId id = raw->id_;
  notify(SceneEvent::NodeAdded, *raw);
  return this->node(id); // an observer may have removed it again
}

Node* Scene::node(const NodeId& id) const
{
  auto it = byId_.find(id);
  return it == byId_.end() ? nullptr : it->second;
}

std::vector<Node*> Scene::nodes() const
{
  std::vector<Node*> out;
  out.reserve(nodes_.size());
  for (const auto& n : nodes_)
    out.push_back(n.get());
  return out;
}

std::vector<Node*> Scene::nodesOfType(NodeType type) const
{
  std::vector<Node*> out;
  for (const auto& n : nodes_)
    if (n->type() == type)
      out.push_back(n.get());
  return out;
}

bool Scene::removeNode(NodeId id)
{
  return remove(id, true);
}

void Scene::takeOut(const NodeId& id)
{
  remove(id, false);
}

void Scene::putBack(NodeType type, const NodeId& id, const nlohmann::json& json)
{
  if (node(id))
    return; // already there (cannot happen through the stack; harmless)
  std::unique_ptr<Node> n = Node::create(type);
  n->id_ = id;
  n->fromJson(json); // not in a scene yet: no notification
  addNode(std::move(n));
}

bool Scene::remove(const NodeId& idToRemove, bool dropUndo)
{
  const NodeId id = idToRemove; // a copy: the caller's may die with the node
  Node* raw = node(id);
  if (!raw)
    return false;
  notify(SceneEvent::NodeAboutToBeRemoved, *raw);
  // An observer may have removed it already (raw then dangles: compare only).
  if (!holds(id, raw))
    return true;
  auto it = std::find_if(nodes_.begin(), nodes_.end(), [&](const auto& n) { return n.get() == raw; });
  if (dropUndo)
    undo_.removeEntriesFor(id);
  byId_.erase(id);
  std::unique_ptr<Node> dead = std::move(*it);
  nodes_.erase(it);
  dead->scene_ = nullptr;
  return true;
}

void Scene::clear()
{
  while (!nodes_.empty())
    removeNode(nodes_.back()->id());
  undo_.clear();
}

void Scene::replaceAll(std::vector<std::unique_ptr<Node>> nodes)
{
  std::set<NodeId> ids;
  for (const auto& n : nodes)
  {
    if (!n)
      throw SceneError("cannot add an empty node to the scene");
    if (n->scene_)
      throw SceneError("node '" + n->id() + "' is already in a scene");
    if (!n->id_.empty() && !ids.insert(n->id_).second)
      throw SceneError("the new nodes have the id '" + n->id_ + "' twice; ids must be unique");
  }

  // Install everything first, then tell the observers.
  std::vector<std::unique_ptr<Node>> old = std::move(nodes_);
  nodes_.clear();
  byId_.clear();
  undo_.clear();
  for (auto& n : old)
    n->scene_ = nullptr;
  for (auto& n : nodes)
    if (!n->id_.empty())
      byId_[n->id_] = n.get();
  std::vector<std::pair<NodeId, Node*>> added;
  for (auto& n : nodes)
  {
    if (n->id_.empty())
    {
      n->id_ = uniqueId(n->type());
      byId_[n->id_] = n.get();
    }
    n->scene_ = this;
    added.emplace_back(n->id_, n.get());
    nodes_.push_back(std::move(n));
  }

  for (auto it = old.rbegin(); it != old.rend(); ++it)
    notify(SceneEvent::NodeAboutToBeRemoved, **it);
  old.clear();
  // An observer may remove a new node before it is announced: skip those.
  for (const auto& [id, raw] : added)
    if (holds(id, raw))
      notify(SceneEvent::NodeAdded, *raw);
}

int Scene::addObserver(Observer observer)
{
  const int tag = nextObserverTag_++;
  observers_.emplace_back(tag, std::make_shared<Observer>(std::move(observer)));
  return tag;
}

void Scene::removeObserver(int tag)
{
  std::erase_if(observers_, [tag](const auto& o) { return o.first == tag; });
}

bool Scene::holds(const NodeId& id, const Node* node) const
{
  auto it = byId_.find(id);
  return it != byId_.end() && it->second == node;
}

void Scene::notify(SceneEvent event, const Node& node)
{
  // An observer may remove (destroy) the node: the others are then not told.
  // Nodes already out of the scene (replaceAll's old ones) are kept alive by
  // the caller, so everybody is told about them.
  const NodeId id = node.id();
  const bool inScene = holds(id, &node);
  // Iterate over a copy so callbacks may add or remove observers; an observer
  // removed during this notification is not called afterwards.
  const auto snapshot = observers_;
  for (const auto& [tag, fn] : snapshot)
  {
    if (inScene && !holds(id, &node))
      return;
    const bool stillThere =
      std::any_of(observers_.begin(), observers_.end(), [t = tag](const auto& o) { return o.first == t; });
    if (stillThere)
      (*fn)(event, node);
  }
}

} // namespace caps
