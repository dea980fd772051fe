#pragma once
/// @file Undermining.h
/// @brief The regions of skin a plan undermines (thesis §3.2.2, §3.2.4
/// item 2: the skin freed from what lies beneath, its bone nodes no longer
/// fixed): checked when drawn, mapped into the plan's chart, and the
/// surface-mesh vertices inside them found.
///
/// The default form, a band of a given width along the sutured edges, is a
/// simulation option (SimulationOptions::underminingWidth,
/// fem::underminingBand()); the regions here are what the surgeon paints or
/// selects on the skin, kept by the plan (IncisionPlan::underminedRegions()).
/// simulatePlan() undermines the union of both.

#include <vector>

#include "fem/SurfaceMesh.h"
#include "planning/IncisionPlan.h"
#include "planning/SkinChart.h"

namespace caps::planning {

/// @brief A region (θn, zn) in @a chart (mm), as one piece.
///
/// The first point goes where the chart puts it; each next one is joined
/// the short way round the head (its θ step wrapped into [-π, π)), so a
/// region straddling the chart's seam (θ = θc ± π) stays one polygon; its
/// u may then leave (-π r0, π r0]: insideRegion() wraps.
std::vector<ChartPoint> regionInChart(const UnderminedRegion& region, const SkinChart& chart);

/// Whether @a p lies inside the closed polygon (even-odd crossing rule:
/// a ray from p towards +u crosses its border an odd number of times). A
/// point on the border may go either way.
bool insidePolygon(const std::vector<ChartPoint>& polygon, const ChartPoint& p);

/// Whether chart point @a p lies inside a region in the chart
/// (regionInChart()), p's u taken as it is and once round the head either
/// way (± 2π r0, @a period).
bool insideRegion(const std::vector<ChartPoint>& region, const ChartPoint& p, double period);

/// @brief Checks a region can be undermined on the skin of @a chart.
///
/// @throws std::invalid_argument saying what is wrong and what to do: fewer
/// than 3 points; a point that is not a number, outside the scanned z range
/// or where the skin map has no surface; two consecutive points at the same
/// place; a region that goes all the way round the head; two edges of its
/// border crossing or touching (a border folding back on itself touches);
/// no area (points on one line). Points are numbered from 0.
void checkUnderminedRegion(const UnderminedRegion& region, const SkinChart& chart);

/// @brief Per vertex of @a surface (chart mm, the plan's chart), 1 where it
/// lies inside any of the plan's undermined regions, else 0.
std::vector<char> underminedRegionVertices(const fem::SurfaceMesh& surface, const IncisionPlan& plan,
                                           const SkinChart& chart);

/// Sets to 1 the flags of the vertices underminedRegionVertices() finds,
/// leaving the others as they are: the union with another undermined set
/// (the band, fem::underminingBand()). @a flags must hold one flag per
/// vertex of @a surface (std::invalid_argument otherwise).
void addUnderminedRegions(const fem::SurfaceMesh& surface, const IncisionPlan& plan, const SkinChart& chart,
                          std::vector<char>& flags);

} // namespace caps::planning
