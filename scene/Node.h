#pragma once

#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "scene/NodeType.h"

namespace caps {

class Scene;

/// Stable node identifier, e.g. "Volume1". Modules keep ids, never pointers.
using NodeId = std::string;

/// @brief Base of every scene node (the MRML node of CAPS).
///
/// Small fields travel as JSON (toJson/fromJson: scene.json and undo
/// mementos); bulky data (images, meshes) goes to one file per node
/// (writeBulk/readBulk) whose extension bulkFileExtension() gives, "" when
/// the node has nothing bulky to store.
class Node
{
public:
  virtual ~Node();
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  virtual NodeType type() const = 0;

  const NodeId& id() const { return id_; }
  /// Only before the node joins a scene (ids are stable); throws SceneError after.
  void setId(NodeId id);

  const std::string& name() const { return name_; }
  void setName(std::string name);

  /// The owning scene, nullptr while the node is not in one.
  Scene* scene() const { return scene_; }

  /// {"id", "type", "name", ...fields of the subclass}.
  nlohmann::json toJson() const;
  /// Reads name and the subclass fields (missing keys keep their value), never
  /// the id or the type; then fires one NodeModified.
  void fromJson(const nlohmann::json& j);

  /// ".nrrd", ".vtu", ".png", or "" when there is nothing bulky to store.
  virtual std::string bulkFileExtension() const { return {}; }
  /// Writes the bulky data; throws SceneError naming @a file on failure.
  virtual void writeBulk(const std::filesystem::path& file) const;
  /// Reads the bulky data written by writeBulk; throws SceneError naming @a file.
  virtual void readBulk(const std::filesystem::path& file);

  /// Tells the owning scene's observers that this node changed.
  void modified();

  /// A default-constructed node of the given type.
  static std::unique_ptr<Node> create(NodeType type);

protected:
  Node() = default;
  /// One line per field each way (Slicer's WriteXML / ReadXMLAttributes).
  virtual void writeFields(nlohmann::json& j) const = 0;
  virtual void readFields(const nlohmann::json& j) = 0;

private:
  friend class Scene;
  NodeId id_;
  std::string name_;
  Scene* scene_ = nullptr;
};

} // namespace caps
