#pragma once
/// @file ThicknessReview.h
/// @brief What the surgeon reads off the range maps while reviewing the soft
/// tissue (thesis §4.2): the values at a point of the
/// unwrapped (θ, z) chart, the thickness painted on the skin surface, its
/// histogram over the face, and landmarks with their thickness. No widgets.

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <vtkSmartPointer.h>

#include "scene/LandmarksNode.h"
#include "segmentation/MetalArtefacts.h"
#include "segmentation/RangeMap.h"

class vtkImageData;
class vtkPolyData;

namespace caps {

class Scene;

/// The maps' values at one point of the chart. Lengths in mm, NaN where a
/// map has no surface.
struct ThicknessProbe
{
  double theta = 0.0; ///< radians, [-π, π)
  double z = 0.0;     ///< mm along the head axis
  double skinRadius = 0.0, boneRadius = 0.0;
  double thickness = 0.0;            ///< radial: skin r − bone r
  double thicknessNormal = 0.0;      ///< along the inward skin normal to the bone
  std::array<double, 3> skinPoint{}; ///< the skin there (patient LPS); NaN without skin
};

/// The thickness along a line drawn on the skin, sampled about every
/// half millimetre of skin.
struct ThicknessProfile
{
  std::vector<double> along;                ///< mm of skin from the line's start
  std::vector<double> thickness;            ///< mm by the measure asked for; NaN over holes
  std::vector<std::array<double, 3>> skin;  ///< the skin points (patient LPS); NaN over holes
  std::vector<std::array<double, 2>> chart; ///< their (θ, z)
};

/// Which thickness a view shows.
enum class ThicknessMeasure
{
  Radial,     ///< skin r − bone r along the ray from the axis
  AlongNormal ///< along the inward skin normal to the bone (the radial one where the scene has no such map)
};

/// "radial", "along the skin normal".
const char* measureName(ThicknessMeasure measure);

/// @class ThicknessReview
/// @brief The skin, bone and thickness maps of the scene's newest range-map set.
class ThicknessReview
{
public:
  /// The newest map of each role ("skin", "bone", "thickness",
  /// "thickness-normal"); std::nullopt when the scene has no skin, bone and
  /// radial thickness map yet.
  static std::optional<ThicknessReview> fromScene(const Scene& scene);
  ThicknessReview(seg::RangeMap skin, seg::RangeMap bone, seg::RangeMap thickness, seg::RangeMap thicknessNormal);

  const seg::RangeMap& skin() const { return skin_; }
  const seg::RangeMap& bone() const { return bone_; }
  const seg::RangeMap& thickness() const { return thickness_; }
  /// Empty when the scene had no normal-thickness map.
  const seg::RangeMap& thicknessNormal() const { return thickness_normal_; }

  /// The values at (θ, z), read bilinearly (eq. 4.9).
  ThicknessProbe probe(double theta, double z) const;
  /// The chart point (θ, z) of a world point, as the maps' frame sees it.
  std::array<double, 2> chartOf(const std::array<double, 3>& world) const;

  /// The thickness by @a measure along the line on the skin from chart
  /// point @a from to @a to (θ radians, z mm): the straight line of the
  /// unwrapped chart (the shorter way round in θ), which on the skin is the
  /// curve the map view shows. Distances are measured along the skin (the
  /// polyline through the skin points); over a hole in the skin map the
  /// distance bridges it straight. Sampled every @a step mm of skin or finer.
  /// @throws std::invalid_argument when neither end lies on the skin map.
  ThicknessProfile profile(const std::array<double, 2>& from, const std::array<double, 2>& to, ThicknessMeasure measure,
                           double step = 0.5) const;

  /// The map of @a measure (the radial one when the normal map is missing).
  const seg::RangeMap& thicknessMap(ThicknessMeasure measure) const;

  /// A copy of @a surface with the point array "thickness_mm": the thickness
  /// by @a measure at each vertex's (θ, z) (NaN off the maps).
  vtkSmartPointer<vtkPolyData> paintThickness(vtkPolyData* surface,
                                              ThicknessMeasure measure = ThicknessMeasure::Radial) const;

  /// Where the skin is not to be trusted: true for a world point (LPS mm)
  /// in the slices a piece of metal's streaks spoil (spoiledBy()), or on
  /// skin pressed against the head holder (RangeMapLogic::againstAnObject);
  /// eitherOf() joins the two. Those samples are left out of
  /// faceHistogram(), and paintThickness() paints no thickness there (NaN)
  /// and marks them 1 in the point array "unreliable_skin". Unset: none.
  using SpoiledTest = std::function<bool(const Eigen::Vector3d&)>;
  void setSpoiled(SpoiledTest spoiled) { spoiled_ = std::move(spoiled); }
  /// 1 for each sample of the skin map (index i + nθ j) whose skin the test
  /// marks, else 0; all 0 without a test.
  std::vector<unsigned char> spoiledSamples() const;
  /// The test for @a volume's CT, from its metal (none: an empty test).
  static SpoiledTest spoiledBy(const std::vector<seg::MetalPiece>& metal, vtkImageData* ct);
  /// True where either test is (an empty test is never true); empty when both are.
  static SpoiledTest eitherOf(SpoiledTest a, SpoiledTest b);

  /// The face's rows of the maps: from 10 mm below the lowest standard
  /// landmark placed on them to 10 mm above the highest (fromScene() finds
  /// them with seg::placeLandmarks); unset: every row.
  void setFaceRows(double zLow, double zHigh) { face_rows_ = std::array<double, 2>{zLow, zHigh}; }
  const std::optional<std::array<double, 2>>& faceRows() const { return face_rows_; }

  /// Counts of the thickness by @a measure over the face: 75° either side of
  /// the front, on the face's rows (faceRows(); every row when unset), in
  /// bins of @a binWidth mm from 0; values from the last bin's start up go
  /// into it. Not the neck, the scalp or the ears, which are far thicker.
  std::vector<int> faceHistogram(double binWidth, int bins, ThicknessMeasure measure = ThicknessMeasure::Radial) const;

  /// A landmark's depth measured in the CT by its convention (LandmarkDepth.h).
  struct CtDepth
  {
    double depth = seg::RangeMap::quietNaN(); ///< mm
    std::string convention;                   ///< how it was measured
    std::string note;                         ///< what spoils it (metal streaks), if anything
  };
  /// The landmarks as CSV, one row each: name, x, y, z (LPS mm), theta
  /// (degrees), z along the axis (mm), skin radius, bone radius, thickness
  /// radial and along the normal (mm), and the depth in the CT with its
  /// convention and note from @a depths (one per landmark, or none); NaN as
  /// empty fields.
  std::string landmarksCsv(const std::vector<LandmarksNode::Landmark>& landmarks,
                           const std::vector<CtDepth>& depths = {}) const;
  /// The distances measured with the ruler as CSV, one row each: name, the
  /// two ends (LPS mm) and the length (mm).
  static std::string distancesCsv(const std::vector<LandmarksNode::Distance>& distances);

private:
  seg::RangeMap skin_, bone_, thickness_, thickness_normal_;
  std::optional<std::array<double, 2>> face_rows_;
  SpoiledTest spoiled_;
};

} // namespace caps
