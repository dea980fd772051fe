#pragma once
/// @file LandmarkPlacement.h
/// @brief Automatic initial placement of the facial landmarks from the skin (and bone) range maps.
///
/// Everything is found on the maps themselves, in the cylindrical frame
/// (θ = -π/2 the front of the face, row 0 the inferior end), with simple rules
/// a person can check on the midline profile. The result is a first guess the
/// user moves; the rules, from the most to the least reliable:
///
/// Midline profile p(z): for each row, the median of the skin map over the
/// 2 · halfColumns + 1 columns around θ = -π/2 (NaN samples ignored). The
/// nasion, glabella, subnasale and lip rules read p through a 5-row running
/// median (one-row glitches are not features); the others read p itself.
/// - pronasale (reliable): the largest p in the upper two thirds of the rows
///   (below lie the neck and the shoulders, which can reach further out),
///   if it is a nose: at least 5 mm inside the scan's rows of skin, and at
///   least 8 mm in front of the skin 20° beside it (the lower side: a head
///   turned a little has cheek there) and of the profile 10 to 50 mm above it (a nose stands 15-30 mm out; a brow or a forehead, the
///   most prominent point of a scan cut above the nose, a few mm). Otherwise
///   the nose is not in the scan, and neither is any landmark below: every
///   rule here starts from the nose tip, so none is placed, each listed as
///   not in the scan with why (LandmarkPlacement::status).
/// - jaw underside (helper, reliable): walking down from the pronasale, the
///   first row with p < 60 % of the pronasale's (the neck is much closer to
///   the axis than the face).
/// - pogonion (reliable): the largest p 5 to 25 mm above the jaw underside.
///   (On real profiles the lips and the chin are within a few mm of the same
///   r, so "the local maximum below the lips" is not stable; the jaw is.)
/// - nasion (reliable): the smallest p 10 to 50 mm above the pronasale.
/// - glabella (reliable): the largest p up to 25 mm above the nasion.
/// - supraglabella (fair): the smallest p up to 25 mm above the glabella,
///   where the profile comes forward again by 0.5 mm above it (the deepest
///   point of the concavity above the glabella; Rhine and Campbell 1980).
///   A forehead that only recedes has none: not found.
/// - rhinion (approximate; needs the bone map): the lower end of the nasal
///   bones. On the bone map's midline, walking down from the nasion's height
///   to the nose tip's, the last row before the bone falls back by more than
///   5 mm (the ray then passes into the nasal cavity); placed on the skin at
///   that height. Thin nasal bones the segmentation loses put it too high.
/// - mid-nasal (approximate): half-way in z from the nasion to the rhinion.
/// - sublabiale (fair): the smallest p between the labrale inferius and the
///   pogonion (the labiomental fold: the tables' chin-lip fold).
/// - forehead (reliable as a place; not anatomical): 75 mm above the
///   pronasale, above the glabella and below the hairline.
/// - menton (fair): where p, walking down from the pogonion to the jaw
///   underside, crosses half-way between them (linear between rows): the
///   underside of the chin is nearly horizontal, so p drops steeply there.
/// - subnasale (fair): walking down from the pronasale, the first row at least
///   5 mm behind it that is the smallest p within ±3 mm of itself (the foot of
///   the columella, before the upper lip comes forward again).
/// - labrale superius / inferius (fair; lips closed and at rest): with
///   d = z_subnasale − z_pogonion, the largest p in (z_sn − 0.45 d, z_sn) and
///   in [z_pog + 0.25 d, z_sn − 0.45 d].
/// - mid-philtrum (fair): on the midline half-way in z between the subnasale
///   and the labrale superius.
/// - mid-cheek left/right (fair): at the height of the nose tip, 32 mm
///   either side of the midsagittal plane (the plane of the axis and the
///   front): under the pupil (half the mean adult interpupillary distance,
///   Farkas 1994), beside the ala over the maxilla. (An angle from the axis
///   would put it at the jaw on a wide face.)
/// - supraorbital / infraorbital left/right (fair; need the bone map): the
///   upper and lower rims of the orbit on the pupil's column (32 mm from the
///   midsagittal plane, 5 mm below the nasion). The deepest bone of the
///   column within 35 mm below and 20 mm above the nasion is the orbit;
///   walking up (down) from it, the rim is where the bone first comes within
///   1 mm of the highest bone in the next 15 mm (where the orbit's wall ends,
///   at the crest of a raised margin), which must stand 8 mm or more above
///   the orbit (De Greef et al. 2006's mid-supraorbital and
///   mid-infraorbital). Placed on the skin at the rim's height on that column.
/// - zygion left/right (approximate): the laterally widest point, largest
///   r·|cos θ|, of the bone map (the skin map without one) for z between the
///   pronasale and the nasion and θ 25° to 80° from the front on that side
///   (stops 10° before the side of the head, where the ears are); placed on
///   the skin at the same (θ, z).
/// - gonion left/right (approximate, check it): the laterally widest point of
///   the bone map (the skin map without one) for z from the menton up to the
///   subnasale (menton + 40 mm without one) and θ 30° to 95° from the front:
///   the mandible's angle is its widest part below the condyles.
///   For both, only widths that peak along z inside the band count: a
///   widest point on the band's end is where the band cuts a bone growing
///   wider beyond it (the maxilla above the jaw), not the feature.
/// The midline features found on rows (pronasale, nasion, glabella,
/// supraglabella, subnasale, the lips, sublabiale, pogonion) are placed at
/// their apexes between rows: the vertex of a parabola fitted to the raw
/// profile over five rows.
/// Left is patient left: θ > -π/2 (towards θ = 0).

