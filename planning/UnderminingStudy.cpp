#include "planning/UnderminingStudy.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "planning/WoundStress.h"

namespace caps::planning {

UnderminingStudy studyUndermining(const seg::RangeMap& skin, const seg::RangeMap& bone, const IncisionPlan& plan,
                                  SimulationOptions options, const std::vector<double>& widths,
                                  double woundStressRadius)
{
  if (widths.empty())
    throw std::invalid_argument("the undermining study needs at least one width");
  for (const double width : widths)
    if (!(width >= 0.0))
      throw std::invalid_argument("an undermining width must be 0 mm or more, not " + std::to_string(width));
  UnderminingStudy study;
  // One meshed region for every width, so the rows differ only in the band.
  const double widest = *std::max_element(widths.begin(), widths.end());
  options.regionRadius = std::max(options.regionRadius, widest + 15.0);
  study.regionRadius = options.regionRadius;
  for (const double width : widths)
  {
    options.underminingWidth = width;
    const PlanPrediction p = simulatePlan(skin, bone, plan, options);
    const WoundStress near = woundSkinStress(p, woundStressRadius);
    UnderminingStudyRow row;
    row.width = width;
    row.releasedBoneNodes = p.continuum.underminedNodes.size();
    row.closureForce = p.closure.magnitudeSum;
    row.largestSutureForce = p.closure.largest;
    row.sutureGap = p.maxSutureGap;
    row.peakVonMisesKPa = 1e3 * near.peakVonMises;
    row.meanVonMisesKPa = 1e3 * near.meanVonMises;
    study.rows.push_back(row);
  }
  return study;
}

} // namespace caps::planning
