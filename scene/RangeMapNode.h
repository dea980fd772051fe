#pragma once

#include <Eigen/Core>
#include <string>

#include "scene/Node.h"

namespace caps {

/// @brief A cylindrical range map r(θ, z) (thesis §4.2).
///
/// values(i, j) is the radius in mm at θ_i = -π + 2π i / nθ (θ covers
/// [-π, π), θ = -π/2 at the front of the face) and z_j = zMin + (zMax - zMin)
/// j / (nz - 1) along the axis; NaN where no surface was found. For the
/// "thickness" role the values are soft-tissue thickness in mm.
/// Bulk file: 2D float NRRD, θ fastest, NaN preserved.
class RangeMapNode : public Node
{
public:
  NodeType type() const override { return NodeType::RangeMap; }

  /// Rows = θ samples, cols = z samples.
  const Eigen::MatrixXf& values() const { return values_; }
  void setValues(Eigen::MatrixXf values);

  /// "skin", "bone" or "thickness".
  const std::string& role() const { return role_; }
  void setRole(std::string role);

  const Eigen::Vector3d& axisOrigin() const { return axisOrigin_; }
  const Eigen::Vector3d& axisDirection() const { return axisDirection_; }
  /// The cylinder axis in patient LPS mm; the direction is stored normalised.
  void setAxis(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction);

  double zMin() const { return zMin_; }
  double zMax() const { return zMax_; }
  void setZRange(double zMin, double zMax);

  /// @name Provenance (empty when unknown: maps of scenes saved before they were recorded)
  ///@{
  /// The CT volume the map was built from.
  const NodeId& sourceVolumeId() const { return sourceVolumeId_; }
  void setSourceVolumeId(NodeId id);
  /// The label map the map was built from.
  const NodeId& sourceLabelMapId() const { return sourceLabelMapId_; }
  void setSourceLabelMapId(NodeId id);
  /// The skin map built in the same run as this map (a skin map's own id):
  /// the bone map that goes with a skin map is the one that names it.
  const NodeId& skinMapId() const { return skinMapId_; }
  void setSkinMapId(NodeId id);
  ///@}

  /// θ of row i, z of column j (see class doc).
  double thetaAt(Eigen::Index i) const;
  double zAt(Eigen::Index j) const;

  std::string bulkFileExtension() const override;
  void writeBulk(const std::filesystem::path& file) const override;
  void readBulk(const std::filesystem::path& file) override;

protected:
  void writeFields(nlohmann::json& j) const override;
  void readFields(const nlohmann::json& j) override;

private:
  Eigen::MatrixXf values_;
  std::string role_ = "skin";
  Eigen::Vector3d axisOrigin_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d axisDirection_ = Eigen::Vector3d::UnitZ(); // patient superior
  double zMin_ = 0.0;
  double zMax_ = 0.0;
  NodeId sourceVolumeId_;
  NodeId sourceLabelMapId_;
  NodeId skinMapId_;
};

} // namespace caps
