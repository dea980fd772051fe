#pragma once
/// @file SkinMeasurements.h
/// @brief Lengths, angles and areas of a plan measured on the 3D skin, and
/// the Z-plasty's gain in length (§2.1, Fig. 2.2; §4.4.3: "all data about
/// edge lengths and border angles is available in world space").

#include <array>
#include <vector>

#include <Eigen/Core>

#include "planning/IncisionPlan.h"

namespace caps::planning {

/// @name On the skin
/// Chart points are lifted to the skin with SkinChart::lift(). Each function
/// throws std::invalid_argument naming the place when the skin map has no
/// surface under what it measures.
///@{
/// Length on the skin of the straight chart segment a→b: the segment is
/// sampled every `step` mm of chart length and the 3D distances between the
/// lifted samples are summed.
double skinLength(const SkinChart& chart, const ChartPoint& a, const ChartPoint& b, double step = 0.05);
/// Angle (radians, in [0, π]) on the skin at `corner` between the limbs
/// towards a and towards b: the angle between the 3D tangents of the two
/// lifted segments where they leave the corner.
double skinAngle(const SkinChart& chart, const ChartPoint& corner, const ChartPoint& a, const ChartPoint& b);
/// Area on the skin of a simple chart polygon (either orientation): a fan of
/// triangles, each cut into sub-triangles no wider than `step` mm, lifted
/// to the skin and summed as flat 3D triangles.
double skinArea(const SkinChart& chart, const std::vector<ChartPoint>& polygon, double step = 0.25);
///@}

/// @name Excised tissue (thesis §3.2.2: removing tissue is one of the
/// primitives of an operation; §3.1.3: volumetric elements let us estimate
/// the volume removed)
///@{
/// Volume (mm³) of the tissue under a simple chart polygon (either
/// orientation), from the skin down to the bone:
/// ∫∫ (r_skin² − r_bone²) / 2 dθ dz over the polygon, which is exact between
/// two surfaces given by their radius in the cylindrical frame; the chart has
/// θ = θc + u / r0 and z = zc + v, so dθ dz = du dv / r0. Integrated over a
/// signed fan of sub-triangles no wider than `step` mm, one sample at each
/// centroid. Where the bone map has no bone (or is empty) the bone lies
/// `noBoneDepth` mm under the skin (SimulationOptions::noBoneDepth).
/// @throws std::invalid_argument where the skin map has no surface, where
/// the bone lies above the skin, for a bone map on another axis or a
/// non-positive noBoneDepth.
double tissueVolume(const SkinChart& chart, const seg::RangeMap& bone, const std::vector<ChartPoint>& polygon,
                    double noBoneDepth = 10.0, double step = 0.25);
/// The volume of tissue a plan removes (mm³): tissueVolume() of its hole,
/// full thickness down to the bone as the simulation's mesh cuts it; 0
/// without excision.
double excisedVolume(const IncisionPlan& plan, const seg::RangeMap& skin, const seg::RangeMap& bone,
                     double noBoneDepth = 10.0);
///@}

/// One limb of the cut: cut points i → i + 1.
struct LimbLength
{
  int from = 0, to = 0;
  double chart = 0.0; ///< length in the chart (mm)
  double skin = 0.0;  ///< length along the 3D skin (mm)
};

/// The angle between the two limbs meeting at an inner cut point.
struct LimbAngle
{
  int point = 0;
  double chart = 0.0; ///< radians, in the chart
  double skin = 0.0;  ///< radians, between the 3D tangents on the skin
};

/// One corner of the hole border, measured on the skin side (the left of the
/// border, §4.4.4 / Fig. 4.11): 2π at the tip of a slit, π on a straight
/// border, less than π where the hole bulges into the skin.
struct BorderAngle
{
  int vertex = 0;
  double skin = 0.0; ///< radians in [0, 2π)
};

/// Everything measured on a plan, for the report and the panel.
struct PlanMeasurements
{
  std::vector<LimbLength> limbs;       ///< every limb of the cut
  std::vector<LimbLength> borderEdges; ///< every hole border edge (differ from limbs in excisions)
  std::vector<LimbAngle> limbAngles;   ///< at every inner cut point
  std::vector<BorderAngle> borderAngles;
  double excisedArea = 0.0; ///< skin area of the hole (mm²): 0 without excision
};

/// Measures a plan on its skin map.
PlanMeasurements measurePlan(const IncisionPlan& plan, const seg::RangeMap& skin);
/// The area of skin a plan removes (mm²): the hole's area on the skin.
double excisedArea(const IncisionPlan& plan, const seg::RangeMap& skin);

/// @name Z-plasty gain in length
///@{
/// Theoretical gain in length of a Z-plasty with equal limbs at this angle
/// (radians), as a fraction of the central limb: the table of Fig. 2.2
/// (after McCarthy [27]: 30° 25 %, 45° 50 %, 60° 75 %, 75° 100 %, 90° 120 %),
/// linearly interpolated between its rows.
/// @throws std::invalid_argument outside the table, 30° to 90°.
double zPlastyTheoreticalGain(double limbAngle);
/// The same gain from the geometry the table rounds: long diagonal minus
/// short diagonal of the Z's parallelogram over the short one, √(5 − 4 cos α) − 1.
double zPlastyGeometricGain(double limbAngle);

/// The gain a simulation predicts: the change of the distance, along the
/// Z's old central axis, between the two ends of the central limb as they
/// stay in the surrounding skin: at each end the copy (of the twin pair) that
/// the opposite flap pivots about, the corner the sutures close, not the copy
/// a flap carries onto a limb tip (that one ends up across the old axis).
/// Ideally the distance grows from the Z's short diagonal to its long one.
struct ZPlastyGain
{
  double before = 0.0;   ///< |(tip1 − tip0) · axis| before the operation (mm)
  double after = 0.0;    ///< the same after (mm)
  double gain = 0.0;     ///< after − before (mm)
  double fraction = 0.0; ///< gain / before, comparable with the Fig. 2.2 table
};
/// @param axis unit 3D direction of the central limb (centralAxis()).
ZPlastyGain zPlastyPredictedGain(const std::array<Eigen::Vector3d, 2>& tipsBefore,
                                 const std::array<Eigen::Vector3d, 2>& tipsAfter, const Eigen::Vector3d& axis);
/// The cut points at the ends of a Z's central limb (the flap tips): {1, 2}
/// for plans of the "z" generator, {2, 4} for "multiple-z" (Z-plasty with excision).
/// @throws std::invalid_argument for a plan that is not a Z.
std::array<int, 2> zPlastyFlapTips(const IncisionPlan& plan);
/// Unit 3D direction of the central limb on the skin, from flap tip 0 to flap tip 1.
Eigen::Vector3d centralAxis(const IncisionPlan& plan, const seg::RangeMap& skin);
///@}

} // namespace caps::planning
