#include "render/Animation.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkUnsignedCharArray.h>

#include "segmentation/CylindricalFrame.h"

namespace fs = std::filesystem;

namespace caps::render {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// Blends two unsigned char arrays of the same shape; null when either is missing or they differ.
vtkSmartPointer<vtkDataArray> blendColours(vtkDataArray* a, vtkDataArray* b, double s)
{
  auto* ca = vtkUnsignedCharArray::SafeDownCast(a);
  auto* cb = vtkUnsignedCharArray::SafeDownCast(b);
  if (!ca || !cb || ca->GetNumberOfTuples() != cb->GetNumberOfTuples() ||
      ca->GetNumberOfComponents() != cb->GetNumberOfComponents())
    return nullptr;
  if (s <= 0.0)
    return a;
  if (s >= 1.0)
    return b;
  auto out = vtkSmartPointer<vtkUnsignedCharArray>::New();
  out->SetName(ca->GetName());
  out->SetNumberOfComponents(ca->GetNumberOfComponents());
  out->SetNumberOfTuples(ca->GetNumberOfTuples());
  const vtkIdType n = ca->GetNumberOfValues();
  for (vtkIdType i = 0; i < n; ++i)
    out->SetValue(i, static_cast<unsigned char>(std::lround((1.0 - s) * ca->GetValue(i) + s * cb->GetValue(i))));
  return out;
}

std::string frameName(int index)
{
  char name[32];
  std::snprintf(name, sizeof name, "frame-%04d.png", index);
  return name;
}

/// An empty folder for a sequence: earlier frames there are removed (ffmpeg
/// would otherwise pick up the frames of a longer earlier run), and so is the
/// earlier run's video beside it, which would no longer match the frames.
void prepareFolder(const fs::path& folder)
{
  fs::create_directories(folder);
  fs::remove(folder.parent_path() / (folder.filename().string() + ".mp4"));
  for (const auto& entry : fs::directory_iterator(folder))
  {
    const std::string name = entry.path().filename().string();
    if (name.rfind("frame-", 0) == 0 && entry.path().extension() == ".png")
      fs::remove(entry.path());
  }
}

std::string shellQuoted(const std::string& s)
{
  std::string q = "'";
  for (char c : s)
  {
    if (c == '\'')
      q += "'\\''";
    else
      q += c;
  }
  q += "'";
  return q;
}

bool isExecutableFile(const fs::path& p)
{
  std::error_code ec;
  return fs::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
}

std::string ffmpegCommandLine(const fs::path& ffmpeg, const FrameSequence& sequence, const fs::path& video,
                              double framesPerSecond)
{
  char rate[32];
  std::snprintf(rate, sizeof rate, "%g", framesPerSecond);
  std::string command = shellQuoted(ffmpeg.string());
  command += " -y -loglevel error -framerate ";
  command += rate;
  command += " -i ";
  command += shellQuoted((sequence.folder / "frame-%04d.png").string());
  command += " -vf 'scale=trunc(iw/2)*2:trunc(ih/2)*2' -c:v libx264 -pix_fmt yuv420p ";
  command += shellQuoted(video.string());
  return command;
}

/// Runs a shell command line; its exit status and what it printed.
std::pair<int, std::string> runCommand(const std::string& command)
{
  std::string output;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe)
    return {-1, "cannot start a shell"};
  std::array<char, 4096> buffer;
  std::size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
    output.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

/// The turntable's camera at θ: it frames a cylinder about the head axis holding
/// the whole skin, sampled at angles that turn with θ, so the distance and the
/// target are the same in every frame (no zooming as the head turns).
Camera turntableCamera(const seg::CylindricalFrame& frame, double rMax, double zMin, double zMax, double theta,
                       double aspect)
{
  std::vector<Eigen::Vector3d> points;
  const int around = 36;
  for (int j = 0; j < around; ++j)
  {
    const Eigen::Vector3d radial = frame.radialDirection(theta + 2.0 * kPi * j / around) * rMax;
    for (double z : {zMin, zMax})
      points.push_back(frame.origin() + frame.direction() * z + radial);
  }
  return fitCamera(points, frame.radialDirection(theta), frame.direction(), aspect, 20.0, 1.04);
}

/// Frame @a k of a morph of @a frames frames from @a from to @a to that may
/// come back (k past the peak walks back down, the peak not repeated).
vtkSmartPointer<vtkPolyData> morphFrame(vtkPolyData* from, vtkPolyData* to, int frames, int k)
{
  const int along = k < frames ? k : 2 * (frames - 1) - k;
  return blendSurfaces(from, to, double(along) / (frames - 1));
}

/// Renders frame k = 0 … @a total − 1 of @a surfaceAt into
/// @a sequence.folder with @a sequence.camera, coloured by the surfaces' skin
/// shade when they have one, else in a skin tone; @a step is called before
/// each frame.
void renderSurfaces(const std::function<vtkSmartPointer<vtkPolyData>(int)>& surfaceAt, int total, const Figure& base,
                    FrameSequence& sequence, const std::function<void(const char*)>& step)
{
  prepareFolder(sequence.folder);
  for (int k = 0; k < total; ++k)
  {
    step("Rendering the animation");
    vtkSmartPointer<vtkPolyData> surface = surfaceAt(k);
    const char* shade = surface->GetPointData()->GetArray("skin_shade")    ? "skin_shade"
                        : surface->GetPointData()->GetArray("skin_colour") ? "skin_colour"
                                                                           : nullptr;
    Figure figure = base;
    figure.camera = sequence.camera;
    figure.surfaces.push_back(shade ? SurfaceLayer::pointColours(surface, shade)
                                    : SurfaceLayer::solid(surface, {0.90, 0.76, 0.66}));
    writePng(renderFigure(figure).GetPointer(), sequence.folder / frameName(k));
    ++sequence.frames;
  }
}

} // namespace

