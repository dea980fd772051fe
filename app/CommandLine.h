#pragma once
/// @file CommandLine.h
/// @brief The headless side of `caps`: help, module listing, the demo and
/// the modules' subcommands, all on the same module logic as the GUI.

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace caps {

class ModuleManager;

/// Runs `caps ARGS...` without a window when ARGS ask for headless work and
/// returns the exit code; std::nullopt when they ask for the workstation.
std::optional<int> runCommandLine(const std::vector<std::string>& args, ModuleManager& modules, std::ostream& out,
                                  std::ostream& err);

/// `caps demo [--out DIR]`: the pipeline on the embedded sample CT.
int runDemo(const std::vector<std::string>& args, ModuleManager& modules, std::ostream& out, std::ostream& err);

/// The text of `caps --help`.
std::string usage(const ModuleManager& modules);

} // namespace caps
