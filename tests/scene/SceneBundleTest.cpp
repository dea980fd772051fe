// Bundle save/load: round trip, stable ids, atomic replacement (including
// saves killed with SIGKILL mid-way), recovery, and load errors that leave
// the scene untouched.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/fs.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "SceneTestUtils.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/SceneBundle.h"
#include "scene/SceneError.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"

namespace caps {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

void fillOldScene(Scene& scene)
{
  auto* v = scene.add<VolumeNode>();
  v->setName("old CT");
  v->setImage(test::makeImage(VTK_SHORT, 8, 7, 6));
  auto* p = scene.add<PlanNode>();
  p->setProcedure("elliptical-excision");
  p->setCutPath({{-0.2, 0.0}, {0.2, 0.0}});
  auto* r = scene.add<RangeMapNode>();
  r->setValues(Eigen::MatrixXf::Constant(16, 8, 75.0f));
}

// A volume big enough that saving takes a while: 256^3 floats of
// pseudo-random content (compresses poorly, so gzip takes about a second).
vtkSmartPointer<vtkImageData> bigVolume()
{
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(256, 256, 256);
  image->AllocateScalars(VTK_FLOAT, 1);
  auto* p = static_cast<float*>(image->GetScalarPointer());
  std::uint32_t x = 12345;
  for (std::size_t i = 0; i < 256u * 256u * 256u; ++i)
  {
    x = x * 1664525u + 1013904223u;
    p[i] = static_cast<float>(x >> 8) * 1e-3f;
  }
  return image;
}

// Same ids, same small fields, same voxels.
void expectSameScene(const Scene& a, const Scene& b)
{
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    const Node* na = a.nodes()[i];
    const Node* nb = b.nodes()[i];
    EXPECT_EQ(na->id(), nb->id());
    EXPECT_EQ(na->toJson(), nb->toJson());
    if (na->type() == NodeType::Volume)
      test::expectSameImage(static_cast<const VolumeNode*>(na)->image(), static_cast<const VolumeNode*>(nb)->image());
  }
}

std::vector<fs::path> entriesStartingWith(const fs::path& dir, const std::string& prefix)
{
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().rfind(prefix, 0) == 0)
      out.push_back(e.path());
  return out;
}

// What a save may leave beside bundle NAME: nothing but its lock file.
std::vector<fs::path> leftovers(const fs::path& dir, const std::string& name)
{
  std::vector<fs::path> out;
  for (const auto& p : entriesStartingWith(dir, "." + name))
    if (p.filename() != "." + name + ".lock")
      out.push_back(p);
  return out;
}

TEST(SceneBundle, RoundTripKeepsIdsAndReportsProgress)
{
  TempDir tmp;
  Scene scene;
  fillOldScene(scene);
  scene.add<PlanNode>();
  scene.removeNode("Plan1"); // ids need not be contiguous
  std::vector<double> fractions;
  saveSceneBundle(scene, tmp.path() / "head.caps", [&](double f, const std::string&) { fractions.push_back(f); });
  ASSERT_FALSE(fractions.empty());
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);

  std::ifstream in(tmp.path() / "head.caps" / "scene.json");
  const auto doc = nlohmann::json::parse(in);
  EXPECT_EQ(doc["format"], "caps-scene");
  EXPECT_EQ(doc["version"], 1);
  EXPECT_EQ(doc["nodes"][0]["file"], "Volume1.nrrd");
  EXPECT_FALSE(doc["nodes"][2].contains("file")); // the plan is JSON only

  Scene loaded;
  int added = 0;
  loaded.addObserver([&](SceneEvent e, const Node&) { added += e == SceneEvent::NodeAdded; });
  loadSceneBundle(loaded, tmp.path() / "head.caps/"); // trailing slash accepted
  EXPECT_EQ(added, 3);
  expectSameScene(scene, loaded);
  EXPECT_TRUE(loaded.node("Plan2"));
  EXPECT_EQ(loaded.add<VolumeNode>()->id(), "Volume2"); // new ids never collide with loaded ones
  EXPECT_TRUE(leftovers(tmp.path(), "head.caps").empty());
}