void renderMorphFrames(vtkPolyData* from, vtkPolyData* to, const Figure& base, FrameSequence& sequence, int frames,
                       bool andBack, const std::function<void(const char*)>& step)
{
  const int total = andBack ? 2 * frames - 2 : frames;
  renderSurfaces([&](int k) { return morphFrame(from, to, frames, k); }, total, base, sequence, step);
}

void renderStagedMorphFrames(const std::vector<vtkPolyData*>& stages, const Figure& base, FrameSequence& sequence,
                             int frames, const std::function<void(const char*)>& step)
{
  if (stages.size() < 2 || frames < 2)
    throw std::invalid_argument("a staged animation needs at least 2 stages and 2 frames");
  for (vtkPolyData* stage : stages)
    if (!stage || stage->GetNumberOfPoints() != stages.front()->GetNumberOfPoints())
      throw std::invalid_argument("the stages of an animation must be surfaces with the same points");
  const int transitions = int(stages.size()) - 1;
  renderSurfaces(
    [&](int k) {
      const double t = double(k) / (frames - 1) * transitions; // 0 .. transitions
      const int from = std::min(int(std::floor(t)), transitions - 1);
      return blendSurfaces(stages[std::size_t(from)], stages[std::size_t(from) + 1], t - from);
    },
    frames, base, sequence, step);
}

void renderTurntableFrames(const Figure& figure, vtkPolyData* framed, const seg::CylindricalFrame& frame, int frames,
                           FrameSequence& sequence, const std::function<void(const char*)>& step)
{
  double rMax = 0.0, zMin = std::numeric_limits<double>::infinity(), zMax = -zMin;
  for (vtkIdType i = 0; framed && i < framed->GetNumberOfPoints(); ++i)
  {
    double x[3];
    framed->GetPoint(i, x);
    const seg::CylindricalPoint c = frame.toCylindrical(Eigen::Vector3d(x[0], x[1], x[2]));
    rMax = std::max(rMax, c.r);
    zMin = std::min(zMin, c.z);
    zMax = std::max(zMax, c.z);
  }
  if (!(rMax > 0.0) || !(zMax > zMin))
    throw std::invalid_argument("the skin surface is empty: segment the CT again");
  Figure turning = figure;
  prepareFolder(sequence.folder);
  for (int k = 0; k < frames; ++k)
  {
    step("Rendering the turntable");
    const double theta = viewTheta(View::Front) + 2.0 * kPi * k / frames;
    turning.camera = turntableCamera(frame, rMax, zMin, zMax, theta, turning.sceneAspect());
    if (k == 0)
      sequence.camera = turning.camera;
    writePng(renderFigure(turning).GetPointer(), sequence.folder / frameName(k));
    ++sequence.frames;
  }
}

