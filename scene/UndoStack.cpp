#include "scene/UndoStack.h"

#include "scene/Scene.h"

namespace caps {

void UndoStack::push(Entry entry) {
  entries_.erase(entries_.begin() + static_cast<std::ptrdiff_t>(applied_), entries_.end());
  entries_.push_back(std::move(entry));
  setDepthLimit(depthLimit_);
  applied_ = entries_.size();
}

std::string UndoStack::undoLabel() const { return canUndo() ? entries_[applied_ - 1].label : std::string(); }

std::string UndoStack::redoLabel() const { return canRedo() ? entries_[applied_].label : std::string(); }

bool UndoStack::undo() {
  if (!canUndo()) return false;
  const Entry& e = entries_[applied_ - 1];
  --applied_;
  if (Node* node = scene_.node(e.nodeId)) node->fromJson(e.before);
  return true;
}

bool UndoStack::redo() {
  if (!canRedo()) return false;
  const Entry& e = entries_[applied_];
  ++applied_;
  if (Node* node = scene_.node(e.nodeId)) node->fromJson(e.after);
  return true;
}

void UndoStack::setDepthLimit(std::size_t limit) {
  depthLimit_ = limit;
  while (entries_.size() > depthLimit_) {
    entries_.pop_front();
    if (applied_ > 0) --applied_;
  }
}

void UndoStack::clear() {
  entries_.clear();
  applied_ = 0;
}

void UndoStack::removeEntriesFor(const NodeId& id) {
  std::deque<Entry> kept;
  std::size_t applied = 0;
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    if (entries_[i].nodeId == id) continue;
    if (i < applied_) ++applied;
    kept.push_back(std::move(entries_[i]));
  }
  entries_ = std::move(kept);
  applied_ = applied;
}

}  // namespace caps
