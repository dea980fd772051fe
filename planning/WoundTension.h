#pragma once
/// @file WoundTension.h
/// @brief The tension a closed wound is held with, per centimetre of wound
/// and per stitch, on the wound lines the surgeon names (thesis §3.2.4: the
/// tension of a closure is what undermining relieves; §4.6, eq. 4.43: the
/// suture forces are the constraints' reactions).

#include <string>
#include <vector>

#include "planning/IncisionPlan.h"
#include "planning/PlanSimulation.h"

namespace caps::planning {

/// Where surgeons place skin stitches on the face: about every 3 to 5 mm
/// (e.g. Baker, Local Flaps in Facial Reconstruction); the report's default.
constexpr double kDefaultStitchSpacing = 4.0; // mm

/// One line of the closed wound (the sutures the procedure names alike, e.g.
/// "the first limb"), with the force across it.
struct WoundLineTension
{
  std::string name;               ///< in the procedure's words (woundLineName())
  std::vector<int> sutures;       ///< the plan's suture pairs along it
  double length = 0.0;            ///< closed length on the skin (mm)
  double acrossForce = 0.0;       ///< force across the line, through every layer sewn (N)
  double perCentimetre = 0.0;     ///< its mean per centimetre of line (N/cm)
  double peakPerCentimetre = 0.0; ///< over its suture pairs, the largest (N/cm)
  std::string peakBetween;        ///< that pair's ends, by cut point ("p1 and p2")
  /// Per suture pair along it (in the order of sutures), N/cm.
  std::vector<double> piecePerCentimetre;
  int stitches = 0;           ///< stitches at the spacing along its length (at least 1)
  double perStitch = 0.0;     ///< mean force one stitch carries (N)
  double peakPerStitch = 0.0; ///< the same at the peak (N)
};

/// The closure's tension along every wound line.
struct WoundTension
{
  double stitchSpacing = kDefaultStitchSpacing; ///< mm
  std::vector<WoundLineTension> lines;          ///< in the order of the plan's sutures
  double peakPerCentimetre = 0.0;               ///< over all lines (N/cm)
  double peakPerStitch = 0.0;                   ///< N
  std::string peakLine;                         ///< the line it is on
};

/// @brief The tension across each wound line of a solved plan.
///
/// A sum of node forces is no quantity a surgeon uses and changes with the
/// mesh; the force across a length of wound is one, and does not. For each suture pair
/// of the plan the force on its first side's sewn nodes (their internal
/// force, which is what the sutures pull them with) is summed through every
/// layer sewn; its component across the closed line in the skin's tangent
/// plane is the force holding that piece closed, and divided by the closed
/// length it is the tension per centimetre. A stitch every @a stitchSpacing
/// mm carries the tension over that spacing. A column where two pieces meet counts half in each.
///
/// @throws std::invalid_argument for a spacing that is not a positive
/// number of mm, or when @a prediction is not the prediction of @a plan.
WoundTension woundTension(const PlanPrediction& prediction, const IncisionPlan& plan,
                          double stitchSpacing = kDefaultStitchSpacing);

} // namespace caps::planning
