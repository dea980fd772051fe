#pragma once

#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <array>

#include "scene/Node.h"

namespace caps {

/// @brief A triangle surface (skin, bone, deformed skin...) with its display
/// properties. Points in patient LPS, mm. Bulk file: VTU (arrays kept).
class SurfaceNode : public Node {
 public:
  NodeType type() const override { return NodeType::Surface; }

  vtkPolyData* polyData() const { return polyData_; }
  void setPolyData(vtkSmartPointer<vtkPolyData> polyData);

  const std::array<double, 3>& color() const { return color_; }
  void setColor(const std::array<double, 3>& rgb);
  double opacity() const { return opacity_; }
  void setOpacity(double opacity);
  bool visible() const { return visible_; }
  void setVisible(bool visible);

  const NodeId& sourceLabelMapId() const { return sourceLabelMapId_; }
  void setSourceLabelMapId(NodeId id);

  std::string bulkFileExtension() const override;
  void writeBulk(const std::filesystem::path& file) const override;
  void readBulk(const std::filesystem::path& file) override;

 protected:
  void writeFields(nlohmann::json& j) const override;
  void readFields(const nlohmann::json& j) override;

 private:
  vtkSmartPointer<vtkPolyData> polyData_;
  std::array<double, 3> color_{0.9, 0.75, 0.65};
  double opacity_ = 1.0;
  bool visible_ = true;
  NodeId sourceLabelMapId_;
};

}  // namespace caps
