#include "segmentation/RangeMapParallel.h"

#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace caps::seg::internal {

void parallelRows(int rows, int threads, const std::function<void(int)>& work, const ProgressCallback& progress,
                  const std::string& step, double from, double to)
{
  if (threads < 1)
    threads = 1;
  std::atomic<int> next{0};
  std::atomic<int> done{0};
  std::atomic<bool> stop{false};
  std::exception_ptr failure;
  std::mutex failureMutex;

  auto loop = [&](bool reportProgress) {
    try
    {
      for (int row = next++; row < rows && !stop; row = next++)
      {
        work(row);
        const int finished = ++done;
        if (reportProgress && progress && !progress(from + (to - from) * finished / rows, step))
          stop = true;
      }
    }
    catch (...)
    {
      std::lock_guard<std::mutex> lock(failureMutex);
      if (!failure)
        failure = std::current_exception();
      stop = true;
    }
  };

  std::vector<std::thread> workers;
  for (int t = 1; t < threads; ++t)
    workers.emplace_back(loop, false);
  loop(true);
  for (auto& w : workers)
    w.join();
  if (failure)
    std::rethrow_exception(failure);
  if (stop)
    throw Cancelled();
}

} // namespace caps::seg::internal
