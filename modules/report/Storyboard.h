#pragma once
/// @file Storyboard.h
/// @brief Snapshots for the storyboard (thesis §3.3.3: the views a surgeon
/// keeps while planning, in order, with captions, printed in the report).

#include <string>

#include "modules/report/PlanFigures.h"

namespace caps {
class Scene;
class SnapshotNode;
} // namespace caps

namespace caps::report {

/// Renders @a view of the plan named @a planName offscreen (@a width ×
/// @a height pixels) and adds it to the scene as a Snapshot node with its
/// camera and @a caption (default: the plan's name and the view). Snapshots
/// are kept in the order taken.
/// @throws std::invalid_argument when the scene has no such plan (the message
/// lists its plans) or lacks the surfaces the view needs.
SnapshotNode& takePlanSnapshot(Scene& scene, const std::string& planName, PlanView view, std::string caption = {},
                               int width = 1200, int height = 900);

/// "front", "oblique", "profile", "before", "after", "stress" → the view.
/// @throws std::invalid_argument for another word, listing these.
PlanView planViewFromName(const std::string& name);

} // namespace caps::report
