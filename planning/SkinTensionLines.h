#pragma once
/// @file SkinTensionLines.h
/// @brief Relaxed skin tension lines (RSTL) of the face as a guide for where
/// to cut (thesis §5.6: the surgeons asked for them), placed on the patient by
/// the facial landmarks.
///
/// The lines are schematic: a direction field drawn by us after the RSTL map
/// of Borges (Plast. Reconstr. Surg. 73:144, 1984) and the textbook figures
/// that reproduce it, not a digitised atlas and not measured on the patient:
/// - forehead: horizontal, arching gently down towards the temples;
/// - glabella: vertical, between the brows;
/// - eyelids: arcs parallel to the lid margins; lateral canthus: lines
///   radiating outwards (crow's feet);
/// - nasal dorsum: across the nose;
/// - cheek: parallel to the nasolabial fold (down and out from the ala),
///   turning vertical in front of the ear;
/// - lips: radial to the mouth (vertical on the upper lip);
/// - chin and neck: horizontal.
/// Each region's direction is blended into the next by smooth weights on the
/// doubled angle (a line has no sign), so the field is continuous except at
/// the few points where the regions meet at right angles, as the real lines
/// are. Where a patient's own wrinkles disagree, the wrinkles win.
#include <string>
#include <vector>

#include <Eigen/Core>
#include <vtkSmartPointer.h>

#include "planning/SkinChart.h"
#include "segmentation/Landmarks.h"
#include "segmentation/RangeMap.h"

class vtkPolyData;

namespace caps::planning {

class IncisionPlan;

/// Where the face's features are, on the skin map's cylindrical frame: the
/// heights (z, mm) of the midline landmarks and the lateral offsets (mm of
/// arc on the skin) of the eyes and the mouth corners.
struct FaceLayout
{
  double frontTheta = -1.5707963267948966; ///< θ of the midline
  double scale = 90.0;                     ///< mm of arc per radian of θ (skin radius at the nasion)
  double zGlabella = 0.0;
  double zNasion = 0.0;
  double zPronasale = 0.0;
  double zSubnasale = 0.0;
  double zStomion = 0.0;
  double zLabraleInferius = 0.0;
  double zMenton = 0.0;
  double eyeOffset = 0.0;      ///< midline to the centre of each eye, mm of arc
  double eyeZ = 0.0;           ///< height of the eyes' centres
  double mouthHalfWidth = 0.0; ///< midline to each mouth corner, mm of arc

  /// The layout from facial landmarks (seg::placeLandmarks() or placed by
  /// hand): glabella, nasion, pronasale, subnasale, labrale_superius,
  /// labrale_inferius and menton (pogonion stands in for a missing menton,
  /// 12 mm below it). The eyes and the mouth are not landmarks yet: they are
  /// placed by average proportions of the adult face (eye centres 32 mm from
  /// the midline and 15 % of nasion–subnasale below the nasion, mouth
  /// corners 25 mm out), scaled by the nasion–subnasale height against its
  /// adult mean of 53 mm (Farkas, Anthropometry of the Head and Face, 1994).
  /// @throws std::invalid_argument naming the landmarks that are missing, or
  /// when the heights are not in anatomical order (nasion above pronasale
  /// above subnasale above the lips above the menton).
  static FaceLayout fromLandmarks(const std::vector<seg::Landmark>& landmarks, const seg::RangeMap& skin);
};

/// @class SkinTensionLines
/// @brief The RSTL direction field on one patient's skin and its lines.
class SkinTensionLines
{
public:
  /// @warning Keeps a pointer to @a skin: the map must outlive this object.
  SkinTensionLines(const seg::RangeMap& skin, FaceLayout layout);

  const FaceLayout& layout() const { return layout_; }
  const seg::RangeMap& skin() const { return *skin_; }

  /// Unit direction of the local line at (θ, z) in the local chart metric
  /// (SkinChart: u = r·dθ along increasing θ, v = dz), sign arbitrary.
  Eigen::Vector2d directionAt(double theta, double z) const;

  /// The angle (degrees, 0..90) between a direction on the skin at (θ, z),
  /// given in the same metric, and the local line.
  double angleTo(double theta, double z, const Eigen::Vector2d& direction) const;

  /// Whether (θ, z) is on the face the guide covers (forehead to neck, ear
  /// to ear in front, not the eyes or the mouth) with skin under it.
  bool covers(double theta, double z) const;

  /// Lines for display: polylines of skin points traced through the field,
  /// about @a spacing mm apart, over the part of the face covers() accepts.
  std::vector<std::vector<SkinPoint>> traceLines(double spacing = 9.0) const;

private:
  // The field in the face plane: x = scale·(θ − frontTheta) (patient left
  // positive), y = z; returns the line's angle from +x in radians.
  double planeAngle(double x, double y) const;

  const seg::RangeMap* skin_;
  FaceLayout layout_;
};

/// The lines on the skin as 3D polylines (world LPS mm), for the 3D view,
/// lifted kIncisionLineLift off the skin like the plan's lines.
vtkSmartPointer<vtkPolyData> skinTensionLinesPolyData(const SkinTensionLines& lines, double spacing = 9.0);

/// How a plan's cut lies against the lines: its axis (a Z-plasty's central
/// limb, whose direction the transposition turns; any other cut's first to
/// last point) and the angle to the local line at the axis's middle.
struct AxisToTensionLines
{
  std::string axis; ///< e.g. "p1–p2"
  double degrees = 0.0;
};
/// @throws std::invalid_argument when the axis's middle is off the guide.
AxisToTensionLines axisToTensionLines(const IncisionPlan& plan, const SkinTensionLines& lines);

} // namespace caps::planning
