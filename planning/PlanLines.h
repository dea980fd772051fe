#pragma once
/// @file PlanLines.h
/// @brief The plan drawn on the 3D skin for the workstation's 3D view
/// (§3.3.1: incision lines solid): the cut path, the hole border of an
/// excision and the numbered cut points, lifted from the plan's chart to
/// the skin in world coordinates.

#include <array>

#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "planning/IncisionPlan.h"
#include "segmentation/RangeMap.h"

namespace caps::planning {

/// How far (mm) the lines sit outside the skin by default: enough that the
/// skin surface, drawn from its own triangles, does not hide them.
inline constexpr double kIncisionLineLift = 0.5;
/// The incision lines' colour (dark blue, as the panel draws them; RGB 0–255).
inline constexpr std::array<unsigned char, 3> kIncisionLineColour = {13, 26, 115};

/// @brief The plan's lines on the skin as polydata, in world coordinates (LPS mm).
///
/// Lines: the cut path as one polyline (sampled every `step` mm of chart
/// length so it follows the skin between cut points) and, for an excision,
/// the hole border as a closed polyline. Vertices: one per cut point, with
/// the point array "cut_point" holding its number (scalpel order, from 0;
/// -1 on line samples); "line_colour" (RGB) is kIncisionLineColour on the
/// cut and the hole border and kUnderminedTint on the outlines of the
/// plan's undermined regions (closed polylines). Every point is the skin point of its chart point
/// moved `lift` mm along the outward radial direction of the map's frame.
/// Chart points where the map has no skin are left out (the plan was
/// checked on this map, so that happens only on a map edited since).
/// @throws std::invalid_argument when the skin map has no surface at the plan's centre.
vtkSmartPointer<vtkPolyData> incisionLinesPolyData(const IncisionPlan& plan, const seg::RangeMap& skin,
                                                   double lift = kIncisionLineLift, double step = 0.5);

} // namespace caps::planning
