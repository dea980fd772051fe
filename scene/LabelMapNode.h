#pragma once

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include <array>
#include <map>
#include <optional>
#include <string>

#include "scene/Node.h"

namespace caps {

/// @brief A segmentation: one unsigned char label per voxel (0 = background).
///
/// Same geometry rules as VolumeNode (LPS, mm, direction matrix), usually on
/// the grid of the reference volume. Bulk file: NRRD.
class LabelMapNode : public Node
{
public:
  /// One entry of the label table.
  struct Label
  {
    std::string name;
    std::array<double, 3> color{1.0, 1.0, 1.0}; ///< RGB in [0, 1]
    bool operator==(const Label&) const = default;
  };

  /// The HU thresholds a segmentation was made with: the range maps search
  /// their sub-voxel skin and bone crossings at the same values.
  struct Thresholds
  {
    double skinHu = 0.0; ///< air / soft tissue
    double boneHu = 0.0; ///< soft tissue / bone
    bool operator==(const Thresholds&) const = default;
  };

  NodeType type() const override { return NodeType::LabelMap; }

  vtkImageData* image() const { return image_; }
  /// Throws SceneError unless the scalars are single-component unsigned char.
  void setImage(vtkSmartPointer<vtkImageData> image);

  const NodeId& referenceVolumeId() const { return referenceVolumeId_; }
  void setReferenceVolumeId(NodeId id);

  /// None for a label map from elsewhere (a file, a scene saved before they
  /// were recorded): its thresholds are unknown.
  const std::optional<Thresholds>& thresholds() const { return thresholds_; }
  void setThresholds(std::optional<Thresholds> thresholds);

  const std::map<int, Label>& labels() const { return labels_; }
  void setLabels(std::map<int, Label> labels);
  void setLabel(int value, Label label);

  std::string bulkFileExtension() const override;
  void writeBulk(const std::filesystem::path& file) const override;
  void readBulk(const std::filesystem::path& file) override;

protected:
  void writeFields(nlohmann::json& j) const override;
  void readFields(const nlohmann::json& j) override;

private:
  vtkSmartPointer<vtkImageData> image_;
  NodeId referenceVolumeId_;
  std::map<int, Label> labels_;
  std::optional<Thresholds> thresholds_;
};

} // namespace caps
