#include "scene/SceneBundle.h"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "scene/Node.h"
#include "scene/Scene.h"
#include "scene/SceneError.h"

namespace caps {

namespace fs = std::filesystem;

namespace {

std::atomic<bool> gForceRenameFallback{false};

const char* kSceneFile = "scene.json";

struct BundlePaths {
  fs::path bundle;  // .../NAME.caps
  fs::path parent;
  std::string name;  // NAME.caps
  std::string savingPrefix() const { return "." + name + ".saving-"; }
  std::string asidePrefix() const { return "." + name + ".old-"; }
};

BundlePaths bundlePaths(const fs::path& dir) {
  fs::path p = dir.lexically_normal();
  if (p.filename().empty()) p = p.parent_path();  // "x.caps/" -> "x.caps"
  if (p.empty() || p.filename() == "." || p.filename() == "..")
    throw SceneError("'" + dir.string() + "' is not a valid scene bundle name: use a folder name like head.caps");
  BundlePaths b;
  b.bundle = p;
  b.parent = p.has_parent_path() ? p.parent_path() : fs::path(".");
  b.name = p.filename().string();
  return b;
}

std::string errnoText() { return std::strerror(errno); }

// Flushes a file or folder to disk, so the rename that publishes it never
// exposes data still in the page cache after a power cut.
void fsyncPath(const fs::path& p, bool directory) {
  const int fd = ::open(p.c_str(), (directory ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) throw SceneError("cannot open " + p.string() + " to flush it to disk: " + errnoText());
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  // Some filesystems cannot fsync a folder (EINVAL); file data is what matters.
  if (rc != 0 && !(directory && (err == EINVAL || err == EROFS)))
    throw SceneError("cannot flush " + p.string() + " to disk: " + std::strerror(err) + "; check the disk");
}

bool processAlive(long pid) {
  if (pid <= 0) return false;
  if (pid == static_cast<long>(::getpid())) return false;  // ours, left by an earlier failed save
  return ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM;
}

// PID suffix of ".NAME.caps.saving-PID"; -1 when not of that form.
long pidSuffix(const std::string& entry, const std::string& prefix) {
  if (entry.rfind(prefix, 0) != 0) return -1;
  const std::string digits = entry.substr(prefix.size());
  if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) return -1;
  return std::stol(digits);
}

// Brings back the previous bundle when a fallback swap was interrupted
// between "rename old aside" and "rename new in".
void recoverAside(const BundlePaths& b) {
  std::error_code ec;
  if (fs::exists(b.bundle, ec) || !fs::is_directory(b.parent, ec)) return;
  for (const auto& entry : fs::directory_iterator(b.parent, ec)) {
    const std::string n = entry.path().filename().string();
    const long pid = pidSuffix(n, b.asidePrefix());
    // A live owner is between its two renames right now: leave it alone.
    if (pid >= 0 && !processAlive(pid) && fs::exists(entry.path() / kSceneFile)) {
      if (::rename(entry.path().c_str(), b.bundle.c_str()) != 0)
        throw SceneError("cannot recover the previous copy " + entry.path().string() + " of " + b.bundle.string() +
                         ": " + errnoText() + "; rename it to " + b.name + " by hand");
      return;
    }
  }
}

// Removes temp folders of saves whose process is gone, and aside copies that
// are no longer needed because the bundle exists.
void removeStale(const BundlePaths& b) {
  std::error_code ec;
  const bool haveBundle = fs::exists(b.bundle, ec);
  for (const auto& entry : fs::directory_iterator(b.parent, ec)) {
    const std::string n = entry.path().filename().string();
    const long saving = pidSuffix(n, b.savingPrefix());
    const long aside = pidSuffix(n, b.asidePrefix());
    if ((saving >= 0 && !processAlive(saving)) || (aside >= 0 && haveBundle && !processAlive(aside))) {
      std::error_code rmEc;
      fs::remove_all(entry.path(), rmEc);
    }
  }
}

int renameExchange(const fs::path& a, const fs::path& b) {
#ifdef RENAME_EXCHANGE
  return ::renameat2(AT_FDCWD, a.c_str(), AT_FDCWD, b.c_str(), RENAME_EXCHANGE);
#elif defined(SYS_renameat2)
  return static_cast<int>(::syscall(SYS_renameat2, AT_FDCWD, a.c_str(), AT_FDCWD, b.c_str(), 2 /*RENAME_EXCHANGE*/));
#else
  errno = ENOSYS;
  return -1;
#endif
}

void writeAll(const Scene& scene, const fs::path& tmp, const BundleProgress& progress) {
  nlohmann::json doc;
  doc["format"] = "caps-scene";
  doc["version"] = kSceneBundleFormatVersion;
  doc["nodes"] = nlohmann::json::array();
  const auto nodes = scene.nodes();
  std::size_t bulky = 0;
  for (const Node* n : nodes)
    if (!n->bulkFileExtension().empty()) ++bulky;
  std::size_t done = 0;
  const double steps = static_cast<double>(bulky + 1);
  for (const Node* n : nodes) {
    nlohmann::json j = n->toJson();
    const std::string ext = n->bulkFileExtension();
    if (!ext.empty()) {
      const std::string file = n->id() + ext;
      if (progress) progress(static_cast<double>(done) / steps, "Saving " + n->name() + " (" + file + ")");
      n->writeBulk(tmp / file);
      fsyncPath(tmp / file, false);
      j["file"] = file;
      ++done;
      if (progress) progress(static_cast<double>(done) / steps, "Saved " + file);
    }
    doc["nodes"].push_back(std::move(j));
  }
  const fs::path sceneFile = tmp / kSceneFile;
  {
    std::ofstream out(sceneFile, std::ios::trunc);
    out << doc.dump(2) << '\n';
    out.close();
    if (!out) throw SceneError("could not write " + sceneFile.string() + ": check free disk space and permissions");
  }
  fsyncPath(sceneFile, false);
  fsyncPath(tmp, true);
}

}  // namespace

namespace detail {
void setSceneBundleForceRenameFallback(bool force) { gForceRenameFallback = force; }
}  // namespace detail

void saveSceneBundle(const Scene& scene, const fs::path& bundleDir, const BundleProgress& progress) {
  const BundlePaths b = bundlePaths(bundleDir);
  const fs::path tmp = b.parent / (b.savingPrefix() + std::to_string(::getpid()));
  try {
    fs::create_directories(b.parent);
    recoverAside(b);
    removeStale(b);
    const bool haveOld = fs::exists(b.bundle);
    if (haveOld) {
      if (!fs::is_directory(b.bundle))
        throw SceneError(b.bundle.string() + " exists and is not a folder: choose another name for the scene");
      if (!fs::exists(b.bundle / kSceneFile) && !fs::is_empty(b.bundle))
        throw SceneError(b.bundle.string() + " exists and is not a CAPS scene bundle (no scene.json): choose another name or move that folder");
    }
    fs::remove_all(tmp);
    fs::create_directory(tmp);
    writeAll(scene, tmp, progress);

    if (!haveOld) {
      if (::rename(tmp.c_str(), b.bundle.c_str()) != 0)
        throw SceneError("cannot move the saved scene into " + b.bundle.string() + ": " + errnoText());
    } else if (!gForceRenameFallback && renameExchange(tmp, b.bundle) == 0) {
      fs::remove_all(tmp);  // now holds the previous bundle
    } else {
      // The filesystem cannot exchange: set the old copy aside, move the new
      // one in, then delete the old. loadSceneBundle recovers the aside copy
      // if we are interrupted in between.
      const fs::path aside = b.parent / (b.asidePrefix() + std::to_string(::getpid()));
      fs::remove_all(aside);
      if (::rename(b.bundle.c_str(), aside.c_str()) != 0)
        throw SceneError("cannot replace " + b.bundle.string() + ": " + errnoText() + "; check the folder permissions");
      if (::rename(tmp.c_str(), b.bundle.c_str()) != 0) {
        const std::string why = errnoText();
        ::rename(aside.c_str(), b.bundle.c_str());
        throw SceneError("cannot move the saved scene into " + b.bundle.string() + ": " + why);
      }
      fs::remove_all(aside);
    }
    fsyncPath(b.parent, true);
    if (progress) progress(1.0, "Saved " + b.bundle.string());
  } catch (const SceneError&) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw;
  } catch (const std::exception& e) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw SceneError("could not save the scene to " + b.bundle.string() + ": " + e.what() +
                     "; check free disk space and permissions. The previous copy is unchanged.");
  }
}

