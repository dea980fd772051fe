#pragma once
/// @file ConvergenceStudy.h
/// @brief How much a prediction depends on the model's own choices (thesis
/// §5.5, validating the results of the physical model): the same plan solved
/// with the mesh refined, with more and fewer tissue layers, and with the
/// meshed region grown, its rim free and clamped; the closure's numbers
/// tabled with their change from the level before. The command line (caps
/// plan --study convergence) and the report's appendix call it.

#include <string>
#include <vector>

#include "planning/IncisionPlan.h"
#include "planning/PlanSimulation.h"
#include "segmentation/RangeMap.h"

namespace caps::planning {

/// What the study varies; the others keep the plan's own options.
struct ConvergenceLevels
{
  /// Element sizes at the wound (mm), coarse to fine; empty: 1.5 h, h and
  /// h / 1.5 about the options' h.
  std::vector<double> elementSizes;
  std::vector<int> layerCounts = {2, 3, 4};
  /// Meshed region radii (mm), each with the rim free and clamped.
  std::vector<double> regionRadii = {15.0, 25.0, 35.0};
};

/// One solve of the study and what it gave.
struct ConvergenceRow
{
  std::string series;    ///< "element size", "tissue layers", "region radius, free rim", "region radius, clamped rim"
  double value = 0.0;    ///< the level: mm, layers or mm
  bool computed = false; ///< the solve returned (its numbers below are filled in)
  bool solved = false;   ///< and its result is a prediction (PredictionCheck::admissible())
  std::string problem;   ///< why it did not solve, or why it is not a prediction (PredictionCheck::problem)
  double closureForce = 0.0;         ///< N, summed over the sutures (mesh dependent: for comparison only)
  double tensionPerCentimetre = 0.0; ///< N/cm, over the whole wound (WoundTension)
  double meanWoundStressKPa = 0.0;   ///< von Mises, skin within the band (the headline stress)
  double peakWoundStressKPa = 0.0;   ///< the same, largest: singular at a wound corner
  double gainPercent = 0.0;          ///< Z-plasty lengthening; NaN for other procedures
  double largestDisplacement = 0.0;  ///< mm, of the skin
  double minDetF = 0.0;
  /// Relative change (%) of each number from the row before in the same
  /// series; NaN on a series' first row or after one that did not solve.
  double forceChange = 0.0, tensionChange = 0.0, meanStressChange = 0.0, gainChange = 0.0, displacementChange = 0.0;
};

struct ConvergenceStudy
{
  std::vector<ConvergenceRow> rows; ///< the series one after another, each coarse to fine / small to large
};

/// @brief The convergence and sensitivity study of @a plan with @a options
/// (the model, materials, depth and undermining of the plan's prediction);
/// the skin stress taken within @a woundStressRadius mm of the wound. A
/// level that fails to solve is a row with its problem, not an exception.
/// @a progress (may be empty) is told which solve runs; returning false
/// stops the study with seg::Cancelled.
/// @throws std::invalid_argument for an empty series or a level that is
/// not a positive number.
ConvergenceStudy studyConvergence(const seg::RangeMap& skin, const seg::RangeMap& bone, const IncisionPlan& plan,
                                  const SimulationOptions& options, ConvergenceLevels levels, double woundStressRadius,
                                  const seg::ProgressCallback& progress = {});

} // namespace caps::planning
