#pragma once
/// @file HeadSegmentation.h
/// @brief Skin (body) and bone label maps of a head CT.

#include <string>
#include <vector>

#include <vtkImageData.h>
#include <vtkSmartPointer.h>

#include "segmentation/Progress.h"

namespace caps::seg {

/// Thresholds and clean-up sizes of segmentHead(). Lengths in mm, volumes in mm³.
struct SegmentationParameters
{
  /// Air/tissue threshold: voxels above it are body candidates (skin, fat,
  /// muscle, bone, but also the table, the head holder, clothes).
  double skinThresholdHu = -400.0;
  /// Bone threshold: body voxels above it are bone.
  double boneThresholdHu = 250.0;
  /// Radius of the opening that cuts the body from the table and the head
  /// holder: structures thinner than twice this (shells, plates, thin
  /// contacts) vanish from the opened mask. Larger radii cut broader contacts
  /// but round off more of the body (restored afterwards, see reconstructionMarginMm).
  double openingRadiusMm = 2.5;
  /// After the opening, the body is grown back into the thresholded mask by
  /// openingRadiusMm + this margin, which restores the detail the opening
  /// rounded off while keeping away from the removed structures, except for
  /// a sliver about this wide where they touched the body.
  double reconstructionMarginMm = 1.0;
  /// Pieces above the skin threshold that the opening cut off the body and
  /// the regrowth did not restore (the rims of the ears, a thin nose or lip)
  /// are put back when they touch the body and are smaller than this; the
  /// table and the head holder are far larger.
  double maxReattachedPieceMm3 = 20000.0;
  /// Fill the enclosed air of each axial slice (airway, sinuses, nostrils,
  /// the cut trachea at the bottom of the scan), then every 3D cavity.
  bool fillInternalAir = true;
  /// Bone pieces smaller than this are removed (noise, calcifications, small
  /// contrast-filled vessels, dental-artefact speckles).
  double minBoneIslandMm3 = 500.0;
  /// Cavities of the bone mask smaller than this (marrow below the bone
  /// threshold, voxels lost to noise) are filled; larger ones (sinuses, the
  /// cranial cavity) are kept.
  double maxBoneHoleMm3 = 500.0;
};

/// Label maps of a head CT.
///
/// Both are unsigned char images holding 0 or 1, with exactly the CT's
/// dimensions, origin, spacing and direction matrix.
struct HeadMasks
{
  vtkSmartPointer<vtkImageData> body; ///< the head and neck as one solid; its boundary is the skin
  vtkSmartPointer<vtkImageData> bone; ///< bone (and whatever else is that dense) inside the body
  /// What the segmentation did and found, for the user and the log
  /// ("body: 4.21 L, 1 component; removed 2 structures touching it ...").
  std::vector<std::string> notes;
};

/// Segments the body and the bone of a head CT given in HU.
///
/// Body: threshold at skinThresholdHu; on a working grid of about 1 mm,
/// erosion by a ball of openingRadiusMm so that thin structures and thin
/// contacts disappear, largest connected component, dilation by
/// openingRadiusMm + reconstructionMarginMm (an opening of the body alone,
/// slightly grown); at full resolution, that region intersected with the
/// threshold mask, plus the small pieces above the threshold it misses
/// (maxReattachedPieceMm3), and the largest 6-connected component kept;
/// enclosed air filled in each axial slice (the image axis closest to patient
/// superior: airway, sinuses, nostrils, the lungs and the trachea cut by the
/// scan range), then every 3D cavity. An open mouth and the nostrils' and
/// ear canals' openings stay open where they reach the outside in the axial
/// slices: they are part of the skin surface.
/// Bone: threshold at boneThresholdHu inside the body; components smaller
/// than minBoneIslandMm3 removed, cavities smaller than maxBoneHoleMm3 filled.
///
/// @warning In a contrast CT, arteries and veins can exceed the bone
/// threshold; the large ones survive the island removal as bone. Metal
/// (dental fillings, implants) and its streak artefacts are classified as bone.
/// @param ct scalar image in HU (any scalar type; int16 or float from readCtVolume)
/// @throws std::invalid_argument for an empty or multi-component image, or
///         when nothing lies above the skin threshold; Cancelled.
HeadMasks segmentHead(vtkImageData* ct, const SegmentationParameters& parameters,
                      const ProgressCallback& progress = {});

} // namespace caps::seg
