// Bundle save/load: round trip, stable ids, atomic replacement (including
// saves killed with SIGKILL mid-way), recovery, and load errors that leave
// the scene untouched.

#include <gtest/gtest.h>
#include <signal.h>
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

void fillOldScene(Scene& scene) {
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
vtkSmartPointer<vtkImageData> bigVolume() {
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(256, 256, 256);
  image->AllocateScalars(VTK_FLOAT, 1);
  auto* p = static_cast<float*>(image->GetScalarPointer());
  std::uint32_t x = 12345;
  for (std::size_t i = 0; i < 256u * 256u * 256u; ++i) {
    x = x * 1664525u + 1013904223u;
    p[i] = static_cast<float>(x >> 8) * 1e-3f;
  }
  return image;
}

// Same ids, same small fields, same voxels.
void expectSameScene(const Scene& a, const Scene& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    const Node* na = a.nodes()[i];
    const Node* nb = b.nodes()[i];
    EXPECT_EQ(na->id(), nb->id());
    EXPECT_EQ(na->toJson(), nb->toJson());
    if (na->type() == NodeType::Volume)
      test::expectSameImage(static_cast<const VolumeNode*>(na)->image(), static_cast<const VolumeNode*>(nb)->image());
  }
}

std::vector<fs::path> entriesStartingWith(const fs::path& dir, const std::string& prefix) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().rfind(prefix, 0) == 0) out.push_back(e.path());
  return out;
}

TEST(SceneBundle, RoundTripKeepsIdsAndReportsProgress) {
  TempDir tmp;
  Scene scene;
  fillOldScene(scene);
  scene.add<PlanNode>();
  scene.removeNode("Plan1");  // ids need not be contiguous
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
  EXPECT_FALSE(doc["nodes"][2].contains("file"));  // the plan is JSON only

  Scene loaded;
  int added = 0;
  loaded.addObserver([&](SceneEvent e, const Node&) { added += e == SceneEvent::NodeAdded; });
  loadSceneBundle(loaded, tmp.path() / "head.caps/");  // trailing slash accepted
  EXPECT_EQ(added, 3);
  expectSameScene(scene, loaded);
  EXPECT_TRUE(loaded.node("Plan2"));
  EXPECT_EQ(loaded.add<VolumeNode>()->id(), "Volume2");  // new ids never collide with loaded ones
  EXPECT_TRUE(entriesStartingWith(tmp.path(), ".head.caps").empty());
}

TEST(SceneBundle, SaveOverwritesAndFallbackSwapWorks) {
  TempDir tmp;
  const fs::path bundle = tmp.path() / "head.caps";
  Scene a, b;
  fillOldScene(a);
  b.add<PlanNode>()->setNotes("second");
  saveSceneBundle(a, bundle);
  saveSceneBundle(b, bundle);  // RENAME_EXCHANGE
  Scene loaded;
  loadSceneBundle(loaded, bundle);
  expectSameScene(b, loaded);
  EXPECT_FALSE(fs::exists(bundle / "Volume1.nrrd"));  // the old files went with the old bundle

  detail::setSceneBundleForceRenameFallback(true);
  saveSceneBundle(a, bundle);
  detail::setSceneBundleForceRenameFallback(false);
  loadSceneBundle(loaded, bundle);
  expectSameScene(a, loaded);
  EXPECT_TRUE(entriesStartingWith(tmp.path(), ".head.caps").empty());
}

TEST(SceneBundle, LoadRecoversAsideCopyOfInterruptedFallbackSwap) {
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

TEST(SceneBundle, RefusesToReplaceAFolderThatIsNotABundle) {
  TempDir tmp;
  fs::create_directories(tmp.path() / "thesis.caps");
  std::ofstream(tmp.path() / "thesis.caps" / "chapter1.txt") << "precious";
  Scene a;
  fillOldScene(a);
  EXPECT_THROW(saveSceneBundle(a, tmp.path() / "thesis.caps"), SceneError);
  EXPECT_TRUE(fs::exists(tmp.path() / "thesis.caps" / "chapter1.txt"));
  EXPECT_TRUE(entriesStartingWith(tmp.path(), ".thesis.caps").empty());
}

// (a) A save killed from outside as soon as its temp folder appears.
// (c) The next save succeeds and removes the stale temp folder.
TEST(SceneBundle, SaveKilledMidwayLeavesOldBundleThenNextSaveCleansUp) {
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
  if (child == 0) {
    try {
      saveSceneBundle(big, bundle);
    } catch (...) {
      _exit(3);
    }
    _exit(0);
  }
  bool sawTemp = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < deadline) {
    if (!entriesStartingWith(tmp.path(), ".head.caps.saving-").empty()) {
      sawTemp = true;
      kill(child, SIGKILL);
      break;
    }
    int status;
    if (waitpid(child, &status, WNOHANG) == child) break;  // finished before we saw it
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(sawTemp) << "the save finished before its temp folder was seen";
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGKILL);
  EXPECT_EQ(entriesStartingWith(tmp.path(), ".head.caps.saving-").size(), 1u);  // left behind

  Scene loaded;
  loadSceneBundle(loaded, bundle);
  expectSameScene(old, loaded);

  // (c)
  Scene next;
  next.add<PlanNode>()->setNotes("after the crash");
  saveSceneBundle(next, bundle);
  EXPECT_TRUE(entriesStartingWith(tmp.path(), ".head.caps").empty());
  loadSceneBundle(loaded, bundle);
  expectSameScene(next, loaded);
}

