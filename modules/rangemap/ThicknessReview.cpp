#include "modules/rangemap/ThicknessReview.h"

#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <sstream>

#include <vtkDoubleArray.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>

#include "modules/rangemap/RangeMapLogic.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"

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
  return ThicknessReview(RangeMapLogic::toRangeMap(*skin), RangeMapLogic::toRangeMap(*bone),
                         RangeMapLogic::toRangeMap(*thickness),
                         normal ? RangeMapLogic::toRangeMap(*normal) : seg::RangeMap());
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

std::array<double, 2> ThicknessReview::chartOf(const std::array<double, 3>& world) const
{
  const seg::CylindricalPoint c = skin_.frame().toCylindrical(Eigen::Vector3d(world[0], world[1], world[2]));
  return {c.theta, c.z};
}

vtkSmartPointer<vtkPolyData> ThicknessReview::paintThickness(vtkPolyData* surface) const
{
  auto painted = vtkSmartPointer<vtkPolyData>::New();
  painted->ShallowCopy(surface);
  // The point data is the source's: a new array must not land in it.
  auto pointData = vtkSmartPointer<vtkPointData>::New();
  pointData->ShallowCopy(surface->GetPointData());
  painted->GetPointData()->ShallowCopy(pointData);
  auto values = vtkSmartPointer<vtkDoubleArray>::New();
  values->SetName("thickness_mm");
  values->SetNumberOfTuples(surface->GetNumberOfPoints());
  for (vtkIdType i = 0; i < surface->GetNumberOfPoints(); ++i)
  {
    double p[3];
    surface->GetPoint(i, p);
    const auto [theta, z] = chartOf({p[0], p[1], p[2]});
    values->SetValue(i, thickness_.sample(theta, z));
  }
  painted->GetPointData()->AddArray(values);
  return painted;
}

std::vector<int> ThicknessReview::faceHistogram(double binWidth, int bins) const
{
  std::vector<int> counts(static_cast<std::size_t>(std::max(bins, 0)), 0);
  if (counts.empty() || !(binWidth > 0.0))
    return counts;
  const seg::CylindricalFrame& frame = thickness_.frame();
  for (int j = 0; j < thickness_.nZ(); ++j)
    for (int i = 0; i < thickness_.nTheta(); ++i)
    {
      const double theta = frame.indexToTheta(i);
      const float t = thickness_.at(i, j);
      if (theta > 0.0 || !std::isfinite(t) || t < 0.0f)
        continue;
      const auto bin = std::min(static_cast<std::size_t>(t / binWidth), counts.size() - 1);
      ++counts[bin];
    }
  return counts;
}

std::string ThicknessReview::landmarksCsv(const std::vector<LandmarksNode::Landmark>& landmarks) const
{
  std::ostringstream csv;
  csv << "name,x_mm,y_mm,z_mm,theta_deg,axis_z_mm,skin_radius_mm,bone_radius_mm,thickness_radial_mm,"
         "thickness_normal_mm\n";
  auto number = [&csv](double v, int digits) {
    csv << ',';
    if (std::isfinite(v))
      csv << std::fixed << std::setprecision(digits) << v;
  };
  for (const auto& landmark : landmarks)
  {
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
    csv << '\n';
  }
  return csv.str();
}

} // namespace caps
