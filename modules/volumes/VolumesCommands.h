#pragma once
/// @file VolumesCommands.h
/// @brief The Volumes module's command-line subcommands: `caps info`, `caps slices`.

#include <vector>

#include "modules/core/Module.h"

namespace caps {

std::vector<ModuleCommand> volumesCommands();

} // namespace caps
