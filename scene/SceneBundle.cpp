#include "scene/SceneBundle.h"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <sys/file.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <sstream>
#include <vector>

#include "scene/Node.h"
#include "scene/Scene.h"
#include "scene/SceneError.h"

namespace caps {

namespace fs = std::filesystem;

namespace {

std::atomic<bool> gForceRenameFallback{false};

const char* kSceneFile = "scene.json";

struct BundlePaths
{
  fs::path bundle; // .../NAME.caps
  fs::path parent;
  std::string name; // NAME.caps
  std::string savingPrefix() const { return "." + name + ".saving-"; }
  std::string asidePrefix() const { return "." + name + ".old-"; }
  fs::path lockFile() const { return parent / ("." + name + ".lock"); }
};

BundlePaths bundlePaths(const fs::path& dir)
{
  fs::path p = dir.lexically_normal();
  if (p.filename().empty())
    p = p.parent_path(); // "x.caps/" -> "x.caps"
  if (p.empty() || p.filename() == "." || p.filename() == "..")
    throw SceneError("'" + dir.string() + "' is not a valid scene bundle name: use a folder name like head.caps");
  BundlePaths b;
  b.bundle = p;
  b.parent = p.has_parent_path() ? p.parent_path() : fs::path(".");
  b.name = p.filename().string();
  return b;
}

// Node ids name the node files: letters, digits, '_' and '-' only, so no id
// can point outside the bundle.
bool isValidId(const std::string& id)
{
  return !id.empty() &&
         std::all_of(id.begin(), id.end(), [](unsigned char c) { return std::isalnum(c) || c == '_' || c == '-'; });
}

std::string errnoText()
{
  return std::strerror(errno);
}

// Flushes a file or folder to disk, so the rename that publishes it never
// exposes data still in the page cache after a power cut.
void fsyncPath(const fs::path& p, bool directory)
{
  const int fd = ::open(p.c_str(), (directory ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC);
  if (fd < 0)
    throw SceneError("cannot open " + p.string() + " to flush it to disk: " + errnoText());
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  // Some filesystems cannot fsync a folder (EINVAL); file data is what matters.
  if (rc != 0 && !(directory && (err == EINVAL || err == EROFS)))
    throw SceneError("cannot flush " + p.string() + " to disk: " + std::strerror(err) + "; check the disk");
}

// An exclusive flock on ".NAME.caps.lock" beside the bundle, held while
// saving or recovering, so that saves (threads, processes, hosts sharing the
// folder) never touch each other's temporary folders. The lock file stays.
// held() is false where no lock can be had (read-only folder, no locking on
// the filesystem): callers then only touch folders of dead local processes.
class BundleLock
{
public:
  explicit BundleLock(const fs::path& file) : fd_(::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666))
  {
    if (fd_ < 0)
      return;
    int rc;
    do
      rc = ::flock(fd_, LOCK_EX);
    while (rc != 0 && errno == EINTR);
    if (rc != 0)
    {
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~BundleLock()
  {
    if (fd_ >= 0)
      ::close(fd_);
  }
  BundleLock(const BundleLock&) = delete;
  BundleLock& operator=(const BundleLock&) = delete;
  bool held() const { return fd_ >= 0; }

private:
  int fd_;
};

std::string hostName()
{
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0 || !buf[0])
    return "localhost";
  std::string host(buf);
  for (char& c : host)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-')
      c = '_';
  return host;
}

// "HOST-PID-TOKEN": names this save's temporary folders, unique across
// hosts, processes and saves.
std::string tempSuffix()
{
  std::random_device random;
  std::ostringstream s;
  s << hostName() << '-' << ::getpid() << '-' << std::hex << random() << random();
  return s.str();
}

// A decimal pid of at most 9 digits; -1 otherwise.
long parsePid(const std::string& text)
{
  long pid = -1;
  if (text.empty() || text.size() > 9)
    return -1;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), pid);
  return ec == std::errc() && end == text.data() + text.size() ? pid : -1;
}

// May the temporary folder "PREFIX-HOST-PID-TOKEN" (or "PREFIX-PID", of
// this host, from older CAPS) be deleted or recovered? Under the bundle lock
// no other save is running, so yes. Without it only when its process, on
// this host, is dead.
bool isStale(const std::string& suffix, bool locked)
{
  if (locked)
    return true;
  std::string host = hostName(), pidText = suffix;
  if (const auto tokenDash = suffix.rfind('-'); tokenDash != std::string::npos)
  {
    const auto pidDash = tokenDash == 0 ? std::string::npos : suffix.rfind('-', tokenDash - 1);
    if (pidDash == std::string::npos)
      return false;
    host = suffix.substr(0, pidDash);
    pidText = suffix.substr(pidDash + 1, tokenDash - pidDash - 1);
  }
  const long pid = parsePid(pidText);
  if (pid <= 0 || host != hostName() || pid == static_cast<long>(::getpid()))
    return false;
  return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno != EPERM;
}

// Entries of the bundle's folder named PREFIX..., with what follows PREFIX.
std::vector<std::pair<fs::path, std::string>> entriesWithPrefix(const fs::path& dir, const std::string& prefix)
{
  std::vector<std::pair<fs::path, std::string>> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec))
  {
    const std::string n = entry.path().filename().string();
    if (n.rfind(prefix, 0) == 0)
      out.emplace_back(entry.path(), n.substr(prefix.size()));
  }
  return out;
}

