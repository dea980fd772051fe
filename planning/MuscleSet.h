#pragma once
/// @file MuscleSet.h
/// @brief Facial muscles as text files in data/muscles/:
/// each muscle a set of force functions (thesis §4.6.2, Table 4.7,
/// eq. 4.40–4.42) whose origins and insertions are placed relative to facial
/// landmarks, so one set fits any patient.
///
/// A file lists muscles; a muscle lists force functions; a function gives its
/// origin and insertion as points relative to a landmark (an offset across
/// the face and up, scaled by the face's size, and a depth under the skin as
/// a fraction of the local soft-tissue thickness, or `bone`). The format is
/// documented in data/muscles/README.md. fitMuscleSet() turns a set into
/// fem::Muscle force functions in world space (LPS mm) for one patient.
///
/// Activation: the unit response of a muscle is its force functions with the
/// loads of the file (times the load_scale keys, over size², see
/// fitMuscleSet()). Activation a scales every
/// function's load by a; activation 1 is the load in the file, meant as a
/// strong contraction (0.5 to 2 N per force function in the default set,
/// before calibration by load_scale); 0 is at rest. Muscles only
/// pull: activations are in [0, 1] (more than 1 is allowed as an
/// exaggeration).

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fem/MuscleLoad.h"
#include "segmentation/Landmarks.h"
#include "segmentation/RangeMap.h"

namespace caps::expression {

/// A muscle file that cannot be used; what() is "FILE:LINE: what is wrong
/// and how to fix it".
class MuscleSetFileError : public std::runtime_error
{
public:
  MuscleSetFileError(const std::filesystem::path& file, int line, const std::string& message);
  const std::filesystem::path& file() const { return file_; }
  int line() const { return line_; } ///< 1-based; 0 when the file as a whole is at fault

private:
  std::filesystem::path file_;
  int line_;
};

/// Which side of the face a muscle definition describes.
enum class MuscleSide
{
  Left,   ///< one muscle on the patient's left, as written
  Right,  ///< one muscle on the patient's right, as written
  Both,   ///< written for the LEFT side; the fit also makes the mirrored right one
  Midline ///< one muscle across the midline (orbicularis oris, the corrugator pair)
};

/// "left", "right", "both", "midline".
const char* sideName(MuscleSide side);

/// One end of a force function, relative to the landmarks, as written in the
/// file. Lengths are mm on the adult mean face; the fit scales them by the
/// face's size (faceSize()).
struct AttachmentDefinition
{
  std::string anchor;  ///< landmark name (standard or derived: muscleAnchorNames())
  std::string towards; ///< "" or a second landmark: the anchor is blend of the way from @a anchor to it
  double blend = 0.0;  ///< fraction 0..1 from @a anchor to @a towards, in (θ, z)
  double across = 0.0; ///< mm across the face (placeAttachment()), + towards the patient's left
  double up = 0.0;     ///< mm along the head axis, + superior
  bool inBone = false; ///< `depth = bone`: on the bone surface (an origin only)
  double depth = 0.0;  ///< 0 the skin .. 1 the bone surface (ignored when inBone)
  double radius = 0.0; ///< attachment sphere radius, mm; 0: no force at this end
  int line = 0;        ///< where the file gives it
};

/// One force function (Table 4.7) as written in the file.
struct ForceFunctionDefinition
{
  std::string name; ///< e.g. "main", "ala"
  AttachmentDefinition origin;
  AttachmentDefinition insertion;
  double load = 0.0;    ///< l, N/mm^4, before the load_scale keys
  double falloff = 0.0; ///< fall-off width b, mm on the adult mean face (fem::Muscle::falloff)
  /// Only in a midline muscle: the fit also makes this function's mirror
  /// image (named NAME_left and NAME_right), so half a ring can be written.
  bool mirror = false;
  int line = 0;
};

/// One muscle as written in the file.
struct MuscleDefinition
{
  std::string id;    ///< "zygomaticus_major"
  std::string title; ///< "Zygomaticus major"
  MuscleSide side = MuscleSide::Both;
  std::string reference;  ///< where its anatomy comes from
  double loadScale = 1.0; ///< multiplies the loads of its functions
  std::vector<ForceFunctionDefinition> functions;
  int line = 0;
};

/// A muscle set read from a file.
struct MuscleSet
{
  std::filesystem::path file;
  std::string id; ///< "default"
  std::string title;
  std::string reference;
  double loadScale = 1.0; ///< multiplies every load of the set (for calibration)
  std::vector<MuscleDefinition> muscles;

