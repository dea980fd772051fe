#include "modules/rangemap/ThicknessReview.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <vtkDoubleArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkUnsignedCharArray.h>

#include "modules/rangemap/RangeMapLogic.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "segmentation/LandmarkPlacement.h"

namespace caps {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// A CSV field: quoted when it holds a comma, a quote or a line break.
std::string csvField(const std::string& text)
{
  if (text.find_first_of(",\"\n\r") == std::string::npos)
    return text;
  std::string quoted = "\"";
  for (char c : text)
  {
    if (c == '"')
      quoted += '"';
    quoted += c;
  }
  quoted += '"';
  return quoted;
}

} // namespace

std::optional<ThicknessReview> ThicknessReview::fromScene(const Scene& scene)
{
  // The newest maps, all of one run (RangeMapLogic::newestMaps).
  const auto [skin, bone] = RangeMapLogic::newestMaps(scene);
  const RangeMapNode* thickness = skin ? RangeMapLogic::builtWith(scene, *skin, "thickness") : nullptr;
  const RangeMapNode* normal = skin ? RangeMapLogic::builtWith(scene, *skin, "thickness-normal") : nullptr;
  if (!skin || !bone || !thickness)
    return std::nullopt;
  ThicknessReview review(RangeMapLogic::toRangeMap(*skin), RangeMapLogic::toRangeMap(*bone),
                         RangeMapLogic::toRangeMap(*thickness),
                         normal ? RangeMapLogic::toRangeMap(*normal) : seg::RangeMap());
  // The face's rows, from the landmarks the maps give (none: every row).
  try
  {
    const seg::LandmarkPlacement placed = seg::placeLandmarks(review.skin_, review.bone_);
    double low = std::numeric_limits<double>::infinity(), high = -low;
    for (const seg::Landmark& l : placed.landmarks)
    {
      low = std::min(low, l.z);
      high = std::max(high, l.z);
    }
    if (low <= high)
      review.setFaceRows(low - 10.0, high + 10.0);
  }
  catch (const std::exception&)
  { // no face on the maps: every row
  }
  return review;
}

const char* measureName(ThicknessMeasure measure)
{
  return measure == ThicknessMeasure::AlongNormal ? "along the skin normal" : "radial";
}

const seg::RangeMap& ThicknessReview::thicknessMap(ThicknessMeasure measure) const
{
  return measure == ThicknessMeasure::AlongNormal && !thickness_normal_.empty() ? thickness_normal_ : thickness_;
}

ThicknessReview::ThicknessReview(seg::RangeMap skin, seg::RangeMap bone, seg::RangeMap thickness,
                                 seg::RangeMap thicknessNormal)
  : skin_(std::move(skin)), bone_(std::move(bone)), thickness_(std::move(thickness)),
    thickness_normal_(std::move(thicknessNormal))
{}

ThicknessProbe ThicknessReview::probe(double theta, double z) const
{
  ThicknessProbe p;
  p.theta = seg::CylindricalFrame::wrapTheta(theta);
  p.z = z;
  p.skinRadius = skin_.sample(p.theta, z);
  p.boneRadius = bone_.sample(p.theta, z);
  p.thickness = thickness_.sample(p.theta, z);
  p.thicknessNormal = thickness_normal_.empty() ? kNaN : thickness_normal_.sample(p.theta, z);
  if (std::isfinite(p.skinRadius))
  {
    const Eigen::Vector3d w = skin_.frame().toWorld(p.skinRadius, p.theta, z);
    p.skinPoint = {w.x(), w.y(), w.z()};
  }
  else
    p.skinPoint = {kNaN, kNaN, kNaN};
  return p;
}

