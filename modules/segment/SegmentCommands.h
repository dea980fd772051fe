#pragma once
/// @file SegmentCommands.h
/// @brief The Segment module's command `caps segment`.

#include <vector>

#include "modules/core/Module.h"

namespace caps {

std::vector<ModuleCommand> segmentCommands();

} // namespace caps
