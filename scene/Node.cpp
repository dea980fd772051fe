#include "scene/Node.h"

#include "scene/ExpressionNode.h"
#include "scene/FeMeshNode.h"
#include "scene/JsonFields.h"
#include "scene/LabelMapNode.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/SceneError.h"
#include "scene/SnapshotNode.h"
#include "scene/LandmarksNode.h"
#include "scene/SolutionNode.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"

namespace caps {

Node::~Node() = default;

void Node::setId(NodeId id)
{
  if (scene_)
    throw SceneError("node '" + id_ + "' is already in a scene; its id cannot change");
  id_ = std::move(id);
}

void Node::setName(std::string name)
{
  name_ = std::move(name);
  modified();
}

nlohmann::json Node::toJson() const
{
  nlohmann::json j;
  j["id"] = id_;
  j["type"] = nodeTypeToString(type());
  j["name"] = name_;
  writeFields(j);
  return j;
}

void Node::fromJson(const nlohmann::json& j)
{
  jsonfields::read(j, "name", name_);
  readFields(j);
  modified();
}

void Node::writeBulk(const std::filesystem::path& file) const
{
  throw SceneError("node '" + id_ + "' has no bulk data to write to " + file.string());
}

void Node::readBulk(const std::filesystem::path& file)
{
  throw SceneError("node '" + id_ + "' (" + nodeTypeToString(type()) +
                   ") does not read bulk data, yet the bundle lists " + file.string() +
                   " for it: the bundle was written by a different CAPS; update CAPS");
}

void Node::modified()
{
  if (scene_)
    scene_->notify(SceneEvent::NodeModified, *this);
}

std::unique_ptr<Node> Node::create(NodeType type)
{
  switch (type)
  {
  case NodeType::Volume:
    return std::make_unique<VolumeNode>();
  case NodeType::LabelMap:
    return std::make_unique<LabelMapNode>();
  case NodeType::Surface:
    return std::make_unique<SurfaceNode>();
  case NodeType::RangeMap:
    return std::make_unique<RangeMapNode>();
  case NodeType::Plan:
    return std::make_unique<PlanNode>();
  case NodeType::FeMesh:
    return std::make_unique<FeMeshNode>();
  case NodeType::Solution:
    return std::make_unique<SolutionNode>();
  case NodeType::Snapshot:
    return std::make_unique<SnapshotNode>();
  case NodeType::Landmarks:
    return std::make_unique<LandmarksNode>();
  case NodeType::Expression:
    return std::make_unique<ExpressionNode>();
  }
  throw SceneError("unknown node type");
}

} // namespace caps
