#pragma once
/// @file CutOnSoundSkin.h
/// @brief Whether a plan's cut lies on skin the CT measured soundly: not in
/// the slices that metal's streaks spoil (seg::findMetal), where the skin and
/// bone the range maps hold are artefacts, not the patient (issue: dental
/// metal made spikes in the skin and holes in the jaw of a cadaver's CT),
/// and not on skin pressed against the head holder, where the skin is the
/// edge of the segmentation's body rather than a surface the CT measured.

#include <functional>
#include <string>
#include <vector>

#include "planning/IncisionPlan.h"
#include "segmentation/MetalArtefacts.h"
#include "segmentation/RangeMap.h"

class vtkImageData;

namespace caps::planning {

/// Why @a plan cannot be cut on @a skin as the CT @a ct shows it: the first
/// point of its cut (every millimetre along each segment, on the plan's
/// chart) whose skin lies in the slices the streaks of a piece of @a metal
/// spoil (seg::streaksAt), with where, which metal, and what to do; "" when
/// the whole cut lies on skin the CT measured soundly (or there is no metal).
std::string cutInMetalStreaks(const IncisionPlan& plan, const seg::RangeMap& skin,
                              const std::vector<seg::MetalPiece>& metal, vtkImageData* ct);

/// Why @a plan cannot be cut on @a skin: the first point of its cut (walked
/// as cutInMetalStreaks walks it) whose skin @a againstAnObject marks (skin
/// pressed against the head holder or the table's pad:
/// seg::skinAgainstAnObject), with where and what to do; "" when
/// none is or the test is empty.
std::string cutAgainstAnObject(const IncisionPlan& plan, const seg::RangeMap& skin,
                               const std::function<bool(const Eigen::Vector3d&)>& againstAnObject);

} // namespace caps::planning
