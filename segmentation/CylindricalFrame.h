#pragma once
/// @file CylindricalFrame.h
/// @brief The cylindrical frame of the head (§4.2): axis, θ, z, and the (θ, z) sample grid.

#include <Eigen/Core>

namespace caps::seg {

/// A point in cylindrical coordinates: r in mm from the axis, θ in radians in
/// [-π, π), z in mm along the axis from the frame origin.
struct CylindricalPoint
{
  double r = 0.0;
  double theta = 0.0;
  double z = 0.0;
};

/// A point in normalised cylindrical space (§4.2.2): θn = θ/π in [-1, 1),
/// zn in [-1, 1] over the frame's [zMin, zMax]; r stays in mm.
struct NormalizedCylindricalPoint
{
  double r = 0.0;
  double thetaN = 0.0;
  double zN = 0.0;
};

/// @class CylindricalFrame
/// @brief The cylinder around the head on which range maps are sampled (§4.2, eq. 4.11–4.12).
///
/// The axis passes through origin() along the unit direction() (patient
/// superior by default). Its in-plane axes follow the thesis's rectangular
/// world space (§4.2.3): xAxis() is patient left (LPS +x) made orthogonal to
/// the axis, yAxis() = direction() × xAxis() is posterior, so a world point p
/// has axis-frame coordinates (x, y, z) = ((p-o)·x̂, (p-o)·ŷ, (p-o)·â) and
/// (x, y) = (r cos θ, r sin θ): θ = 0 is patient left, θ = -π/2 the front of
/// the face (anterior, -y), θ = π/2 the back of the head.
///
/// The sample grid has nTheta() columns and nZ() rows. Column i sits at
/// θ_i = -π + 2π i / nθ (periodic: column nθ is column 0 again); row j sits
/// at z_j = zMin + j (zMax - zMin) / (nz - 1), so the first and last rows are
/// on the ends of the range. Row 0 is the inferior end (the thesis's eq. 4.10
/// flips rows because its images are stored top-down; we do not).
///
/// @warning The frame is a value: copying it is cheap and two frames compare
/// equal when every field is equal.
class CylindricalFrame
{
public:
  /// Axis through the world origin along +z (superior), z in [-100, 100] mm, 512 × 256.
  CylindricalFrame();
  /// @throws std::invalid_argument if direction is zero, zMax <= zMin, nTheta < 4 or nZ < 2.
  CylindricalFrame(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double zMin, double zMax,
                   int nTheta = 512, int nZ = 256);

  const Eigen::Vector3d& origin() const { return origin_; }
  const Eigen::Vector3d& direction() const { return axis_; }
  /// Patient left made orthogonal to the axis (θ = 0).
  const Eigen::Vector3d& xAxis() const { return xAxis_; }
  /// direction() × xAxis(): patient posterior for an upright axis (θ = π/2).
  const Eigen::Vector3d& yAxis() const { return yAxis_; }
  double zMin() const { return zMin_; }
  double zMax() const { return zMax_; }
  int nTheta() const { return nTheta_; }
  int nZ() const { return nZ_; }
  /// 2π / nθ, radians between columns.
  double thetaStep() const;
  /// (zMax - zMin) / (nz - 1), mm between rows.
  double zStep() const;

  /// The same axis with another z range or grid.
  CylindricalFrame withRange(double zMin, double zMax) const;
  CylindricalFrame withGrid(int nTheta, int nZ) const;

  /// @name World (LPS mm) ↔ cylindrical (eq. 4.11–4.12)
  ///@{
  CylindricalPoint toCylindrical(const Eigen::Vector3d& world) const;
  Eigen::Vector3d toWorld(const CylindricalPoint& point) const;
  Eigen::Vector3d toWorld(double r, double theta, double z) const;
  /// Unit vector from the axis towards θ, in world coordinates.
  Eigen::Vector3d radialDirection(double theta) const;
  /// The axis point at height z.
  Eigen::Vector3d axisPoint(double z) const;
  ///@}

  /// @name Cylindrical ↔ normalised cylindrical (§4.2.2)
  ///@{
  NormalizedCylindricalPoint toNormalized(const CylindricalPoint& point) const;
  CylindricalPoint fromNormalized(const NormalizedCylindricalPoint& point) const;
  ///@}

  /// @name Cylindrical ↔ continuous sample indices
  /// u is the column (θ) coordinate in [0, nθ), v the row (z) coordinate,
  /// 0 at zMin and nz - 1 at zMax (not clamped).
  ///@{
  double thetaToIndex(double theta) const;
  double zToIndex(double z) const;
  double indexToTheta(double u) const;
  double indexToZ(double v) const;
  ///@}

  /// θ wrapped into [-π, π).
  static double wrapTheta(double theta);

  bool operator==(const CylindricalFrame& other) const;
  bool operator!=(const CylindricalFrame& other) const { return !(*this == other); }

private:
  Eigen::Vector3d origin_;
  Eigen::Vector3d axis_;
  Eigen::Vector3d xAxis_;
  Eigen::Vector3d yAxis_;
  double zMin_ = -100.0;
  double zMax_ = 100.0;
  int nTheta_ = 512;
  int nZ_ = 256;
};

} // namespace caps::seg
