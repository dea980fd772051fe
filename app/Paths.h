#pragma once
/// @file Paths.h
/// @brief Where the running caps finds itself and its data.

#include <filesystem>

namespace caps {

/// The running executable (from /proc/self/exe).
std::filesystem::path executablePath();

/// The data folder holding sample-ct/ and procedures/: $CAPS_DATA_DIR, else
/// share/caps/data beside the installation, else the source tree's data/.
std::filesystem::path dataDirectory();

/// The embedded sample CT series (a DICOM folder).
std::filesystem::path sampleCtPath();

} // namespace caps
