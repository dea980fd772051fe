#pragma once
// The demo's output (scene with two predicted plans, snapshots and the plan
// report) that the Report module's tests read: made once per test run by the
// ctest fixture report_demo into CAPS_REPORT_DEMO_DIR, or by the test process
// itself when a test runs alone. Tests only read it, or write files of their
// own names into it.

#include <filesystem>
#include <string>
#include <unistd.h>

#include <gtest/gtest.h>

#include "app/RunProcess.h"

namespace caps::test {

inline const std::filesystem::path& reportDemoFolder()
{
  static const std::filesystem::path folder = [] {
    const std::filesystem::path shared = CAPS_REPORT_DEMO_DIR;
    if (std::filesystem::exists(shared / "plan-report.pdf") && std::filesystem::exists(shared / "sample.caps"))
      return shared;
    const std::filesystem::path out =
      std::filesystem::temp_directory_path() / "caps-tests" / ("report-demo-" + std::to_string(getpid()));
    std::filesystem::remove_all(out);
    const auto r = runProcess(quoted(CAPS_EXECUTABLE) + " demo --out " + quoted(out.string()));
    if (r.exitCode != 0)
      ADD_FAILURE() << r.output;
    return out;
  }();
  return folder;
}

} // namespace caps::test
