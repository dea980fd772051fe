#include "planning/CutOnSoundSkin.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace caps::planning {

std::string cutInMetalStreaks(const IncisionPlan& plan, const seg::RangeMap& skin,
                              const std::vector<seg::MetalPiece>& metal, vtkImageData* ct)
{
  if (metal.empty() || !ct || plan.cutPath().empty())
    return {};
  const SkinChart chart = plan.chart(skin);
  const std::vector<Eigen::Vector2d>& path = plan.cutPath();
  // Along each segment of the cut on the chart, a point every millimetre
  // (and the cut's own points).
  for (std::size_t k = 0; k < path.size(); ++k)
  {
    const ChartPoint a = chart.fromNormalized(path[k]);
    const ChartPoint b = chart.fromNormalized(path[std::min(k + 1, path.size() - 1)]);
    const double length = (b - a).norm();
    const int steps = std::max(1, int(std::ceil(length)));
    for (int s = 0; s <= steps; ++s)
    {
      const double t = double(s) / steps;
      const ChartPoint p = a + t * (b - a);
      const Eigen::Vector3d world = chart.lift(p);
      const seg::MetalPiece* piece = seg::streaksAt(metal, ct, world);
      if (!piece)
        continue;
      const SkinPoint at = chart.fromChart(p);
      std::ostringstream why;
      why.precision(0);
      why << std::fixed << "the cut runs through skin (near cut point " << k + 1 << ", at (" << world.x() << ", "
          << world.y() << ", " << world.z() << ") mm; θ " << at.theta * 180.0 / M_PI << "°, " << at.z
          << " mm along the head axis) in CT slices that streaks spoil: " << seg::describe(*piece, ct)
          << ". The skin and bone there are the streaks' artefacts, not the patient's, and no prediction made on "
             "them can be trusted. Place the plan away from those slices, or use a CT without the metal (the "
             "dental work out of the field, or reconstructed with metal-artefact reduction)";
      return why.str();
    }
  }
  return {};
}

} // namespace caps::planning
