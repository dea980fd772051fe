#include "segmentation/LandmarkPlacement.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>

namespace caps::seg {

namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
constexpr double nan = std::numeric_limits<double>::quiet_NaN();

/// Row nearest z, clamped to the grid.
int rowOf(const CylindricalFrame& frame, double z)
{
  const long v = std::lround(frame.zToIndex(z));
  return static_cast<int>(std::clamp<long>(v, 0, frame.nZ() - 1));
}

/// Row of the largest (sign +1) or smallest (sign -1) finite p among the rows
/// nearest z in [zLow, zHigh]; -1 if none.
int extremum(const std::vector<double>& p, const CylindricalFrame& frame, double zLow, double zHigh, double sign)
{
  if (!(zHigh >= zLow))
    return -1;
  int best = -1;
  for (int j = rowOf(frame, zLow); j <= rowOf(frame, zHigh); ++j)
    if (std::isfinite(p[j]) && (best < 0 || sign * p[j] > sign * p[best]))
      best = j;
  return best;
}

/// z of the apex of the profile @a p near row @a j: the vertex of the
/// parabola fitted by least squares to the raw profile over rows j - 2 ..
/// j + 2 (a row more than 1 mm off the fit, a glitch, left out once), where
/// it bends the right way (@a sign +1 a maximum) and lies within two rows of
/// j; else z_j. Rows are 0.8 mm apart on a 256-row map, and the running
/// median that finds a feature shifts it on uneven slopes: half a row off
/// the apex of a lip, its skin normal leans by 10 degrees and its depth
/// perpendicular to the skin changes by half a millimetre.
double apexZ(const std::vector<double>& p, const CylindricalFrame& frame, int j, double sign)
{
  if (j < 0)
    return nan;
  std::vector<int> rows;
  for (int k = j - 2; k <= j + 2; ++k)
    if (k >= 0 && k < static_cast<int>(p.size()) && std::isfinite(p[k]))
      rows.push_back(k);
  for (int attempt = 0; attempt < 2 && rows.size() >= 4; ++attempt)
  {
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (int k : rows)
    {
      const Eigen::Vector3d basis(1.0, k - j, double(k - j) * (k - j));
      normal += basis * basis.transpose();
      rhs += basis * p[k];
    }
    const Eigen::Vector3d c = normal.ldlt().solve(rhs);
    std::size_t worst = 0;
    double worstResidual = 0.0;
    for (std::size_t r = 0; r < rows.size(); ++r)
    {
      const double x = rows[r] - j;
      const double residual = std::abs(p[rows[r]] - (c(0) + c(1) * x + c(2) * x * x));
      if (residual > worstResidual)
        worstResidual = residual, worst = r;
    }
    if (worstResidual > 1.0)
    {
      rows.erase(rows.begin() + static_cast<std::ptrdiff_t>(worst));
      continue;
    }
    if (!(sign * c(2) < 0.0))
      break;
    const double vertex = -c(1) / (2.0 * c(2));
    if (std::abs(vertex) <= 2.0)
      return frame.indexToZ(j) + vertex * frame.zStep();
    break;
  }
  return frame.indexToZ(j);
}

/// Running median of 2 · half + 1 rows (fewer at the ends; NaN ignored).
std::vector<double> runningMedian(const std::vector<double>& p, int half)
{
  std::vector<double> out(p.size(), nan);
  std::vector<double> v;
  const int n = static_cast<int>(p.size());
  for (int j = 0; j < n; ++j)
  {
    v.clear();
    for (int k = std::max(0, j - half); k <= std::min(n - 1, j + half); ++k)
      if (std::isfinite(p[k]))
        v.push_back(p[k]);
    if (v.empty() || !std::isfinite(p[j]))
      continue;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    out[j] = v[v.size() / 2];
  }
  return out;
}

struct LateralPoint
{
  double theta = nan;
  double z = nan;
};

/// The sample of @a map with the largest lateral extent r·|cos θ| for z in
/// [zLow, zHigh] and θ between @a fromFront and @a toFront (radians) from the
/// front, on the side @a side (+1 left: θ > -π/2, -1 right).
LateralPoint widest(const RangeMap& map, double zLow, double zHigh, double fromFront, double toFront, int side)
{
  LateralPoint best;
  if (!(zHigh >= zLow))
    return best;
  const CylindricalFrame& frame = map.frame();
  double bestWidth = -1.0;
  const int jLow = rowOf(frame, zLow), jHigh = rowOf(frame, zHigh);
  const int steps = static_cast<int>(std::floor((toFront - fromFront) / frame.thetaStep()));
  const double theta0 = kFrontTheta + side * fromFront;
  for (int s = 0; s <= steps; ++s)
  {
    const double theta = theta0 + side * s * frame.thetaStep();
    const int i = static_cast<int>(std::lround(frame.thetaToIndex(theta))) % frame.nTheta();
    const double t = frame.indexToTheta(i);
    // Only where the width peaks along z inside the band: a widest point at
    // the band's end is where the band cuts a bone that grows wider beyond
    // it (the maxilla above the jaw), not the feature.
    auto width = [&](int j) { return map.at(i, j) * std::abs(std::cos(t)); };
    for (int j = jLow + 1; j < jHigh; ++j)
    {
      const double w = width(j);
      if (std::isfinite(w) && w > bestWidth && w >= width(j - 1) && w >= width(j + 1))
      {
        bestWidth = w;
        best = {t, frame.indexToZ(j)};
      }
    }
  }
  return best;
}

/// Why the most prominent point of the midline profile @a p, at row @a tip,
/// is not a nose tip, or "" when it is one. A nose is a narrow feature: its
/// tip stands 15-30 mm in front of the cheeks beside it and of the nasion
/// above it, where a brow or a forehead stands a few mm in front of what
/// surrounds it. The most prominent point at the edge of the scan is where
/// the scan cuts the face, not a feature.
std::string whyNotANose(const RangeMap& skin, const std::vector<double>& p, int tip)
{
  constexpr double kEdgeMargin = 5.0;        // mm of face the scan must show beyond the tip
  constexpr double kSmallestNose = 8.0;      // mm the tip must stand in front of the cheeks and the nasion
  constexpr double kBeside = 20.0 * kDegree; // beside the nose: the cheek next to the ala
  const CylindricalFrame& frame = skin.frame();
  int lowest = -1, highest = -1;
  for (int j = 0; j < static_cast<int>(p.size()); ++j)
    if (std::isfinite(p[j]))
    {
      lowest = lowest < 0 ? j : lowest;
      highest = j;
    }
  const double zTip = frame.indexToZ(tip);
  auto mm = [](double v) {
    std::ostringstream s;
    s.precision(1);
    s << std::fixed << v;
    return s.str();
  };
  if (zTip - frame.indexToZ(lowest) < kEdgeMargin)
    return "the most prominent point of the face's profile is at the lower edge of the scan (z = " + mm(zTip) +
           " mm): the scan ends above the nose";
  if (frame.indexToZ(highest) - zTip < kEdgeMargin)
    return "the most prominent point of the face's profile is at the upper edge of the scan (z = " + mm(zTip) + " mm)";
  // The lower of the two sides: on a head turned a little on the table one
  // side of the nose is nearer the midline, but the other is cheek.
  const double right = midlineProfile(skin, kFrontTheta - kBeside, 1)[tip];
  const double left = midlineProfile(skin, kFrontTheta + kBeside, 1)[tip];
  const double beside = std::isfinite(right) && std::isfinite(left) ? std::min(right, left)
                        : std::isfinite(right)                      ? right
                                                                    : left;
  if (std::isfinite(beside) && p[tip] - beside < kSmallestNose)
    return "the most prominent point of the face's profile (z = " + mm(zTip) + " mm) stands only " +
           mm(p[tip] - beside) + " mm in front of the skin 20 degrees beside it, less than a nose (" +
           mm(kSmallestNose) + " mm or more): the nose is not in the scan";
  const int above = frame.indexToZ(highest) >= zTip + 10.0 ? extremum(p, frame, zTip + 10.0, zTip + 50.0, -1.0) : -1;
  if (above >= 0 && p[tip] - p[above] < kSmallestNose)
    return "the most prominent point of the face's profile (z = " + mm(zTip) + " mm) stands only " +
           mm(p[tip] - p[above]) + " mm in front of the profile 10-50 mm above it, less than a nose (" +
           mm(kSmallestNose) + " mm or more): the nose is not in the scan";
  return {};
}

/// The mid-cheek's distance from the midline: under the pupil, half the
/// mean adult interpupillary distance (63 mm; Farkas, Anthropometry of the
/// Head and Face, 1994).
constexpr double kCheekOffset = 32.0;

/// θ of the skin @a offset mm from the midsagittal plane (the plane of the
/// axis and the front) at height @a z, on @a side (+1 left, -1 right):
/// walking out from the front, the first sample whose r |cos θ| reaches it;
/// NaN when the skin ends first.
double besideTheMidline(const RangeMap& skin, double z, double offset, int side)
{
  const CylindricalFrame& frame = skin.frame();
  const double step = 0.25 * frame.thetaStep();
  for (double a = 0.0; a <= 0.5 * std::numbers::pi; a += step)
  {
    const double theta = kFrontTheta + side * a;
    const double r = skin.sample(theta, z);
    if (!std::isfinite(r))
      return nan;
    if (r * std::abs(std::cos(theta)) >= offset)
      return theta;
  }
  return nan;
}

/// z of the rhinion, the lower end of the nasal bones, on the bone map's
/// midline: walking down from the nasion's height towards the nose tip's,
/// the last row before the bone falls back by more than 5 mm (the ray
/// passes the bones' end into the nasal cavity and meets the maxilla or
/// nothing). NaN where the bone does not end between them.
double rhinionZ(const RangeMap& bone, double zNasion, double zTip)
{
  if (bone.empty() || !(zNasion > zTip))
    return nan;
  constexpr double kFallsBack = 5.0; // mm
  const CylindricalFrame& frame = bone.frame();
  const std::vector<double> b = midlineProfile(bone, kFrontTheta, 1);
  const int top = rowOf(frame, zNasion), bottom = rowOf(frame, zTip);
  for (int j = top; j > bottom; --j)
    if (std::isfinite(b[j]) && !(b[j - 1] >= b[j] - kFallsBack))
      return j == top ? nan : frame.indexToZ(j);
  return nan;
}

/// The eyes' height for the pupils' columns: a little below the nasion
/// (the soft-tissue nasion lies about at the upper lid's crease).
constexpr double kPupilBelowNasion = 5.0; // mm
/// An orbit on the bone map: a pit at least this deep below both rims.
constexpr double kOrbitDepth = 8.0; // mm

/// The orbital rims on the bone map's column @a theta (the pupil's), the
/// tables' mid-supraorbital and mid-infraorbital (De Greef et al. 2006).
/// The orbit is the deepest bone within 35 mm below and 20 mm above the
/// nasion (its roof lies 10-20 mm above the soft-tissue nasion), read
/// through a 5-row running median (one-row glitches are not orbits or rims).
/// Walking up (down) the column from it, the rim is where the bone first
/// comes within 1 mm of the highest bone in the next 15 mm: the edge where
/// the orbit's wall ends, at the crest of a raised margin; that highest
/// bone must stand kOrbitDepth above the orbit. Linear between rows.
struct OrbitRims
{
  double supra = nan, infra = nan; ///< z (mm); NaN where not found
};
OrbitRims orbitRims(const RangeMap& bone, double theta, double zNasion)
{
  OrbitRims rims;
  if (bone.empty() || !std::isfinite(theta) || !std::isfinite(zNasion))
    return rims;
  const CylindricalFrame& frame = bone.frame();
  std::vector<double> raw(static_cast<std::size_t>(frame.nZ()));
  for (int j = 0; j < frame.nZ(); ++j)
    raw[j] = bone.sample(theta, frame.indexToZ(j));
  const std::vector<double> p = runningMedian(raw, 2);
  // A row without bone is a hole in the map (bone too thin for the
  // segmentation), not the orbit, whose rays meet its walls.
  const auto depthOf = [&p](int j) { return std::isfinite(p[j]) ? p[j] : -std::numeric_limits<double>::infinity(); };
  const int low = std::max(0, rowOf(frame, zNasion - 35.0)), high = rowOf(frame, zNasion + 20.0);
  int orbit = -1;
  for (int j = low; j <= high; ++j)
    if (std::isfinite(p[j]) && (orbit < 0 || p[j] < p[orbit]))
      orbit = j;
  if (orbit < 0)
    return rims;
  const double floor = p[orbit];
  const int ahead = static_cast<int>(std::lround(15.0 / frame.zStep()));
  const auto rim = [&](int direction) {
    for (int j = orbit + direction; j >= 0 && j < frame.nZ(); j += direction)
    {
      double highest = -std::numeric_limits<double>::infinity();
      for (int k = j; k >= 0 && k < frame.nZ() && std::abs(k - j) <= ahead; k += direction)
        highest = std::max(highest, depthOf(k));
      if (!(highest - floor >= kOrbitDepth))
        return nan; // the bone never rises out of the orbit: no rim
      if (depthOf(j) >= highest - 1.0)
      {
        const int before = j - direction;
        const double target = highest - 1.0, b = depthOf(before), t = (target - b) / (p[j] - b);
        const double zBefore = frame.indexToZ(before), zHere = frame.indexToZ(j);
        return std::isfinite(b) && t > 0.0 && t <= 1.0 ? zBefore + t * (zHere - zBefore) : zHere;
      }
    }
    return nan;
  };
  rims.supra = rim(+1);
  rims.infra = rim(-1);
  return rims;
}

/// How far a landmark's rule can be trusted (this file's header comment).
const char* confidenceOf(std::string_view name)
{
  if (name == "pronasale" || name == "pogonion" || name == "nasion" || name == "glabella" || name == "forehead")
    return "reliable";
  if (name.starts_with("zygion") || name.starts_with("gonion") || name == "rhinion" || name == "mid_nasal")
    return "approximate";
  return "fair";
}

} // namespace

