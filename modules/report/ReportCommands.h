#pragma once
/// @file ReportCommands.h
/// @brief The Report module's command `caps report`.

#include <vector>

#include "modules/core/Module.h"

namespace caps {

std::vector<ModuleCommand> reportCommands();

} // namespace caps
