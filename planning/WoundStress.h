#pragma once
/// @file WoundStress.h
/// @brief The largest stress in the skin near the closed wound
/// (thesis §4.7, eq. 4.47–4.48: stress recovered from the solution;
/// §3.2.4: the tension of a closure is what undermining relieves).

#include <Eigen/Core>

#include "fem/SurfaceMesh.h"
#include "planning/PlanSimulation.h"

namespace caps::planning {

/// The stress in the skin within a distance of the wound after the closure.
/// Stresses in MPa (the model is in mm and N), lengths in mm.
struct WoundStress
{
  double radius = 0.0; ///< the band: skin vertices at most this far from the hole border (chart mm)
  int vertexCount = 0; ///< skin (surface-mesh) vertices in the band
  /// Where the von Mises stress is largest in the band.
  int vertex = -1;                                     ///< surface-mesh vertex (DisplacedSkin index)
  int node = -1;                                       ///< its FE skin node
  fem::ChartPoint chart = fem::ChartPoint::Zero();     ///< its chart point (mm) before the operation
  double distance = 0.0;                               ///< its chart distance to the hole border (mm)
  Eigen::Vector3d original = Eigen::Vector3d::Zero();  ///< world (LPS mm) before
  Eigen::Vector3d displaced = Eigen::Vector3d::Zero(); ///< world after the closure
  double peakVonMises = 0.0;                           ///< the largest von Mises stress there (MPa)
  /// The largest maximum principal stress (tension) in the band (MPa) and
  /// its vertex; it need not be where the von Mises stress peaks.
  double peakMaxPrincipal = 0.0;
  int maxPrincipalVertex = -1;
  /// The von Mises stress averaged over the band, each vertex weighted by
  /// its share of the chart area of the polygons around it (a quad gives a
  /// quarter of its area to each corner, a triangle a third), MPa.
  double meanVonMises = 0.0;
};

/// @brief The largest skin stress within @a radius mm of the wound (thesis
/// §4.7; §3.2.4).
///
/// The skin is the FE skin node under each surface-mesh vertex
/// (PlanPrediction::skin). Its stress is the nodal average of the stresses
/// extrapolated from the 2 × 2 × 2 Gauss points of the skin elements around
/// it (fem::recoverNodalStresses(), averaged within the skin's region: the
/// stiffer skin's stress is not diluted by the fat's where they meet), the
/// smoothed field a surgeon sees on the display. A vertex is in the band when its chart point lies within
/// @a radius of an edge of the refined hole loop (PlanPrediction::hole),
/// i.e. the distance is measured on the skin before the operation; the
/// border vertices themselves are at distance 0.
///
/// @throws std::invalid_argument for a radius that is not a positive finite
/// number of mm, or a prediction without skin or hole.
WoundStress woundSkinStress(const PlanPrediction& prediction, double radius = 10.0);

/// Chart distance (mm) from @a p to the nearest edge of the closed loop @a hole.
double distanceToHoleBorder(const fem::HoleLoop& hole, const fem::ChartPoint& p);

} // namespace caps::planning
