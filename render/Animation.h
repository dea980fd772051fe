#pragma once
/// @file Animation.h
/// @brief Animations of surfaces (thesis §3.3.3
/// documentation, §5.3 expressions): a morph between two surfaces with the
/// same points, given frames, a turntable round the head axis; each written
/// as a PNG sequence and, when Debian's ffmpeg is there, as an MP4.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <vtkSmartPointer.h>

#include <Eigen/Core>

#include "render/Figure.h"
#include "segmentation/Progress.h"

class vtkPolyData;

namespace caps::render {

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
  Camera camera;               ///< the pre → post camera; the turntable's first (front) camera
  std::filesystem::path video; ///< the MP4, empty when none was made
  std::string ffmpegCommand;   ///< the command line that makes (or would make) the MP4
};

/// What an animation writer wrote.
struct AnimationResult
{
  std::string planName; ///< the plan animated (report/PlanAnimation.h), or the animation's name
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

/// @name Building blocks of an animation writer
///@{
/// The frame size of @a options, evened (video needs even sizes).
/// @throws std::invalid_argument for a side outside 16–8192 pixels or a frame rate that is not positive.
std::pair<int, int> animationFrameSize(const AnimationOptions& options);

/// Renders @a frames frames of @a base from @a from to @a to (then back to
/// @a from, the peak not repeated, when @a andBack) into @a sequence.folder
/// (emptied of earlier frames first) with @a sequence.camera, coloured by the
/// surfaces' skin_shade (or skin_colour) point array when they have one, else
/// in a skin tone; @a step is called before each frame.
void renderMorphFrames(vtkPolyData* from, vtkPolyData* to, const Figure& base, FrameSequence& sequence, int frames,
                       bool andBack, const std::function<void(const char*)>& step);

/// The same through several stages (intact → incised and gaping → closed):
/// @a frames frames from the first of @a stages to the last, each stage
/// reached at an even share of them, blended linearly in between. Throws
/// std::invalid_argument for fewer than 2 stages or frames, or stages with
/// other point counts than the first.
void renderStagedMorphFrames(const std::vector<vtkPolyData*>& stages, const Figure& base, FrameSequence& sequence,
                             int frames, const std::function<void(const char*)>& step);

/// Renders @a figure (its surfaces and lines) @a frames times into
/// @a sequence.folder, the camera going once round @a frame's axis from the
/// front (θ = −π/2), at the same distance in every frame: it frames a
/// cylinder about the axis holding @a framed. @a sequence.camera is the first.
/// @throws std::invalid_argument when @a framed is empty.
void renderTurntableFrames(const Figure& figure, vtkPolyData* framed, const seg::CylindricalFrame& frame, int frames,
                           FrameSequence& sequence, const std::function<void(const char*)>& step);

/// The MP4 of each of @a sequences, beside its folder, when ffmpeg is found
/// and @a options.video asks for them; otherwise @a result.videoMessage says
/// how to make them. Every sequence's ffmpegCommand is set.
/// @throws std::runtime_error when ffmpeg fails, seg::Cancelled when
/// @a progress asks to stop.
void encodeVideos(const std::vector<FrameSequence*>& sequences, const AnimationOptions& options,
                  const seg::ProgressCallback& progress, AnimationResult& result);
///@}

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
                                    const AnimationOptions& options, const seg::ProgressCallback& progress = {});

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
                                      const seg::ProgressCallback& progress = {});

} // namespace caps::render
