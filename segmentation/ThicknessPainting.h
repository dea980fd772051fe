#pragma once
/// @file ThicknessPainting.h
/// @brief Thickness painted on the skin surface as a point array.

#include <string>

#include "segmentation/RangeMap.h"

class vtkPolyData;

namespace caps::seg {

/// For each vertex of @a surface (world LPS mm), its (θ, z) on the map's
/// frame and the map read there bilinearly (RangeMap::sample): stored as the
/// float point array @a arrayName (replacing one of that name; it becomes the
/// active scalars), NaN where the map is (holes, outside its z range, a vertex
/// on the axis). Returns the number of vertices with a finite value.
/// @throws std::invalid_argument if surface is null or the map is empty.
long long paintThickness(vtkPolyData* surface, const RangeMap& thickness,
                         const std::string& arrayName = "thickness_mm");

} // namespace caps::seg
