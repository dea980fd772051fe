#pragma once

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include <map>
#include <string>

#include "scene/Node.h"

namespace caps {

/// @brief A scalar image, usually a CT (Hounsfield units).
///
/// The geometry (origin, spacing and the 3x3 direction matrix of the
/// vtkImageData) is in the patient frame, DICOM LPS, mm. Scalars are short,
/// unsigned short, unsigned char, int, float or double. Bulk file: NRRD.
/// After changing the image's voxels in place, call modified().
class VolumeNode : public Node
{
public:
  NodeType type() const override { return NodeType::Volume; }

  vtkImageData* image() const { return image_; }
  void setImage(vtkSmartPointer<vtkImageData> image);

  /// DICOM patient/study/series fields ("PatientName", "StudyDate", ...).
  const std::map<std::string, std::string>& metadata() const { return metadata_; }
  void setMetadata(std::map<std::string, std::string> metadata);

  /// Where the volume was read from (a DICOM folder or a file).
  const std::string& sourcePath() const { return sourcePath_; }
  void setSourcePath(std::string path);

  double window() const { return window_; }
  double level() const { return level_; }
  void setWindowLevel(double window, double level);

  std::string bulkFileExtension() const override;
  void writeBulk(const std::filesystem::path& file) const override;
  void readBulk(const std::filesystem::path& file) override;

protected:
  void writeFields(nlohmann::json& j) const override;
  void readFields(const nlohmann::json& j) override;

private:
  vtkSmartPointer<vtkImageData> image_;
  std::map<std::string, std::string> metadata_;
  std::string sourcePath_;
  double window_ = 400.0; // a soft-tissue CT window
  double level_ = 40.0;
};

} // namespace caps