ThicknessProfile ThicknessReview::profile(const std::array<double, 2>& from, const std::array<double, 2>& to,
                                          ThicknessMeasure measure, double step) const
{
  if (!std::isfinite(probe(from[0], from[1]).skinRadius) && !std::isfinite(probe(to[0], to[1]).skinRadius))
    throw std::invalid_argument("Neither end of the line is on the skin map: draw it on the face.");
  const double dTheta = std::remainder(to[0] - from[0], 2.0 * std::numbers::pi); // the shorter way round
  const double dZ = to[1] - from[1];
  const auto chartAt = [&](double t) { return std::array<double, 2>{from[0] + t * dTheta, from[1] + t * dZ}; };
  // Enough samples for the step on the skin: the line's length on the
  // cylinder through the widest skin along it bounds the skin's.
  double widest = 0.0;
  for (int k = 0; k <= 64; ++k)
  {
    const auto c = chartAt(k / 64.0);
    if (const double r = probe(c[0], c[1]).skinRadius; std::isfinite(r))
      widest = std::max(widest, r);
  }
  const double length = std::hypot(widest * dTheta, dZ);
  const int n = std::max(2, static_cast<int>(std::ceil(2.0 * length / std::max(step, 1e-3))));
  const seg::RangeMap& map = thicknessMap(measure);
  ThicknessProfile profile;
  std::optional<Eigen::Vector3d> last;
  double along = 0.0;
  for (int k = 0; k <= n; ++k)
  {
    const auto c = chartAt(static_cast<double>(k) / n);
    const ThicknessProbe p = probe(c[0], c[1]);
    const Eigen::Vector3d skin(p.skinPoint[0], p.skinPoint[1], p.skinPoint[2]);
    if (skin.allFinite())
    {
      if (last)
        along += (skin - *last).norm();
      last = skin;
    }
    profile.along.push_back(along);
    profile.thickness.push_back(skin.allFinite() ? map.sample(p.theta, c[1]) : kNaN);
    profile.skin.push_back(p.skinPoint);
    profile.chart.push_back({p.theta, c[1]});
  }
  return profile;
}

std::array<double, 2> ThicknessReview::chartOf(const std::array<double, 3>& world) const
{
  const seg::CylindricalPoint c = skin_.frame().toCylindrical(Eigen::Vector3d(world[0], world[1], world[2]));
  return {c.theta, c.z};
}

vtkSmartPointer<vtkPolyData> ThicknessReview::paintThickness(vtkPolyData* surface, ThicknessMeasure measure) const
{
  const seg::RangeMap& map = thicknessMap(measure);
  auto painted = vtkSmartPointer<vtkPolyData>::New();
  painted->ShallowCopy(surface);
  // The point data is the source's: a new array must not land in it.
  auto pointData = vtkSmartPointer<vtkPointData>::New();
  pointData->ShallowCopy(surface->GetPointData());
  painted->GetPointData()->ShallowCopy(pointData);
  auto values = vtkSmartPointer<vtkDoubleArray>::New();
  values->SetName("thickness_mm");
  values->SetNumberOfTuples(surface->GetNumberOfPoints());
  auto streaks = vtkSmartPointer<vtkUnsignedCharArray>::New();
  streaks->SetName("unreliable_skin");
  streaks->SetNumberOfTuples(surface->GetNumberOfPoints());
  for (vtkIdType i = 0; i < surface->GetNumberOfPoints(); ++i)
  {
    double p[3];
    surface->GetPoint(i, p);
    const auto [theta, z] = chartOf({p[0], p[1], p[2]});
    const bool spoiled = spoiled_ && spoiled_(Eigen::Vector3d(p[0], p[1], p[2]));
    values->SetValue(i, spoiled ? std::numeric_limits<double>::quiet_NaN() : map.sample(theta, z));
    streaks->SetValue(i, spoiled ? 1 : 0);
  }
  painted->GetPointData()->AddArray(values);
  if (spoiled_)
    painted->GetPointData()->AddArray(streaks);
  return painted;
}

std::vector<unsigned char> ThicknessReview::spoiledSamples() const
{
  std::vector<unsigned char> out(static_cast<std::size_t>(skin_.nTheta()) * skin_.nZ(), 0);
  if (!spoiled_)
    return out;
  const seg::CylindricalFrame& frame = skin_.frame();
  for (int j = 0; j < skin_.nZ(); ++j)
    for (int i = 0; i < skin_.nTheta(); ++i)
      out[std::size_t(i) + std::size_t(skin_.nTheta()) * j] =
        spoiled_(frame.toWorld(skin_.at(i, j), frame.indexToTheta(i), frame.indexToZ(j))) ? 1 : 0;
  return out;
}

