#pragma once
/// @file SkinChart.h
/// @brief The local millimetre chart of the skin around an incision
/// (fem/SurfaceMesh.h ChartPoint), its conversions to cylindrical and
/// normalised cylindrical space (§4.2.2), and the lift onto the 3D skin.

#include <Eigen/Core>

#include "fem/SurfaceMesh.h"
#include "segmentation/RangeMap.h"

namespace caps::planning {

using fem::ChartPoint;

/// A point on the skin in cylindrical coordinates: θ in radians, z in mm.
struct SkinPoint
{
  double theta = 0.0;
  double z = 0.0;
};

/// @class SkinChart
/// @brief u = r0·(θ − θc), v = z − zc about a centre (θc, zc) on the skin.
///
/// r0 is the skin radius at the centre, so near the centre a millimetre in
/// u is a millimetre on the skin around the head and the chart is the
/// surgeon's flat drawing of the plan (§2.1: lengths and angles of the limbs
/// are set in millimetres and degrees). θ is unwrapped about θc, so a plan
/// straddling the θ = ±π seam (the back of the head) is one piece in the
/// chart; fromChart() wraps θ back into [-π, π).
///
/// @warning The chart keeps a pointer to the skin map: the map must outlive it.
class SkinChart
{
public:
  /// @throws std::invalid_argument when the skin map has no surface at the
  /// centre (outside the scanned z range or in a hole of the map).
  SkinChart(const seg::RangeMap& skin, double centreTheta, double centreZ);

  double centreTheta() const { return centreTheta_; }
  double centreZ() const { return centreZ_; }
  /// r0: the skin radius at the centre (mm), the chart's u scale.
  double radius() const { return radius_; }
  const seg::RangeMap& skin() const { return *skin_; }

  /// @name Cylindrical (θ, z) ↔ chart (u, v)
  ///@{
  ChartPoint toChart(const SkinPoint& p) const;
  SkinPoint fromChart(const ChartPoint& p) const;
  ///@}

  /// @name Normalised cylindrical (θn, zn) ∈ [-1, 1]² (§4.2.2) ↔ chart (u, v)
  ///@{
  ChartPoint fromNormalized(const Eigen::Vector2d& thetaZN) const;
  Eigen::Vector2d toNormalized(const ChartPoint& p) const;
  ///@}

  /// The world point (LPS mm) of the skin above a chart point: r from the
  /// skin map (bilinear, eq. 4.9) placed by the frame (eq. 4.12). NaN when
  /// the map has no surface there.
  Eigen::Vector3d lift(const ChartPoint& p) const;

private:
  const seg::RangeMap* skin_;
  double centreTheta_;
  double centreZ_;
  double radius_;
};

/// How far the chart is from the skin at @a p: the largest factor by which
/// the lift stretches or shrinks a chart length in any direction (1 where
/// the chart is true to the skin; the singular values σ of d lift / d(u, v)
/// over central differences @a step mm apart, max(σmax, 1/σmin)). It grows
/// where the skin is oblique to the head's axis (the top of the head, under
/// the chin, the side of the nose): there a plan drawn in the chart is not
/// the plan on the skin. NaN when the map has no surface about @a p.
double chartDistortion(const SkinChart& chart, const ChartPoint& p, double step = 1.0);

/// Plans are refused where the chart stretches or shrinks lengths on the
/// skin by more than this (chartDistortion()).
inline constexpr double kMaxChartDistortion = 1.3;

/// Normalised (θn, zn) ↔ cylindrical (θ, z) on a frame (§4.2.2).
SkinPoint skinPointFromNormalized(const seg::CylindricalFrame& frame, const Eigen::Vector2d& thetaZN);
Eigen::Vector2d normalizedFromSkinPoint(const seg::CylindricalFrame& frame, const SkinPoint& p);

} // namespace caps::planning
