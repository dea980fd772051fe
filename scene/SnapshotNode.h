#pragma once

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include <array>
#include <string>

#include "render/Camera.h"
#include "scene/Node.h"

namespace caps {

/// @brief A saved view for the report: caption, camera and an RGB picture.
/// Bulk file: PNG, none while the image is null.
class SnapshotNode : public Node
{
public:
  /// A camera as vtkCamera describes it (patient LPS, mm; view angle in degrees as VTK).
  using Camera = render::Camera;

  NodeType type() const override { return NodeType::Snapshot; }

  const std::string& caption() const { return caption_; }
  void setCaption(std::string caption);

  const Camera& camera() const { return camera_; }
  void setCamera(const Camera& camera);

  /// RGB (or RGBA) unsigned char image, may be null.
  vtkImageData* image() const { return image_; }
  void setImage(vtkSmartPointer<vtkImageData> image);

  std::string bulkFileExtension() const override;
  void writeBulk(const std::filesystem::path& file) const override;
  void readBulk(const std::filesystem::path& file) override;

protected:
  void writeFields(nlohmann::json& j) const override;
  void readFields(const nlohmann::json& j) override;

private:
  std::string caption_;
  Camera camera_;
  vtkSmartPointer<vtkImageData> image_;
};

} // namespace caps