// (b) Deterministic: the saving process dies right after the first node file.
TEST(SceneBundle, SaveDyingAfterFirstNodeFileLeavesOldBundle) {
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
  if (child == 0) {
    try {
      saveSceneBundle(changed, bundle, [](double, const std::string& what) {
        if (what.rfind("Saved ", 0) == 0) raise(SIGKILL);
      });
    } catch (...) {
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

  saveSceneBundle(changed, bundle);  // (c) again
  EXPECT_TRUE(entriesStartingWith(tmp.path(), ".head.caps").empty());
  loadSceneBundle(loaded, bundle);
  expectSameScene(changed, loaded);
}

// Load errors: a clear SceneError naming the file, and the scene untouched.
class BundleLoadErrors : public ::testing::Test {
 protected:
  TempDir tmp;
  fs::path bundle;
  Scene target;
  std::vector<Node*> before;

  void SetUp() override {
    bundle = tmp.path() / "head.caps";
    Scene saved;
    fillOldScene(saved);
    saved.add<SurfaceNode>()->setPolyData(test::makeSurface());
    saveSceneBundle(saved, bundle);
    target.add<PlanNode>()->setNotes("work in progress");
    target.add<VolumeNode>();
    before = target.nodes();
  }

  void editSceneJson(const std::function<void(nlohmann::json&)>& edit) {
    std::ifstream in(bundle / "scene.json");
    auto doc = nlohmann::json::parse(in);
    in.close();
    edit(doc);
    std::ofstream(bundle / "scene.json", std::ios::trunc) << doc.dump();
  }

  void expectLoadError(const std::vector<std::string>& fragments) {
    try {
      loadSceneBundle(target, bundle);
      ADD_FAILURE() << "loading did not fail";
    } catch (const SceneError& e) {
      for (const auto& f : fragments) EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
    }
    EXPECT_EQ(target.nodes(), before);
    EXPECT_EQ(target.nodeAs<PlanNode>("Plan1")->notes(), "work in progress");
  }
};

TEST_F(BundleLoadErrors, NewerFormatVersion) {
  editSceneJson([](nlohmann::json& d) { d["version"] = 7; });
  expectLoadError({"scene.json", "saved by a newer CAPS (format version 7); this build reads up to 1: update CAPS"});
}

TEST_F(BundleLoadErrors, DamagedSceneJson) {
  std::ofstream(bundle / "scene.json", std::ios::trunc) << "{\"format\": \"caps-scene\", \"version\": 1, \"nod";
  expectLoadError({(bundle / "scene.json").string(), "damaged"});
}

TEST_F(BundleLoadErrors, WrongFieldTypeInSceneJson) {
  editSceneJson([](nlohmann::json& d) { d["nodes"][1]["cutPath"] = "oops"; });
  expectLoadError({"scene.json", "damaged", "Plan1"});
}

TEST_F(BundleLoadErrors, MissingSceneJson) {
  fs::remove(bundle / "scene.json");
  expectLoadError({"scene.json", "missing"});
}

TEST_F(BundleLoadErrors, MissingNodeFile) {
  fs::remove(bundle / "RangeMap1.nrrd");
  expectLoadError({"RangeMap1.nrrd", "missing"});
}

TEST_F(BundleLoadErrors, TruncatedNrrd) {
  const auto file = bundle / "Volume1.nrrd";
  fs::resize_file(file, fs::file_size(file) / 2);
  expectLoadError({"Volume1.nrrd", "truncated"});
}

TEST_F(BundleLoadErrors, TruncatedVtu) {
  const auto file = bundle / "Surface1.vtu";
  fs::resize_file(file, fs::file_size(file) - 200);
  expectLoadError({"Surface1.vtu"});
}

TEST_F(BundleLoadErrors, UnknownNodeType) {
  editSceneJson([](nlohmann::json& d) { d["nodes"][1]["type"] = "Hologram"; });
  expectLoadError({"scene.json", "Hologram", "update CAPS"});
}

TEST_F(BundleLoadErrors, MissingBundle) {
  bundle = tmp.path() / "nothere.caps";
  expectLoadError({"nothere.caps", "not found"});
}

}  // namespace
}  // namespace caps
