#pragma once
/// @file RangeMapParallel.h
/// @brief Internal: the row loop of range map work on a few std::threads.

#include <functional>
#include <string>

#include "segmentation/Progress.h"

namespace caps::seg::internal {

/// Calls work(row) once for every row in [0, rows) on `threads` threads (the
/// calling thread is one of them; threads < 1 means 1). Rows are handed out
/// one at a time, so the split changes from run to run, but each row's result
/// depends only on the row: the output is the same for any thread count.
/// progress (may be empty) is called from the calling thread only, with
/// fractions from `from` to `to`; returning false stops the work and throws
/// Cancelled. An exception thrown by work is rethrown here after all threads end.
void parallelRows(int rows, int threads, const std::function<void(int row)>& work,
                  const ProgressCallback& progress = {}, const std::string& step = {}, double from = 0.0,
                  double to = 1.0);

} // namespace caps::seg::internal
