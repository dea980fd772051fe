#pragma once
/// @file DicomFileCheck.h
/// @brief A structural check of a DICOM file before a DICOM library parses it.
///
/// Debian's GDCM is built with assertions: a file cut short inside its
/// header aborts the whole program instead of failing the read. So every
/// file is walked here first, element by element, checking that each
/// declared length fits in the file, and damaged files never reach GDCM.

#include <filesystem>
#include <optional>
#include <string>

namespace caps::seg {

enum class DicomFileKind
{
  NotDicom, ///< no "DICM" marker and no plausible raw data set
  Damaged,  ///< DICOM, but cut short, structurally broken, or without pixel data
  Sound,    ///< walks to its end cleanly (or uses an encoding not walked here)
};

struct DicomFileCheck
{
  DicomFileKind kind = DicomFileKind::NotDicom;
  std::string problem; ///< for Damaged: where and how ("cut short at byte 300 ...")
};

/// Walks the file's elements (Part 10 meta group, then the data set in
/// explicit or implicit VR little endian, sequences and encapsulated pixel
/// data included). Big-endian and deflated data sets are only checked up to
/// the end of the meta group.
DicomFileCheck checkDicomFile(const std::filesystem::path& file);

} // namespace caps::seg
