#pragma once
/// @file RangeMapLogic.h
/// @brief Logic of the RangeMap module: a CT Volume node (and its skin/bone
/// label map) in, skin, bone and thickness range maps out; no widgets.

#include <map>
#include <optional>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <vtkImageData.h>

#include "modules/core/Module.h"
#include "segmentation/HeadAxis.h"
#include "segmentation/Landmarks.h"
#include "segmentation/MetalArtefacts.h"
#include "segmentation/RangeMap.h"
#include "segmentation/Thickness.h"

namespace caps {

class LabelMapNode;
class PlanNode;
class Scene;
class RangeMapNode;
class VolumeNode;

/// Everything RangeMapLogic::compute() finds, before it goes into the scene.
struct RangeMapOutput
{
  seg::HeadAxisFit axis;
  seg::RangeMap skin;            ///< r of the skin (mm)
  seg::RangeMap bone;            ///< r of the bone (mm)
  seg::RangeMap thickness;       ///< r_skin − r_bone (mm), along the ray from the axis
  seg::RangeMap thicknessNormal; ///< along the inward skin normal to the bone (mm)
  seg::ThicknessStatistics radialStatistics;
  seg::ThicknessStatistics normalStatistics;
  /// Samples whose r is the mask edge (no HU crossing next to it).
  std::size_t skinFromMaskEdge = 0;
  std::size_t boneFromMaskEdge = 0;
};

/// The ids of the four RangeMap nodes, and the label map they came from.
struct RangeMapResult
{
  std::string skinId, boneId, thicknessId, thicknessNormalId;
  std::string labelMapId;
  bool segmented = false; ///< the volume had no label map: run() segmented it first
};

/// A skin range map and the bone map built with it (either may be null).
struct SkinAndBoneMaps
{
  const RangeMapNode* skin = nullptr;
  const RangeMapNode* bone = nullptr;
};

/// @class RangeMapLogic
/// @brief Cylindrical range maps of the skin and bone and the soft-tissue
/// thickness, as scene nodes with roles "skin", "bone",
/// "thickness" and "thickness-normal".
///
/// run() = the label map of the volume (the Segment module's, made first if
/// there is none) + compute() (no scene: the GUI runs it on a worker thread)
/// + addToScene() (replaces the maps an earlier run made for the same volume).
class RangeMapLogic : public ModuleLogic
{
public:
  using ModuleLogic::ModuleLogic;

  struct Parameters
  {
    int nTheta = 512; ///< samples around the head
    int nZ = 256;     ///< samples along the axis
    /// 3 × 3 box smoothing of the skin and bone maps (§4.2.1, eq. 4.2) before the thickness.
    bool smooth = false;
    /// HU of the skin and bone crossings; also the thresholds when run() has
    /// to segment. A label map that records its own (LabelMapNode::thresholds)
    /// overrides them: see forLabelMap().
    double skinThresholdHu = -400.0;
    double boneThresholdHu = 250.0;
    /// The axis the user sets (LPS mm point, direction); none: fitted to the head.
    struct Axis
    {
      Eigen::Vector3d point;
      Eigen::Vector3d direction;
    };
    std::optional<Axis> axis;
  };

  /// Fits the head axis to the body (label ≥ 1), or takes Parameters::axis, and builds the maps from the
  /// CT and the label map (1 soft tissue, 2 bone). Touches no scene.
  /// @throws std::invalid_argument (no body, other grids, ...), seg::Cancelled.
  static RangeMapOutput compute(vtkImageData* ct, vtkImageData* labels, const Parameters& parameters,
                                const TaskProgress& progress = {});

  /// @a parameters with the thresholds @a labels was segmented with, when it
  /// records them: the sub-voxel crossings are searched at the HU where the
  /// masks were cut (segmenting at -300 HU gives crossings at -300 HU too).
  static Parameters forLabelMap(Parameters parameters, const LabelMapNode& labels);

  /// Adds the four RangeMap nodes for @a volume, made from the label map
  /// @a labelMapId (each records both, and the new skin map's id), and
  /// removes the maps an earlier run made for the same volume (those
  /// recording it as their source). Plans drawn on a
  /// removed skin map move to the new one (their cut paths are on the chart).
  RangeMapResult addToScene(const VolumeNode& volume, const RangeMapOutput& output, const NodeId& labelMapId = {});

  /// @name Which maps go together
  /// The one rule every module uses to pair maps: a bone map goes with the
  /// skin map it was built with (RangeMapNode::skinMapId), never with a map
  /// of another run. Maps of scenes saved before that was recorded pair with
  /// the newest map of the other role.
  ///@{
  /// The newest skin map of @a scene and the bone map built with it.
  static SkinAndBoneMaps newestMaps(const Scene& scene);
  /// The maps @a plan is drawn on: its own skin map (the newest one when
  /// that is gone) and the bone map built with it.
  static SkinAndBoneMaps mapsOf(const Scene& scene, const PlanNode& plan);
  /// The map of @a role ("bone", "thickness", ...) built with @a skin, or null.
  static const RangeMapNode* builtWith(const Scene& scene, const RangeMapNode& skin, const std::string& role);
  ///@}

  /// The whole pipeline on the scene (segmenting first when the volume has no
  /// label map), at the label map's thresholds (forLabelMap). @a output, when given, receives what compute() found.
  RangeMapResult run(const VolumeNode& volume, const Parameters& parameters, const TaskProgress& progress = {},
                     RangeMapOutput* output = nullptr);

  /// @name Conversions between the library's maps and the scene's nodes
  ///@{
  /// Rows θ, columns z (RangeMapNode's layout).
  static Eigen::MatrixXf toMatrix(const seg::RangeMap& map);
  /// The map a node holds, on its frame.
  static seg::RangeMap toRangeMap(const RangeMapNode& node);
  ///@}

  /// Fills the CT-measured depth columns of @a rows (seg::LandmarkDepth:
  /// along the skin's normal, to the nearest bone, and the depth by each
  /// landmark's published convention) from @a volume's CT and the bone and
  /// thresholds of its label map, each from the row's skin point. Leaves
  /// them NaN (and returns false) when the volume has no label map yet.
  bool measureLandmarkDepths(const VolumeNode& volume, std::vector<seg::LandmarkThickness>& rows) const;

  /// The metal in @a volume's CT (seg::findMetal), found once per image and
  /// kept; a landmark in the slices its streaks spoil gets a note.
  const std::vector<seg::MetalPiece>& metalOf(const VolumeNode& volume) const;

  /// Where the skin of @a volume's CT lies against an object outside the
  /// body (seg::skinAgainstAnObject, looking out along the radial direction
  /// of @a frame: the head holder, the table's pad), as a test of a skin
  /// point (LPS mm), at the label map's skin threshold; an empty test while
  /// the volume has no label map. The test holds the CT it reads.
  std::function<bool(const Eigen::Vector3d&)> againstAnObject(const VolumeNode& volume,
                                                              const seg::CylindricalFrame& frame) const;

  /// One line per fact: the axis (origin, direction, tilt, slices, residual) and z range.
  static std::string describeAxis(const seg::HeadAxisFit& axis);

private:
  /// metalOf()'s findings, for the image (and its modification time) they are of.
  struct MetalCache
  {
    const void* image = nullptr;
    unsigned long modified = 0;
    std::vector<seg::MetalPiece> pieces;
  };
  mutable MetalCache metal_;

  /// The maps a new run for @a volume replaces: those recording it as their
  /// source, whichever logic made them.
  static std::vector<NodeId> mapsOfVolume(const Scene& scene, const VolumeNode& volume);
};

} // namespace caps
