#include "scene/VolumeNode.h"

#include "scene/JsonFields.h"
#include "scene/NrrdIO.h"
#include "scene/SceneError.h"

namespace caps {

void VolumeNode::setImage(vtkSmartPointer<vtkImageData> image)
{
  image_ = std::move(image);
  modified();
}

void VolumeNode::setMetadata(std::map<std::string, std::string> metadata)
{
  metadata_ = std::move(metadata);
  modified();
}

void VolumeNode::setSourcePath(std::string path)
{
  sourcePath_ = std::move(path);
  modified();
}

void VolumeNode::setWindowLevel(double window, double level)
{
  window_ = window;
  level_ = level;
  modified();
}

std::string VolumeNode::bulkFileExtension() const
{
  return image_ ? ".nrrd" : "";
}

void VolumeNode::writeBulk(const std::filesystem::path& file) const
{
  NrrdIO::writeImage(image_, file);
}

void VolumeNode::readBulk(const std::filesystem::path& file)
{
  image_ = NrrdIO::readImage(file);
}

void VolumeNode::writeFields(nlohmann::json& j) const
{
  j["metadata"] = metadata_;
  j["sourcePath"] = sourcePath_;
  j["window"] = window_;
  j["level"] = level_;
}

void VolumeNode::readFields(const nlohmann::json& j)
{
  jsonfields::read(j, "metadata", metadata_);
  jsonfields::read(j, "sourcePath", sourcePath_);
  jsonfields::read(j, "window", window_);
  jsonfields::read(j, "level", level_);
}

} // namespace caps
