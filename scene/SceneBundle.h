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
/// ".NAME.caps.saving-HOST-PID-TOKEN", then swapped in (renameat2
/// RENAME_EXCHANGE, or rename old aside / new in where the filesystem
/// refuses), so an interrupted save leaves the previous bundle intact. Files
/// the user put into the bundle (not scene.json nor the old node files) are
/// carried into the new copy. An flock on ".NAME.caps.lock" beside the bundle
/// is held while saving, so concurrent saves wait for each other; temporary
/// folders of finished or killed saves are removed first. Refuses to replace
/// a folder that is not a CAPS bundle. Throws SceneError naming the path, and
/// only while the previous copy is still in place.
void saveSceneBundle(const Scene& scene, const std::filesystem::path& bundleDir, const BundleProgress& progress = {});

/// @brief Replaces the scene's contents by the bundle's.
///
/// The scene is changed only once the whole bundle was read; on any error
/// (missing or damaged scene.json, newer format version, unknown node type,
/// missing or truncated node file) it throws SceneError naming the file and
/// leaves the scene as it was. Then Scene::replaceAll installs all nodes
/// before observers are told. Recovers the aside copy left by an interrupted
/// fallback swap when the bundle itself is missing. Clears the undo stack.
void loadSceneBundle(Scene& scene, const std::filesystem::path& bundleDir);

namespace detail {
/// Tests only: skip RENAME_EXCHANGE and use the rename-aside fallback.
void setSceneBundleForceRenameFallback(bool force);
} // namespace detail

} // namespace caps