void encodeVideos(const std::vector<FrameSequence*>& sequences, const AnimationOptions& options,
                  const seg::ProgressCallback& progress, AnimationResult& result)
{
  const std::optional<fs::path> ffmpeg = findFfmpeg();
  result.ffmpegFound = ffmpeg.has_value();
  for (FrameSequence* sequence : sequences)
    sequence->ffmpegCommand = ffmpegCommandLine(
      ffmpeg.value_or("ffmpeg"), *sequence,
      sequence->folder.parent_path() / (sequence->folder.filename().string() + ".mp4"), options.framesPerSecond);
  if (options.video && !ffmpeg)
  {
    const char* env = std::getenv("CAPS_FFMPEG");
    std::string message = "no MP4 written: ";
    if (env && *env)
    {
      message += "CAPS_FFMPEG is set to ";
      message += env;
      message += ", which is not an executable file";
    }
    else
      message += "ffmpeg was not found on PATH";
    message += ". Install it (Debian package ffmpeg: apt-get install ffmpeg) and run:";
    for (const FrameSequence* sequence : sequences)
    {
      message += "\n  ";
      message += sequence->ffmpegCommand;
    }
    result.videoMessage = message;
  }
  else if (options.video)
  {
    for (std::size_t i = 0; i < sequences.size(); ++i)
    {
      FrameSequence& sequence = *sequences[i];
      const fs::path video = sequence.folder.parent_path() / (sequence.folder.filename().string() + ".mp4");
      std::string step = "Encoding ";
      step += video.filename().string();
      seg::reportProgress(progress, 0.95 + 0.05 * double(i) / double(sequences.size()), step);
      const auto [status, output] = runCommand(sequence.ffmpegCommand);
      if (status != 0 || !fs::exists(video) || fs::file_size(video) == 0)
      {
        std::string problem = "ffmpeg could not encode ";
        problem += video.string();
        problem += " (exit status ";
        problem += std::to_string(status);
        problem += "): ";
        problem += output.empty() ? std::string("no message") : output;
        problem += "\nThe frames are written; the command was:\n  ";
        problem += sequence.ffmpegCommand;
        throw std::runtime_error(problem);
      }
      sequence.video = video;
    }
  }
}

std::pair<int, int> animationFrameSize(const AnimationOptions& options)
{
  const int width = options.width - options.width % 2;
  const int height = options.height - options.height % 2;
  if (width < 16 || height < 16 || width > 8192 || height > 8192)
    throw std::invalid_argument("the frame size must be within 16–8192 pixels a side (got " +
                                std::to_string(options.width) + " × " + std::to_string(options.height) + ")");
  if (!(options.framesPerSecond > 0.0))
    throw std::invalid_argument("the frame rate must be positive");
  return {width, height};
}

vtkSmartPointer<vtkPolyData> blendSurfaces(vtkPolyData* before, vtkPolyData* after, double s)
{
  if (!before || !after)
    throw std::invalid_argument("blendSurfaces: a surface is missing");
  const vtkIdType n = before->GetNumberOfPoints();
  if (after->GetNumberOfPoints() != n)
    throw std::invalid_argument("the skin before has " + std::to_string(n) + " points and the skin after " +
                                std::to_string(after->GetNumberOfPoints()) +
                                ": they are not the same display surface (predict the plan again, caps plan)");
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  for (vtkIdType i = 0; i < n; ++i)
  {
    double a[3], b[3];
    before->GetPoint(i, a);
    after->GetPoint(i, b);
    points->SetPoint(i, (1.0 - s) * a[0] + s * b[0], (1.0 - s) * a[1] + s * b[1], (1.0 - s) * a[2] + s * b[2]);
  }
  auto out = vtkSmartPointer<vtkPolyData>::New();
  out->SetPoints(points);
  out->SetVerts(before->GetVerts());
  out->SetLines(before->GetLines());
  out->SetPolys(before->GetPolys());
  out->SetStrips(before->GetStrips());
  for (const char* name : {"skin_shade", "skin_colour"})
    if (auto blended = blendColours(before->GetPointData()->GetArray(name), after->GetPointData()->GetArray(name), s))
      out->GetPointData()->AddArray(blended);
  vtkDataArray* na = before->GetPointData()->GetNormals();
  vtkDataArray* nb = after->GetPointData()->GetNormals();
  if (na && nb && na->GetNumberOfTuples() == n && nb->GetNumberOfTuples() == n && na->GetNumberOfComponents() == 3 &&
      nb->GetNumberOfComponents() == 3)
  {
    auto normals = vtkSmartPointer<vtkFloatArray>::New();
    normals->SetName("Normals");
    normals->SetNumberOfComponents(3);
    normals->SetNumberOfTuples(n);
    for (vtkIdType i = 0; i < n; ++i)
    {
      double a[3], b[3];
      na->GetTuple(i, a);
      nb->GetTuple(i, b);
      Eigen::Vector3d v((1.0 - s) * a[0] + s * b[0], (1.0 - s) * a[1] + s * b[1], (1.0 - s) * a[2] + s * b[2]);
      if (v.norm() > 0.0)
        v.normalize();
      normals->SetTuple3(i, v.x(), v.y(), v.z());
    }
    out->GetPointData()->SetNormals(normals);
  }
  return out;
}

