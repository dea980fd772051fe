#pragma once

#include <stdexcept>
#include <string>

namespace caps {

/// Error raised by the scene library.
///
/// The message is meant for the user: it names the file involved and says
/// what to do about it (update CAPS, restore a backup, free disk space...).
class SceneError : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};

} // namespace caps
