#pragma once
/// @file SegmentLogic.h
/// @brief Logic of the Segment module: a CT Volume node in, a skin/bone label
/// map and display surfaces out; no widgets.

#include <filesystem>
#include <string>
#include <vector>

#include <vtkImageData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "modules/core/Module.h"
#include "scene/LabelMapNode.h"
#include "segmentation/HeadSegmentation.h"

namespace caps {

class SurfaceNode;
class VolumeNode;

/// Label values of the label maps the Segment module makes.
inline constexpr unsigned char kBackgroundLabel = 0;
inline constexpr unsigned char kSoftTissueLabel = 1;
inline constexpr unsigned char kBoneLabel = 2;

/// What segmenting a CT produces before anything goes into the scene: the
/// worker-thread half of SegmentLogic::segment().
struct SegmentationOutput
{
  /// 0 background, 1 soft tissue, 2 bone, on the CT's grid.
  vtkSmartPointer<vtkImageData> labels;
  /// Lightly smoothed surfaces for display, from the masks at half resolution.
  vtkSmartPointer<vtkPolyData> skinDisplay;
  vtkSmartPointer<vtkPolyData> boneDisplay;
  /// What the segmentation did and found (seg::HeadMasks::notes).
  std::vector<std::string> notes;
  /// The thresholds it was made with; addToScene() records them on the label map.
  LabelMapNode::Thresholds thresholds;
};

/// The ids of the nodes segment() made, and the segmentation's notes.
struct SegmentationResult
{
  std::string labelMapId;
  std::string skinSurfaceId;
  std::string boneSurfaceId;
  std::vector<std::string> notes;
};

/// @class SegmentLogic
/// @brief Skin and bone of a head CT, as scene nodes.
///
/// segment() = compute() (no scene: the GUI runs it on a worker thread) +
/// addToScene() (replaces an earlier segmentation of the same volume). The
/// thresholds default to the issue's -400 HU (air/tissue) and 250 HU (bone).
class SegmentLogic : public ModuleLogic
{
public:
  using ModuleLogic::ModuleLogic;

  struct Parameters
  {
    double skinThresholdHu = -400.0;
    double boneThresholdHu = 250.0;
  };

  /// Segments a CT in HU and makes the display surfaces. Touches no scene.
  /// @throws std::invalid_argument (nothing above the skin threshold, ...), seg::Cancelled.
  static SegmentationOutput compute(vtkImageData* ct, const Parameters& parameters, const TaskProgress& progress = {});

  /// Adds the label map and the "Skin" and "Bone" surfaces for @a volume,
  /// removing the ones an earlier segmentation of it left.
  SegmentationResult addToScene(const VolumeNode& volume, SegmentationOutput output);

  /// compute() + addToScene().
  SegmentationResult segment(const VolumeNode& volume, const Parameters& parameters, const TaskProgress& progress = {});

  /// The label map made from @a volume (the newest), or nullptr.
  LabelMapNode* findLabelMap(const VolumeNode& volume) const;

  /// @name Helpers on label images (static: usable without a scene)
  ///@{
  /// 0/1/2 label image from the body and bone masks (bone inside body).
  static vtkSmartPointer<vtkImageData> makeLabels(vtkImageData* body, vtkImageData* bone);
  /// 0/1 mask of the voxels whose label is at least @a minLabel (1: body, 2: bone).
  static vtkSmartPointer<vtkImageData> maskOf(vtkImageData* labels, int minLabel);
  /// The mask at half resolution (a 2×2×2 block is inside when at least 4 of
  /// its voxels are), with the geometry of the blocks' centres.
  static vtkSmartPointer<vtkImageData> halfResolution(vtkImageData* mask);
  /// Number of voxels whose label is at least @a minLabel, times the voxel volume (mm³).
  static double volumeMm3(vtkImageData* labels, int minLabel);
  /// Total triangle area (mm²).
  static double surfaceAreaMm2(vtkPolyData* surface);
  ///@}

  /// Display surface (half resolution, smoothed) and full-resolution surface
  /// (smoothed, not decimated: for STL/VTP export) of a 0/1 mask.
  static vtkSmartPointer<vtkPolyData> displaySurface(vtkImageData* mask);
  static vtkSmartPointer<vtkPolyData> fullSurface(vtkImageData* mask);
};

} // namespace caps