// Brings back the previous bundle when a fallback swap was interrupted
// between "rename old aside" and "rename new in".
void recoverAside(const BundlePaths& b, bool locked)
{
  std::error_code ec;
  if (fs::exists(b.bundle, ec) || !fs::is_directory(b.parent, ec))
    return;
  for (const auto& [path, suffix] : entriesWithPrefix(b.parent, b.asidePrefix()))
  {
    // A live owner is between its two renames right now: leave it alone.
    if (isStale(suffix, locked) && fs::exists(path / kSceneFile, ec))
    {
      if (::rename(path.c_str(), b.bundle.c_str()) != 0)
        throw SceneError("cannot recover the previous copy " + path.string() + " of " + b.bundle.string() + ": " +
                         errnoText() + "; rename it to " + b.name + " by hand");
      return;
    }
  }
}

// Removes temp folders of saves that are over, and aside copies that are no
// longer needed because the bundle exists.
void removeStale(const BundlePaths& b, bool locked)
{
  std::error_code ec;
  const bool haveBundle = fs::exists(b.bundle, ec);
  auto stale = entriesWithPrefix(b.parent, b.savingPrefix());
  if (haveBundle)
    for (auto& e : entriesWithPrefix(b.parent, b.asidePrefix()))
      stale.push_back(std::move(e));
  for (const auto& [path, suffix] : stale)
    if (isStale(suffix, locked))
      fs::remove_all(path, ec);
}

int renameExchange(const fs::path& a, const fs::path& b)
{
#ifdef RENAME_EXCHANGE
  return ::renameat2(AT_FDCWD, a.c_str(), AT_FDCWD, b.c_str(), RENAME_EXCHANGE);
#elif defined(SYS_renameat2)
  return static_cast<int>(::syscall(SYS_renameat2, AT_FDCWD, a.c_str(), AT_FDCWD, b.c_str(), 2 /*RENAME_EXCHANGE*/));
#else
  errno = ENOSYS;
  return -1;
#endif
}

void writeAll(const Scene& scene, const fs::path& tmp, const BundleProgress& progress)
{
  nlohmann::json doc;
  doc["format"] = "caps-scene";
  doc["version"] = kSceneBundleFormatVersion;
  doc["nodes"] = nlohmann::json::array();
  const auto nodes = scene.nodes();
  std::size_t bulky = 0;
  for (const Node* n : nodes)
    if (!n->bulkFileExtension().empty())
      ++bulky;
  std::size_t done = 0;
  const double steps = static_cast<double>(bulky + 1);
  for (const Node* n : nodes)
  {
    nlohmann::json j = n->toJson();
    if (!isValidId(n->id()))
      throw SceneError("node id '" + n->id() + "' cannot name a file: use letters, digits, '_' and '-' only");
    const std::string ext = n->bulkFileExtension();
    if (!ext.empty())
    {
      const std::string file = n->id() + ext;
      if (progress)
        progress(static_cast<double>(done) / steps, "Saving " + n->name() + " (" + file + ")");
      n->writeBulk(tmp / file);
      fsyncPath(tmp / file, false);
      j["file"] = file;
      ++done;
      if (progress)
        progress(static_cast<double>(done) / steps, "Saved " + file);
    }
    doc["nodes"].push_back(std::move(j));
  }
  const fs::path sceneFile = tmp / kSceneFile;
  {
    std::ofstream out(sceneFile, std::ios::trunc);
    out << doc.dump(2) << '\n';
    out.close();
    if (!out)
      throw SceneError("could not write " + sceneFile.string() + ": check free disk space and permissions");
  }
  fsyncPath(sceneFile, false);
  fsyncPath(tmp, true);
}

} // namespace

namespace detail {
void setSceneBundleForceRenameFallback(bool force)
{
  gForceRenameFallback = force;
}
} // namespace detail

