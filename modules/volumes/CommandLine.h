#pragma once
/// @file CommandLine.h
/// @brief What the modules' commands share: arguments of the form INPUT
/// --out DIR [options] (with --series for a CT, --help), numbers, the output
/// folder, progress on a terminal, reading the CT into the scene through the
/// Volumes logic, STL files.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <exception>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "modules/core/Module.h"
#include "segmentation/CtReader.h"

class vtkPolyData;

namespace caps {

class VolumeNode;

namespace cli {

/// What every command working on a CT takes: the CT, `--out DIR`,
/// `--series N|UID` and `--help`.
struct CtCommandArgs
{
  std::filesystem::path ct;
  std::filesystem::path out;
  seg::CtReadOptions read;
  bool help = false;
};

/// Handles a command's own option @a option found at args[i], advancing @a i
/// past a value it takes; returns an error text (also for an option it does
/// not know), or nothing.
using CommandOption = std::function<std::optional<std::string>(const std::string& option,
                                                               const std::vector<std::string>& args, std::size_t& i)>;

/// Parses a command's arguments of the form INPUT --out DIR [options]:
/// INPUT, --out and --help here, the others through @a option; then checks
/// that INPUT (named @a inputName in messages) and --out are there (unless
/// --help). Returns an error text for the usage message, or nothing.
std::optional<std::string> parseInputOutputCommand(const std::vector<std::string>& args, std::filesystem::path& input,
                                                   std::filesystem::path& out, bool& help, const CommandOption& option,
                                                   const char* inputName);

/// parseInputOutputCommand() for a CT command, which also takes --series.
std::optional<std::string> parseCtCommand(const std::vector<std::string>& args, CtCommandArgs& parsed,
                                          const CommandOption& option);

/// Creates the output folder of a command.
/// @throws std::runtime_error naming it when it cannot be made.
void makeOutputFolder(const std::filesystem::path& folder);

/// Parses a command's arguments into its Args; an error text, or nothing.
template <class Args>
using CommandParser = std::function<std::optional<std::string>(const std::vector<std::string>& argv, Args& args)>;

/// Runs command `caps NAME` as every command runs: @a parse reads @a argv
/// (its error text goes to @a err with the usage: exit status 2); with
/// --help (Args::help) the usage goes to @a out (0); otherwise @a run, whose
/// exit status is the command's, and whose exception is printed as
/// "caps NAME: what" (1).
template <class Args>
int runCommand(const std::string& name, const std::string& usage, const std::vector<std::string>& argv,
               std::ostream& out, std::ostream& err, const CommandParser<Args>& parse,
               const std::function<int(Args& args)>& run)
{
  Args args;
  if (auto problem = parse(argv, args))
  {
    err << "caps " << name << ": " << *problem << "\n" << usage;
    return 2;
  }
  if (args.help)
  {
    out << usage;
    return 0;
  }
  try
  {
    return run(args);
  }
  catch (const std::exception& e)
  {
    err << "caps " << name << ": " << e.what() << "\n";
    return 1;
  }
}

/// Parses `--series N|UID` into @a options (N counts from 1); an error text on failure.
std::optional<std::string> parseSeries(const std::string& value, seg::CtReadOptions& options);

/// Parses a number; false when @a text is not one.
bool parseNumber(const std::string& text, double& value);

/// Progress for a terminal: one line on @a err per step, with the percentage
/// and the seconds since the callback was made.
TaskProgress consoleProgress(std::ostream& err);

/// Reads the CT at @a path into @a logic's scene (reusing a volume already
/// read from it), printing the reader's warnings on @a err.
VolumeNode* loadCt(ModuleLogic& logic, const std::filesystem::path& path, const seg::CtReadOptions& options,
                   std::ostream& err);

/// Writes a triangle surface as binary STL (mm, patient LPS).
/// @throws std::runtime_error naming the file when it cannot be written.
void writeStl(vtkPolyData* surface, const std::filesystem::path& file);

} // namespace cli
} // namespace caps
