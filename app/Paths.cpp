#include "app/Paths.h"

#include <cstdlib>

namespace fs = std::filesystem;

namespace caps {

fs::path executablePath()
{
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path("caps") : exe;
}

fs::path dataDirectory()
{
  if (const char* env = std::getenv("CAPS_DATA_DIR"))
    return env;
  std::error_code ec;
  const fs::path installed = executablePath().parent_path().parent_path() / "share" / "caps" / "data";
  if (fs::is_directory(installed, ec))
    return installed;
  return CAPS_SOURCE_DATA_DIR;
}

fs::path sampleCtPath()
{
  return dataDirectory() / "sample-ct" / "dicom";
}

} // namespace caps