namespace {

// Files the user put into the bundle (a report, screenshots) are not the
// scene's: carry them into the new copy, hard linked (copied where links are
// refused), so the swap does not delete them. scene.json and the node files
// it lists stay behind with the previous copy.
void carryUserFiles(const fs::path& oldBundle, const fs::path& tmp)
{
  std::set<std::string> sceneFiles{kSceneFile};
  try
  {
    std::ifstream in(oldBundle / kSceneFile);
    const auto doc = nlohmann::json::parse(in);
    for (const auto& j : doc.at("nodes"))
      if (auto f = j.find("file"); f != j.end() && f->is_string())
        sceneFiles.insert(f->get<std::string>());
  }
  catch (const std::exception&)
  {
    // Unreadable: carry every other file; at worst an old node file survives.
  }
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(oldBundle))
  {
    const fs::path name = entry.path().filename();
    if (sceneFiles.count(name.string()) || fs::exists(fs::symlink_status(tmp / name, ec)))
      continue;
    const auto options = fs::copy_options::recursive | fs::copy_options::copy_symlinks;
    fs::copy(entry.path(), tmp / name, options | fs::copy_options::create_hard_links, ec);
    if (!ec)
      continue;
    fs::remove_all(tmp / name, ec);
    try
    {
      fs::copy(entry.path(), tmp / name, options);
      if (fs::is_regular_file(fs::symlink_status(tmp / name)))
        fsyncPath(tmp / name, false);
      if (fs::is_directory(fs::symlink_status(tmp / name)))
        for (const auto& f : fs::recursive_directory_iterator(tmp / name))
          if (f.is_regular_file() && !f.is_symlink())
            fsyncPath(f.path(), false);
    }
    catch (const std::exception& e)
    {
      throw SceneError("cannot keep " + entry.path().string() + " in the new copy of the scene (" + e.what() +
                       "): move it out of " + oldBundle.string() + " and save again. The previous copy is unchanged.");
    }
  }
}

// Moves the new copy @a tmp to the bundle's place. Returns where the
// previous copy went ("" when there was none), for the caller to delete.
// Throws only while the previous copy is still (or again) in place.
fs::path swapIn(const BundlePaths& b, const fs::path& tmp, const fs::path& aside, bool haveOld)
{
  if (!haveOld)
  {
    if (::rename(tmp.c_str(), b.bundle.c_str()) != 0)
      throw SceneError("cannot move the saved scene into " + b.bundle.string() + ": " + errnoText());
    return {};
  }
  if (!gForceRenameFallback && renameExchange(tmp, b.bundle) == 0)
    return tmp; // tmp now holds the previous bundle
  // The filesystem cannot exchange: set the old copy aside, move the new one
  // in. loadSceneBundle recovers the aside copy if we are interrupted in between.
  if (::rename(b.bundle.c_str(), aside.c_str()) != 0)
    throw SceneError("cannot replace " + b.bundle.string() + ": " + errnoText() + "; check the folder permissions");
  if (::rename(tmp.c_str(), b.bundle.c_str()) != 0)
  {
    const std::string why = errnoText();
    ::rename(aside.c_str(), b.bundle.c_str());
    throw SceneError("cannot move the saved scene into " + b.bundle.string() + ": " + why);
  }
  return aside;
}

} // namespace

void saveSceneBundle(const Scene& scene, const fs::path& bundleDir, const BundleProgress& progress)
{
  const BundlePaths b = bundlePaths(bundleDir);
  const std::string suffix = tempSuffix();
  const fs::path tmp = b.parent / (b.savingPrefix() + suffix);
  std::error_code ec;
  fs::create_directories(b.parent, ec); // a failure shows when the temp folder cannot be made
  const BundleLock lock(b.lockFile());
  fs::path previous;
  try
  {
    recoverAside(b, lock.held());
    removeStale(b, lock.held());
    const bool haveOld = fs::exists(b.bundle);
    if (haveOld)
    {
      if (!fs::is_directory(b.bundle))
        throw SceneError(b.bundle.string() + " exists and is not a folder: choose another name for the scene");
      if (!fs::exists(b.bundle / kSceneFile) && !fs::is_empty(b.bundle))
        throw SceneError(
          b.bundle.string() +
          " exists and is not a CAPS scene bundle (no scene.json): choose another name or move that folder");
    }
    fs::create_directory(tmp);
    writeAll(scene, tmp, progress);
    if (haveOld)
    {
      carryUserFiles(b.bundle, tmp);
      fsyncPath(tmp, true);
    }
    previous = swapIn(b, tmp, b.parent / (b.asidePrefix() + suffix), haveOld);
  }
  catch (const SceneError&)
  {
    fs::remove_all(tmp, ec);
    throw;
  }
  catch (const std::exception& e)
  {
    fs::remove_all(tmp, ec);
    throw SceneError("could not save the scene to " + b.bundle.string() + ": " + e.what() +
                     "; check free disk space and permissions. The previous copy is unchanged.");
  }
  // The new bundle is in place: the save succeeded. Tidying up may fail
  // (a leftover folder is removed by the next save) but is no error.
  if (!previous.empty())
    fs::remove_all(previous, ec);
  if (const int fd = ::open(b.parent.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); fd >= 0)
  {
    ::fsync(fd);
    ::close(fd);
  }
  if (progress)
    progress(1.0, "Saved " + b.bundle.string());
}