void loadSceneBundle(Scene& scene, const fs::path& bundleDir) {
  const BundlePaths b = bundlePaths(bundleDir);
  recoverAside(b);
  std::error_code ec;
  if (!fs::is_directory(b.bundle, ec))
    throw SceneError("scene bundle " + b.bundle.string() + " not found: check the path");
  const fs::path sceneFile = b.bundle / kSceneFile;
  std::ifstream in(sceneFile);
  if (!in) throw SceneError(sceneFile.string() + " is missing: " + b.bundle.string() + " is not a complete CAPS scene; restore it from a backup");
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    throw SceneError(sceneFile.string() + " is damaged and cannot be read (" + e.what() + "); restore it from a backup");
  }
  if (!doc.is_object() || doc.value("format", "") != "caps-scene" || !doc.contains("version") ||
      !doc["version"].is_number_integer())
    throw SceneError(sceneFile.string() + " is not a CAPS scene file (format or version missing); restore it from a backup");
  const int version = doc["version"].get<int>();
  if (version > kSceneBundleFormatVersion)
    throw SceneError(sceneFile.string() + " was saved by a newer CAPS (format version " + std::to_string(version) +
                     "); this build reads up to " + std::to_string(kSceneBundleFormatVersion) + ": update CAPS");
  if (!doc.contains("nodes") || !doc["nodes"].is_array())
    throw SceneError(sceneFile.string() + " is damaged (no node list); restore it from a backup");

  // Read everything aside first: the scene changes only if the whole bundle is good.
  std::vector<std::unique_ptr<Node>> loaded;
  std::set<std::string> ids;
  for (const auto& j : doc["nodes"]) {
    std::string id, typeName;
    try {
      id = j.at("id").get<std::string>();
      typeName = j.at("type").get<std::string>();
    } catch (const std::exception& e) {
      throw SceneError(sceneFile.string() + " is damaged (a node lacks its id or type: " + e.what() + "); restore it from a backup");
    }
    const auto type = nodeTypeFromString(typeName);
    if (!type)
      throw SceneError(sceneFile.string() + ": node '" + id + "' has the unknown type '" + typeName +
                       "'; it was saved by a newer or different CAPS: update CAPS");
    if (id.empty() || !ids.insert(id).second)
      throw SceneError(sceneFile.string() + " is damaged (empty or duplicate node id '" + id + "'); restore it from a backup");
    auto node = Node::create(*type);
    node->setId(id);
    try {
      node->fromJson(j);
    } catch (const std::exception& e) {
      throw SceneError(sceneFile.string() + " is damaged (node '" + id + "': " + e.what() + "); restore it from a backup");
    }
    if (auto f = j.find("file"); f != j.end()) {
      const fs::path file = b.bundle / f->get<std::string>();
      if (!fs::is_regular_file(file, ec))
        throw SceneError(file.string() + " (node '" + id + "') listed in scene.json is missing: the bundle is incomplete; restore it from a backup");
      try {
        node->readBulk(file);
      } catch (const SceneError&) {
        throw;
      } catch (const std::exception& e) {
        throw SceneError("cannot read " + file.string() + " (node '" + id + "'): " + e.what());
      }
    }
    loaded.push_back(std::move(node));
  }

  scene.clear();
  for (auto& n : loaded) scene.addNode(std::move(n));
  scene.undoStack().clear();
}

}  // namespace caps
