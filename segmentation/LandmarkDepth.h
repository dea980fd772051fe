#pragma once
/// @file LandmarkDepth.h
/// @brief Soft-tissue depth at a landmark, measured in the CT itself (not in
///        the range maps) by the conventions of the published depth tables.
///
/// The range maps give thickness along the ray from the cylinder's axis and
/// along the map's own normal, marched to the bone map: both miss bone the
/// radial ray never meets (the teeth behind the lips, bone that overhangs)
/// and follow the map's resolution. A landmark's depth is read from the CT
/// at full resolution instead, two ways (thesis §4.3 measures landmark
/// distances; the conventions are those of the soft-tissue depth tables):
/// - along the skin normal: from the skin point inward, perpendicular to the
///   skin, to where the line first enters bone. This is what an ultrasound
///   probe held perpendicular to the skin measures (De Greef et al. 2006,
///   "Large-scale in-vivo Caucasian facial soft tissue thickness database
///   for craniofacial reconstruction", Forensic Sci Int 159S:S126-S146,
///   967 adults), the largest table with these landmarks.
/// - to the nearest bone: the shortest distance from the skin point to the
///   bone surface, which is perpendicular to the bone there: the convention
///   of the CT and MRI studies that measure "perpendicular to the bone"
///   (Stephan and Simpson 2008, J Forensic Sci 53:1257-1272, review them).
/// The nearest bone is never farther than the bone along the normal.

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

#include "segmentation/Landmarks.h"
#include "segmentation/RangeMap.h"
#include "segmentation/RangeMapImageGeometry.h"

class vtkImageData;

namespace caps::seg {

/// Which of the two measures a landmark's published depth follows.
enum class DepthConvention
{
  SkinNormal,  ///< perpendicular to the skin, to the first bone met
  NearestBone, ///< the shortest distance to the bone surface
  NotADepth,   ///< no bone lies under the landmark (the nose tip: cartilage); shown, never compared
};

/// "perpendicular to the skin", "to the nearest bone", "not a bone depth".
const char* conventionName(DepthConvention convention);

/// The convention the published tables use for a standard landmark (by
/// name); SkinNormal for a name that is not a standard landmark.
DepthConvention depthConventionOf(const std::string& landmarkName);

/// Where the bone is from one skin point.
struct BoneDepth
{
  /// Where both are measured from: the point asked for, moved along the
  /// skin's normal onto the CT's skin (ontoSkin()).
  Eigen::Vector3d skinPoint = Eigen::Vector3d::Constant(RangeMap::quietNaN());
  /// Inward unit normal of the skin at skinPoint, from the CT's gradient.
  Eigen::Vector3d inwardNormal = Eigen::Vector3d::Constant(RangeMap::quietNaN());
  double alongSkinNormal = RangeMap::quietNaN(); ///< mm; NaN: no bone within the search distance
  Eigen::Vector3d boneAlongNormal = Eigen::Vector3d::Constant(RangeMap::quietNaN());
  double toNearestBone = RangeMap::quietNaN(); ///< mm; NaN: no bone within the search distance
  Eigen::Vector3d nearestBone = Eigen::Vector3d::Constant(RangeMap::quietNaN());
};

/// The HU of a CT at world points (LPS mm): trilinear between voxel
/// centres, air (-1000 HU) outside the CT. References the image, which must
/// outlive the sampler.
class CtSampler
{
public:
  /// @throws std::invalid_argument for a CT without one value per voxel or
  /// with fewer than two voxels along an axis.
  explicit CtSampler(vtkImageData* ct);
  double hu(const Eigen::Vector3d& world) const;
  /// At 0-based continuous voxel indices (the extent's start at 0).
  double huAtIndex(const Eigen::Vector3d& index) const;
  Eigen::Vector3d indexOf(const Eigen::Vector3d& world) const;
  Eigen::Vector3d worldOf(const Eigen::Vector3d& index) const;
  const ImageGeometry& geometry() const { return geometry_; }
  const std::array<int, 3>& dimensions() const { return dims_; }

private:
  vtkImageData* ct_;
  ImageGeometry geometry_;
  std::array<int, 3> dims_;
};

/// Whether the skin at @a skinPoint lies against something outside the
/// body: tissue-like HU (at or above @a skinThresholdHu) 1.5 mm and 3 mm
/// out along the unit @a outward. There the segmentation's skin is the edge
/// of its body mask beside the head holder, the table's pad or a dressing,
/// not a surface the CT measured, and no thickness read there can be
/// trusted. Outside the CT is air.
bool skinAgainstAnObject(const CtSampler& ct, const Eigen::Vector3d& skinPoint, const Eigen::Vector3d& outward,
                         double skinThresholdHu);

/**
 * @brief Finds the bone surface from points on the skin, in the CT: the
 *        crossing of boneThresholdHu (trilinear HU, refined by bisection, as
 *        the range maps find it) next to the bone mask.
 *
 * The images are referenced, not copied: they must outlive the probe.
 */
class BoneDepthProbe
{
public:
  /// @a ct HU, one component, any scalar type; @a boneMask unsigned char on
  /// the same grid, non-zero in bone; the HU of the bone's and the skin's
  /// surfaces (the segmentation's thresholds). @a searchDistance (mm)
  /// bounds both measures.
  /// @throws std::invalid_argument for a missing image, another grid or type.
  BoneDepthProbe(vtkImageData* ct, vtkImageData* boneMask, double boneThresholdHu, double skinThresholdHu = -400.0,
                 double searchDistance = 60.0);

