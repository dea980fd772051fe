#pragma once
/// @file VolumesLogic.h
/// @brief Logic of the Volumes module: CT in, Volume node out; no widgets.

#include <filesystem>
#include <string>
#include <vector>

#include "modules/core/Module.h"
#include "segmentation/CtReader.h"

namespace caps {

class VolumeNode;

class VolumesLogic : public ModuleLogic
{
public:
  using ModuleLogic::ModuleLogic;

  /// Reads a CT (DICOM folder or file, NIfTI, NRRD, MetaImage). Touches no
  /// scene, so the GUI runs it on a worker thread.
  /// @throws seg::CtReadError, seg::Cancelled
  static seg::CtVolume read(const std::filesystem::path& path, const seg::CtReadOptions& options = {});

  /// Adds a read CT to the scene as a Volume node named after its series,
  /// with the soft-tissue window.
  VolumeNode* addVolume(seg::CtVolume volume);

  /// The Volume node already read from @a path, or nullptr.
  VolumeNode* findBySource(const std::filesystem::path& path) const;

  /// read() + addVolume(), reusing a node already read from the same path.
  /// Warnings about the data go to @a warnings.
  VolumeNode* load(const std::filesystem::path& path, const seg::CtReadOptions& options,
                   std::vector<std::string>& warnings);

  /// What `caps info` prints: dimensions, spacing, origin, orientation,
  /// extent, HU range and the DICOM patient/study/series fields.
  static std::string describe(const VolumeNode& volume);

  /// Writes the middle axial, coronal and sagittal slices as 8-bit PNGs in
  /// radiological orientation with square pixels; returns the files.
  static std::vector<std::filesystem::path>
  writeMiddleSlices(const VolumeNode& volume, const std::filesystem::path& folder, double window, double level);
};

} // namespace caps