ThicknessReview::SpoiledTest ThicknessReview::spoiledBy(const std::vector<seg::MetalPiece>& metal, vtkImageData* ct)
{
  if (metal.empty() || !ct)
    return {};
  vtkSmartPointer<vtkImageData> image(ct);
  return [metal, image](const Eigen::Vector3d& p) { return seg::streaksAt(metal, image, p) != nullptr; };
}

ThicknessReview::SpoiledTest ThicknessReview::eitherOf(SpoiledTest a, SpoiledTest b)
{
  if (!a)
    return b;
  if (!b)
    return a;
  return [a = std::move(a), b = std::move(b)](const Eigen::Vector3d& p) { return a(p) || b(p); };
}

std::vector<int> ThicknessReview::faceHistogram(double binWidth, int bins, ThicknessMeasure measure) const
{
  constexpr double kHalfWidth = 75.0 * std::numbers::pi / 180.0; // the cheeks, not the ears
  std::vector<int> counts(static_cast<std::size_t>(std::max(bins, 0)), 0);
  if (counts.empty() || !(binWidth > 0.0))
    return counts;
  const seg::RangeMap& map = thicknessMap(measure);
  const seg::CylindricalFrame& frame = map.frame();
  for (int j = 0; j < map.nZ(); ++j)
  {
    const double z = frame.indexToZ(j);
    if (face_rows_ && (z < (*face_rows_)[0] || z > (*face_rows_)[1]))
      continue;
    for (int i = 0; i < map.nTheta(); ++i)
    {
      const double fromFront = std::abs(seg::CylindricalFrame::wrapTheta(frame.indexToTheta(i) + std::numbers::pi / 2));
      const float t = map.at(i, j);
      if (fromFront > kHalfWidth || !std::isfinite(t) || t < 0.0f)
        continue;
      if (spoiled_ && spoiled_(frame.toWorld(skin_.at(i, j), frame.indexToTheta(i), z)))
        continue;
      const auto bin = std::min(static_cast<std::size_t>(t / binWidth), counts.size() - 1);
      ++counts[bin];
    }
  }
  return counts;
}

std::string ThicknessReview::landmarksCsv(const std::vector<LandmarksNode::Landmark>& landmarks,
                                          const std::vector<CtDepth>& depths) const
{
  if (!depths.empty() && depths.size() != landmarks.size())
    throw std::invalid_argument("landmarksCsv: one depth per landmark, or none");
  std::ostringstream csv;
  csv << "name,x_mm,y_mm,z_mm,theta_deg,axis_z_mm,skin_radius_mm,bone_radius_mm,thickness_radial_mm,"
         "thickness_normal_mm,depth_mm,convention,note\n";
  auto number = [&csv](double v, int digits) {
    csv << ',';
    if (std::isfinite(v))
      csv << std::fixed << std::setprecision(digits) << v;
  };
  for (std::size_t k = 0; k < landmarks.size(); ++k)
  {
    const auto& landmark = landmarks[k];
    const auto [theta, z] = chartOf(landmark.position);
    const ThicknessProbe p = probe(theta, z);
    csv << csvField(landmark.name);
    for (double c : landmark.position)
      number(c, 2);
    number(theta * 180.0 / std::numbers::pi, 2);
    number(z, 2);
    number(p.skinRadius, 2);
    number(p.boneRadius, 2);
    number(p.thickness, 2);
    number(p.thicknessNormal, 2);
    const CtDepth d = depths.empty() ? CtDepth{} : depths[k];
    number(d.depth, 2);
    csv << ',' << csvField(d.convention) << ',' << csvField(d.note) << '\n';
  }
  return csv.str();
}

std::string ThicknessReview::distancesCsv(const std::vector<LandmarksNode::Distance>& distances)
{
  std::ostringstream csv;
  csv << "name,from_x_mm,from_y_mm,from_z_mm,to_x_mm,to_y_mm,to_z_mm,length_mm\n" << std::fixed << std::setprecision(2);
  for (const auto& d : distances)
  {
    csv << csvField(d.name);
    for (const auto& end : {d.from, d.to})
      for (double c : end)
        csv << ',' << c;
    csv << ',' << d.length() << '\n';
  }
  return csv.str();
}

} // namespace caps
