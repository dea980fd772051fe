#include "scene/LabelMapNode.h"

#include <vtkPointData.h>

#include <cmath>

#include "scene/JsonFields.h"
#include "scene/NrrdIO.h"
#include "scene/SceneError.h"

namespace caps {

namespace {
bool isLabelImage(vtkImageData* image)
{
  return image && image->GetScalarType() == VTK_UNSIGNED_CHAR && image->GetNumberOfScalarComponents() == 1;
}
} // namespace

void LabelMapNode::setImage(vtkSmartPointer<vtkImageData> image)
{
  if (image && !isLabelImage(image))
    throw SceneError("label map '" + name() + "' needs a single-component unsigned char image, got " +
                     image->GetScalarTypeAsString());
  image_ = std::move(image);
  modified();
}

void LabelMapNode::setReferenceVolumeId(NodeId id)
{
  referenceVolumeId_ = std::move(id);
  modified();
}

void LabelMapNode::setThresholds(std::optional<Thresholds> thresholds)
{
  thresholds_ = thresholds;
  modified();
}

void LabelMapNode::setLabels(std::map<int, Label> labels)
{
  labels_ = std::move(labels);
  modified();
}

void LabelMapNode::setLabel(int value, Label label)
{
  labels_[value] = std::move(label);
  modified();
}

std::string LabelMapNode::bulkFileExtension() const
{
  return image_ ? ".nrrd" : "";
}

void LabelMapNode::writeBulk(const std::filesystem::path& file) const
{
  NrrdIO::writeImage(image_, file);
}

void LabelMapNode::readBulk(const std::filesystem::path& file)
{
  auto image = NrrdIO::readImage(file);
  if (!isLabelImage(image))
    throw SceneError(file.string() + " holds " + image->GetScalarTypeAsString() +
                     " voxels; a label map must be unsigned char: re-save the scene or restore a backup");
  image_ = image;
}

void LabelMapNode::writeFields(nlohmann::json& j) const
{
  j["referenceVolumeId"] = referenceVolumeId_;
  auto& table = j["labels"] = nlohmann::json::array();
  for (const auto& [value, label] : labels_)
    table.push_back({{"value", value}, {"name", label.name}, {"color", label.color}});
  if (thresholds_)
    j["thresholdsHu"] = {{"skin", thresholds_->skinHu}, {"bone", thresholds_->boneHu}};
}

void LabelMapNode::readFields(const nlohmann::json& j)
{
  jsonfields::read(j, "referenceVolumeId", referenceVolumeId_);
  if (const auto* table = jsonfields::find(j, "labels"))
  {
    std::map<int, Label> labels;
    for (const auto& e : jsonfields::list(*table, "labels"))
      labels[jsonfields::toInt(e.at("value"), "a label value")] =
        Label{e.value("name", ""), e.at("color").get<std::array<double, 3>>()};
    labels_ = std::move(labels);
  }
  if (const auto* t = jsonfields::find(j, "thresholdsHu"))
  {
    const Thresholds read{t->at("skin").get<double>(), t->at("bone").get<double>()};
    if (!std::isfinite(read.skinHu) || !std::isfinite(read.boneHu) || read.boneHu <= read.skinHu)
      throw SceneError("label map '" + name() + "' records thresholds skin " + t->at("skin").dump() + " HU and bone " +
                       t->at("bone").dump() +
                       " HU; the bone's must be above the skin's: correct scene.json or segment again");
    thresholds_ = read;
  }
}

} // namespace caps
