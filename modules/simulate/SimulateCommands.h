#pragma once
/// @file SimulateCommands.h
/// @brief The Simulate module's command-line subcommand: `caps fem`.

#include <vector>

#include "modules/core/Module.h"

namespace caps {

std::vector<ModuleCommand> simulateCommands();

} // namespace caps