std::vector<double> midlineProfile(const RangeMap& skin, double theta, int halfColumns)
{
  const CylindricalFrame& frame = skin.frame();
  std::vector<double> profile(static_cast<std::size_t>(skin.nZ()), nan);
  if (skin.empty())
    return profile;
  const int n = frame.nTheta();
  const int centre = static_cast<int>(std::lround(frame.thetaToIndex(theta))) % n;
  std::vector<float> v;
  for (int j = 0; j < skin.nZ(); ++j)
  {
    v.clear();
    for (int d = -halfColumns; d <= halfColumns; ++d)
    {
      const float x = skin.at(((centre + d) % n + n) % n, j);
      if (std::isfinite(x))
        v.push_back(x);
    }
    if (v.empty())
      continue;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    profile[j] = v[v.size() / 2];
  }
  return profile;
}

ProfileFeatures findProfileFeatures(const RangeMap& skin, int halfColumns)
{
  ProfileFeatures f;
  f.profile = midlineProfile(skin, kFrontTheta, halfColumns);
  const std::vector<double>& p = f.profile;
  const CylindricalFrame& frame = skin.frame();
  const int nz = skin.nZ();
  auto z = [&frame](int j) { return frame.indexToZ(j); };

  for (int j = nz / 3; j < nz; ++j)
    if (std::isfinite(p[j]) && (f.pronasale < 0 || p[j] > p[f.pronasale]))
      f.pronasale = j;
  if (f.pronasale < 0)
    throw std::runtime_error("The skin range map has no skin on the front of the face (θ = -90°) "
                             "in the upper two thirds of the scan: no landmark can be placed.");
  f.noseMissing = whyNotANose(skin, p, f.pronasale);
  if (!f.noseMissing.empty())
  {
    f.pronasale = -1; // every midline rule starts from the nose tip
    return f;
  }
  const int n = f.pronasale;
  const double zN = z(n);

  for (int j = n; j >= 0 && f.jawUnderside < 0; --j)
    if (p[j] < 0.6 * p[n])
      f.jawUnderside = j;
  if (f.jawUnderside >= 0)
    f.pogonion = extremum(p, frame, z(f.jawUnderside) + 5.0, z(f.jawUnderside) + 25.0, +1.0);
  // The rules that look for dips and bumps read the profile through a 5-row
  // running median: one-row glitches (a 4 mm deep one at the nasion's height
  // on the sample CT) are not features.
  const std::vector<double> q = runningMedian(p, 2);
  f.nasion = extremum(q, frame, zN + 10.0, zN + 50.0, -1.0);
  if (f.nasion >= 0)
    f.glabella = extremum(q, frame, z(f.nasion) + frame.zStep(), z(f.nasion) + 25.0, +1.0);

  // Subnasale: the first row below the nose tip, at least 5 mm behind it,
  // that is the smallest p within ±3 mm of itself.
  const int lowest = f.pogonion >= 0 ? f.pogonion : rowOf(frame, zN - 40.0);
  for (int j = n - 1; j > lowest && f.subnasale < 0; --j)
  {
    if (!std::isfinite(q[j]) || p[n] - q[j] < 5.0)
      continue;
    if (extremum(q, frame, z(j) - 3.0, z(j) + 3.0, -1.0) == j)
      f.subnasale = j;
  }
  if (f.subnasale >= 0 && f.pogonion >= 0)
  {
    const double zSn = z(f.subnasale), zPog = z(f.pogonion), d = zSn - zPog;
    f.labraleSuperius = extremum(q, frame, zSn - 0.45 * d, zSn - frame.zStep(), +1.0);
    f.labraleInferius = extremum(q, frame, zPog + 0.25 * d, zSn - 0.45 * d, +1.0);
  }
  // Supraglabella: the deepest point of the concavity above the glabella,
  // where the forehead comes forward again (at least 0.5 mm) above it
  // within 25 mm; a forehead that only recedes has none.
  if (f.glabella >= 0)
  {
    const int top = rowOf(frame, z(f.glabella) + 25.0);
    const int j = extremum(q, frame, z(f.glabella) + frame.zStep(), z(top), -1.0);
    double above = -std::numeric_limits<double>::infinity();
    for (int k = j + 1; j >= 0 && k <= top; ++k)
      if (std::isfinite(q[k]))
        above = std::max(above, q[k]);
    if (j >= 0 && above - q[j] >= 0.5)
      f.supraglabella = j;
  }
  // Sublabiale: the deepest point of the fold between the lower lip and the chin.
  if (f.labraleInferius >= 0 && f.pogonion >= 0)
  {
    const int j = extremum(q, frame, z(f.pogonion) + frame.zStep(), z(f.labraleInferius) - frame.zStep(), -1.0);
    if (j >= 0 && q[j] < q[f.labraleInferius] && q[j] < q[f.pogonion])
      f.sublabiale = j;
  }
  // Menton: walking down from the pogonion, where p crosses half-way to the jaw underside.
  if (f.pogonion >= 0)
  {
    const double half = 0.5 * (p[f.pogonion] + p[f.jawUnderside]);
    for (int j = f.pogonion; j > f.jawUnderside; --j)
      if (std::isfinite(p[j]) && std::isfinite(p[j - 1]) && p[j] >= half && p[j - 1] < half)
      {
        const double t = (p[j] - half) / (p[j] - p[j - 1]);
        f.mentonZ = z(j) - t * frame.zStep();
        break;
      }
  }
  return f;
}

