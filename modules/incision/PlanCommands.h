#pragma once
/// @file PlanCommands.h
/// @brief The Incision module's command `caps plan`.

#include <vector>

#include "modules/core/Module.h"

namespace caps {

std::vector<ModuleCommand> planCommands();

} // namespace caps
