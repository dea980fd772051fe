#pragma once
// The demo's output (scene with two predicted plans, snapshots and the plan
// report) that the Report module's tests read: made once per test run by the
// ctest fixture report_demo into CAPS_REPORT_DEMO_DIR, or by the test process
// itself when a test runs alone. Tests only read it, or write files of their
// own names into it.

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <utility>
#include <vector>
#include <unistd.h>

#include <gtest/gtest.h>

#include "app/RunProcess.h"

namespace caps::test {

/// The caps executable run with @a args (a shell command line's words).
inline ProcessResult runCaps(const std::string& args)
{
  return runProcess(quoted(CAPS_EXECUTABLE) + " " + args);
}

/// A whole file, as bytes.
inline std::string fileText(const std::filesystem::path& file)
{
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// A PDF's text as poppler's pdftotext lays it out (pages separated by form feeds).
/// @a value with @a decimals digits after the point, as the reports print it.
inline std::string fixed(double value, int decimals)
{
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << value;
  return s.str();
}

/// The pages of pdftotext's output (form feeds between them) that hold
/// any text.
inline std::vector<std::string> pdfPages(const std::string& text)
{
  std::vector<std::string> pages;
  for (std::size_t start = 0, end; start < text.size(); start = end + 1)
  {
    end = text.find('\f', start);
    if (end == std::string::npos)
      end = text.size();
    std::string page = text.substr(start, end - start);
    if (page.find_first_not_of(" \n") != std::string::npos)
      pages.push_back(std::move(page));
  }
  return pages;
}

inline std::string pdfText(const std::filesystem::path& pdf)
{
  const std::filesystem::path text = pdf.string() + ".txt";
  const auto r = runProcess("pdftotext -layout " + quoted(pdf.string()) + " " + quoted(text.string()));
  EXPECT_EQ(r.exitCode, 0) << r.output;
  return fileText(text);
}

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
