#pragma once

#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <array>
#include <string>

#include "scene/Node.h"

namespace caps {

/// @brief A triangle surface (skin, bone, deformed skin...) with its display
/// properties. Points in patient LPS, mm. Bulk file: VTU (arrays kept).
class SurfaceNode : public Node
{
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

  /// @name Colouring by a point array (stress, displacement, thickness...)
  ///@{
  /// The point array the surface is coloured by; empty: the solid color().
  /// An unsigned-char array of 3 components is shown as RGB as it is; any
  /// other through colourMap() over scalarRange() (its first component).
  const std::string& colourArray() const { return colourArray_; }
  void setColourArray(std::string name);
  /// Values mapped to the ends of the colour map; lo >= hi: the array's own range.
  const std::array<double, 2>& scalarRange() const { return scalarRange_; }
  void setScalarRange(const std::array<double, 2>& range);
  /// A name of render/ColourMaps.h ("viridis", "cool-warm", "thickness").
  const std::string& colourMap() const { return colourMap_; }
  void setColourMap(std::string name);
  /// Title of the colour bar with its unit ("von Mises stress (kPa)"); empty: the array's name.
  const std::string& colourBarTitle() const { return colourBarTitle_; }
  void setColourBarTitle(std::string title);
  ///@}
  /// Width (pixels) of the surface's lines (an incision path); points for vertices.
  double lineWidth() const { return lineWidth_; }
  void setLineWidth(double width);

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
  std::string colourArray_;
  std::array<double, 2> scalarRange_{0.0, 0.0};
  std::string colourMap_ = "viridis";
  std::string colourBarTitle_;
  double lineWidth_ = 1.0;
  NodeId sourceLabelMapId_;
};

} // namespace caps
