#pragma once
/// @file RangeMapCommands.h
/// @brief The RangeMap module's commands `caps rangemap` and `caps scan`.

#include <string>
#include <vector>

#include <Eigen/Core>

#include "modules/core/Module.h"

namespace caps {

std::vector<ModuleCommand> rangeMapCommands();

/// "PX,PY,PZ,DX,DY,DZ" (mm) into a point and a direction; false unless six
/// finite numbers with a non-zero direction (`--axis` of rangemap and scan).
bool parseAxis(const std::string& text, Eigen::Vector3d& point, Eigen::Vector3d& direction);

/// `caps scan`: a surface scan to range and colour map pictures (ScanCommands.cpp).
ModuleCommand scanCommand();

} // namespace caps