  /// nullptr when there is no muscle definition of that id.
  const MuscleDefinition* find(const std::string& id) const;
};

/// Reads and validates one muscle file.
/// @throws MuscleSetFileError naming the file and line at fault and what to
///         write instead (unknown key or landmark, bad number, a function
///         with no insertion, ...).
MuscleSet readMuscleSet(const std::filesystem::path& path);

/// The default muscle set, default.muscles in the muscles folder:
/// $CAPS_DATA_DIR/muscles, else share/caps/data/muscles beside the installed
/// executable, else the source tree's data/muscles (as
/// planning::defaultProceduresFolder()).
std::filesystem::path defaultMuscleSetPath();

/// The landmark names an attachment may be anchored on: the standard ones
/// (seg::standardLandmarks()) and the derived ones of derivedAnchorNames().
std::vector<std::string> muscleAnchorNames();

/// Anchors derived from the landmarks through planning::FaceLayout (average
/// adult proportions, Farkas 1994): stomion (mouth centre), cheilion_left/right
/// (mouth corners), eye_left/right (eye centres), endocanthion_left/right and
/// exocanthion_left/right (inner and outer eye corners, 16 and 15 mm × size
/// medial and lateral of the eye centre).
std::vector<std::string> derivedAnchorNames();

/// The size of the face against the adult mean: nasion–subnasale height over
/// its adult mean of 53 mm (Farkas 1994), the measure planning::FaceLayout
/// scales the eyes and the mouth corners by, so that offsets from the derived
/// anchors stay in proportion with them.
/// @throws std::invalid_argument when nasion or subnasale is missing or the
///         nasion is not at least 20 mm above the subnasale.
double faceSize(const std::vector<seg::Landmark>& landmarks);

/// The landmarks a muscle set is placed by on one patient.
struct MuscleAnchors
{
  /// Every anchor, standard and derived, as landmarks (θ, z). Derived anchors
  /// are present only when planning::FaceLayout can be made.
  std::vector<seg::Landmark> anchors;
  double size = 1.0; ///< faceSize()
  /// mm of arc per radian of θ for the offsets across: the skin radius at the
  /// nasion (90 mm without one), as planning::FaceLayout::scale.
  double arcRadius = 90.0;
};

/// The anchors, the size and the arc radius of one patient.
/// @throws std::invalid_argument as faceSize().
MuscleAnchors muscleAnchors(const std::vector<seg::Landmark>& landmarks, const seg::RangeMap& skin);

/// Options of the fit.
struct MuscleFitOptions
{
  /// Soft-tissue thickness (mm) used where the bone map has no bone at or near
  /// a point (the nose, the lips over the mouth) or where the bone lies deeper
  /// than @a maximumThickness (the ray from the axis went through the orbit or
  /// the nasal cavity): 12 mm, about the soft tissue of the lips and cheeks
  /// over the maxilla (tissue-depth tables).
  double defaultThickness = 12.0;
  double maximumThickness = 30.0;
  /// Holes of the bone map up to this far (mm on the skin, each way) are
  /// bridged by the median of the measured thicknesses within this distance.
  double boneSearch = 5.0;
};

/// Where the soft-tissue thickness of an attachment came from.
enum class ThicknessSource
{
  Measured, ///< skin − bone at the point itself
  /// The median of the valid samples within MuscleFitOptions::boneSearch:
  /// where the point has none, or one off that median by more than 3 mm and
  /// 30 % (a ray through a thin wall that found the bone behind it).
  Nearby,
  Default ///< MuscleFitOptions::defaultThickness
};

/// One attachment placed on the patient.
struct AttachmentPlacement
{
  double theta = 0.0;      ///< cylindrical frame, radians
  double z = 0.0;          ///< mm
  double r = 0.0;          ///< mm from the axis
  double skinRadius = 0.0; ///< skin map at (θ, z)
  double thickness = 0.0;  ///< soft-tissue thickness used, mm
  ThicknessSource source = ThicknessSource::Measured;
  Eigen::Vector3d position = Eigen::Vector3d::Zero(); ///< world LPS mm
};

/// One muscle of the patient: a definition fitted, on one side.
struct FittedMuscle
{
  std::string id;         ///< "zygomaticus_major_left"; a midline muscle keeps its id
  std::string title;      ///< "Zygomaticus major (left)"
  std::string definition; ///< the id in the file, "zygomaticus_major"
  std::string side;       ///< "left", "right" or "midline"
  /// The force functions in world space, loads times the load_scale keys:
  /// the unit response (activation 1). Names "MUSCLE.FUNCTION".
  std::vector<fem::Muscle> functions;
  /// Origin and insertion of each function, same order.
  std::vector<std::pair<AttachmentPlacement, AttachmentPlacement>> placements;
};

/// Places one attachment: the anchor's (θ, z) (blended in θ and z when
/// @a point names two), then up × size added to z and across × size turned
/// into θ on the face's reference cylinder (Δθ = across × size / arcRadius,
/// negated when @a mirrored), then moved in along the ray towards the axis by
/// depth × the soft-tissue thickness there (skin − bone; see MuscleFitOptions
/// where there is no bone). Anchor names are mirrored (_left ↔ _right) when
/// @a mirrored.
///
/// Why one radius for the offsets rather than the skin's own arc or radius
/// at the anchor: the skin's section runs over the nose (10 mm across from
/// the nasion would end on the nasal side wall) and under the chin (the
/// menton's radius is a third smaller than the chin's front), and the
/// derived anchors (mouth corners, eyes) are already placed this way by
/// planning::FaceLayout. Heights are exact and a mirrored point is exactly
/// the mirror in θ about the mirrored anchors.
/// @throws std::invalid_argument for a missing anchor or a point off the skin map.
AttachmentPlacement placeAttachment(const AttachmentDefinition& point, bool mirrored, const MuscleAnchors& anchors,
                                    const seg::RangeMap& skin, const seg::RangeMap& bone,
                                    const MuscleFitOptions& options = {});

/// The muscles of @a set on one patient, in file order, a both-sided muscle
/// as its left then its right one. Radii and fall-offs are scaled by the
/// face's size; loads (written for the adult mean face) are multiplied by the
/// set's and the muscle's load_scale and divided by size²: the force density
/// l (p_o − p_i) grows with the face's size and the tissue's displacement
/// under a body force with the square of its extent, so a face scaled by k
/// makes the same expression (the same strains) with forces k² times those
/// of the mean face. @a bone may be empty (0 × 0): every
/// thickness is then the default.
/// @throws std::invalid_argument naming the landmarks that are missing, a
///         point that falls off the skin map, or a bone map on another frame.
std::vector<FittedMuscle> fitMuscleSet(const MuscleSet& set, const std::vector<seg::Landmark>& landmarks,
                                       const seg::RangeMap& skin, const seg::RangeMap& bone,
                                       const MuscleFitOptions& options = {});

} // namespace caps::expression
