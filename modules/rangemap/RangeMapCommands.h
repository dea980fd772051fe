#pragma once
/// @file RangeMapCommands.h
/// @brief The RangeMap module's commands `caps rangemap` and `caps scan`.

#include <vector>

#include "modules/core/Module.h"

namespace caps {

std::vector<ModuleCommand> rangeMapCommands();

/// `caps scan`: a surface scan to range and colour map pictures (ScanCommands.cpp).
ModuleCommand scanCommand();

} // namespace caps
