#pragma once
/// @file RangeMapBuilder.h
/// @brief Skin and bone range maps from a CT and its body and bone masks.

#include <cstddef>

#include "segmentation/Progress.h"
#include "segmentation/RangeMap.h"

class vtkImageData;

namespace caps::seg {

struct RangeMapBuildOptions
{
  /// HU of the skin (air / soft tissue) crossing.
  double skinThreshold = -400.0;
  /// HU of the bone (soft tissue / bone) crossing.
  double boneThreshold = 250.0;
  /// Step of the march through the masks, in units of the smallest voxel spacing.
  double maskStep = 0.5;
  /// Step of the HU search near the mask edge, in the same units; the crossing
  /// is then refined by bisection on the trilinear interpolant.
  double crossingStep = 0.25;
  /// Threads over z rows (the result does not depend on it).
  int threads = 2;
  ProgressCallback progress;
};

/// The two maps on the same frame, and how many samples fell back to the mask edge.
struct SkinBoneRangeMaps
{
  RangeMap skin;
  RangeMap bone;
  /// Samples with no HU crossing next to the mask edge (the skin pressed
  /// against the head holder, say): r is the mask edge there, to a voxel.
  std::size_t skinFromMaskEdge = 0;
  std::size_t boneFromMaskEdge = 0;
};

/// Skin and bone range maps of a CT on frame's grid.
///
/// Each (θ_i, z_j) ray is marched inward from where it leaves the body
/// mask's bounding box: the first crossing met from outside is the outermost
/// one by construction, the march ends there (the skin is near the outside,
/// so it is short), and nothing outside the body can be taken for skin.
/// The march steps through the body mask (nearest voxel) until it enters
/// the mask; around that point (two voxels either way) the HU along the ray,
/// trilinearly interpolated, is searched for the first rise through
/// skinThreshold whose trilinear cell touches the mask, and the crossing is
/// refined by bisection (sub-voxel: the interpolated HU crossing, not the
/// voxel edge). The table and head holder are not in the mask, so they are
/// never skin. The bone map repeats this from the skin inward with the bone
/// mask and boneThreshold. NaN where the ray misses the mask, and where the
/// body mask reaches the edge of the scan along the ray (the skin there is
/// outside the CT: the top of a cut-off skull, shoulders wider than the field
/// of view); where the mask
/// is entered but no HU crossing lies next to it, the mask edge is used and
/// counted in SkinBoneRangeMaps.
///
/// @param ct HU, one component, any VTK scalar type (int16 and float are the usual).
/// @param bodyMask, boneMask unsigned char, non-zero inside, same grid as ct.
/// @throws std::invalid_argument for missing images, other grids or mask types; Cancelled.
SkinBoneRangeMaps buildRangeMaps(vtkImageData* ct, vtkImageData* bodyMask, vtkImageData* boneMask,
                                 const CylindricalFrame& frame, const RangeMapBuildOptions& options = {});

} // namespace caps::seg
