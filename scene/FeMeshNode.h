#pragma once

#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include "scene/Node.h"

namespace caps {

/// @brief The continuum finite element mesh of a plan (thesis §4.5.2):
/// quadratic hexahedra and wedges, skin to bone, with the region id of each
/// element as cell data. Points in patient LPS, mm. Bulk file: VTU.
class FeMeshNode : public Node
{
public:
  NodeType type() const override { return NodeType::FeMesh; }

  vtkUnstructuredGrid* mesh() const { return mesh_; }
  void setMesh(vtkSmartPointer<vtkUnstructuredGrid> mesh);

  /// The plan this mesh was generated from.
  const NodeId& planId() const { return planId_; }
  void setPlanId(NodeId id);

  std::string bulkFileExtension() const override;
  void writeBulk(const std::filesystem::path& file) const override;
  void readBulk(const std::filesystem::path& file) override;

protected:
  void writeFields(nlohmann::json& j) const override;
  void readFields(const nlohmann::json& j) override;

private:
  vtkSmartPointer<vtkUnstructuredGrid> mesh_;
  NodeId planId_;
};

} // namespace caps
