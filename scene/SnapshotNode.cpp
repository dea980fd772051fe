#include "scene/SnapshotNode.h"

#include <vtkPNGReader.h>
#include <vtkPNGWriter.h>

#include "scene/JsonFields.h"
#include "scene/SceneError.h"
#include "scene/VtkErrorCatcher.h"

namespace caps {

void SnapshotNode::setCaption(std::string caption)
{
  caption_ = std::move(caption);
  modified();
}

void SnapshotNode::setCamera(const Camera& camera)
{
  camera_ = camera;
  modified();
}

void SnapshotNode::setImage(vtkSmartPointer<vtkImageData> image)
{
  image_ = std::move(image);
  modified();
}

std::string SnapshotNode::bulkFileExtension() const
{
  return image_ ? ".png" : "";
}

void SnapshotNode::writeBulk(const std::filesystem::path& file) const
{
  if (!image_)
    throw SceneError("snapshot '" + name() + "' has no image to write to " + file.string());
  if (image_->GetScalarType() != VTK_UNSIGNED_CHAR && image_->GetScalarType() != VTK_UNSIGNED_SHORT)
    throw SceneError("cannot write " + file.string() + ": a snapshot image must be unsigned char RGB");
  auto writer = vtkSmartPointer<vtkPNGWriter>::New();
  VtkErrorCatcher errors(writer);
  writer->SetInputData(image_);
  writer->SetFileName(file.c_str());
  writer->Write();
  if (errors.failed() || writer->GetErrorCode() != 0)
    throw SceneError("could not write " + file.string() + ": check free disk space and permissions (" +
                     errors.message() + ")");
}

void SnapshotNode::readBulk(const std::filesystem::path& file)
{
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec))
    throw SceneError("cannot open " + file.string() + ": the file is missing");
  auto reader = vtkSmartPointer<vtkPNGReader>::New();
  VtkErrorCatcher errors(reader);
  if (!reader->CanReadFile(file.c_str()))
    throw SceneError(file.string() + " is not a readable PNG image: restore it from a backup");
  reader->SetFileName(file.c_str());
  reader->Update();
  if (errors.failed() || reader->GetErrorCode() != 0)
    throw SceneError(file.string() + " is damaged or truncated: restore it from a backup (" + errors.message() + ")");
  image_ = vtkSmartPointer<vtkImageData>::New();
  image_->DeepCopy(reader->GetOutput());
}

void SnapshotNode::writeFields(nlohmann::json& j) const
{
  j["caption"] = caption_;
  j["cameraPosition"] = camera_.position;
  j["cameraFocalPoint"] = camera_.focalPoint;
  j["cameraViewUp"] = camera_.viewUp;
  j["cameraViewAngle"] = camera_.viewAngle;
}

void SnapshotNode::readFields(const nlohmann::json& j)
{
  jsonfields::read(j, "caption", caption_);
  jsonfields::read(j, "cameraPosition", camera_.position);
  jsonfields::read(j, "cameraFocalPoint", camera_.focalPoint);
  jsonfields::read(j, "cameraViewUp", camera_.viewUp);
  jsonfields::read(j, "cameraViewAngle", camera_.viewAngle);
}

} // namespace caps
