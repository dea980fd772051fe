#pragma once
/// @file Progress.h
/// @brief How long work reports progress and learns it was cancelled.

#include <functional>
#include <stdexcept>
#include <string>

namespace caps::seg {

/// Called with a fraction in [0,1] and a short description of the current
/// step. Returning false asks the work to stop; it then throws Cancelled.
using ProgressCallback = std::function<bool(double fraction, const std::string& step)>;

/// Thrown when the user cancelled long work through the progress callback.
class Cancelled : public std::runtime_error
{
public:
  Cancelled() : std::runtime_error("Cancelled by the user.") {}
};

/// Tells @a progress (when there is one) that the work is at @a fraction
/// (clamped to [0,1]) doing @a step.
/// @throws Cancelled when it answers that the user asked to stop.
inline void reportProgress(const ProgressCallback& progress, double fraction, const std::string& step)
{
  if (progress && !progress(fraction < 0.0 ? 0.0 : fraction > 1.0 ? 1.0 : fraction, step))
    throw Cancelled();
}

} // namespace caps::seg