TEST(SceneBundle, SaveOverwritesAndFallbackSwapWorks)
{
  TempDir tmp;
  const fs::path bundle = tmp.path() / "head.caps";
  Scene a, b;
  fillOldScene(a);
  b.add<PlanNode>()->setNotes("second");
  saveSceneBundle(a, bundle);
  saveSceneBundle(b, bundle); // RENAME_EXCHANGE
  Scene loaded;
  loadSceneBundle(loaded, bundle);
  expectSameScene(b, loaded);
  EXPECT_FALSE(fs::exists(bundle / "Volume1.nrrd")); // the old files went with the old bundle

  detail::setSceneBundleForceRenameFallback(true);
  saveSceneBundle(a, bundle);
  detail::setSceneBundleForceRenameFallback(false);
  loadSceneBundle(loaded, bundle);
  expectSameScene(a, loaded);
  EXPECT_TRUE(leftovers(tmp.path(), "head.caps").empty());
}

TEST(SceneBundle, LoadRecoversAsideCopyOfInterruptedFallbackSwap)
{
  TempDir tmp;
  const fs::path bundle = tmp.path() / "head.caps";
  Scene a;
  fillOldScene(a);
  saveSceneBundle(a, bundle);
  // State after "rename old aside" when the process died before "rename new in".
  fs::rename(bundle, tmp.path() / ".head.caps.old-999999");
  Scene loaded;
  loadSceneBundle(loaded, bundle);
  expectSameScene(a, loaded);
  EXPECT_TRUE(fs::exists(bundle / "scene.json"));
}

TEST(SceneBundle, RefusesToReplaceAFolderThatIsNotABundle)
{
  TempDir tmp;
  fs::create_directories(tmp.path() / "thesis.caps");
  std::ofstream(tmp.path() / "thesis.caps" / "chapter1.txt") << "precious";
  Scene a;
  fillOldScene(a);
  EXPECT_THROW(saveSceneBundle(a, tmp.path() / "thesis.caps"), SceneError);
  EXPECT_TRUE(fs::exists(tmp.path() / "thesis.caps" / "chapter1.txt"));
  EXPECT_TRUE(leftovers(tmp.path(), "thesis.caps").empty());
}

// (a) A save killed from outside as soon as its temp folder appears.
// (c) The next save succeeds and removes the stale temp folder.
TEST(SceneBundle, SaveKilledMidwayLeavesOldBundleThenNextSaveCleansUp)
{
  TempDir tmp;
  const fs::path bundle = tmp.path() / "head.caps";
  Scene old;
  fillOldScene(old);
  saveSceneBundle(old, bundle);

  Scene big;
  big.add<VolumeNode>()->setImage(bigVolume());
  big.add<PlanNode>()->setNotes("new");
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0)
  {
    try
    {
      saveSceneBundle(big, bundle);
    }
    catch (...)
    {
      _exit(3);
    }
    _exit(0);
  }
  bool sawTemp = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < deadline)
  {
    if (!entriesStartingWith(tmp.path(), ".head.caps.saving-").empty())
    {
      sawTemp = true;
      kill(child, SIGKILL);
      break;
    }
    int status;
    if (waitpid(child, &status, WNOHANG) == child)
      break; // finished before we saw it
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(sawTemp) << "the save finished before its temp folder was seen";
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGKILL);
  EXPECT_EQ(entriesStartingWith(tmp.path(), ".head.caps.saving-").size(), 1u); // left behind

  Scene loaded;
  loadSceneBundle(loaded, bundle);
  expectSameScene(old, loaded);

  // (c)
  Scene next;
  next.add<PlanNode>()->setNotes("after the crash");
  saveSceneBundle(next, bundle);
  EXPECT_TRUE(leftovers(tmp.path(), "head.caps").empty());
  loadSceneBundle(loaded, bundle);
  expectSameScene(next, loaded);
}

