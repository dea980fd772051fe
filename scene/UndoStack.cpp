#include "scene/UndoStack.h"

#include "scene/Scene.h"
#include "scene/SceneError.h"

namespace caps {

void UndoStack::push(Entry entry)
{
  entries_.erase(entries_.begin() + static_cast<std::ptrdiff_t>(applied_), entries_.end());
  entries_.push_back(std::move(entry));
  setDepthLimit(depthLimit_);
  applied_ = entries_.size();
}

void UndoStack::pushAddition(const Node& node, std::string label)
{
  if (node.scene() != &scene_)
    throw SceneError("cannot record the addition of '" + node.id() + "': it is not in this scene");
  if (!node.bulkFileExtension().empty())
    throw SceneError("cannot record the addition of '" + node.id() +
                     "' for undo: its bulk data would not come back with redo");
  Entry entry;
  entry.label = std::move(label);
  entry.nodeId = node.id();
  entry.after = node.toJson();
  entry.added = node.type();
  push(std::move(entry));
}

std::string UndoStack::undoLabel() const
{
  return canUndo() ? entries_[applied_ - 1].label : std::string();
}

std::string UndoStack::redoLabel() const
{
  return canRedo() ? entries_[applied_].label : std::string();
}

bool UndoStack::undo()
{
  if (!canUndo())
    return false;
  // A copy: taking a node out tells observers, who may push edits of their own.
  const Entry e = entries_[applied_ - 1];
  --applied_;
  if (e.added)
    scene_.takeOut(e.nodeId);
  else if (Node* node = scene_.node(e.nodeId))
    node->fromJson(e.before);
  return true;
}

bool UndoStack::redo()
{
  if (!canRedo())
    return false;
  const Entry e = entries_[applied_];
  ++applied_;
  if (e.added)
    scene_.putBack(*e.added, e.nodeId, e.after);
  else if (Node* node = scene_.node(e.nodeId))
    node->fromJson(e.after);
  return true;
}

void UndoStack::setDepthLimit(std::size_t limit)
{
  depthLimit_ = limit;
  while (entries_.size() > depthLimit_)
  {
    entries_.pop_front();
    if (applied_ > 0)
      --applied_;
  }
}

void UndoStack::clear()
{
  entries_.clear();
  applied_ = 0;
}

void UndoStack::removeEntriesFor(const NodeId& id)
{
  std::deque<Entry> kept;
  std::size_t applied = 0;
  for (std::size_t i = 0; i < entries_.size(); ++i)
  {
    if (entries_[i].nodeId == id)
      continue;
    if (i < applied_)
      ++applied;
    kept.push_back(std::move(entries_[i]));
  }
  entries_ = std::move(kept);
  applied_ = applied;
}

} // namespace caps
