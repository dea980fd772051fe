// Animation export on the sample CT's demo scene: the pre →
// post frames start at a render of the skin before and end at one of the
// skin after from the same camera, and move away from the start step by
// step; the turntable starts at the face and is at the back half way round;
// sizes are even; `caps animate` writes the frames and, without ffmpeg, says
// how to make the videos; with a real ffmpeg (scripts/setup installs it) the MP4s
// are H.264 with one video frame per PNG, each decoded frame close to its PNG.

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "TestPaths.h"
#include "DemoScene.h"
#include "app/RunProcess.h"
#include "modules/report/PlanAnimation.h"
#include "modules/report/PlanFigures.h"
#include "render/Figure.h"
#include "scene/Scene.h"
#include "scene/SceneBundle.h"
#include "scene/SurfaceNode.h"
#include "segmentation/Progress.h"

namespace fs = std::filesystem;
using caps::test::quoted;
using caps::test::runCaps;
namespace report = caps::report;
namespace render = caps::render;

namespace {

const fs::path& demoFolder()
{
  return caps::test::reportDemoFolder();
}

fs::path sceneBundle()
{
  return demoFolder() / "sample.caps";
}

/// The demo scene, loaded once.
caps::Scene& demoScene()
{
  static caps::Scene* scene = [] {
    auto* s = new caps::Scene;
    caps::loadSceneBundle(*s, sceneBundle());
    return s;
  }();
  return *scene;
}

render::AnimationOptions smallOptions()
{
  render::AnimationOptions options;
  options.width = 320;
  options.height = 240;
  options.prePostFrames = 7;
  options.turntableFrames = 12;
  options.video = false;
  return options;
}

struct Animated
{
  fs::path out;
  render::AnimationResult result;
  double seconds = 0.0;
};

/// The first plan's animations at 320 × 240, made once.
const Animated& animated()
{
  static const Animated a = [] {
    Animated made;
    // One folder per test process: ctest runs these tests side by side.
    made.out = fs::temp_directory_path() / "caps-tests" / ("PlanAnimation.frames-" + std::to_string(getpid()));
    fs::remove_all(made.out);
    caps::Scene& scene = demoScene();
    const auto start = std::chrono::steady_clock::now();
    made.result = report::writePlanAnimation(scene, "", made.out, smallOptions());
    made.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return made;
  }();
  return a;
}

vtkSmartPointer<vtkImageData> readPng(const fs::path& file)
{
  auto reader = vtkSmartPointer<vtkPNGReader>::New();
  reader->SetFileName(file.c_str());
  reader->Update();
  vtkSmartPointer<vtkImageData> image = reader->GetOutput();
  return image;
}

std::string frameName(int k)
{
  std::string name = "frame-";
  const std::string digits = std::to_string(k);
  name += std::string(4 - digits.size(), '0');
  name += digits;
  name += ".png";
  return name;
}

/// Mean absolute difference over all pixels and the RGB channels (0–255).
double meanDifference(vtkImageData* a, vtkImageData* b)
{
  int da[3], db[3];
  a->GetDimensions(da);
  b->GetDimensions(db);
  EXPECT_EQ(da[0], db[0]);
  EXPECT_EQ(da[1], db[1]);
  vtkDataArray* pa = a->GetPointData()->GetScalars();
  vtkDataArray* pb = b->GetPointData()->GetScalars();
  const vtkIdType n = std::min(pa->GetNumberOfTuples(), pb->GetNumberOfTuples());
  double sum = 0.0;
  for (vtkIdType i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c)
      sum += std::abs(pa->GetComponent(i, c) - pb->GetComponent(i, c));
  return sum / (3.0 * double(n));
}

/// Pixels close to the incision's violet (surgical marker, 0.42, 0, 0.55).
int violetPixels(vtkImageData* image)
{
  vtkDataArray* p = image->GetPointData()->GetScalars();
  int count = 0;
  for (vtkIdType i = 0; i < p->GetNumberOfTuples(); ++i)
  {
    const double r = p->GetComponent(i, 0), g = p->GetComponent(i, 1), b = p->GetComponent(i, 2);
    count += g < 60.0 && b > 90.0 && r > 50.0 && r < b;
  }
  return count;
}

vtkPolyData* surfaceNamed(const caps::Scene& scene, const std::string& name)
{
  for (caps::Node* n : scene.nodesOfType(caps::NodeType::Surface))
    if (n->name() == name)
      return static_cast<const caps::SurfaceNode*>(n)->polyData();
  return nullptr;
}

/// The surface alone, coloured by skin_shade, from @a camera, as writePlanAnimation renders a frame.
vtkSmartPointer<vtkImageData> renderAlone(vtkPolyData* surface, const render::Camera& camera)
{
  const render::AnimationOptions options = smallOptions();
  render::Figure figure;
  figure.width = options.width;
  figure.height = options.height;
  figure.multiSamples = options.multiSamples;
  figure.camera = camera;
  figure.surfaces.push_back(render::SurfaceLayer::pointColours(surface, "skin_shade"));
  return render::renderFigure(figure);
}

} // namespace