std::optional<fs::path> findFfmpeg()
{
  std::string wanted = "ffmpeg";
  if (const char* env = std::getenv("CAPS_FFMPEG"); env && *env)
    wanted = env;
  if (wanted.find('/') != std::string::npos)
    return isExecutableFile(wanted) ? std::optional<fs::path>(fs::absolute(wanted)) : std::nullopt;
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  for (std::size_t start = 0; start <= dirs.size();)
  {
    std::size_t end = dirs.find(':', start);
    if (end == std::string::npos)
      end = dirs.size();
    const fs::path candidate = fs::path(end > start ? dirs.substr(start, end - start) : ".") / wanted;
    if (isExecutableFile(candidate))
      return fs::absolute(candidate);
    start = end + 1;
  }
  return std::nullopt;
}

namespace {

/// Renders frame k = 0 … @a total − 1 of @a surfaceAt as @a outDir/@a name,
/// one camera framing @a framing, then the video (writeMorphAnimation(),
/// writeSurfaceAnimation()).
AnimationResult writeSequence(const std::function<vtkSmartPointer<vtkPolyData>(int)>& surfaceAt, int total,
                              const std::vector<vtkPolyData*>& framing, const std::string& name,
                              const Eigen::Vector3d& toCamera, const Eigen::Vector3d& viewUp, const fs::path& outDir,
                              const AnimationOptions& options, const seg::ProgressCallback& progress)
{
  const auto [width, height] = animationFrameSize(options);
  if (name.empty() || name.find('/') != std::string::npos)
    throw std::invalid_argument("an animation's name must be a plain file name");
  AnimationResult result;
  result.planName = name;
  Figure base;
  base.width = width;
  base.height = height;
  base.multiSamples = options.multiSamples;
  result.prePost.folder = fs::absolute(outDir) / name;
  result.prePost.width = width;
  result.prePost.height = height;
  // One camera for every frame, so the surface moves and the view does not.
  result.prePost.camera = fitCamera(framing, toCamera, viewUp, base.sceneAspect(), 20.0, 1.05);
  const auto started = std::chrono::steady_clock::now();
  int done = 0;
  renderSurfaces(surfaceAt, total, base, result.prePost, [&](const char* step) {
    seg::reportProgress(progress, 0.95 * done / total, step);
    ++done;
  });
  result.framesRendered = done;
  result.renderSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  encodeVideos({&result.prePost}, options, progress, result);
  seg::reportProgress(progress, 1.0, "Animation written");
  return result;
}

} // namespace

AnimationResult writeMorphAnimation(vtkPolyData* from, vtkPolyData* to, const std::string& name,
                                    const Eigen::Vector3d& toCamera, const Eigen::Vector3d& viewUp,
                                    const fs::path& outDir, int frames, bool andBack, const AnimationOptions& options,
                                    const seg::ProgressCallback& progress)
{
  if (frames < 2)
    throw std::invalid_argument("an animation needs at least 2 frames");
  if (!from || !to || from->GetNumberOfPoints() == 0)
    throw std::invalid_argument("the animation \"" + name + "\" has no surface to show");
  if (from->GetNumberOfPoints() != to->GetNumberOfPoints())
    throw std::invalid_argument("the animation \"" + name + "\": its two surfaces have " +
                                std::to_string(from->GetNumberOfPoints()) + " and " +
                                std::to_string(to->GetNumberOfPoints()) + " points, so one cannot become the other");
  // There and back: the peak not repeated.
  const int total = andBack ? 2 * frames - 2 : frames;
  return writeSequence([&](int k) { return morphFrame(from, to, frames, k); }, total, {from, to}, name, toCamera,
                       viewUp, outDir, options, progress);
}

AnimationResult writeSurfaceAnimation(const std::vector<vtkSmartPointer<vtkPolyData>>& frames, const std::string& name,
                                      const Eigen::Vector3d& toCamera, const Eigen::Vector3d& viewUp,
                                      const fs::path& outDir, const AnimationOptions& options,
                                      const seg::ProgressCallback& progress)
{
  if (frames.size() < 2)
    throw std::invalid_argument("an animation needs at least 2 frames");
  std::vector<vtkPolyData*> surfaces;
  for (const auto& f : frames)
  {
    if (!f || f->GetNumberOfPoints() == 0)
      throw std::invalid_argument("the animation \"" + name + "\" has a frame with no surface to show");
    surfaces.push_back(f);
  }
  return writeSequence([&](int k) { return frames[std::size_t(k)]; }, int(frames.size()), surfaces, name, toCamera,
                       viewUp, outDir, options, progress);
}

} // namespace caps::render
