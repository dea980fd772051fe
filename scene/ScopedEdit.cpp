#include "scene/ScopedEdit.h"

#include "scene/Scene.h"
#include "scene/SceneError.h"

namespace caps {

ScopedEdit::ScopedEdit(Scene& scene, NodeId id, std::string label)
  : scene_(scene), id_(std::move(id)), label_(std::move(label))
{
  Node* node = scene_.node(id_);
  if (!node)
    throw SceneError("cannot edit node '" + id_ + "': it is not in the scene");
  before_ = node->toJson();
}

ScopedEdit::~ScopedEdit()
{
  // A destructor must not throw: an edit that cannot be recorded is simply not undoable.
  try
  {
    Node* node = scene_.node(id_);
    if (!node)
      return;
    nlohmann::json after = node->toJson();
    if (after != before_)
      scene_.undoStack().push({label_, id_, std::move(before_), std::move(after), std::nullopt});
  }
  catch (...)
  {}
}

} // namespace caps