TEST(PlanAnimation, TheSequencesHaveTheirFrameCountsAndEvenSizes)
{
  const Animated& a = animated();
  std::cout << "rendered " << a.result.framesRendered << " frames of 320x240 in " << a.result.renderSeconds
            << " s: " << a.result.framesRendered / a.result.renderSeconds << " frames/s (" << a.seconds
            << " s in all)\n";
  EXPECT_EQ(a.result.planName, "Z-plasty 1") << "the scene's first plan";
  EXPECT_EQ(a.result.prePost.frames, 7);
  ASSERT_TRUE(a.result.turntable);
  EXPECT_EQ(a.result.turntable->frames, 12);
  EXPECT_EQ(a.result.framesRendered, 19);
  EXPECT_TRUE(a.result.videoMessage.empty()) << "no video asked for";
  for (const auto& [folder, count] : {std::pair{a.out / "pre-post", 7}, std::pair{a.out / "turntable", 12}})
  {
    int files = 0;
    for (const auto& entry : fs::directory_iterator(folder))
    {
      ++files;
      int d[3];
      readPng(entry.path())->GetDimensions(d);
      EXPECT_EQ(d[0], 320) << entry.path();
      EXPECT_EQ(d[1], 240) << entry.path();
    }
    EXPECT_EQ(files, count) << folder;
    EXPECT_TRUE(fs::exists(folder / frameName(count - 1)));
  }

  // Odd sizes are made even (yuv420p needs it); a second, shorter run
  // replaces the earlier frames rather than leaving them for ffmpeg to find.
  const fs::path out = caps::test::scratchFolder() / "odd";
  render::AnimationOptions odd = smallOptions();
  odd.width = 161;
  odd.height = 121;
  odd.prePostFrames = 3;
  odd.turntable = false;
  const auto first = report::writePlanAnimation(demoScene(), "Z-plasty 1", out, odd);
  EXPECT_EQ(first.prePost.width, 160);
  EXPECT_EQ(first.prePost.height, 120);
  EXPECT_FALSE(first.turntable);
  odd.prePostFrames = 2;
  report::writePlanAnimation(demoScene(), "Z-plasty 1", out, odd);
  int d[3];
  readPng(out / "pre-post" / frameName(0))->GetDimensions(d);
  EXPECT_EQ(d[0], 160);
  EXPECT_EQ(d[1], 120);
  EXPECT_TRUE(fs::exists(out / "pre-post" / frameName(1)));
  EXPECT_FALSE(fs::exists(out / "pre-post" / frameName(2))) << "a frame of the earlier, longer run is left";
}