// (b) Deterministic: the saving process dies right after the first node file.
TEST(SceneBundle, SaveDyingAfterFirstNodeFileLeavesOldBundle)
{
  TempDir tmp;
  const fs::path bundle = tmp.path() / "head.caps";
  Scene old;
  fillOldScene(old);
  saveSceneBundle(old, bundle);

  Scene changed;
  fillOldScene(changed);
  changed.nodeAs<VolumeNode>("Volume1")->setName("changed CT");
  changed.add<VolumeNode>()->setImage(test::makeImage(VTK_FLOAT));
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0)
  {
    try
    {
      saveSceneBundle(changed, bundle, [](double, const std::string& what) {
        if (what.rfind("Saved ", 0) == 0)
          raise(SIGKILL);
      });
    }
    catch (...)
    {
      _exit(3);
    }
    _exit(0);
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGKILL);
  const auto temps = entriesStartingWith(tmp.path(), ".head.caps.saving-");
  ASSERT_EQ(temps.size(), 1u);
  EXPECT_TRUE(fs::exists(temps[0] / "Volume1.nrrd"));
  EXPECT_FALSE(fs::exists(temps[0] / "scene.json"));

  Scene loaded;
  loadSceneBundle(loaded, bundle);
  expectSameScene(old, loaded);
  EXPECT_EQ(loaded.node("Volume1")->name(), "old CT");

  saveSceneBundle(changed, bundle); // (c) again
  EXPECT_TRUE(leftovers(tmp.path(), "head.caps").empty());
  loadSceneBundle(loaded, bundle);
  expectSameScene(changed, loaded);
}

// Files the user put into the bundle (a report, screenshots) survive saving,
// with either swap; the old scene's node files do not.
TEST(SceneBundle, UserFilesInTheBundleSurviveSaving)
{
  TempDir tmp;
  const fs::path bundle = tmp.path() / "head.caps";
  Scene a, b;
  fillOldScene(a);
  b.add<PlanNode>()->setNotes("second");
  saveSceneBundle(a, bundle);
  std::ofstream(bundle / "report.txt") << "my report";
  fs::create_directories(bundle / "shots");
  std::ofstream(bundle / "shots" / "front.png") << "png";
  for (bool fallback : {false, true})
  {
    detail::setSceneBundleForceRenameFallback(fallback);
    saveSceneBundle(b, bundle);
    detail::setSceneBundleForceRenameFallback(false);
    std::ifstream report(bundle / "report.txt");
    std::string text;
    std::getline(report, text);
    EXPECT_EQ(text, "my report") << "fallback " << fallback;
    EXPECT_TRUE(fs::exists(bundle / "shots" / "front.png")) << "fallback " << fallback;
    EXPECT_FALSE(fs::exists(bundle / "Volume1.nrrd")); // a node file of the old scene
    EXPECT_TRUE(leftovers(tmp.path(), "head.caps").empty());
  }
  Scene loaded;
  loadSceneBundle(loaded, bundle);
  expectSameScene(b, loaded);
}

// Sets or clears the immutable flag (root only, on filesystems that have it).
bool setImmutable(const fs::path& p, bool on)
{
  const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    return false;
  int flags = 0;
  bool ok = ::ioctl(fd, FS_IOC_GETFLAGS, &flags) == 0;
  if (ok)
  {
    flags = on ? (flags | FS_IMMUTABLE_FL) : (flags & ~FS_IMMUTABLE_FL);
    ok = ::ioctl(fd, FS_IOC_SETFLAGS, &flags) == 0;
  }
  ::close(fd);
  return ok;
}

// Makes the previous copy undeletable (its scene.json immutable as root, the
// folder read-only otherwise); false where that cannot be done.
bool pin(const fs::path& dir, bool on)
{
  if (::geteuid() != 0)
  {
    fs::permissions(dir, on ? fs::perms::owner_read | fs::perms::owner_exec : fs::perms::owner_all);
    return true;
  }
  return setImmutable(dir / "scene.json", on);
}

// Once the new bundle is in place the save has succeeded: failing to delete
// the previous copy afterwards must not be reported as a failed save.
TEST(SceneBundle, FailureToDeleteThePreviousCopyIsNoError)
{
  TempDir tmp;
  const fs::path bundle = tmp.path() / "head.caps";
  Scene a, b;
  fillOldScene(a);
  b.add<PlanNode>()->setNotes("second");
  for (bool fallback : {false, true})
  {
    saveSceneBundle(a, bundle);
    if (!pin(bundle, true))
      GTEST_SKIP() << "cannot make a folder undeletable here";
    detail::setSceneBundleForceRenameFallback(fallback);
    EXPECT_NO_THROW(saveSceneBundle(b, bundle)) << "fallback " << fallback;
    detail::setSceneBundleForceRenameFallback(false);
    EXPECT_FALSE(leftovers(tmp.path(), "head.caps").empty()); // the previous copy could not go
    for (const auto& p : leftovers(tmp.path(), "head.caps"))
      pin(p, false);
    Scene loaded;
    loadSceneBundle(loaded, bundle);
    expectSameScene(b, loaded);
  }
  saveSceneBundle(a, bundle); // removes what is left of the previous copies
  EXPECT_TRUE(leftovers(tmp.path(), "head.caps").empty());
}

