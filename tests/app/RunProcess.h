#pragma once
// Runs a command line and collects its exit code and output (stdout and
// stderr together), for tests of the `caps` executable.

#include <array>
#include <cstdio>
#include <string>
#include <sys/wait.h>

namespace caps::test {

struct ProcessResult
{
  int exitCode = -1;
  bool crashed = false; ///< killed by a signal (a crash, an abort)
  std::string output;
};

inline ProcessResult runProcess(const std::string& command)
{
  ProcessResult result;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe)
    return result;
  std::array<char, 4096> buffer;
  size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
    result.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  if (WIFEXITED(status))
  {
    result.exitCode = WEXITSTATUS(status);
    // The shell reports a child killed by a signal as 128 + signal.
    result.crashed = result.exitCode > 128;
  }
  else
    result.crashed = true;
  return result;
}

inline std::string quoted(const std::string& s)
{
  std::string q = "'";
  for (char c : s)
    q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

} // namespace caps::test