TEST(PlanAnimation, PrePostGoesFromTheSkinBeforeToTheSkinAfter)
{
  const Animated& a = animated();
  caps::Scene& scene = demoScene();
  vtkPolyData* before = surfaceNamed(scene, "Z-plasty 1 skin before");
  vtkPolyData* after = surfaceNamed(scene, "Z-plasty 1 skin after");
  ASSERT_TRUE(before && after);
  const auto beforeAlone = renderAlone(before, a.result.prePost.camera);
  const auto afterAlone = renderAlone(after, a.result.prePost.camera);
  const int n = a.result.prePost.frames;
  std::vector<vtkSmartPointer<vtkImageData>> frames;
  for (int k = 0; k < n; ++k)
    frames.push_back(readPng(a.out / "pre-post" / frameName(k)));

  EXPECT_GT(render::pixelVariance(frames[0]), 100.0) << "the first frame is blank";
  EXPECT_GT(render::occupiedFraction(frames[0]), 0.3) << "the skin should fill the frame";
  const double beforeChange = meanDifference(beforeAlone, afterAlone);
  EXPECT_GT(beforeChange, 2.0) << "the operation should show";
  EXPECT_LT(meanDifference(frames.front(), beforeAlone), 0.05 * beforeChange);
  EXPECT_LT(meanDifference(frames.back(), afterAlone), 0.05 * beforeChange);
  // The demo's skin carries its pre-tension: the middle stage is the wound
  // gaping before it is sutured, reached at the middle frame (n - 1 even).
  vtkPolyData* gaping = surfaceNamed(scene, "Z-plasty 1 skin gaping");
  ASSERT_TRUE(gaping) << "the demo's prediction should have the wound gaping under the skin's pre-tension";
  ASSERT_EQ((n - 1) % 2, 0) << "the gaping stage falls between frames";
  const auto gapingAlone = renderAlone(gaping, a.result.prePost.camera);
  const int middle = (n - 1) / 2;
  EXPECT_LT(meanDifference(frames[middle], gapingAlone), 0.05 * beforeChange);
  EXPECT_GT(meanDifference(gapingAlone, beforeAlone), 0.01 * beforeChange) << "the wound should be seen to open";
  // Half way through the closing, the skin is neither as cut nor as closed.
  const int closing = (middle + n - 1) / 2;
  EXPECT_GT(meanDifference(frames[closing], beforeAlone), 0.2 * beforeChange);
  EXPECT_GT(meanDifference(frames[closing], afterAlone), 0.2 * beforeChange);
  // Away from the start step by step.
  std::vector<double> fromStart;
  for (int k = 0; k < n; ++k)
    fromStart.push_back(meanDifference(frames[k], frames[0]));
  std::cout << "mean pixel difference before/after alone " << beforeChange << "; first frame/before alone "
            << meanDifference(frames.front(), beforeAlone) << "; last frame/after alone "
            << meanDifference(frames.back(), afterAlone) << "; frames from the first:";
  for (double d : fromStart)
    std::cout << " " << d;
  std::cout << "\n";
  for (int k = 1; k < n; ++k)
    EXPECT_GT(fromStart[k], fromStart[k - 1]) << "frame " << k << " is no further from the first than frame " << k - 1;

  // Different point counts get a clear message.
  auto fewer = vtkSmartPointer<vtkPolyData>::New();
  fewer->DeepCopy(after);
  fewer->GetPoints()->SetNumberOfPoints(after->GetNumberOfPoints() - 1);
  try
  {
    render::blendSurfaces(before, fewer, 0.5);
    ADD_FAILURE() << "blended surfaces of different point counts";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("points"), std::string::npos) << e.what();
  }
}

TEST(PlanAnimation, TheTurntableStartsAtTheFaceAndGoesRoundTheHead)
{
  const Animated& a = animated();
  const int m = a.result.turntable->frames;
  const auto front = readPng(a.out / "turntable" / frameName(0));
  const auto back = readPng(a.out / "turntable" / frameName(m / 2));
  const auto quarter = readPng(a.out / "turntable" / frameName(m / 4));
  EXPECT_GT(render::pixelVariance(front), 100.0) << "the front frame is blank";
  const double occupied = render::occupiedFraction(front);
  EXPECT_GT(occupied, 0.15) << "the head should fill much of the frame";
  EXPECT_LT(occupied, 0.95);
  EXPECT_GT(meanDifference(front, back), 5.0) << "the front and the back look the same";
  EXPECT_GT(meanDifference(front, quarter), 5.0);
  std::cout << "turntable: occupied " << occupied << " at the front; front/back difference "
            << meanDifference(front, back) << "; incision pixels front " << violetPixels(front) << ", back "
            << violetPixels(back) << "\n";
  // The incision is on the face: drawn from the front, hidden by the head from behind.
  EXPECT_GT(violetPixels(front), 20) << "no incision on the front view";
  EXPECT_LT(violetPixels(back), violetPixels(front) / 10 + 1);
  // The camera keeps its distance: the head occupies about as much all the way round.
  for (int k = 0; k < m; ++k)
  {
    const auto frame = readPng(a.out / "turntable" / frameName(k));
    EXPECT_GT(render::occupiedFraction(frame), 0.5 * occupied) << k;
    EXPECT_LT(render::occupiedFraction(frame), 2.0 * occupied) << k;
  }
}