  /// Both measures from @a skinPoint (LPS mm), along skinNormal().
  BoneDepth measure(const Eigen::Vector3d& skinPoint) const;

  /// The inward normal of the skin at @a skinPoint, at the CT's resolution:
  /// the polynomial surface (a cubic jet) fitted to the skin's HU crossings
  /// within 3 mm of the point (started from the HU gradient); NaN where the
  /// CT has no skin edge there.
  Eigen::Vector3d skinNormal(const Eigen::Vector3d& skinPoint) const;

  /// Distance along the unit @a direction from @a from to the first bone
  /// crossing (0 if @a from is in bone); NaN if none within the search
  /// distance. @a hit gets the crossing.
  double alongRay(const Eigen::Vector3d& from, const Eigen::Vector3d& direction, Eigen::Vector3d* hit = nullptr) const;

  /// Distance from @a from to the nearest point of the bone surface within
  /// @a radius (mm; at most the search distance); NaN if none. @a hit gets it.
  double toNearest(const Eigen::Vector3d& from, double radius, Eigen::Vector3d* hit = nullptr) const;

  /// The skin crossing nearest @a point on the line through it along the
  /// unit @a inwardNormal (within 4 mm); @a point itself where there is none.
  Eigen::Vector3d ontoSkin(const Eigen::Vector3d& point, const Eigen::Vector3d& inwardNormal) const;

  /// The HU at a world point (trilinear; -1000 outside the CT).
  double hu(const Eigen::Vector3d& world) const { return ct_.hu(world); }

private:
  // Indices are 0-based continuous voxel indices (the extent's start at 0).
  Eigen::Vector3d indexOf(const Eigen::Vector3d& world) const { return ct_.indexOf(world); }
  Eigen::Vector3d worldOf(const Eigen::Vector3d& index) const { return ct_.worldOf(index); }
  double huAtIndex(const Eigen::Vector3d& index) const { return ct_.huAtIndex(index); }
  bool inMask(int i, int j, int k) const;
  bool inMask(const Eigen::Vector3d& index) const;      ///< the nearest voxel
  bool maskTouches(const Eigen::Vector3d& index) const; ///< any voxel of the trilinear cell
  /// Whether a line along @a direction at @a world heads into the bone:
  /// within 60 degrees of the HU's gradient.
  bool goesIntoBone(const Eigen::Vector3d& world, const Eigen::Vector3d& direction) const;

  CtSampler ct_;
  const unsigned char* mask_;
  double threshold_;
  double skinThreshold_;
  double searchDistance_;
};

/// One row of the landmark depth table.
struct LandmarkDepth
{
  Landmark landmark;
  DepthConvention convention = DepthConvention::SkinNormal;
  BoneDepth bone;
  /// The convention the depth was measured by: the landmark's, except where
  /// the line perpendicular to the skin meets no bone within reach (the lips
  /// of a patient without teeth, skin over a thin bone the CT cannot show)
  /// and the nearest bone is taken instead.
  DepthConvention measuredBy() const;
  /// The depth by measuredBy() (mm); NaN where there is none.
  double depth() const;
  /// The deep end of the depth by measuredBy(): where the line from
  /// bone.skinPoint meets the bone; NaN where there is no depth.
  Eigen::Vector3d boneEnd() const;
  /// measuredBy()'s name, with why when it is not the landmark's own.
  std::string describeConvention() const;
};

} // namespace caps::seg
