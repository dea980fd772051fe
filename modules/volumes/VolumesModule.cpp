// The Volumes module plugin: metadata and factories only.

#include <algorithm>

#include "modules/core/Module.h"
#include "modules/volumes/VolumesCommands.h"
#include "modules/volumes/VolumesLogic.h"
#include "modules/volumes/VolumesPanel.h"

namespace caps {
namespace {

class VolumesModule : public Module
{
public:
  std::string name() const override { return "volumes"; }
  std::string title() const override { return "Volumes"; }
  std::string help() const override
  {
    return "Open a CT: a DICOM folder (choose the series if it holds several), or a NIfTI, "
           "NRRD or MetaImage file. Shows dimensions, spacing, orientation, HU range and the "
           "patient, study and series fields.";
  }
  std::unique_ptr<ModuleLogic> createLogic(Scene& scene) const override
  {
    return std::make_unique<VolumesLogic>(scene);
  }
  QWidget* createPanel(ModuleLogic& logic, ModuleHost& host, QWidget* parent) const override
  {
    return new VolumesPanel(static_cast<VolumesLogic&>(logic), host, parent);
  }
  std::vector<ModuleCommand> commands() const override { return volumesCommands(); }
  bool canOpen(const std::filesystem::path& path) const override
  {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
      return path.extension() != ".caps"; // scene bundles are the app's
    std::string name = path.filename().string();
    std::transform(name.begin(), name.end(), name.begin(), ::tolower);
    for (const char* ext : {".dcm", ".nii", ".nii.gz", ".nrrd", ".nhdr", ".mha", ".mhd", ".ima"})
      if (name.size() > std::string(ext).size() && name.ends_with(ext))
        return true;
    return false;
  }
  void open(ModuleLogic& logic, ModuleHost& host, const std::filesystem::path& path) const override
  {
    loadVolumeInBackground(static_cast<VolumesLogic&>(logic), host, path);
  }
};

} // namespace
} // namespace caps

CAPS_DECLARE_MODULE(caps::VolumesModule)
