#pragma once
/// @file ProcedureTemplate.h
/// @brief Surgical procedures as text files in data/procedures/ (§4.1:
/// "adding new types of surgeries is done by creating a text file which
/// describes the suture connections needed for that procedure").
///
/// A file names a cut-path generator (its topology), gives the generator's
/// parameters with defaults and valid ranges, and lists the sutures as pairs
/// of hole-border edges in the thesis's notation (§4.4.5). The format is
/// documented in data/procedures/README.md.

#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "planning/IncisionPlan.h"

namespace caps::planning {

/// A procedure file that cannot be used; what() is "FILE:LINE: what is wrong".
class ProcedureFileError : public std::runtime_error
{
public:
  ProcedureFileError(const std::filesystem::path& file, int line, const std::string& message);
  const std::filesystem::path& file() const { return file_; }
  int line() const { return line_; } ///< 1-based; 0 when the file as a whole is at fault

private:
  std::filesystem::path file_;
  int line_;
};

/// How a parameter is measured: the file and the UI use mm, degrees and
/// plain ratios; the API uses mm, radians and ratios (DESIGN.md conventions).
enum class ParameterUnit
{
  Millimetre,
  Degree,
  Ratio
};

/// One parameter of a procedure, in API units (mm, radians, ratio).
struct ProcedureParameter
{
  std::string name; ///< "limb_angle"
  ParameterUnit unit = ParameterUnit::Millimetre;
  double defaultValue = 0.0;
  double minimum = 0.0;
  double maximum = 0.0;
  std::string label; ///< what it is, for the surgeon
  int line = 0;      ///< where the file declares it
};

/// The cut of a procedure in its own chart frame, before placement: x along
/// the procedure's axis, y to its left, millimetres.
struct ProcedureCut
{
  std::vector<ChartPoint> path;    ///< cut points in scalpel order
  std::vector<ChartPoint> offsets; ///< per hole-loop vertex (§4.4.4), holeLoopSize() long
};

/// The undermining a procedure states by default (thesis §3.2.2, §3.2.4
/// item 2): a band along the sutured edges, `millimetres` wide plus
/// `factor` times the length parameter `parameter` (if named), so the band
/// grows with the procedure.
struct DefaultUndermining
{
  double millimetres = 0.0;
  double factor = 0.0;
  std::string parameter; ///< a length (mm) parameter of the procedure, or empty
  int line = 0;          ///< where the file states it; 0: not stated (no undermining)

  /// The band's width (mm) for complete parameter values (API units).
  double width(const std::map<std::string, double>& values) const;
};

/// @class ProcedureTemplate
/// @brief One procedure read from its file: generator, parameters, sutures.
class ProcedureTemplate
{
public:
  /// Reads and validates one file.
  /// @throws ProcedureFileError naming the file and line at fault.
  static ProcedureTemplate load(const std::filesystem::path& file);

  const std::string& id() const { return id_; }       ///< "z-plasty"
  const std::string& title() const { return title_; } ///< "Z-plasty"
  const std::string& reference() const { return reference_; }
  const std::string& generator() const { return generator_; } ///< "z", "ellipse", ...
  const std::filesystem::path& file() const { return file_; }
  int pathPoints() const { return pathPoints_; }
  int holeVertices() const { return holeLoopSize(pathPoints_); }
  const std::vector<ProcedureParameter>& parameters() const { return parameters_; }
  const ProcedureParameter* parameter(const std::string& name) const;
  /// Sutures as written in the file (zip lines expanded) and resolved.
  const std::vector<SutureEdges>& writtenSutures() const { return written_; }
  const std::vector<fem::SutureEdgePair>& sutures() const { return sutures_; }
  /// Per written suture, the wound line it closes in the surgeon's words
  /// (the file's `suture = EDGES : NAME`, a zip's name for each of its
  /// sutures); "" where the file names none.
  const std::vector<std::string>& woundLineNames() const { return woundLineNames_; }
  /// What the procedure undermines unless the surgeon says otherwise.
  const DefaultUndermining& undermining() const { return undermining_; }
  /// How deep it cuts and where it raises the undermined tissue (the file's
  /// `depth`; the thesis's full thickness when the file says nothing).
  CutDepth depth() const { return depth_; }

  /// Defaults overridden by values (API units); every parameter filled in.
  /// @throws std::invalid_argument for an unknown name or a value out of range.
  std::map<std::string, double> resolveValues(const std::map<std::string, double>& values) const;
  /// The cut in the procedure's frame, for complete values (resolveValues()).
  ProcedureCut cut(const std::map<std::string, double>& values) const;

  /// The plan of this procedure centred at a skin point: the cut rotated by
  /// its axis_angle parameter (from the direction of increasing θ towards
  /// increasing z, i.e. towards superior) in the chart about that point,
  /// stored in normalised cylindrical coordinates, with the sutures, the
  /// procedure's default undermining (IncisionPlan::underminingBand()) and
  /// its depth (IncisionPlan::cutDepth()).
  /// @throws std::invalid_argument for bad values or when the cut does not
  /// fit on the measured skin (checkPlan()).
  IncisionPlan place(const seg::RangeMap& skin, const SkinPoint& at,
                     const std::map<std::string, double>& values = {}) const;

private:
  std::filesystem::path file_;
  std::string id_, title_, reference_, generator_;
  int pathPoints_ = 0;
  std::vector<ProcedureParameter> parameters_;
  std::vector<SutureEdges> written_;
  std::vector<fem::SutureEdgePair> sutures_;
  std::vector<std::string> woundLineNames_;
  DefaultUndermining undermining_;
  CutDepth depth_ = CutDepth::Bone;
};

/// The cut generators a procedure file can name: "ellipse", "z",
/// "multiple-z", "rhomboid", "v-y".
std::vector<std::string> procedureGenerators();

/// @class ProcedureLibrary
/// @brief Every procedure file (*.procedure) of a folder.
///
/// A bad file does not stop the others: it is left out and its error kept
/// in errors(), so the workstation can show it.
class ProcedureLibrary
{
public:
  /// @throws std::runtime_error when the folder does not exist.
  static ProcedureLibrary load(const std::filesystem::path& folder);

  const std::vector<ProcedureTemplate>& procedures() const { return procedures_; }
  /// nullptr when there is no procedure of that id.
  const ProcedureTemplate* find(const std::string& id) const;
  /// One "FILE:LINE: message" per file left out.
  const std::vector<std::string>& errors() const { return errors_; }

private:
  std::vector<ProcedureTemplate> procedures_;
  std::vector<std::string> errors_;
};

/// The procedures folder: $CAPS_DATA_DIR/procedures, else
/// share/caps/data/procedures beside the installed executable, else the
/// source tree's data/procedures (as app/Paths.cpp finds the sample CT).
std::filesystem::path defaultProceduresFolder();

} // namespace caps::planning
