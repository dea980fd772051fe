#pragma once
// Paths the tests share: the embedded sample, a scratch folder per test.

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace caps::test {

inline std::filesystem::path sampleCt()
{
  return std::filesystem::path(CAPS_TEST_DATA_DIR) / "sample-ct" / "dicom";
}

inline std::filesystem::path artifacts()
{
  return CAPS_TEST_ARTIFACTS_DIR;
}

/// A fresh, empty folder named after the running test.
inline std::filesystem::path scratchFolder()
{
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const auto folder =
    std::filesystem::temp_directory_path() / "caps-tests" / (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder;
}

} // namespace caps::test
