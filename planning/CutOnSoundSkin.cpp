#include "planning/CutOnSoundSkin.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

namespace caps::planning {

namespace {

/// Where on the skin a cut is checked.
struct CutPoint
{
  std::size_t afterPoint = 0; ///< the cut point (0-based) the segment starts at
  Eigen::Vector3d world;
  SkinPoint at;
};

/// The first point of @a plan's cut, every millimetre along each segment on
/// the plan's chart (and the cut's own points), where @a unsound is true.
std::optional<CutPoint> firstUnsound(const IncisionPlan& plan, const seg::RangeMap& skin,
                                     const std::function<bool(const Eigen::Vector3d&)>& unsound)
{
  const SkinChart chart = plan.chart(skin);
  const std::vector<Eigen::Vector2d>& path = plan.cutPath();
  for (std::size_t k = 0; k < path.size(); ++k)
  {
    const ChartPoint a = chart.fromNormalized(path[k]);
    const ChartPoint b = chart.fromNormalized(path[std::min(k + 1, path.size() - 1)]);
    const int steps = std::max(1, int(std::ceil((b - a).norm())));
    for (int s = 0; s <= steps; ++s)
    {
      const ChartPoint p = a + (double(s) / steps) * (b - a);
      const Eigen::Vector3d world = chart.lift(p);
      if (unsound(world))
        return CutPoint{k, world, chart.fromChart(p)};
    }
  }
  return std::nullopt;
}

/// "near cut point 2, at (x, y, z) mm; θ -40°, -30 mm along the head axis".
std::string describe(const CutPoint& c)
{
  std::ostringstream where;
  where.precision(0);
  where << std::fixed << "near cut point " << c.afterPoint + 1 << ", at (" << c.world.x() << ", " << c.world.y() << ", "
        << c.world.z() << ") mm; θ " << c.at.theta * 180.0 / M_PI << "°, " << c.at.z << " mm along the head axis";
  return where.str();
}

} // namespace

std::string cutInMetalStreaks(const IncisionPlan& plan, const seg::RangeMap& skin,
                              const std::vector<seg::MetalPiece>& metal, vtkImageData* ct)
{
  if (metal.empty() || !ct || plan.cutPath().empty())
    return {};
  const seg::MetalPiece* piece = nullptr;
  const auto found = firstUnsound(plan, skin, [&](const Eigen::Vector3d& world) {
    piece = seg::streaksAt(metal, ct, world);
    return piece != nullptr;
  });
  if (!found)
    return {};
  return "the cut runs through skin (" + describe(*found) +
         ") in CT slices that streaks spoil: " + seg::describe(*piece, ct) +
         ". The skin and bone there are the streaks' artefacts, not the patient's, and no prediction made on "
         "them can be trusted. Place the plan away from those slices, or use a CT without the metal (the "
         "dental work out of the field, or reconstructed with metal-artefact reduction)";
}

std::string cutAgainstAnObject(const IncisionPlan& plan, const seg::RangeMap& skin,
                               const std::function<bool(const Eigen::Vector3d&)>& againstAnObject)
{
  if (!againstAnObject || plan.cutPath().empty())
    return {};
  const auto found = firstUnsound(plan, skin, againstAnObject);
  if (!found)
    return {};
  return "the cut runs over skin pressed against something outside the body (" + describe(*found) +
         "): the head holder or the table's pad. The skin there is the edge of the segmentation, not a surface "
         "the CT measured, and no prediction made on it can be trusted. Place the plan on skin that faces air, "
         "or use a CT in which the head lies clear of the holder there";
}

} // namespace caps::planning
