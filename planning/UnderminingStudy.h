#pragma once
/// @file UnderminingStudy.h
/// @brief The surgeon's question "how far must I undermine?" (thesis §3.2.4
/// item 2): the same plan predicted with the bone released under bands of
/// growing width along the sutured edges, and what each does to the closure
/// force and the skin stress by the wound. The command line (caps plan
/// --undermine) and the workstation call the same function.

#include <cstddef>
#include <vector>

#include "planning/IncisionPlan.h"
#include "planning/PlanSimulation.h"
#include "segmentation/RangeMap.h"

namespace caps::planning {

/// The plan predicted with one undermining width.
struct UnderminingStudyRow
{
  double width = 0.0;                ///< mm, of the band along the sutured edges
  std::size_t releasedBoneNodes = 0; ///< bone nodes no longer fixed
  double closureForce = 0.0;         ///< N, summed over the sutures
  double largestSutureForce = 0.0;   ///< N
  double sutureGap = 0.0;            ///< mm, after closure
  double peakVonMisesKPa = 0.0;      ///< skin within woundStressRadius of the wound
  double meanVonMisesKPa = 0.0;      ///< the same band
};

struct UnderminingStudy
{
  /// The meshed region around the wound, mm: the options' radius, or 15 mm
  /// beyond the widest band when that is larger (a band as wide as the
  /// region would free every bone node and leave the skin nothing to hold it).
  double regionRadius = 0.0;
  std::vector<UnderminingStudyRow> rows; ///< in the order of the widths asked
};

/// The study of @a plan on @a skin and @a bone with @a options (their
/// undermining width and region radius replaced), one row per width in
/// @a widths (mm, not negative), the skin stress taken within
/// @a woundStressRadius mm of the wound (woundSkinStress()).
/// @throws std::invalid_argument for no widths or a negative one, and what
///         simulatePlan() throws.
UnderminingStudy studyUndermining(const seg::RangeMap& skin, const seg::RangeMap& bone, const IncisionPlan& plan,
                                  SimulationOptions options, const std::vector<double>& widths,
                                  double woundStressRadius);

} // namespace caps::planning
