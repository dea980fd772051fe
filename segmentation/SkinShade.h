#pragma once
/// @file SkinShade.h
/// @brief A colour for the skin of a CT, which has none: the "source color"
/// of the display surfaces (thesis §4.7, Table 4.9), and the reading of a
/// colour map between its samples.

#include <vtkImageData.h>

#include "segmentation/RangeMap.h"
#include "segmentation/SurfaceScanColourMap.h"

namespace caps::seg {

/// The colour of a surface with no source colour: grey, as in the thesis (§4.7).
inline constexpr Rgb8 kNoSourceColour = {170, 170, 170};

/// Options of skinShadeFromCt().
struct SkinShadeOptions
{
  /// Depths (mm) under the skin between which the CT is read, along the ray
  /// towards the axis (the direction the mesher extrudes along, §4.5). The
  /// first millimetre is left out: there the voxels mix skin and air.
  double depthBegin = 1.0;
  double depthEnd = 3.0;
  /// Samples (trilinear) between depthBegin and depthEnd, averaged.
  int samples = 5;
  /// CT values (HU) shown darkest and lightest: subcutaneous fat (about
  /// -100 HU) dark, dermis, muscle and cartilage (+20 to +100 HU) light.
  double darkHu = -150.0;
  double lightHu = 100.0;
  /// The ends of the ramp: a skin tone in shadow and in light.
  Rgb8 dark = {105, 70, 55};
  Rgb8 light = {245, 212, 190};
};

/// @brief A colour map of the skin derived from the CT (§4.7 "source color").
///
/// A CT has no colour. What it has a little under the skin is the tissue:
/// dense dermis, cartilage (nose, ears) and muscle read bright, fat dark,
/// so the mean CT value between depthBegin and depthEnd under each skin
/// sample, put through a window onto a skin-tone ramp, is a texture that
/// belongs to the tissue (it rides with the body coordinates when the skin
/// moves) and shows the anatomy at the scan's resolution, where a baked
/// lighting of the scan surface would show the pre-operative light on the
/// post-operative shape. Samples outside the CT are skipped; a skin sample
/// that is NaN, or with every sample outside, gets kNoSourceColour.
///
/// @param ct    HU voxels in the patient frame (origin, spacing, direction).
/// @param skin  the skin range map; the result is on its frame's grid.
/// @throws std::invalid_argument for a null or empty CT, an empty skin map
/// or bad options.
ColourMap skinShadeFromCt(vtkImageData* ct, const RangeMap& skin, const SkinShadeOptions& options = {});

/// The colour of @a map at θ (radians, wrapped) and z (mm): bilinear between
/// its samples (eq. 4.9 per channel), wrapping in θ; kNoSourceColour outside
/// the z range or for an empty map.
Rgb8 sampleColour(const ColourMap& map, double theta, double z);

} // namespace caps::seg