#include <string>
#include <vector>

#include "segmentation/Landmarks.h"
#include "segmentation/RangeMap.h"

namespace caps::seg {

/// θ of the front of the face.
inline constexpr double kFrontTheta = -1.5707963267948966;

/// p(z): per row j, the median of the finite skin samples in the columns
/// nearest θ within ±halfColumns (NaN if none).
std::vector<double> midlineProfile(const RangeMap& skin, double theta = kFrontTheta, int halfColumns = 3);

/// Rows of the midline profile features (-1 where not found) and the profile.
struct ProfileFeatures
{
  std::vector<double> profile;
  int pronasale = -1;
  int jawUnderside = -1;
  int pogonion = -1;
  int nasion = -1;
  int glabella = -1;
  int subnasale = -1;
  int labraleSuperius = -1;
  int labraleInferius = -1;
  int supraglabella = -1;
  int sublabiale = -1;
  /// z of the menton (mm, between rows); NaN where not found.
  double mentonZ = RangeMap::quietNaN();
  /// Why the profile's most prominent point is not a nose tip (at the edge
  /// of the scan, or standing less than a nose in front of the profile above
  /// it): the nose is not in the scan, pronasale is -1 and so is every
  /// feature found from it. Empty when the nose tip was found.
  std::string noseMissing;
};

/// The profile features by the rules in this file's comment; none when the
/// nose is not in the scan (ProfileFeatures::noseMissing says why).
/// @throws std::runtime_error if the profile has no finite sample in its upper two thirds.
ProfileFeatures findProfileFeatures(const RangeMap& skin, int halfColumns = 3);

/// Whether a standard landmark was placed.
enum class LandmarkState
{
  Placed,
  NotInScan, ///< its anatomy lies outside the scanned region
  NotFound,  ///< inside the scan, but its feature is not on the profile
};

/// What became of one standard landmark.
struct LandmarkStatus
{
  std::string name;
  LandmarkState state = LandmarkState::Placed;
  /// How far its rule can be trusted: "reliable", "fair" or "approximate"
  /// (this file's header comment); a person checks the others first.
  const char* confidence = "";
  std::string reason; ///< why it is not placed; empty when it is
};

struct LandmarkPlacement
{
  /// The landmarks found, in standardLandmarks() order (missing ones left out).
  std::vector<Landmark> landmarks;
  /// Every standard landmark, in standardLandmarks() order, placed or not.
  std::vector<LandmarkStatus> status;
  /// One line per landmark not placed, saying why: "<name> not in the scan:
  /// ..." or "<name> not found: ...".
  std::vector<std::string> warnings;
  ProfileFeatures features;

  /// The landmark of that name, nullptr if absent.
  const Landmark* find(const std::string& name) const;
};

/// Initial placement of the standard landmarks. @a bone may be empty (0 × 0):
/// zygion and gonion then use the skin map.
/// @throws std::invalid_argument if a non-empty bone map is on another frame;
///         std::runtime_error as findProfileFeatures().
LandmarkPlacement placeLandmarks(const RangeMap& skin, const RangeMap& bone = RangeMap());

} // namespace caps::seg
