#pragma once
/// @file ColourMaps.h
/// @brief The colour maps CAPS paints scalars with (stress, strain,
/// thickness), shared by the workstation's views and the printed report so
/// a colour means the same value on screen and on paper.

#include <array>
#include <optional>
#include <string>

#include <vtkSmartPointer.h>

class vtkLookupTable;

namespace caps::render {

/// An RGB colour, each channel in [0, 1].
using Rgb = std::array<double, 3>;

/// Colour maps for scalars on the face, all readable in print and in grey.
enum class ColourMap
{
  CoolWarm,  ///< Moreland's diverging blue → grey → red; for signed values (strain, displacement)
  Viridis,   ///< perceptually uniform dark blue → green → yellow; for stress
  Thickness, ///< ColorBrewer YlGnBu: pale yellow (thin) → dark blue (thick); for tissue thickness
};

/// The map's colour at t in [0, 1] (clamped; NaN gives the low end).
Rgb colourMapColour(ColourMap map, double t);

/// A 256-entry VTK lookup table of the map over [range[0], range[1]], NaN grey.
vtkSmartPointer<vtkLookupTable> colourMapLookupTable(ColourMap map, const std::array<double, 2>& range);

/// "cool-warm", "viridis", "thickness": the names scene files use.
std::string colourMapName(ColourMap map);
/// The map of a name colourMapName() gives; std::nullopt for any other.
std::optional<ColourMap> colourMapFromName(const std::string& name);

} // namespace caps::render