const Landmark* LandmarkPlacement::find(const std::string& name) const
{
  for (const Landmark& l : landmarks)
    if (l.name == name)
      return &l;
  return nullptr;
}

LandmarkPlacement placeLandmarks(const RangeMap& skin, const RangeMap& bone)
{
  if (!bone.empty() && bone.frame() != skin.frame())
    throw std::invalid_argument("The bone range map is on another cylinder or grid than the skin map.");
  LandmarkPlacement result;
  result.features = findProfileFeatures(skin);
  const ProfileFeatures& f = result.features;
  const CylindricalFrame& frame = skin.frame();
  // The profile's features at their apexes, between rows.
  const auto apex = [&](int j, double sign) { return apexZ(f.profile, frame, j, sign); };
  const double zPrn = apex(f.pronasale, +1), zN = apex(f.nasion, -1), zSn = apex(f.subnasale, -1);
  const double zLs = apex(f.labraleSuperius, +1), zLi = apex(f.labraleInferius, +1);
  const double zG = apex(f.glabella, +1), zPog = apex(f.pogonion, +1);

  // Lateral landmarks: on the bone map when there is one.
  const RangeMap& lateral = bone.empty() ? skin : bone;
  const double zygionTop = std::isfinite(zN) ? zN : zPrn + 30.0;
  const double gonionTop = std::isfinite(zSn) ? zSn : f.mentonZ + 40.0;
  const LateralPoint zyL = widest(lateral, zPrn, zygionTop, 25 * kDegree, 80 * kDegree, +1);
  const LateralPoint zyR = widest(lateral, zPrn, zygionTop, 25 * kDegree, 80 * kDegree, -1);
  LateralPoint goL, goR;
  if (std::isfinite(f.mentonZ))
  {
    goL = widest(lateral, f.mentonZ, gonionTop, 30 * kDegree, 95 * kDegree, +1);
    goR = widest(lateral, f.mentonZ, gonionTop, 30 * kDegree, 95 * kDegree, -1);
  }

  struct Candidate
  {
    double theta, z;
    const char* why;
  };
  const double front = kFrontTheta;
  const double cheekLeft = std::isfinite(zPrn) ? besideTheMidline(skin, zPrn, kCheekOffset, +1) : nan;
  const double cheekRight = std::isfinite(zPrn) ? besideTheMidline(skin, zPrn, kCheekOffset, -1) : nan;
  const double pupilLeft = std::isfinite(zN) ? besideTheMidline(skin, zN - kPupilBelowNasion, kCheekOffset, +1) : nan;
  const double pupilRight = std::isfinite(zN) ? besideTheMidline(skin, zN - kPupilBelowNasion, kCheekOffset, -1) : nan;
  const OrbitRims orbitLeft = orbitRims(bone, pupilLeft, zN), orbitRight = orbitRims(bone, pupilRight, zN);
  const char* noOrbit = bone.empty() ? "the orbits are read on the bone range map, and there is none"
                                     : "no orbit under the pupil beside the nasion on the bone map (bone 8 mm "
                                       "deeper than the bone above and below it)";
  const char* noJaw = "no jaw underside (profile below 60 % of the nose tip) below the nose tip";
  const double zRhinion = rhinionZ(bone, zN, zPrn);
  const char* noRhinion = bone.empty() ? "the nasal bones are read on the bone range map, and there is none"
                                       : "the bone on the midline does not end between the nasion and the nose tip "
                                         "(no nasal bones on the bone map, or a bone map with a hole at the nasion)";
  const Candidate candidates[] = {
    {front, apex(f.supraglabella, -1),
     "the forehead does not come forward again within 25 mm above the glabella: no concavity above it"},
    {front, zG, "no nasion 10-50 mm above the nose tip"},
    {front, zN, "no finite profile 10-50 mm above the nose tip"},
    {front, 0.5 * (zN + zRhinion), noRhinion},
    {front, zRhinion, noRhinion},
    {front, zPrn, ""},
    {front, zSn, "no local minimum of the profile 5 mm behind and below the nose tip"},
    {front, 0.5 * (zSn + zLs), "no subnasale or labrale superius"},
    {front, zLs, "no subnasale or pogonion"},
    {front, zLi, "no subnasale or pogonion"},
    {front, apex(f.sublabiale, -1), "no fold between the lower lip and the chin on the profile"},
    {front, zPog, noJaw},
    {front, f.mentonZ, "no pogonion, or the profile does not cross half-way from it to the jaw underside"},
    {zyL.theta, zyL.z, "no finite sample beside the face between the nose tip and the nasion"},
    {zyR.theta, zyR.z, "no finite sample beside the face between the nose tip and the nasion"},
    {goL.theta, goL.z, "no menton, or no finite sample beside the jaw"},
    {goR.theta, goR.z, "no menton, or no finite sample beside the jaw"},
    {cheekLeft, zPrn, "no skin 32 mm left of the midline at the nose tip's height"},
    {cheekRight, zPrn, "no skin 32 mm right of the midline at the nose tip's height"},
    {pupilLeft, orbitLeft.supra, noOrbit},
    {pupilRight, orbitRight.supra, noOrbit},
    {pupilLeft, orbitLeft.infra, noOrbit},
    {pupilRight, orbitRight.infra, noOrbit},
    {front, zPrn + 75.0, "75 mm above the nose tip is beyond the scan"},
  };
  const auto& definitions = standardLandmarks();
  if (definitions.size() != std::size(candidates))
    throw std::logic_error("placeLandmarks: one rule per standard landmark");
  for (std::size_t k = 0; k < definitions.size(); ++k)
  {
    const Candidate& c = candidates[k];
    LandmarkStatus status{definitions[k].name, LandmarkState::Placed, confidenceOf(definitions[k].name), {}};
    if (!f.noseMissing.empty())
    {
      status.state = LandmarkState::NotInScan;
      status.reason = "placed from the nose tip, and " + f.noseMissing;
    }
    else if (std::isfinite(c.z) && (c.z < frame.zMin() || c.z > frame.zMax()))
    {
      status.state = LandmarkState::NotInScan;
      status.reason = "its place (z = " + std::to_string(static_cast<int>(std::lround(c.z))) +
                      " mm) is beyond the scan (z " + std::to_string(static_cast<int>(std::lround(frame.zMin()))) +
                      " to " + std::to_string(static_cast<int>(std::lround(frame.zMax()))) + " mm)";
    }
    else if (!(std::isfinite(c.theta) && std::isfinite(c.z)))
    {
      status.state = LandmarkState::NotFound;
      status.reason = c.why;
    }
    if (status.state == LandmarkState::Placed)
      result.landmarks.push_back({definitions[k].name, CylindricalFrame::wrapTheta(c.theta), c.z});
    else
      result.warnings.push_back(status.name +
                                (status.state == LandmarkState::NotInScan ? " not in the scan: " : " not found: ") +
                                status.reason + ".");
    result.status.push_back(std::move(status));
  }
  return result;
}

} // namespace caps::seg