TEST(PlanAnimation, TheCommandWritesTheFramesAndSaysHowToMakeTheVideosWithoutFfmpeg)
{
  const fs::path out = caps::test::scratchFolder() / "animation";
  const std::string missing = (out / "no-such-ffmpeg").string();
  const auto r = caps::test::runProcess("CAPS_FFMPEG=" + quoted(missing) + " " + quoted(CAPS_EXECUTABLE) + " animate " +
                                        quoted(sceneBundle().string()) + " --out " + quoted(out.string()) +
                                        " --frames 3 --turntable-frames 4 --size 161x120");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_NE(r.output.find("Debian package ffmpeg"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(missing), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("-pix_fmt yuv420p"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("pre-post.mp4"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("turntable.mp4"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frames/s"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(out / "pre-post" / frameName(2)));
  EXPECT_TRUE(fs::exists(out / "turntable" / frameName(3)));
  EXPECT_FALSE(fs::exists(out / "pre-post.mp4"));
  int d[3];
  readPng(out / "turntable" / frameName(0))->GetDimensions(d);
  EXPECT_EQ(d[0], 160);
  EXPECT_EQ(d[1], 120);

  // Usage and scene problems.
  auto bad = runCaps("animate " + quoted(sceneBundle().string()));
  EXPECT_EQ(bad.exitCode, 2) << bad.output;
  EXPECT_NE(bad.output.find("--out DIR missing"), std::string::npos) << bad.output;
  bad = runCaps("animate " + quoted(sceneBundle().string()) + " --out " + quoted(out.string()) + " --frames 1");
  EXPECT_EQ(bad.exitCode, 2) << bad.output;
  bad = runCaps("animate " + quoted((out / "missing.caps").string()) + " --out " + quoted(out.string()));
  EXPECT_EQ(bad.exitCode, 1) << bad.output;
  EXPECT_NE(bad.output.find("there is no scene at"), std::string::npos) << bad.output;
  bad = runCaps("animate " + quoted(sceneBundle().string()) + " --out " + quoted(out.string()) +
                " --plan 'no such plan' --no-video");
  EXPECT_EQ(bad.exitCode, 1) << bad.output;
  EXPECT_NE(bad.output.find("Z-plasty 1"), std::string::npos) << "lists the plans there are\n" << bad.output;
}

TEST(PlanAnimation, WithFfmpegTheVideosAreWritten)
{
  unsetenv("CAPS_FFMPEG");
  if (!render::findFfmpeg())
    GTEST_SKIP() << "no ffmpeg on PATH (Debian package ffmpeg): the MP4 export is not tested here";
  const fs::path out = caps::test::scratchFolder() / "animation";
  const auto r = runCaps("animate " + quoted(sceneBundle().string()) + " --out " + quoted(out.string()) +
                         " --plan 'Elliptical excision 2' --frames 4 --turntable-frames 6 --size 161x121");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  // What the videos hold, read back by ffprobe and decoded by ffmpeg itself:
  // H.264 in yuv420p at the frames' size, one video frame per PNG frame, and
  // each decoded frame close to its PNG (lossy, so not equal).
  const struct
  {
    const char* video;
    const char* frames;
    int count;
  } videos[] = {{"pre-post.mp4", "pre-post", 4}, {"turntable.mp4", "turntable", 6}};
  for (const auto& v : videos)
  {
    const fs::path video = out / v.video;
    ASSERT_TRUE(fs::exists(video)) << v.video << "\n" << r.output;
    EXPECT_NE(r.output.find(v.video), std::string::npos) << r.output;
    const auto probe =
      caps::test::runProcess("ffprobe -v error -select_streams v:0 -count_frames -show_entries "
                             "stream=codec_name,pix_fmt,width,height,nb_read_frames -of default=noprint_wrappers=1 " +
                             quoted(video.string()));
    ASSERT_EQ(probe.exitCode, 0) << probe.output;
    std::string frameCount = "nb_read_frames=";
    frameCount += std::to_string(v.count);
    for (const std::string& expected :
         std::vector<std::string>{"codec_name=h264", "pix_fmt=yuv420p", "width=160", "height=120", frameCount})
      EXPECT_NE(probe.output.find(expected), std::string::npos) << expected << " in\n" << probe.output;
    const fs::path decoded = out / (std::string(v.frames) + "-decoded");
    fs::create_directories(decoded);
    const auto decode = caps::test::runProcess("ffmpeg -v error -y -i " + quoted(video.string()) + " " +
                                               quoted((decoded / "frame-%04d.png").string()));
    ASSERT_EQ(decode.exitCode, 0) << decode.output;
    for (int k = 0; k < v.count; ++k)
    {
      // ffmpeg numbers its output from 1, our frames from 0.
      const auto original = readPng(out / v.frames / frameName(k));
      const auto back = readPng(decoded / frameName(k + 1));
      const double loss = meanDifference(original, back);
      std::cout << "[" << v.video << " frame " << k << "] decoded differs from its PNG by " << loss << "/255\n";
      EXPECT_LT(loss, 6.0) << v.video << " frame " << k;
      if (k > 0) // and it is that frame, not a neighbour: the sequence moves more than the codec loses
      {
        EXPECT_LT(meanDifference(original, back), meanDifference(readPng(out / v.frames / frameName(k - 1)), back))
          << v.video << " frame " << k;
      }
    }
  }
}

TEST(PlanAnimation, TheVideoCommandRunsAsPrintedAndItsFailureIsReported)
{
  // A stand-in for ffmpeg that keeps its arguments and writes the file named last.
  const fs::path folder = caps::test::scratchFolder();
  const fs::path fake = folder / "fake-ffmpeg";
  {
    std::ofstream script(fake);
    script << "#!/bin/sh\necho \"$@\" >> " << quoted((folder / "arguments.txt").string())
           << "\nfor last; do :; done\necho video > \"$last\"\n";
  }
  fs::permissions(fake, fs::perms::owner_all);
  const fs::path out = folder / "animation";
  auto r = caps::test::runProcess("CAPS_FFMPEG=" + quoted(fake.string()) + " " + quoted(CAPS_EXECUTABLE) + " animate " +
                                  quoted(sceneBundle().string()) + " --out " + quoted(out.string()) +
                                  " --frames 2 --turntable-frames 2 --size 64x48 --fps 12");
  ASSERT_EQ(r.exitCode, 0) << r.output;
  EXPECT_EQ(r.output.find("no MP4 written"), std::string::npos) << r.output;
  for (const char* video : {"pre-post.mp4", "turntable.mp4"})
  {
    EXPECT_TRUE(fs::exists(out / video)) << video;
    EXPECT_NE(r.output.find((out / video).string()), std::string::npos) << r.output;
  }
  std::ifstream in(folder / "arguments.txt");
  const std::string arguments{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  for (const char* expected : {"-y -loglevel error -framerate 12 -i", "pre-post/frame-%04d.png",
                               "turntable/frame-%04d.png", "-c:v libx264 -pix_fmt yuv420p"})
    EXPECT_NE(arguments.find(expected), std::string::npos) << expected << " in\n" << arguments;

  // An ffmpeg that fails: exit 1 with its message and the command; the frames stay.
  {
    std::ofstream script(fake);
    script << "#!/bin/sh\necho 'Unknown encoder libx264' >&2\nexit 1\n";
  }
  r = caps::test::runProcess("CAPS_FFMPEG=" + quoted(fake.string()) + " " + quoted(CAPS_EXECUTABLE) + " animate " +
                             quoted(sceneBundle().string()) + " --out " + quoted(out.string()) +
                             " --frames 2 --no-turntable --size 64x48");
  EXPECT_EQ(r.exitCode, 1) << r.output;
  EXPECT_NE(r.output.find("Unknown encoder libx264"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("-pix_fmt yuv420p"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(out / "pre-post" / frameName(1)));
  EXPECT_FALSE(fs::exists(out / "pre-post.mp4")) << "the earlier run's video no longer matches the frames";
}

TEST(PlanAnimation, ProgressIsReportedAndCancelStops)
{
  const fs::path out = caps::test::scratchFolder() / "cancelled";
  render::AnimationOptions options = smallOptions();
  options.width = 64;
  options.height = 48;
  options.prePostFrames = 4;
  options.turntableFrames = 4;
  std::vector<double> fractions;
  const caps::TaskProgress progress = [&](double fraction, const std::string&) {
    fractions.push_back(fraction);
    return fractions.size() < 3; // stop before the third frame
  };
  EXPECT_THROW(report::writePlanAnimation(demoScene(), "", out, options, progress), caps::seg::Cancelled);
  EXPECT_EQ(fractions.size(), 3u);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_TRUE(fs::exists(out / "pre-post" / frameName(1)));
  EXPECT_FALSE(fs::exists(out / "pre-post" / frameName(2)));
}

// A morph there and back (an expression played and released): the
// frames go out to the peak and return through the same shapes, so frame k
// and frame 2(n−1)−k are the same picture; the peak is the second surface.
TEST(PlanAnimation, AMorphThereAndBackReturnsThroughTheSameFrames)
{
  caps::Scene& scene = demoScene();
  vtkPolyData* before = report::surfaceNamed(scene, "Z-plasty 1 skin before");
  vtkPolyData* after = report::surfaceNamed(scene, "Z-plasty 1 skin after");
  ASSERT_TRUE(before && after);
  const fs::path out = caps::test::scratchFolder();
  render::AnimationOptions options = smallOptions();
  const Eigen::Vector3d toCamera(0.0, -1.0, 0.0), up(0.0, 0.0, 1.0);
  const auto r = render::writeMorphAnimation(before, after, "there-and-back", toCamera, up, out, 4, true, options);
  EXPECT_EQ(r.prePost.frames, 6);
  EXPECT_EQ(r.framesRendered, 6);
  const fs::path folder = out / "there-and-back";
  EXPECT_FALSE(fs::exists(folder / frameName(6)));
  for (int k = 1; k <= 2; ++k)
    EXPECT_EQ(meanDifference(readPng(folder / frameName(k)), readPng(folder / frameName(6 - k))), 0.0) << k;
  EXPECT_GT(meanDifference(readPng(folder / frameName(0)), readPng(folder / frameName(3))), 0.05);
  // The peak is the after surface: the same as a one-way morph's last frame.
  render::writeMorphAnimation(before, after, "one-way", toCamera, up, out, 4, false, options);
  EXPECT_EQ(meanDifference(readPng(folder / frameName(3)), readPng(out / "one-way" / frameName(3))), 0.0);
  EXPECT_THROW(render::writeMorphAnimation(before, after, "a/b", toCamera, up, out, 4, true, options),
               std::invalid_argument);
}

TEST(PlanAnimation, GivenFramesAreRenderedInTheirOrderAsTheMorphRendersThem)
{
  caps::Scene& scene = demoScene();
  vtkPolyData* before = report::surfaceNamed(scene, "Z-plasty 1 skin before");
  vtkPolyData* after = report::surfaceNamed(scene, "Z-plasty 1 skin after");
  ASSERT_TRUE(before && after);
  const fs::path out = caps::test::scratchFolder();
  const render::AnimationOptions options = smallOptions();
  const Eigen::Vector3d toCamera(0.0, -1.0, 0.0), up(0.0, 0.0, 1.0);
  render::writeMorphAnimation(before, after, "morph", toCamera, up, out, 4, false, options);
  // The morph's own frames given back to front: the same pictures, reversed
  // (the camera framing all four frames is the morph's, which frames the ends).
  std::vector<vtkSmartPointer<vtkPolyData>> frames;
  for (int k = 3; k >= 0; --k)
    frames.push_back(render::blendSurfaces(before, after, k / 3.0));
  const auto r = render::writeSurfaceAnimation(frames, "given", toCamera, up, out, options);
  EXPECT_EQ(r.prePost.frames, 4);
  EXPECT_FALSE(fs::exists(out / "given" / frameName(4)));
  for (int k = 0; k < 4; ++k)
    EXPECT_EQ(meanDifference(readPng(out / "given" / frameName(k)), readPng(out / "morph" / frameName(3 - k))), 0.0)
      << k;
  EXPECT_THROW(render::writeSurfaceAnimation({frames.front()}, "one", toCamera, up, out, options),
               std::invalid_argument);
  EXPECT_THROW(render::writeSurfaceAnimation({frames.front(), nullptr}, "hole", toCamera, up, out, options),
               std::invalid_argument);
}
