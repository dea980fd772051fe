#pragma once
/// @file PlanAnimation.h
/// @brief A plan's animations (thesis §3.3.3 documentation):
/// the skin morphing from before the operation to the predicted result, and
/// a turntable around the head with the incision drawn, found in the scene
/// and written by render/Animation.h.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <vtkSmartPointer.h>

#include <Eigen/Core>

#include "modules/core/Module.h"
#include "render/Animation.h"

class vtkPolyData;

namespace caps {
class Scene;
}

namespace caps::report {

/// Writes the animations of the plan named @a planName (empty: the scene's
/// first plan) into @a outDir: pre-post/frame-NNNN.png (the display surfaces
/// "<plan> skin before" → "<plan> skin after" coloured by skin_shade, through
/// "<plan> skin gaping" when the prediction has one: as cut, gaping under the
/// skin's tension, closed; one camera framing them all),
/// turntable/frame-NNNN.png (the "Skin" surface with the incision, the camera going once round the head axis from the front), and
/// pre-post.mp4 / turntable.mp4 when ffmpeg is found. Frames already in those
/// folders are replaced.
/// @throws std::invalid_argument naming what is missing (no such plan, no
/// display surfaces, different point counts, no skin range map), seg::Cancelled
/// when @a progress asks to stop, std::runtime_error when a file cannot be
/// written or ffmpeg fails.
render::AnimationResult writePlanAnimation(Scene& scene, const std::string& planName,
                                           const std::filesystem::path& outDir, const render::AnimationOptions& options,
                                           const TaskProgress& progress = {});

} // namespace caps::report
