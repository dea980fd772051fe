#pragma once
/// @file ExpressionCommands.h
/// @brief `caps expression`: the face of a saved scene under an expression
/// (thesis §5.3), a plan of it under that expression or a fingertip's push
/// (§5.4) with its contour bumps compared, and the expression's animation.

#include <vector>

#include "modules/core/Module.h"

namespace caps {

/// The Expression module's command-line commands.
std::vector<ModuleCommand> expressionCommands();

} // namespace caps
