#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace caps {

class Scene;

/// Progress of a save: fraction in [0, 1] and what is being written.
using BundleProgress = std::function<void(double fraction, const std::string& what)>;

/// Highest scene.json format version this build reads and the one it writes.
inline constexpr int kSceneBundleFormatVersion = 1;

/// @brief Saves the scene to the bundle folder @a bundleDir ("NAME.caps/"):
/// scene.json plus one file per bulky node, named after the node id.
///
/// Atomic: everything is written and fsynced into the sibling folder
/// ".NAME.caps.saving-PID", then swapped in (renameat2 RENAME_EXCHANGE, or
/// rename old aside / new in / delete old where the filesystem refuses), so
/// an interrupted save leaves the previous bundle intact. Stale temporary
/// folders of killed saves are removed first. Refuses to replace a folder
/// that is not a CAPS bundle. Throws SceneError naming the path.
void saveSceneBundle(const Scene& scene, const std::filesystem::path& bundleDir,
                     const BundleProgress& progress = {});

/// @brief Replaces the scene's contents by the bundle's.
///
/// The scene is changed only once the whole bundle was read; on any error
/// (missing or damaged scene.json, newer format version, unknown node type,
/// missing or truncated node file) it throws SceneError naming the file and
/// leaves the scene as it was. Recovers the aside copy left by an interrupted
/// fallback swap when the bundle itself is missing. Clears the undo stack.
void loadSceneBundle(Scene& scene, const std::filesystem::path& bundleDir);

namespace detail {
/// Tests only: skip RENAME_EXCHANGE and use the rename-aside fallback.
void setSceneBundleForceRenameFallback(bool force);
}  // namespace detail

}  // namespace caps