namespace {

// Reads every node of scene.json and its file. nlohmann exceptions are left
// to the caller, which names scene.json.
std::vector<std::unique_ptr<Node>> readNodes(const nlohmann::json& doc, const BundlePaths& b, const fs::path& sceneFile)
{
  if (!doc.is_object() || doc.value("format", nlohmann::json()) != "caps-scene" || !doc.contains("version") ||
      !doc["version"].is_number_integer())
    throw SceneError(sceneFile.string() +
                     " is not a CAPS scene file (format or version missing); restore it from a backup");
  const auto version = doc["version"].get<std::int64_t>();
  if (version > kSceneBundleFormatVersion)
    throw SceneError(sceneFile.string() + " was saved by a newer CAPS (format version " + std::to_string(version) +
                     "); this build reads up to " + std::to_string(kSceneBundleFormatVersion) + ": update CAPS");
  if (!doc.contains("nodes") || !doc["nodes"].is_array())
    throw SceneError(sceneFile.string() + " is damaged (no node list); restore it from a backup");

  std::vector<std::unique_ptr<Node>> loaded;
  std::set<std::string> ids;
  std::error_code ec;
  for (const auto& j : doc["nodes"])
  {
    std::string id, typeName;
    try
    {
      id = j.at("id").get<std::string>();
      typeName = j.at("type").get<std::string>();
    }
    catch (const std::exception& e)
    {
      throw SceneError(sceneFile.string() + " is damaged (a node lacks its id or type: " + e.what() +
                       "); restore it from a backup");
    }
    const auto type = nodeTypeFromString(typeName);
    if (!type)
      throw SceneError(sceneFile.string() + ": node '" + id + "' has the unknown type '" + typeName +
                       "'; it was saved by a newer or different CAPS: update CAPS");
    if (!isValidId(id) || !ids.insert(id).second)
      throw SceneError(sceneFile.string() + " is damaged (invalid or duplicate node id '" + id +
                       "'); restore it from a backup");
    auto node = Node::create(*type);
    node->setId(id);
    try
    {
      node->fromJson(j);
    }
    catch (const std::exception& e)
    {
      throw SceneError(sceneFile.string() + " is damaged (node '" + id + "': " + e.what() +
                       "); restore it from a backup");
    }
    if (auto f = j.find("file"); f != j.end())
    {
      // A plain file name inside the bundle: no folders, nothing absolute.
      const std::string name = f->is_string() ? f->get<std::string>() : std::string();
      if (name.empty() || name == "." || name == ".." || fs::path(name).filename() != name)
        throw SceneError(sceneFile.string() + " is damaged (node '" + id + "' names the file " + f->dump() +
                         ", which is not a file of the bundle); restore it from a backup");
      const fs::path file = b.bundle / name;
      if (!fs::is_regular_file(file, ec))
        throw SceneError(file.string() + " (node '" + id +
                         "') listed in scene.json is missing: the bundle is incomplete; restore it from a backup");
      try
      {
        node->readBulk(file);
      }
      catch (const SceneError&)
      {
        throw;
      }
      catch (const std::exception& e)
      {
        throw SceneError("cannot read " + file.string() + " (node '" + id + "'): " + e.what());
      }
    }
    loaded.push_back(std::move(node));
  }
  return loaded;
}

} // namespace

void loadSceneBundle(Scene& scene, const fs::path& bundleDir)
{
  const BundlePaths b = bundlePaths(bundleDir);
  std::error_code ec;
  if (!fs::exists(b.bundle, ec) && !entriesWithPrefix(b.parent, b.asidePrefix()).empty())
  {
    const BundleLock lock(b.lockFile());
    recoverAside(b, lock.held());
  }
  if (!fs::is_directory(b.bundle, ec))
    throw SceneError("scene bundle " + b.bundle.string() + " not found: check the path");
  const fs::path sceneFile = b.bundle / kSceneFile;
  std::ifstream in(sceneFile);
  if (!in)
    throw SceneError(sceneFile.string() + " is missing: " + b.bundle.string() +
                     " is not a complete CAPS scene; restore it from a backup");

  // Read everything aside first: the scene changes only if the whole bundle is good.
  std::vector<std::unique_ptr<Node>> loaded;
  try
  {
    loaded = readNodes(nlohmann::json::parse(in), b, sceneFile);
  }
  catch (const nlohmann::json::exception& e)
  {
    throw SceneError(sceneFile.string() + " is damaged and cannot be read (" + e.what() +
                     "); restore it from a backup");
  }
  scene.replaceAll(std::move(loaded));
}

} // namespace caps
