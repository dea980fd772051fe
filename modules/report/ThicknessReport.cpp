#include "modules/report/ThicknessReport.h"
#include "modules/report/ReportDocument.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <vtkImageData.h>
#include <vtkPolyData.h>

#include "modules/rangemap/RangeMapLogic.h"
#include "modules/rangemap/RangeMapPreview.h"
#include "modules/rangemap/ThicknessReview.h"
#include "modules/report/PlanFigures.h"
#include "modules/report/PlanReport.h"
#include "modules/segment/SegmentLogic.h"
#include "render/Figure.h"
#include "scene/LabelMapNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"
#include "segmentation/LandmarkDepth.h"
#include "segmentation/LandmarkPlacement.h"
#include "segmentation/MetalArtefacts.h"
#include "segmentation/Landmarks.h"
#include "segmentation/Thickness.h"

#ifndef CAPS_VERSION
#define CAPS_VERSION "unknown"
#endif

namespace caps::report {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
/// Every thickness picture of the report uses the same colours for the same mm.
constexpr double kThicknessHigh = 30.0;

/// Numbers as this report prints them: a dash where there is none.
std::string fixed(double value, int decimals)
{
  return report::fixed(value, decimals, "—");
}

std::string orDash(const std::string& s)
{
  return s.empty() ? "—" : s;
}

int pixels(double widthMm, double dpi)
{
  return int(std::lround(widthMm / 25.4 * dpi));
}

/// "labrale superius" for "labrale_superius".
std::string readable(std::string name)
{
  std::replace(name.begin(), name.end(), '_', ' ');
  return name;
}

/// The convention a row's depth was measured by, as the table's short column.
std::string shortConvention(const seg::LandmarkThickness& row)
{
  if (row.convention.empty())
    return "—";
  if (row.convention == seg::conventionName(seg::DepthConvention::SkinNormal))
    return "⊥ skin";
  if (row.convention == seg::conventionName(seg::DepthConvention::NotADepth))
    return "none";
  if (row.convention == seg::conventionName(seg::DepthConvention::NearestBone))
    return "nearest";
  return "nearest*"; // the nearest bone in place of the perpendicular (LandmarkDepth::describeConvention)
}

/// What the review is made from: the CT, its maps and the landmarks on them.
struct Review
{
  const VolumeNode* volume = nullptr;
  const RangeMapNode* skinNode = nullptr;
  seg::RangeMap skin, bone, radial, normal;
  seg::LandmarkPlacement placement;
  std::string notPlacedAtAll; ///< why no landmark could be placed (the profile has no face)
  std::vector<seg::LandmarkThickness> rows;
  std::optional<LabelMapNode::Thresholds> thresholds;
  std::vector<std::string> metal;       ///< each piece of metal (or undiluted contrast) and the slices it spoils
  ThicknessReview::SpoiledTest spoiled; ///< skin in those slices or against the head holder
};

/// 1. The CT, the newest maps, the landmarks and their depths.
Review gather(Scene& scene)
{
  Review r;
  const auto volumes = scene.nodesOfType(NodeType::Volume);
  if (volumes.empty())
    throw std::invalid_argument("the scene has no CT volume: load the patient's CT (the Volumes module or caps "
                                "thickness-report CT) before making a thickness report");
  r.volume = static_cast<const VolumeNode*>(volumes.front());
  const SkinAndBoneMaps maps = RangeMapLogic::newestMaps(scene);
  if (!maps.skin)
    throw std::invalid_argument("the scene has no range maps: make them (the Range maps module, or caps rangemap) "
                                "before making a thickness report");
  r.skinNode = maps.skin;
  r.skin = RangeMapLogic::toRangeMap(*maps.skin);
  if (maps.bone)
    r.bone = RangeMapLogic::toRangeMap(*maps.bone);
  if (const RangeMapNode* n = RangeMapLogic::builtWith(scene, *maps.skin, "thickness"))
    r.radial = RangeMapLogic::toRangeMap(*n);
  if (const RangeMapNode* n = RangeMapLogic::builtWith(scene, *maps.skin, "thickness-normal"))
    r.normal = RangeMapLogic::toRangeMap(*n);
  try
  {
    r.placement = seg::placeLandmarks(r.skin, r.bone);
  }
  catch (const std::exception& e)
  {
    r.notPlacedAtAll = e.what();
  }
  r.rows = seg::landmarkThickness(r.placement.landmarks, r.skin, r.radial, r.normal);
  const RangeMapLogic logic(scene);
  logic.measureLandmarkDepths(*r.volume, r.rows);
  for (const seg::MetalPiece& piece : logic.metalOf(*r.volume))
    r.metal.push_back(seg::describe(piece, r.volume->image()));
  r.spoiled = ThicknessReview::eitherOf(ThicknessReview::spoiledBy(logic.metalOf(*r.volume), r.volume->image()),
                                        logic.againstAnObject(*r.volume, r.skin.frame()));
  if (const LabelMapNode* labels = SegmentLogic(scene).findLabelMap(*r.volume))
    r.thresholds = labels->thresholds();
  return r;
}

void addHeader(ReportDocument& doc, const PatientFacts& patient, const ThicknessReportOptions& options)
{
  doc.heading("Soft-tissue thickness review", 1);
  doc.fields({{"Patient", patient.name},
              {"Patient ID", patient.id},
              {"Birth date", orDash(patient.birthDate)},
              {"Sex, age", orDash(patient.sex) + ", " + orDash(patient.age)},
              {"Study", orDash(patient.studyDate) + " · " + orDash(patient.studyDescription)},
              {"Series", orDash(patient.modality) + " · " + orDash(patient.seriesDescription)},
              {"Review date", options.date.empty() ? todayIso() : options.date},
              {"Reviewed by", options.reviewer.empty() ? std::string("________________________") : options.reviewer},
              {"Software", std::string("CAPS ") + CAPS_VERSION}});
  if (!patient.source.empty())
    doc.paragraph("CT read from " + patient.source + ".");
}

/// 2. The landmark table, then the landmarks not placed and why.
void addLandmarks(ReportDocument& doc, const Review& r)
{
  doc.heading("Landmarks", 1);
  doc.paragraph("The standard soft-tissue landmarks, placed automatically on the skin's range map (check them: "
                "the confidence says how far each rule can be trusted). The depth is measured in the CT from "
                "the skin point by the landmark's convention: perpendicular to the skin, to the first bone the "
                "line meets, or to the nearest bone; radial and normal are the thickness maps' values at the "
                "landmark (along the ray from the head axis, and along the map's normal). The depths are not "
                "compared with published norms in this version.");
  if (!r.notPlacedAtAll.empty())
    doc.paragraph("No landmark could be placed: " + r.notPlacedAtAll);
  std::vector<std::vector<std::string>> rows;
  for (std::size_t k = 0; k < r.rows.size(); ++k)
  {
    const seg::LandmarkThickness& row = r.rows[k];
    std::string confidence;
    for (const seg::LandmarkStatus& s : r.placement.status)
      if (s.name == row.landmark.name)
        confidence = s.confidence;
    rows.push_back({std::to_string(k + 1), readable(row.landmark.name), orDash(confidence), fixed(row.depth, 1),
                    shortConvention(row), fixed(row.ctSkinNormal, 1), fixed(row.ctNearestBone, 1), fixed(row.radial, 1),
                    fixed(row.normal, 1)});
  }
  if (!rows.empty())
  {
    doc.table({"#", "Landmark", "Confidence", "Depth (mm)", "Measured", "⊥ skin (mm)", "Nearest bone (mm)",
               "Radial map (mm)", "Normal map (mm)"},
              rows, {4, 19, 14, 9, 12, 10, 11, 10, 11});
    doc.paragraph("Measured: ⊥ skin, perpendicular to the skin to the first bone; nearest, to the nearest bone; "
                  "nearest*, to the nearest bone because no bone lies perpendicular to the skin within 60 mm "
                  "(lips without teeth behind them, bone too thin for the CT); none, no bone beneath (the nose "
                  "tip's cartilage).");
  }
  std::vector<std::vector<std::string>> spoiled;
  for (std::size_t k = 0; k < r.rows.size(); ++k)
    if (!r.rows[k].note.empty())
      spoiled.push_back({std::to_string(k + 1), readable(r.rows[k].landmark.name), r.rows[k].note});
  if (!spoiled.empty())
  {
    doc.heading("Landmarks to check on the slices", 2);
    doc.table({"#", "Landmark", "Why"}, spoiled);
  }
  std::vector<std::vector<std::string>> missing;
  for (const seg::LandmarkStatus& s : r.placement.status)
    if (s.state != seg::LandmarkState::Placed)
      missing.push_back(
        {readable(s.name), s.state == seg::LandmarkState::NotInScan ? "not in the scan" : "not found", s.reason});
  if (!missing.empty())
  {
    doc.heading("Landmarks not placed", 2);
    doc.table({"Landmark", "Status", "Why"}, missing);
  }
}

/// The region the face statistics cover: 75° either side of the front, and
/// from 10 mm below the lowest landmark to 10 mm above the highest (the
/// whole map without landmarks).
struct FaceRegion
{
  double zLow, zHigh;
  double halfWidth = 75.0 * kDegree;
};

FaceRegion faceRegion(const Review& r)
{
  FaceRegion region{r.skin.frame().zMin(), r.skin.frame().zMax()};
  if (r.placement.landmarks.empty())
    return region;
  double lo = 1e300, hi = -1e300;
  for (const seg::Landmark& l : r.placement.landmarks)
  {
    lo = std::min(lo, l.z);
    hi = std::max(hi, l.z);
  }
  region.zLow = std::max(region.zLow, lo - 10.0);
  region.zHigh = std::min(region.zHigh, hi + 10.0);
  return region;
}

/// @a map with every sample outside @a region NaN.
seg::RangeMap within(const seg::RangeMap& map, const FaceRegion& region)
{
  seg::RangeMap out = map;
  const seg::CylindricalFrame& f = map.frame();
  for (int j = 0; j < map.nZ(); ++j)
    for (int i = 0; i < map.nTheta(); ++i)
    {
      const double fromFront = std::abs(seg::CylindricalFrame::wrapTheta(f.indexToTheta(i) - seg::kFrontTheta));
      const double z = f.indexToZ(j);
      if (fromFront > region.halfWidth || z < region.zLow || z > region.zHigh)
        out.at(i, j) = seg::RangeMap::quietNaN();
    }
  return out;
}

/// What spoils the CT: metal, or contrast still undiluted in a vein.
void addArtefacts(ReportDocument& doc, const Review& r)
{
  if (r.metal.empty())
    return;
  doc.heading("Metal and dense contrast", 2);
  doc.paragraph("Voxels at 3000 HU and above: metal (fillings, crowns, plates) or contrast still undiluted in a "
                "vein. Their streaks cross the whole slice, so skin, bone and thickness found in these slices are "
                "not measurements to trust.");
  std::vector<std::vector<std::string>> rows;
  for (std::size_t k = 0; k < r.metal.size() && k < 8; ++k)
    rows.push_back({std::to_string(k + 1), r.metal[k]});
  if (r.metal.size() > 8)
    rows.push_back({"…", std::to_string(r.metal.size() - 8) + " smaller pieces"});
  doc.table({"#", "Where, and the slices it spoils"}, rows);
}

/// 3. The face's thickness statistics, both measures.
void addStatistics(ReportDocument& doc, const Review& r)
{
  const FaceRegion region = faceRegion(r);
  doc.heading("Thickness over the face", 1);
  doc.paragraph("Over the face: 75° either side of the front and z " + fixed(region.zLow, 0) + " to " +
                fixed(region.zHigh, 0) + " mm along the head axis" +
                (r.placement.landmarks.empty() ? " (the whole map: no landmark was placed)"
                                               : " (10 mm beyond the lowest and highest landmarks)") +
                "; each map sample counts once.");
  std::vector<std::vector<std::string>> rows;
  for (const auto& [name, map] :
       {std::pair<const char*, const seg::RangeMap*>{"Radial (skin to bone along the ray)", &r.radial},
        {"Along the skin normal", &r.normal}})
  {
    if (map->empty())
      continue;
    const seg::ThicknessStatistics s = seg::thicknessStatistics(within(*map, region));
    rows.push_back({name, std::to_string(s.count), fixed(s.min, 1), fixed(s.p25, 1), fixed(s.median, 1),
                    fixed(s.mean, 1), fixed(s.p75, 1), fixed(s.p95, 1)});
  }
  if (!rows.empty())
    doc.table({"Measure", "Samples", "Min (mm)", "25 % (mm)", "Median (mm)", "Mean (mm)", "75 % (mm)", "95 % (mm)"},
              rows);
}

/// The unwrapped map as a print figure, widthMm wide.
QImage unwrapped(const seg::RangeMap& map, const std::string& title, double widthMm, double dpi)
{
  PreviewStyle style;
  style.low = 0.0;
  style.high = kThicknessHigh;
  style.title = title;
  style.pixelsPerSample = std::max(1, int(std::ceil(widthMm / 25.4 * dpi / std::max(1, map.nTheta()) * 0.8)));
  const double mapWidth = double(map.nTheta() * style.pixelsPerSample);
  style.textScale = std::max(1.0, 2.5 * mapWidth / (widthMm * 13.0 - 2.5 * 180.0));
  return render::toQImage(
    renderRangeMapPreview(RangeMapLogic::toMatrix(map), map.frame().zMin(), map.frame().zMax(), style).GetPointer());
}

/// The face painted with the radial thickness, the landmarks numbered as in the table.
std::optional<QImage> paintedFace(Scene& scene, const Review& r, double dpi)
{
  vtkPolyData* head = headSkin(scene);
  if (!head || r.radial.empty())
    return std::nullopt;
  const seg::CylindricalFrame& frame = r.radial.frame();
  // The Range maps panel's painting (its "thickness_mm"), radial.
  ThicknessReview review(r.skin, r.bone, r.radial, r.normal);
  review.setSpoiled(r.spoiled); // no thickness painted in the metal's streaks or against the head holder
  const vtkSmartPointer<vtkPolyData> painted = review.paintThickness(head, ThicknessMeasure::Radial);
  render::Figure figure;
  figure.printWidthMm = 120.0;
  figure.width = pixels(figure.printWidthMm, dpi);
  figure.height = int(std::lround(figure.width * 0.95));
  figure.colourBar = render::ColourBar{
    "soft-tissue thickness, radial (mm)", {0.0, kThicknessHigh}, render::ColourMap::Viridis, 7, "%.0f"};
  const FaceRegion region = faceRegion(r);
  const Eigen::Vector3d target = frame.origin() + frame.direction() * (0.5 * (region.zLow + region.zHigh));
  // A sphere round the face's landmarks (their z range, 10 mm beyond).
  const double radius = std::clamp(0.5 * (region.zHigh - region.zLow), 60.0, 130.0);
  figure.camera = render::lookAtCamera(target, frame.radialDirection(render::viewTheta(render::View::Front)),
                                       frame.direction(), radius, figure.sceneAspect(), 20.0, 1.05);
  figure.surfaces.push_back(
    render::SurfaceLayer::scalars(painted, "thickness_mm", 0.0, kThicknessHigh, render::ColourMap::Viridis));
  // Each landmark a dot with its number: a line of two points 0.01 mm apart.
  for (std::size_t k = 0; k < r.rows.size(); ++k)
  {
    const Eigen::Vector3d p = r.rows[k].position;
    if (!p.allFinite())
      continue;
    render::LineLayer mark;
    mark.points = {p, p + 0.01 * frame.radialDirection(r.rows[k].landmark.theta)};
    mark.labels = {std::to_string(k + 1), ""};
    mark.colour = {0.85, 0.1, 0.1};
    mark.widthPixels = std::max(3.0, 1.2 * figure.pixelsPerPoint());
    figure.lines.push_back(mark);
  }
  return render::toQImage(render::renderFigure(figure).GetPointer());
}

/// 4. The maps unwrapped and painted on the face.
void addFigures(ReportDocument& doc, Scene& scene, const Review& r, double dpi)
{
  doc.pageBreak();
  doc.heading("Thickness maps", 1);
  const double widthMm = 170.0;
  if (!r.radial.empty())
    doc.figures({unwrapped(r.radial, "Soft-tissue thickness, radial (r_skin - r_bone)", widthMm, dpi)}, widthMm,
                {"Radial thickness unwrapped around the head axis: the face in the middle, z up (mm); 0 to " +
                 fixed(kThicknessHigh, 0) + " mm, thicker regions saturate, grey where no bone is met."});
  if (!r.normal.empty())
    doc.figures({unwrapped(r.normal, "Soft-tissue thickness along the inward skin normal", widthMm, dpi)}, widthMm,
                {"Thickness along the skin's normal to the bone map, the same colours."});
  if (const auto face = paintedFace(scene, r, dpi))
    doc.figures({*face}, 120.0,
                {"The radial thickness painted on the face, the same colours; the landmarks numbered as in the "
                 "table (red)."});
}

/// 5. How it was measured.
void addMethod(ReportDocument& doc, const Review& r)
{
  doc.heading("Method", 1);
  const seg::CylindricalFrame& f = r.skin.frame();
  const Eigen::Vector3d& o = f.origin();
  const Eigen::Vector3d& d = f.direction();
  doc.fields({{"Skin and bone", r.thresholds
                                  ? "the CT thresholded at " + fixed(r.thresholds->skinHu, 0) +
                                      " HU (air / tissue) and " + fixed(r.thresholds->boneHu, 0) + " HU (tissue / bone)"
                                  : std::string("a label map of unknown thresholds")},
              {"Head axis", "through (" + fixed(o.x(), 1) + ", " + fixed(o.y(), 1) + ", " + fixed(o.z(), 1) +
                              ") mm, direction (" + fixed(d.x(), 3) + ", " + fixed(d.y(), 3) + ", " + fixed(d.z(), 3) +
                              ") (LPS)"},
              {"Range maps", std::to_string(f.nTheta()) + " × " + std::to_string(f.nZ()) + " samples, z " +
                               fixed(f.zMin(), 0) + " to " + fixed(f.zMax(), 0) + " mm (thesis §4.2)"}});
  doc.paragraph(
    "Depth conventions. Perpendicular to the skin: from the skin point along the skin's own normal (the cubic "
    "surface fitted to the skin's CT crossings within 3 mm) to where the line first enters bone (the CT's HU crossing "
    "next to the bone mask), as an ultrasound probe held perpendicular to the skin measures (De Greef et al. "
    "2006, Forensic Sci Int 159S:S126-S146, 967 adults). To the nearest bone: the shortest distance from the "
    "skin point to the bone surface, perpendicular to the bone, as the CT studies measure under the chin, at "
    "the jaw's angle and at the nasal bones' end (Stephan and Simpson 2008, J Forensic Sci 53:1257-1272, review "
    "the conventions). Where "
    "no bone lies perpendicular to the skin within 60 mm the nearest bone is given, and the table says so. "
    "The nose tip has cartilage beneath it: it has no bone depth.");
  doc.paragraph("Landmarks are placed from the midline profile of the skin's range map and the bone map (the "
                "rules are in the software's segmentation/LandmarkPlacement.h). A landmark is placed only where "
                "its anatomy is in the scan: when the face's most prominent point is not a nose (it stands less "
                "than 8 mm in front of the skin beside it or above it, or lies at the edge of the scan) no "
                "landmark is placed, since every rule starts from the nose tip. Metal and undiluted contrast: "
                "connected voxels at 3000 HU and above (4 or more); the slices within 5 mm of them are spoiled "
                "by their streaks, a landmark there is listed to be checked on the slices, the skin there is "
                "left out of the statistics and unpainted on the face, and no plan may be cut there. Skin pressed "
                "against the head holder or the table's pad (tissue-like HU 1.5 mm and 3 mm outside it, along "
                "the ray from the head axis) is the edge of the segmentation's body, not a measured surface: it "
                "is left out and unpainted too.");
}

} // namespace

ReportDocument buildThicknessReport(Scene& scene, const ThicknessReportOptions& options, const TaskProgress& progress)
{
  seg::reportProgress(progress, 0.0, "Landmarks and depths");
  const Review r = gather(scene);
  const PatientFacts patient = patientFacts(*r.volume, options.deidentify);
  ReportDocument doc(kThicknessReportTitle);
  doc.setPatientLine(patientLine(patient));
  doc.setFooterNote(std::string("CAPS ") + CAPS_VERSION +
                    " · landmarks placed automatically: check each before relying on its depth");
  addHeader(doc, patient, options);
  addLandmarks(doc, r);
  addArtefacts(doc, r);
  addStatistics(doc, r);
  seg::reportProgress(progress, 0.4, "Rendering the thickness maps");
  addFigures(doc, scene, r, options.figureDpi);
  addMethod(doc, r);
  seg::reportProgress(progress, 1.0, "Done");
  return doc;
}

} // namespace caps::report
