#include "scene/RangeMapNode.h"

#include <cmath>
#include <numbers>

#include "scene/JsonFields.h"
#include "scene/NrrdIO.h"
#include "scene/SceneError.h"

namespace caps {

void RangeMapNode::setValues(Eigen::MatrixXf values)
{
  values_ = std::move(values);
  modified();
}

void RangeMapNode::setRole(std::string role)
{
  role_ = std::move(role);
  modified();
}

void RangeMapNode::setAxis(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction)
{
  if (!(direction.norm() > 0))
    throw SceneError("range map '" + name() + "': the axis direction must not be zero");
  axisOrigin_ = origin;
  axisDirection_ = direction.normalized();
  modified();
}

void RangeMapNode::setZRange(double zMin, double zMax)
{
  zMin_ = zMin;
  zMax_ = zMax;
  modified();
}

double RangeMapNode::thetaAt(Eigen::Index i) const
{
  return -std::numbers::pi + 2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(values_.rows());
}

double RangeMapNode::zAt(Eigen::Index j) const
{
  if (values_.cols() < 2)
    return zMin_;
  return zMin_ + (zMax_ - zMin_) * static_cast<double>(j) / static_cast<double>(values_.cols() - 1);
}

std::string RangeMapNode::bulkFileExtension() const
{
  return values_.size() > 0 ? ".nrrd" : "";
}

void RangeMapNode::writeBulk(const std::filesystem::path& file) const
{
  NrrdIO::writeMatrix(values_, file);
}

void RangeMapNode::readBulk(const std::filesystem::path& file)
{
  values_ = NrrdIO::readMatrix(file);
}

void RangeMapNode::setSourceVolumeId(NodeId id)
{
  sourceVolumeId_ = std::move(id);
  modified();
}

void RangeMapNode::setSourceLabelMapId(NodeId id)
{
  sourceLabelMapId_ = std::move(id);
  modified();
}

void RangeMapNode::setSkinMapId(NodeId id)
{
  skinMapId_ = std::move(id);
  modified();
}

void RangeMapNode::writeFields(nlohmann::json& j) const
{
  j["role"] = role_;
  j["axisOrigin"] = jsonfields::toJson(axisOrigin_);
  j["axisDirection"] = jsonfields::toJson(axisDirection_);
  j["zMin"] = zMin_;
  j["zMax"] = zMax_;
  if (!sourceVolumeId_.empty())
    j["sourceVolumeId"] = sourceVolumeId_;
  if (!sourceLabelMapId_.empty())
    j["sourceLabelMapId"] = sourceLabelMapId_;
  if (!skinMapId_.empty())
    j["skinMapId"] = skinMapId_;
}

void RangeMapNode::readFields(const nlohmann::json& j)
{
  jsonfields::read(j, "role", role_);
  jsonfields::read(j, "axisOrigin", axisOrigin_);
  jsonfields::read(j, "axisDirection", axisDirection_);
  jsonfields::read(j, "zMin", zMin_);
  jsonfields::read(j, "zMax", zMax_);
  jsonfields::read(j, "sourceVolumeId", sourceVolumeId_);
  jsonfields::read(j, "sourceLabelMapId", sourceLabelMapId_);
  jsonfields::read(j, "skinMapId", skinMapId_);
}

} // namespace caps
