#pragma once
/// @file PlanAnimation.h
/// @brief Animation export (issue 7 item 3; thesis §3.3.3 documentation):
/// the skin morphing from before the operation to the predicted result, and
/// a turntable around the head with the incision drawn, each written as a
/// PNG sequence and, when Debian's ffmpeg is there, as an MP4.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <vtkSmartPointer.h>

#include <Eigen/Core>

#include "modules/core/Module.h"
#include "modules/report/ReportFigures.h"

class vtkPolyData;

namespace caps {
class Scene;
}

namespace caps::report {

/// What to write and how.
struct AnimationOptions
{
  /// Frame size in pixels; odd values are rounded down to even (yuv420p video needs even sizes).
  int width = 960;
  int height = 720;
  /// Frames of the pre → post morph (at least 2: the first is the skin before, the last after).
  int prePostFrames = 30;
  /// Frames of one turn around the head axis (at least 2), starting from the front.
  int turntableFrames = 72;
  bool turntable = true;
  /// Encode each sequence as an MP4 when ffmpeg is found.
  bool video = true;
  double framesPerSecond = 24.0;
  /// MSAA samples of each frame (0: none).
  int multiSamples = 4;
};

/// One PNG sequence: folder/frame-0000.png … and, when made, its video.
struct FrameSequence
{
  std::filesystem::path folder;
  int frames = 0;
  int width = 0;
  int height = 0;
  Camera camera;                 ///< the pre → post camera; the turntable's first (front) camera
  std::filesystem::path video;   ///< the MP4, empty when none was made
  std::string ffmpegCommand;     ///< the command line that makes (or would make) the MP4
};

/// What writePlanAnimation() wrote.
struct AnimationResult
{
  std::string planName;
  FrameSequence prePost;
  std::optional<FrameSequence> turntable;
  /// False when videos were asked for and ffmpeg was not found (nothing failed: the frames are written).
  bool ffmpegFound = false;
  /// For the user: why there is no video and how to make it later; empty when the videos were made or not asked for.
  std::string videoMessage;
  int framesRendered = 0;
  double renderSeconds = 0.0; ///< wall time spent rendering and writing the frames
};

/// The skin at @a s in [0, 1] of the way from @a before to @a after: points
/// (1−s)·before + s·after, and the point arrays skin_shade / skin_colour and
/// normals blended the same way when both surfaces have them. Cells are
/// before's.
/// @throws std::invalid_argument when the point counts differ.
vtkSmartPointer<vtkPolyData> blendSurfaces(vtkPolyData* before, vtkPolyData* after, double s);

/// The ffmpeg to run: $CAPS_FFMPEG when set (a path, or a name searched on
/// PATH), otherwise `ffmpeg` on PATH; nullopt when it is not an executable file.
std::optional<std::filesystem::path> findFfmpeg();

/// Writes the animations of the plan named @a planName (empty: the scene's
/// first plan) into @a outDir: pre-post/frame-NNNN.png (the display surfaces
/// "<plan> skin before" → "<plan> skin after" coloured by skin_shade, one
/// camera framing both), turntable/frame-NNNN.png (the "Skin" surface with the
/// incision, the camera going once round the head axis from the front), and
/// pre-post.mp4 / turntable.mp4 when ffmpeg is found. Frames already in those
/// folders are replaced.
/// @throws std::invalid_argument naming what is missing (no such plan, no
/// display surfaces, different point counts, no skin range map), seg::Cancelled
/// when @a progress asks to stop, std::runtime_error when a file cannot be
/// written or ffmpeg fails.
AnimationResult writePlanAnimation(Scene& scene, const std::string& planName, const std::filesystem::path& outDir,
                                   const AnimationOptions& options, const TaskProgress& progress = {});

/// Writes a morph between two display surfaces with the same points and
/// cells, e.g. a face at rest and under an expression (thesis §5.3), like the
/// pre → post animation: @a outDir/@a name/frame-NNNN.png and
/// @a outDir/@a name.mp4 when ffmpeg is found (options.video). @a frames
/// frames from @a from to @a to, then back again to @a from (the peak not
/// repeated) when @a andBack. The camera looks along −@a toCamera with
/// @a viewUp up, framing both surfaces. Coloured by the surfaces' skin_shade
/// (or skin_colour) point array when they have one, else a skin tone.
/// @throws std::invalid_argument for fewer than 2 frames, a bad size, a name
/// that is not a plain file name, empty surfaces or different point counts;
/// seg::Cancelled when @a progress asks to stop; std::runtime_error when a
/// file cannot be written or ffmpeg fails.
AnimationResult writeMorphAnimation(vtkPolyData* from, vtkPolyData* to, const std::string& name,
                                    const Eigen::Vector3d& toCamera, const Eigen::Vector3d& viewUp,
                                    const std::filesystem::path& outDir, int frames, bool andBack,
                                    const AnimationOptions& options, const TaskProgress& progress = {});

/// Writes an animation whose frames are given, one surface each (a push
/// along a bent path, thesis §5.4, is not a blend of two surfaces): like
/// writeMorphAnimation(), @a outDir/@a name/frame-NNNN.png and @a name.mp4,
/// one camera framing every frame.
/// @throws std::invalid_argument for fewer than 2 frames, an empty frame, a
/// bad size or a name that is not a plain file name; seg::Cancelled when
/// @a progress asks to stop; std::runtime_error when a file cannot be written
/// or ffmpeg fails.
AnimationResult writeSurfaceAnimation(const std::vector<vtkSmartPointer<vtkPolyData>>& frames, const std::string& name,
                                      const Eigen::Vector3d& toCamera, const Eigen::Vector3d& viewUp,
                                      const std::filesystem::path& outDir, const AnimationOptions& options,
                                      const TaskProgress& progress = {});

} // namespace caps::report
