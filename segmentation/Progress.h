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

} // namespace caps::seg