// Two saves of one process to one bundle: the second waits for the first
// instead of deleting its temporary folder.
TEST(SceneBundle, TwoSavesInOneProcessDoNotClobberEachOther)
{
  TempDir tmp;
  const fs::path bundle = tmp.path() / "head.caps";
  Scene old, big, small;
  fillOldScene(old);
  saveSceneBundle(old, bundle);
  big.add<VolumeNode>()->setImage(bigVolume());
  small.add<PlanNode>()->setNotes("small");
  std::string firstError = "not finished";
  std::thread first([&] {
    try
    {
      saveSceneBundle(big, bundle);
      firstError.clear();
    }
    catch (const std::exception& e)
    {
      firstError = e.what();
    }
  });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (entriesStartingWith(tmp.path(), ".head.caps.saving-").empty() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  EXPECT_NO_THROW(saveSceneBundle(small, bundle));
  first.join();
  EXPECT_EQ(firstError, "");
  Scene loaded;
  loadSceneBundle(loaded, bundle);
  expectSameScene(small, loaded); // the second save came last
  EXPECT_TRUE(leftovers(tmp.path(), "head.caps").empty());
}

// Leftovers with odd suffixes (a huge "pid", another host's save) must not
// make saving fail; with the lock free they are stale and go.
TEST(SceneBundle, OddTempFolderNamesDoNotBreakSaving)
{
  TempDir tmp;
  const fs::path bundle = tmp.path() / "head.caps";
  Scene a;
  fillOldScene(a);
  saveSceneBundle(a, bundle);
  for (const char* n : {".head.caps.saving-99999999999999999999999", ".head.caps.old-99999999999999999999999",
                        ".head.caps.saving-otherhost-4242-0123abcd", ".head.caps.saving-host-99999999999999999999-x"})
    fs::create_directories(tmp.path() / n);
  EXPECT_NO_THROW(saveSceneBundle(a, bundle));
  EXPECT_TRUE(leftovers(tmp.path(), "head.caps").empty());
}

// An observer adding nodes while the loaded ones are announced must not make
// the load fail half-way (it used to take an id the bundle still had to add).
TEST(SceneBundle, LoadIsAllOrNothingWhenObserversAddNodes)
{
  TempDir tmp;
  const fs::path bundle = tmp.path() / "head.caps";
  Scene saved;
  fillOldScene(saved); // Volume1, Plan1, RangeMap1
  saveSceneBundle(saved, bundle);
  Scene target;
  bool added = false;
  target.addObserver([&](SceneEvent e, const Node& n) {
    if (e == SceneEvent::NodeAdded && n.type() == NodeType::Volume && !added)
    {
      added = true;
      target.add<PlanNode>()->setNotes("made by an observer");
    }
  });
  ASSERT_NO_THROW(loadSceneBundle(target, bundle));
  ASSERT_EQ(target.size(), 4u);
  EXPECT_EQ(target.nodeAs<PlanNode>("Plan1")->procedure(), "elliptical-excision");
  EXPECT_TRUE(target.node("RangeMap1"));
  EXPECT_EQ(target.nodes().back()->id(), "Plan2");
}

// Load errors: a clear SceneError naming the file, and the scene untouched.
class BundleLoadErrors : public ::testing::Test
{
protected:
  TempDir tmp;
  fs::path bundle;
  Scene target;
  std::vector<Node*> before;

  void SetUp() override
  {
    bundle = tmp.path() / "head.caps";
    Scene saved;
    fillOldScene(saved);
    saved.add<SurfaceNode>()->setPolyData(test::makeSurface());
    saveSceneBundle(saved, bundle);
    target.add<PlanNode>()->setNotes("work in progress");
    target.add<VolumeNode>();
    before = target.nodes();
  }

  void editSceneJson(const std::function<void(nlohmann::json&)>& edit)
  {
    std::ifstream in(bundle / "scene.json");
    auto doc = nlohmann::json::parse(in);
    in.close();
    edit(doc);
    std::ofstream(bundle / "scene.json", std::ios::trunc) << doc.dump();
  }

  void expectLoadError(const std::vector<std::string>& fragments)
  {
    try
    {
      loadSceneBundle(target, bundle);
      ADD_FAILURE() << "loading did not fail";
    }
    catch (const SceneError& e)
    {
      for (const auto& f : fragments)
        EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
    }
    EXPECT_EQ(target.nodes(), before);
    EXPECT_EQ(target.nodeAs<PlanNode>("Plan1")->notes(), "work in progress");
  }
};

TEST_F(BundleLoadErrors, NewerFormatVersion)
{
  editSceneJson([](nlohmann::json& d) { d["version"] = 7; });
  expectLoadError({"scene.json", "saved by a newer CAPS (format version 7); this build reads up to 1: update CAPS"});
}

TEST_F(BundleLoadErrors, DamagedSceneJson)
{
  std::ofstream(bundle / "scene.json", std::ios::trunc) << "{\"format\": \"caps-scene\", \"version\": 1, \"nod";
  expectLoadError({(bundle / "scene.json").string(), "damaged"});
}

TEST_F(BundleLoadErrors, WrongFieldTypeInSceneJson)
{
  editSceneJson([](nlohmann::json& d) { d["nodes"][1]["cutPath"] = "oops"; });
  expectLoadError({"scene.json", "damaged", "Plan1"});
}

TEST_F(BundleLoadErrors, MissingSceneJson)
{
  fs::remove(bundle / "scene.json");
  expectLoadError({"scene.json", "missing"});
}

TEST_F(BundleLoadErrors, MissingNodeFile)
{
  fs::remove(bundle / "RangeMap1.nrrd");
  expectLoadError({"RangeMap1.nrrd", "missing"});
}

TEST_F(BundleLoadErrors, TruncatedNrrd)
{
  const auto file = bundle / "Volume1.nrrd";
  fs::resize_file(file, fs::file_size(file) / 2);
  expectLoadError({"Volume1.nrrd", "truncated"});
}

TEST_F(BundleLoadErrors, TruncatedVtu)
{
  const auto file = bundle / "Surface1.vtu";
  fs::resize_file(file, fs::file_size(file) - 200);
  expectLoadError({"Surface1.vtu"});
}

TEST_F(BundleLoadErrors, UnknownNodeType)
{
  editSceneJson([](nlohmann::json& d) { d["nodes"][1]["type"] = "Hologram"; });
  expectLoadError({"scene.json", "Hologram", "update CAPS"});
}

TEST_F(BundleLoadErrors, FormatOfTheWrongKind)
{
  editSceneJson([](nlohmann::json& d) { d["format"] = 5; });
  expectLoadError({"scene.json"});
}

TEST_F(BundleLoadErrors, NodeFileOfTheWrongKind)
{
  editSceneJson([](nlohmann::json& d) { d["nodes"][0]["file"] = nullptr; });
  expectLoadError({"scene.json", "damaged", "Volume1"});
  editSceneJson([](nlohmann::json& d) { d["nodes"][0]["file"] = 5; });
  expectLoadError({"scene.json", "damaged", "Volume1"});
}

TEST_F(BundleLoadErrors, NodeFileOutsideTheBundle)
{
  const std::string absolute = (bundle / "Volume1.nrrd").string();
  editSceneJson([](nlohmann::json& d) { d["nodes"][0]["file"] = "../head.caps/Volume1.nrrd"; });
  expectLoadError({"scene.json", "not a file of the bundle"});
  editSceneJson([&](nlohmann::json& d) { d["nodes"][0]["file"] = absolute; });
  expectLoadError({"scene.json", "not a file of the bundle"});
  editSceneJson([&](nlohmann::json& d) { d["nodes"][0]["file"] = ".."; });
  expectLoadError({"scene.json", "not a file of the bundle"});
}

// Ids name the node files of the next save: "../x" would write outside it.
TEST_F(BundleLoadErrors, NodeIdThatIsNotAFileName)
{
  editSceneJson([](nlohmann::json& d) { d["nodes"][1]["id"] = "../x"; });
  expectLoadError({"scene.json", "../x"});
}

TEST_F(BundleLoadErrors, MissingBundle)
{
  bundle = tmp.path() / "nothere.caps";
  expectLoadError({"nothere.caps", "not found"});
}

} // namespace
} // namespace caps
