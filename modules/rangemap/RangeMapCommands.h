#pragma once
/// @file RangeMapCommands.h
/// @brief The RangeMap module's command `caps rangemap`.

#include <vector>

#include "modules/core/Module.h"

namespace caps {

std::vector<ModuleCommand> rangeMapCommands();

} // namespace caps
