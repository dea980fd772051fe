#include "scene/SurfaceNode.h"

#include "scene/JsonFields.h"
#include "scene/VtuIO.h"

namespace caps {

void SurfaceNode::setPolyData(vtkSmartPointer<vtkPolyData> polyData)
{
  polyData_ = std::move(polyData);
  modified();
}

void SurfaceNode::setColor(const std::array<double, 3>& rgb)
{
  color_ = rgb;
  modified();
}

void SurfaceNode::setOpacity(double opacity)
{
  opacity_ = opacity;
  modified();
}

void SurfaceNode::setVisible(bool visible)
{
  visible_ = visible;
  modified();
}

void SurfaceNode::setColourArray(std::string name)
{
  colourArray_ = std::move(name);
  modified();
}

void SurfaceNode::setScalarRange(const std::array<double, 2>& range)
{
  scalarRange_ = range;
  modified();
}

void SurfaceNode::setColourMap(std::string name)
{
  colourMap_ = std::move(name);
  modified();
}

void SurfaceNode::setColourBarTitle(std::string title)
{
  colourBarTitle_ = std::move(title);
  modified();
}

void SurfaceNode::setLineWidth(double width)
{
  lineWidth_ = width;
  modified();
}

void SurfaceNode::setSourceLabelMapId(NodeId id)
{
  sourceLabelMapId_ = std::move(id);
  modified();
}

std::string SurfaceNode::bulkFileExtension() const
{
  return polyData_ ? ".vtu" : "";
}

void SurfaceNode::writeBulk(const std::filesystem::path& file) const
{
  VtuIO::writePolyData(polyData_, file);
}

void SurfaceNode::readBulk(const std::filesystem::path& file)
{
  polyData_ = VtuIO::readPolyData(file);
}

void SurfaceNode::writeFields(nlohmann::json& j) const
{
  j["color"] = color_;
  j["opacity"] = opacity_;
  j["visible"] = visible_;
  j["sourceLabelMapId"] = sourceLabelMapId_;
  j["colourArray"] = colourArray_;
  j["scalarRange"] = scalarRange_;
  j["colourMap"] = colourMap_;
  j["colourBarTitle"] = colourBarTitle_;
  j["lineWidth"] = lineWidth_;
}

void SurfaceNode::readFields(const nlohmann::json& j)
{
  jsonfields::read(j, "color", color_);
  jsonfields::read(j, "opacity", opacity_);
  jsonfields::read(j, "visible", visible_);
  jsonfields::read(j, "sourceLabelMapId", sourceLabelMapId_);
  jsonfields::read(j, "colourArray", colourArray_);
  jsonfields::read(j, "scalarRange", scalarRange_);
  jsonfields::read(j, "colourMap", colourMap_);
  jsonfields::read(j, "colourBarTitle", colourBarTitle_);
  jsonfields::read(j, "lineWidth", lineWidth_);
}

} // namespace caps
