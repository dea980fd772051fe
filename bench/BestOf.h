#pragma once
// The benchmarks' timing: the best of several runs (the least disturbed by
// the rest of the machine).

#include <algorithm>
#include <chrono>
#include <functional>

namespace caps::bench {

/// Seconds of the fastest of @a repeats runs of @a work.
inline double secondsOf(const std::function<void()>& work, int repeats)
{
  double best = 1e300;
  for (int i = 0; i < repeats; ++i)
  {
    const auto start = std::chrono::steady_clock::now();
    work();
    const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
    best = std::min(best, elapsed.count());
  }
  return best;
}

} // namespace caps::bench
