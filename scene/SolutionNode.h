#pragma once

#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include <string>

#include "scene/Node.h"

namespace caps {

/// @brief The result of one load case on an FE mesh: the mesh with
/// point-data displacement (mm) and cell/point stress arrays (MPa).
/// Bulk file: VTU.
class SolutionNode : public Node
{
public:
  NodeType type() const override { return NodeType::Solution; }

  const NodeId& meshId() const { return meshId_; }
  void setMeshId(NodeId id);

  vtkUnstructuredGrid* result() const { return result_; }
  void setResult(vtkSmartPointer<vtkUnstructuredGrid> result);

  /// e.g. "sutures", "sutures+gravity".
  const std::string& loadCase() const { return loadCase_; }
  void setLoadCase(std::string loadCase);

  std::string bulkFileExtension() const override;
  void writeBulk(const std::filesystem::path& file) const override;
  void readBulk(const std::filesystem::path& file) override;

protected:
  void writeFields(nlohmann::json& j) const override;
  void readFields(const nlohmann::json& j) override;

private:
  NodeId meshId_;
  vtkSmartPointer<vtkUnstructuredGrid> result_;
  std::string loadCase_;
};

} // namespace caps
