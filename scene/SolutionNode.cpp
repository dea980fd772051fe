#include "scene/SolutionNode.h"

#include "scene/JsonFields.h"
#include "scene/VtuIO.h"

namespace caps {

void SolutionNode::setMeshId(NodeId id)
{
  meshId_ = std::move(id);
  modified();
}

void SolutionNode::setResult(vtkSmartPointer<vtkUnstructuredGrid> result)
{
  result_ = std::move(result);
  modified();
}

void SolutionNode::setLoadCase(std::string loadCase)
{
  loadCase_ = std::move(loadCase);
  modified();
}

std::string SolutionNode::bulkFileExtension() const
{
  return result_ ? ".vtu" : "";
}

void SolutionNode::writeBulk(const std::filesystem::path& file) const
{
  VtuIO::writeGrid(result_, file);
}

void SolutionNode::readBulk(const std::filesystem::path& file)
{
  result_ = VtuIO::readGrid(file);
}

void SolutionNode::writeFields(nlohmann::json& j) const
{
  j["meshId"] = meshId_;
  j["loadCase"] = loadCase_;
}

void SolutionNode::readFields(const nlohmann::json& j)
{
  jsonfields::read(j, "meshId", meshId_);
  jsonfields::read(j, "loadCase", loadCase_);
}

} // namespace caps
