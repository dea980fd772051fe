#pragma once
/// @file Landmarks.h
/// @brief Facial soft-tissue landmarks on the cylindrical frame, thickness at them, CSV.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "segmentation/RangeMap.h"

namespace caps::seg {

/// A landmark the user (or automatic placement) put on the skin: where on the
/// cylindrical frame, θ in radians (θ = -π/2 the front of the face, θ = 0
/// patient left) and z in mm along the axis. The skin point is the skin range
/// map at (θ, z). Landmarks are data: the user may move or add any.
struct Landmark
{
  std::string name;
  double theta = 0.0;
  double z = 0.0;
};

/// A standard facial soft-tissue landmark: its name (as in Landmark::name and
/// the CSV) and a one-line description.
struct LandmarkDefinition
{
  const char* name;
  const char* description;
};

/// The standard landmarks, in the order placeLandmarks() returns them:
/// supraglabella, glabella, nasion, mid_nasal, rhinion, pronasale, subnasale,
/// mid_philtrum, labrale_superius, labrale_inferius, sublabiale, pogonion,
/// menton, zygion_left/right, gonion_left/right, mid_cheek_left/right,
/// supraorbital_left/right, infraorbital_left/right, forehead.
const std::vector<LandmarkDefinition>& standardLandmarks();

/// The description of a standard landmark, or "" for a name that is not one.
std::string landmarkDescription(std::string_view name);

/// One row of the landmark thickness table.
struct LandmarkThickness
{
  Landmark landmark;
  /// The skin point at (θ, z), world LPS mm; NaN where the skin map is.
  Eigen::Vector3d position = Eigen::Vector3d::Constant(RangeMap::quietNaN());
  /// Radial thickness r_skin − r_bone at (θ, z), mm; NaN where none.
  double radial = RangeMap::quietNaN();
  /// Thickness along the inward skin normal at (θ, z), mm; NaN where none.
  double normal = RangeMap::quietNaN();
  /// Measured in the CT at full resolution (LandmarkDepth.h): from the skin
  /// point along the skin's normal to the first bone, and to the nearest
  /// bone (mm); the depth by the landmark's published convention and that
  /// convention's name. NaN and empty where not measured.
  double ctSkinNormal = RangeMap::quietNaN();
  double ctNearestBone = RangeMap::quietNaN();
  double depth = RangeMap::quietNaN();
  std::string convention;
  /// The measured segment: from the skin (the point moved onto the CT's
  /// skin) to the bone end of the depth; NaN where there is no depth.
  Eigen::Vector3d depthSkinEnd = Eigen::Vector3d::Constant(RangeMap::quietNaN());
  Eigen::Vector3d depthBoneEnd = Eigen::Vector3d::Constant(RangeMap::quietNaN());
  /// What spoils the measure, if anything (metal streaks in its slices).
  std::string note;
};

/// The thickness table: for each landmark, its skin point and the radial and
/// normal thickness maps read bilinearly at its (θ, z) (RangeMap::sample, so
/// NaN next to holes and outside the z range). Any map may be empty (0 × 0):
/// its column is NaN.
/// @throws std::invalid_argument if two non-empty maps are on different frames.
std::vector<LandmarkThickness> landmarkThickness(const std::vector<Landmark>& landmarks, const RangeMap& skin,
                                                 const RangeMap& radial, const RangeMap& normal);

/// Writes the table as CSV with the header
/// `name,theta_deg,z_mm,x,y,z,radial_mm,normal_mm,ct_skin_normal_mm,ct_nearest_bone_mm,depth_mm,convention,note`
/// (x, y, z in LPS mm), one row per landmark, numbers in the shortest form
/// that reads back exactly, NaN as an empty field. Atomic: written beside,
/// then renamed.
/// @throws std::invalid_argument if a name is empty or holds a comma, quote or line break;
///         std::runtime_error if the file cannot be written.
void writeLandmarkCsv(const std::filesystem::path& path, const std::vector<LandmarkThickness>& rows);

/// Reads a file writeLandmarkCsv() wrote (or a person edited): the header must
/// name the 13 columns in that order, or the first 8 (the table before the
/// CT-measured depths); blank lines are skipped; an empty field or "nan" is
/// NaN. name, theta_deg and z_mm are required on each row.
/// @throws std::runtime_error naming the file and line of the first problem.
std::vector<LandmarkThickness> readLandmarkCsv(const std::filesystem::path& path);

} // namespace caps::seg
