#include "scene/FeMeshNode.h"

#include "scene/JsonFields.h"
#include "scene/VtuIO.h"

namespace caps {

void FeMeshNode::setMesh(vtkSmartPointer<vtkUnstructuredGrid> mesh)
{
  mesh_ = std::move(mesh);
  modified();
}

void FeMeshNode::setPlanId(NodeId id)
{
  planId_ = std::move(id);
  modified();
}

std::string FeMeshNode::bulkFileExtension() const
{
  return mesh_ ? ".vtu" : "";
}

void FeMeshNode::writeBulk(const std::filesystem::path& file) const
{
  VtuIO::writeGrid(mesh_, file);
}

void FeMeshNode::readBulk(const std::filesystem::path& file)
{
  mesh_ = VtuIO::readGrid(file);
}

void FeMeshNode::writeFields(nlohmann::json& j) const
{
  j["planId"] = planId_;
}

void FeMeshNode::readFields(const nlohmann::json& j)
{
  jsonfields::read(j, "planId", planId_);
}

} // namespace caps
