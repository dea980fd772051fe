#include "planning/ProcedureTemplate.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <regex>
#include <set>
#include <sstream>

#include <Eigen/Geometry>

namespace fs = std::filesystem;

namespace caps::planning {
namespace {

constexpr double pi = 3.14159265358979323846;
constexpr double degree = pi / 180.0;
/// Facial skin is undermined a few centimetres from the wound at most;
/// beyond that the gain in closure is small and the flap's blood supply at
/// risk. A file asking for more by default is taken for a mistake.
constexpr double kWidestDefaultUndermining = 40.0;

using Values = std::map<std::string, double>;

/// A cut-path generator: the topology of a procedure in C++, its geometry
/// set by the file's parameters. Generators rather than point expressions
/// in the files: the topology (which points are twins, which sides open for
/// an excision) is what the sutures refer to, so it must not drift with the
/// parameters, and a handful of shapes covers the procedures of §2.1.
struct Generator
{
  std::string name;
  /// Parameters the file must declare, with their unit; alternatives
  /// ("ratio|width") mean exactly one of them.
  std::vector<std::pair<std::string, ParameterUnit>> required;
  int fixedPoints = 0; ///< path points; 0: the file's "points" key (ellipse)
  std::function<ProcedureCut(const Values&, int points)> build;
};

ChartPoint polar(double length, double angle)
{
  return {length * std::cos(angle), length * std::sin(angle)};
}

/// A cut with no excision: every border point on its cut point.
ProcedureCut slit(std::vector<ChartPoint> path)
{
  ProcedureCut cut;
  cut.offsets.assign(holeLoopSize(int(path.size())), ChartPoint::Zero());
  cut.path = std::move(path);
  return cut;
}

/// Elliptical excision (§2.1, Fig. 2.1; the simple excision of Fig. 4.12):
/// the cut runs along the major axis and its two sides open into the
/// ellipse. Border points sit at equal steps of the ellipse's parameter, so
/// the hole is the inscribed polygon of area (N/2)·a·b·sin(2π/N), N = 2(n−1).
ProcedureCut ellipse(const Values& v, int n)
{
  const double a = 0.5 * v.at("length");
  const double b = 0.5 * (v.count("width") ? v.at("width") : v.at("length") / v.at("ratio"));
  std::vector<ChartPoint> path;
  for (int i = 0; i < n; ++i)
    path.emplace_back(a * std::cos(pi * (1.0 - double(i) / (n - 1))), 0.0);
  ProcedureCut cut = slit(path);
  for (int i = 1; i + 1 < n; ++i)
  {
    const double h = b * std::sin(pi * (1.0 - double(i) / (n - 1)));
    cut.offsets[i] = {0.0, h};                      // left side of the cut opens to the left
    cut.offsets[rightSideVertex(i, n)] = {0.0, -h}; // and its twin to the right
  }
  return cut;
}

/// Z-plasty (§2.1, Fig. 2.2; Fig. 4.11): limbs as long as the central limb
/// (Fig. 2.2: "the limbs of the Z must be equal in length to the central
/// member"), leaving its ends at limb_angle on opposite sides. p0's limb
/// leaves p1 on the left of the central limb p1→p2: with the hole loop of
/// Fig. 4.11 that is the Z the thesis's sutures ((5,0),(5,4)), ((2,1),(2,3)),
/// ((0,1),(3,4)) transpose.
ProcedureCut zPlasty(const Values& v, int)
{
  const double length = v.at("central_length"), alpha = v.at("limb_angle");
  const ChartPoint p1(-0.5 * length, 0.0), p2(0.5 * length, 0.0);
  return slit({p1 + polar(length, alpha), p1, p2, p2 - polar(length, alpha)});
}

/// Z-plasty with excision of the central member (the thesis's second
/// procedure, §4.1, Fig. 2.3, Fig. 5.3–5.4): the scar along the central limb
/// is excised as a rhombus of width excision_width, each member of the Z is
/// cut in two segments so the flaps can be shaped, and the flaps are
/// transposed as in the Z-plasty.
ProcedureCut zWithExcision(const Values& v, int)
{
  const double length = v.at("central_length"), alpha = v.at("limb_angle");
  const double halfWidth = 0.5 * v.at("excision_width");
  const ChartPoint p2(-0.5 * length, 0.0), p4(0.5 * length, 0.0);
  const ChartPoint p0 = p2 + polar(length, alpha), p6 = p4 - polar(length, alpha);
  ProcedureCut cut = slit({p0, 0.5 * (p0 + p2), p2, ChartPoint(0.0, 0.0), p4, 0.5 * (p4 + p6), p6});
  cut.offsets[3] = {0.0, halfWidth};
  cut.offsets[rightSideVertex(3, 7)] = {0.0, -halfWidth};
  return cut;
}

/// Rhomboid (Limberg) flap [42]: a 60°/120° rhombus A B C D of side s is
/// excised (long diagonal A→C along the axis, centred on the placement
/// point); the flap is cut by extending the short diagonal B→D by s to E and
/// drawing E→F parallel to D→C, length s. The cut runs F, E, D, centre, B;
/// the centre's two sides open to A (left) and C (right).
ProcedureCut rhomboid(const Values& v, int)
{
  const double s = v.at("side_length");
  const double h = 0.5 * std::sqrt(3.0) * s; // half the long diagonal
  const ChartPoint a(-h, 0.0), b(0.0, 0.5 * s), c(h, 0.0), d(0.0, -0.5 * s);
  const ChartPoint e = d + (d - b), f = e + (c - d);
  ProcedureCut cut = slit({f, e, d, ChartPoint(0.0, 0.0), b});
  cut.offsets[3] = a;
  cut.offsets[rightSideVertex(3, 5)] = c;
  return cut;
}

/// V-Y advancement: a V with its apex behind the placement point and its
/// arms opening along the axis at ±apex_angle/2, each arm cut in three
/// segments. The flap inside the V advances along the axis; the skin behind
/// it closes into the stem of the Y.
ProcedureCut vy(const Values& v, int)
{
  const double arm = v.at("arm_length"), half = 0.5 * v.at("apex_angle");
  const ChartPoint apex(-0.5 * arm * std::cos(half), 0.0);
  const ChartPoint end0 = apex + polar(arm, half), end6 = apex + polar(arm, -half);
  std::vector<ChartPoint> path;
  for (int i = 0; i < 3; ++i)
    path.push_back(apex + (end0 - apex) * (double(3 - i) / 3.0));
  for (int i = 0; i <= 3; ++i)
    path.push_back(apex + (end6 - apex) * (double(i) / 3.0));
  return slit(path);
}

const std::vector<Generator>& generators()
{
  using U = ParameterUnit;
  static const std::vector<Generator> table = {
    {"ellipse", {{"length", U::Millimetre}, {"ratio|width", U::Ratio}, {"axis_angle", U::Degree}}, 0, ellipse},
    {"z", {{"central_length", U::Millimetre}, {"limb_angle", U::Degree}, {"axis_angle", U::Degree}}, 4, zPlasty},
    {"multiple-z",
     {{"central_length", U::Millimetre},
      {"limb_angle", U::Degree},
      {"excision_width", U::Millimetre},
      {"axis_angle", U::Degree}},
     7,
     zWithExcision},
    {"rhomboid", {{"side_length", U::Millimetre}, {"axis_angle", U::Degree}}, 5, rhomboid},
    {"v-y", {{"arm_length", U::Millimetre}, {"apex_angle", U::Degree}, {"axis_angle", U::Degree}}, 7, vy},
  };
  return table;
}

const Generator* findGenerator(const std::string& name)
{
  for (const auto& g : generators())
    if (g.name == name)
      return &g;
  return nullptr;
}

std::string trim(const std::string& s)
{
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos)
    return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

const char* unitName(ParameterUnit u)
{
  switch (u)
  {
  case ParameterUnit::Millimetre:
    return "mm";
  case ParameterUnit::Degree:
    return "deg";
  case ParameterUnit::Ratio:
    return "ratio";
  }
  return "?";
}

/// A value in the file's units, for messages.
std::string shownValue(const ProcedureParameter& p, double apiValue)
{
  std::ostringstream o;
  o.precision(6);
  if (p.unit == ParameterUnit::Degree)
    o << apiValue / degree << "°";
  else if (p.unit == ParameterUnit::Millimetre)
    o << apiValue << " mm";
  else
    o << apiValue;
  return o.str();
}

double toApi(ParameterUnit u, double v)
{
  return u == ParameterUnit::Degree ? v * degree : v;
}

/// What a procedure file says, line by line, before the whole-file checks.
struct ProcedureFile
{
  fs::path file;
  std::string id, title, reference, generator;
  int pointsLine = 0, generatorLine = 0, explicitPoints = 0;
  std::vector<ProcedureParameter> parameters;
  std::vector<SutureEdges> written;
  std::vector<int> sutureLines;                          // file line of each written suture
  std::vector<std::string> sutureNames;                  // the wound line each one closes ("" unnamed)
  std::vector<std::pair<int, std::pair<int, int>>> zips; // line, (from, to) cut points
  std::vector<std::string> zipNames;
  DefaultUndermining undermining;
  CutDepth depth = CutDepth::Bone;
  std::map<std::string, int> seenKeys;
};

void readId(ProcedureFile& read, int lineNo, const std::string& value)
{
  static const std::regex idRe(R"(^[a-z0-9][a-z0-9-]*$)");
  if (!std::regex_match(value, idRe))
    throw ProcedureFileError(read.file, lineNo,
                             "procedure id '" + value + "' must be lower case letters, digits and '-' (e.g. z-plasty)");
  read.id = value;
}

void readGenerator(ProcedureFile& read, int lineNo, const std::string& value)
{
  if (!findGenerator(value))
  {
    std::string known;
    for (const auto& g : procedureGenerators())
      known += (known.empty() ? "" : ", ") + g;
    throw ProcedureFileError(read.file, lineNo, "unknown generator '" + value + "'; known: " + known);
  }
  read.generator = value;
  read.generatorLine = lineNo;
}

void readPoints(ProcedureFile& read, int lineNo, const std::string& value)
{
  char* end = nullptr;
  const long n = std::strtol(value.c_str(), &end, 10);
  if (value.empty() || *end || n < 3 || n > 65)
    throw ProcedureFileError(read.file, lineNo, "points must be a whole number from 3 to 65, got '" + value + "'");
  read.explicitPoints = int(n);
  read.pointsLine = lineNo;
}

/// "param NAME = DEFAULT UNIT [MIN, MAX] label", in API units.
ProcedureParameter readParameter(const ProcedureFile& read, int lineNo, const std::string& paramName,
                                 const std::string& value)
{
  static const std::string number = R"(([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?))";
  static const std::regex paramRe("^" + number + R"(\s*(mm|deg|ratio)\s*\[\s*)" + number + R"(\s*,\s*)" + number +
                                  R"(\s*\]\s*(.*)$)");
  static const std::regex nameRe(R"(^[a-z][a-z0-9_]*$)");
  const fs::path& file = read.file;
  if (!std::regex_match(paramName, nameRe))
    throw ProcedureFileError(file, lineNo,
                             "parameter name '" + paramName + "' must be lower case letters, digits and '_'");
  std::smatch m;
  if (!std::regex_match(value, m, paramRe))
    throw ProcedureFileError(file, lineNo,
                             "parameter '" + paramName +
                               "': expected 'DEFAULT UNIT [MIN, MAX] label' with UNIT mm, deg "
                               "or ratio, e.g. '60 deg [30, 90] limb angle'");
  for (const auto& p : read.parameters)
    if (p.name == paramName)
      throw ProcedureFileError(
        file, lineNo, "parameter '" + paramName + "' is declared twice (first on line " + std::to_string(p.line) + ")");
  ProcedureParameter p;
  p.name = paramName;
  p.unit = m[2] == "mm" ? ParameterUnit::Millimetre : m[2] == "deg" ? ParameterUnit::Degree : ParameterUnit::Ratio;
  const double def = std::stod(m[1]), lo = std::stod(m[3]), hi = std::stod(m[4]);
  if (!(lo < hi))
    throw ProcedureFileError(file, lineNo,
                             "parameter '" + paramName + "': the range [" + std::string(m[3]) + ", " +
                               std::string(m[4]) + "] is empty; write [MIN, MAX] with MIN < MAX");
  if (def < lo || def > hi)
    throw ProcedureFileError(file, lineNo,
                             "parameter '" + paramName + "': the default " + std::string(m[1]) +
                               " is outside its range [" + std::string(m[3]) + ", " + std::string(m[4]) + "]");
  if (p.unit != ParameterUnit::Degree && lo <= 0.0)
    throw ProcedureFileError(file, lineNo,
                             "parameter '" + paramName +
                               "': lengths and ratios must be positive; "
                               "the range starts at " +
                               std::string(m[3]));
  p.defaultValue = toApi(p.unit, def);
  p.minimum = toApi(p.unit, lo);
  p.maximum = toApi(p.unit, hi);
  p.label = m[5];
  p.line = lineNo;
  return p;
}

/// 'EDGES : NAME': the suture's edges and the wound line it closes, in
/// the surgeon's words ("" when the file gives none).
std::pair<std::string, std::string> withWoundLineName(const std::string& value)
{
  const auto colon = value.find(':');
  if (colon == std::string::npos)
    return {value, ""};
  return {trim(value.substr(0, colon)), trim(value.substr(colon + 1))};
}

void readSuture(ProcedureFile& read, int lineNo, const std::string& line)
{
  const auto [value, name] = withWoundLineName(line);
  static const std::regex edgePairRe(R"(^\(?\s*\(\s*(\d+)\s*,\s*(\d+)\s*\)\s*,?\s*\(\s*(\d+)\s*,\s*(\d+)\s*\)\s*\)?$)");
  std::smatch m;
  if (!std::regex_match(value, m, edgePairRe))
    throw ProcedureFileError(read.file, lineNo,
                             "expected a pair of border edges like '(5,0) (5,4)' or "
                             "'((5,0),(5,4))', got '" +
                               value + "'");
  read.written.push_back({{std::stoi(m[1]), std::stoi(m[2])}, {std::stoi(m[3]), std::stoi(m[4])}});
  read.sutureLines.push_back(lineNo);
  read.sutureNames.push_back(name);
}

/// Kept as written: its range can only be checked once the cut's points are known.
void readZip(ProcedureFile& read, int lineNo, const std::string& line)
{
  const auto [value, name] = withWoundLineName(line);
  static const std::regex zipRe(R"(^(\d+)\s+(\d+)$)");
  std::smatch m;
  if (!std::regex_match(value, m, zipRe) || std::stoi(m[1]) >= std::stoi(m[2]))
    throw ProcedureFileError(read.file, lineNo,
                             "expected 'zip = FIRST LAST' with two cut point numbers, FIRST < "
                             "LAST, got '" +
                               value + "'");
  read.zips.push_back({lineNo, {std::stoi(m[1]), std::stoi(m[2])}});
  read.zipNames.push_back(name);
}

/// 'undermining = band W mm', 'band F PARAM' or 'band F PARAM + W mm':
/// the parameter is checked once all are read.
void readUndermining(ProcedureFile& read, int lineNo, const std::string& value)
{
  static const std::regex millimetresRe(R"(^band\s+([0-9]*\.?[0-9]+)\s*mm$)");
  static const std::regex scaledRe(
    R"(^band\s+([0-9]*\.?[0-9]+)\s+([a-z_][a-z0-9_]*)(\s*\+\s*([0-9]*\.?[0-9]+)\s*mm)?$)");
  std::smatch m;
  DefaultUndermining& u = read.undermining;
  if (std::regex_match(value, m, millimetresRe))
    u.millimetres = std::stod(m[1]);
  else if (std::regex_match(value, m, scaledRe))
  {
    u.factor = std::stod(m[1]);
    u.parameter = m[2];
    u.millimetres = m[4].matched ? std::stod(m[4]) : 0.0;
  }
  else
    throw ProcedureFileError(read.file, lineNo,
                             "expected 'undermining = band W mm', 'band F PARAMETER' or 'band F PARAMETER + W mm' "
                             "(the band along the sutured edges), got '" +
                               value + "'");
  u.line = lineNo;
}

/// One non-blank, non-comment line: 'key = value', where "param NAME" keys
/// carry the parameter's name.
void readLine(ProcedureFile& read, int lineNo, const std::string& line)
{
  const fs::path& file = read.file;
  const auto eq = line.find('=');
  if (eq == std::string::npos)
    throw ProcedureFileError(file, lineNo, "expected 'key = value', got '" + line + "'");
  std::string key = trim(line.substr(0, eq));
  const std::string value = trim(line.substr(eq + 1));
  std::string paramName;
  if (key.rfind("param", 0) == 0 && key.size() > 5 && (key[5] == ' ' || key[5] == '\t'))
  {
    paramName = trim(key.substr(5));
    key = "param";
  }
  const bool repeatable = key == "param" || key == "suture" || key == "zip";
  if (!repeatable && read.seenKeys.count(key))
    throw ProcedureFileError(file, lineNo,
                             "'" + key + "' is given twice (first on line " + std::to_string(read.seenKeys[key]) + ")");
  read.seenKeys.emplace(key, lineNo);
  if (key == "procedure")
    readId(read, lineNo, value);
  else if (key == "title")
    read.title = value;
  else if (key == "reference")
    read.reference = value;
  else if (key == "generator")
    readGenerator(read, lineNo, value);
  else if (key == "points")
    readPoints(read, lineNo, value);
  else if (key == "param")
    read.parameters.push_back(readParameter(read, lineNo, paramName, value));
  else if (key == "suture")
    readSuture(read, lineNo, value);
  else if (key == "zip")
    readZip(read, lineNo, value);
  else if (key == "undermining")
    readUndermining(read, lineNo, value);
  else if (key == "depth")
  {
    const std::optional<CutDepth> depth = cutDepthFromId(value);
    if (!depth)
      throw ProcedureFileError(file, lineNo,
                               "expected 'depth = fascia' (through the skin and fat, raised on the fascia) or "
                               "'depth = bone' (through every layer, raised on the periosteum), got '" +
                                 value + "'");
    read.depth = *depth;
  }
  else
    throw ProcedureFileError(file, lineNo,
                             "unknown key '" + key +
                               "'; known: procedure, title, reference, generator, points, param, "
                               "suture, zip, undermining, depth");
}

/// Every line of the file, each checked on its own.
ProcedureFile readProcedureFile(const fs::path& file)
{
  std::ifstream in(file);
  if (!in)
    throw ProcedureFileError(file, 0, "cannot be read");
  ProcedureFile read;
  read.file = file;
  std::string raw;
  int lineNo = 0;
  while (std::getline(in, raw))
  {
    ++lineNo;
    const std::string line = trim(raw);
    if (line.empty() || line[0] == '#')
      continue;
    readLine(read, lineNo, line);
  }
  return read;
}

void checkRequiredKeys(const ProcedureFile& read)
{
  for (const char* key : {"procedure", "generator"})
    if (!read.seenKeys.count(key))
      throw ProcedureFileError(read.file, 0, std::string("'") + key + " = ...' is missing");
}

/// The generator's own count, or the file's for generators that take one.
int cutPoints(const ProcedureFile& read, const Generator& g)
{
  if (g.fixedPoints > 0)
  {
    if (read.explicitPoints && read.explicitPoints != g.fixedPoints)
      throw ProcedureFileError(read.file, read.pointsLine,
                               "the '" + g.name + "' generator cuts " + std::to_string(g.fixedPoints) +
                                 " points, not " + std::to_string(read.explicitPoints));
    return g.fixedPoints;
  }
  if (!read.explicitPoints)
    throw ProcedureFileError(read.file, read.generatorLine,
                             "the '" + g.name + "' generator needs 'points = N' (cut points)");
  return read.explicitPoints;
}

/// The file declares exactly the generator's parameters, in their units.
void checkParameters(const ProcedureTemplate& t, const Generator& g, int generatorLine)
{
  const fs::path& file = t.file();
  std::set<std::string> expected;
  for (const auto& [names, unit] : g.required)
  {
    std::vector<const ProcedureParameter*> found;
    std::stringstream alternatives(names);
    for (std::string name; std::getline(alternatives, name, '|');)
    {
      expected.insert(name);
      if (const ProcedureParameter* p = t.parameter(name))
        found.push_back(p);
    }
    if (found.size() != 1)
      throw ProcedureFileError(
        file, found.empty() ? generatorLine : found[1]->line,
        "the '" + g.name + "' generator needs " +
          (names.find('|') == std::string::npos ? "parameter '" + names + "'" : "exactly one of '" + names + "'"));
    const ProcedureParameter& p = *found[0];
    const ParameterUnit want = p.name == "width" ? ParameterUnit::Millimetre : unit;
    if (p.unit != want)
      throw ProcedureFileError(
        file, p.line, "parameter '" + p.name + "' is measured in " + unitName(want) + ", not " + unitName(p.unit));
  }
  for (const auto& p : t.parameters())
    if (!expected.count(p.name))
      throw ProcedureFileError(file, p.line, "the '" + g.name + "' generator has no parameter '" + p.name + "'");
}

/// Appends each zip's sutures to the written ones, with the zip's line.
void expandZips(ProcedureFile& read, int pathPoints)
{
  for (std::size_t z = 0; z < read.zips.size(); ++z)
  {
    const auto& [line, range] = read.zips[z];
    if (range.second >= pathPoints)
      throw ProcedureFileError(read.file, line,
                               "zip to cut point " + std::to_string(range.second) + ", but the cut has " +
                                 std::to_string(pathPoints) + " points (0.." + std::to_string(pathPoints - 1) + ")");
    // The two sides of the cut between the two points, sewn back together.
    for (int i = range.first; i < range.second; ++i)
    {
      read.written.push_back({{i, i + 1}, {rightSideVertex(i, pathPoints), rightSideVertex(i + 1, pathPoints)}});
      read.sutureLines.push_back(line);
      read.sutureNames.push_back(read.zipNames[z]);
    }
  }
}

/// A suture error points at the file line that wrote the offending suture.
std::vector<fem::SutureEdgePair> resolvedSutures(const ProcedureTemplate& t, const std::vector<int>& sutureLines)
{
  if (t.writtenSutures().empty())
    throw ProcedureFileError(t.file(), 0, "no sutures: give 'suture = (a,b) (c,d)' or 'zip = FIRST LAST' lines");
  try
  {
    return resolveSutures(t.holeVertices(), t.writtenSutures());
  }
  catch (const SutureError& e)
  {
    const int line = e.suture() >= 0 ? sutureLines[e.suture()] : 0;
    throw ProcedureFileError(t.file(), line,
                             std::string(e.what()) + " (the hole of a " + std::to_string(t.pathPoints()) +
                               "-point cut has border points 0.." + std::to_string(t.holeVertices() - 1) + ")");
  }
}

/// The default cut must be a valid hole: distinct points, sides not swapped.
void checkDefaultCut(const ProcedureTemplate& t, int generatorLine)
{
  try
  {
    const ProcedureCut cut = t.cut(t.resolveValues({}));
    const fem::HoleLoop loop = makeHoleLoop(cut.path, cut.offsets);
    double twiceArea = 0.0;
    for (size_t e = 0; e < loop.points.size(); ++e)
    {
      const auto& p = loop.points[e];
      const auto& q = loop.points[(e + 1) % loop.points.size()];
      twiceArea += p.x() * q.y() - p.y() * q.x();
    }
    for (size_t i = 0; i + 1 < cut.path.size(); ++i)
      if ((cut.path[i + 1] - cut.path[i]).norm() < 1e-6)
        throw std::invalid_argument("cut points " + std::to_string(i) + " and " + std::to_string(i + 1) +
                                    " coincide with the default parameters");
    if (twiceArea > 1e-9)
      throw std::invalid_argument("with the default parameters the hole runs counter-clockwise");
  }
  catch (const std::invalid_argument& e)
  {
    throw ProcedureFileError(t.file(), generatorLine, e.what());
  }
}

} // namespace

ProcedureFileError::ProcedureFileError(const fs::path& file, int line, const std::string& message)
  : std::runtime_error(file.string() + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + message),
    file_(file), line_(line)
{}

std::vector<std::string> procedureGenerators()
{
  std::vector<std::string> names;
  for (const auto& g : generators())
    names.push_back(g.name);
  return names;
}

namespace {

/// The band's parameter is one of the procedure's lengths, and the band at
/// the defaults is no wider than an undermining on the face can be.
DefaultUndermining checkedUndermining(const ProcedureTemplate& t, const DefaultUndermining& u)
{
  if (!u.parameter.empty())
  {
    const ProcedureParameter* p = t.parameter(u.parameter);
    if (!p || p->unit != ParameterUnit::Millimetre)
      throw ProcedureFileError(t.file(), u.line,
                               "the undermining band is scaled by '" + u.parameter +
                                 "', which is not a length (mm) parameter of this procedure");
  }
  const double atDefaults = u.width(t.resolveValues({}));
  if (atDefaults > kWidestDefaultUndermining)
    throw ProcedureFileError(t.file(), u.line,
                             "the undermining band is " + std::to_string(atDefaults) +
                               " mm wide at the default parameters; the face is rarely undermined more than " +
                               std::to_string(int(kWidestDefaultUndermining)) + " mm from the wound");
  return u;
}

} // namespace

ProcedureTemplate ProcedureTemplate::load(const fs::path& file)
{
  ProcedureFile read = readProcedureFile(file);

  // Whole-file checks: what must be there, and whether it fits together.
  checkRequiredKeys(read);
  // The template first, so the checks can use its own lookups (parameter(), cut()).
  ProcedureTemplate t;
  t.file_ = file;
  t.id_ = read.id;
  t.title_ = read.title.empty() ? read.id : read.title;
  t.reference_ = read.reference;
  t.generator_ = read.generator;
  t.parameters_ = std::move(read.parameters);
  const Generator& g = *findGenerator(t.generator_);
  t.pathPoints_ = cutPoints(read, g);
  checkParameters(t, g, read.generatorLine);
  expandZips(read, t.pathPoints_);
  t.written_ = std::move(read.written);
  t.sutures_ = resolvedSutures(t, read.sutureLines);
  t.woundLineNames_ = std::move(read.sutureNames);
  checkDefaultCut(t, read.generatorLine);
  t.undermining_ = checkedUndermining(t, read.undermining);
  t.depth_ = read.depth;
  return t;
}

double DefaultUndermining::width(const std::map<std::string, double>& values) const
{
  if (parameter.empty())
    return millimetres;
  const auto it = values.find(parameter);
  return millimetres + factor * (it == values.end() ? 0.0 : it->second);
}

const ProcedureParameter* ProcedureTemplate::parameter(const std::string& name) const
{
  for (const auto& p : parameters_)
    if (p.name == name)
      return &p;
  return nullptr;
}

std::map<std::string, double> ProcedureTemplate::resolveValues(const std::map<std::string, double>& values) const
{
  std::map<std::string, double> result;
  for (const auto& p : parameters_)
    result[p.name] = p.defaultValue;
  for (const auto& [name, value] : values)
  {
    const ProcedureParameter* p = parameter(name);
    if (!p)
    {
      std::string known;
      for (const auto& q : parameters_)
        known += (known.empty() ? "" : ", ") + q.name;
      throw std::invalid_argument(title_ + " has no parameter '" + name + "'; its parameters: " + known);
    }
    // Half a micro-unit of slack so a value typed in degrees at the limit passes.
    const double slack = 1e-9 * std::max(1.0, std::abs(p->maximum - p->minimum));
    if (!std::isfinite(value) || value < p->minimum - slack || value > p->maximum + slack)
      throw std::invalid_argument(title_ + ": " + name + " = " + shownValue(*p, value) + " is outside its range " +
                                  shownValue(*p, p->minimum) + " to " + shownValue(*p, p->maximum) + " (" +
                                  file_.filename().string() + ")");
    result[name] = value;
  }
  return result;
}

ProcedureCut ProcedureTemplate::cut(const std::map<std::string, double>& values) const
{
  return findGenerator(generator_)->build(values, pathPoints_);
}

IncisionPlan ProcedureTemplate::place(const seg::RangeMap& skin, const SkinPoint& at,
                                      const std::map<std::string, double>& values) const
{
  const Values v = resolveValues(values);
  ProcedureCut local = cut(v);
  const double phi = v.at("axis_angle");
  const Eigen::Matrix2d rotation = Eigen::Rotation2Dd(phi).toRotationMatrix();
  const SkinChart chart(skin, at.theta, at.z);
  std::vector<Eigen::Vector2d> path;
  for (const auto& p : local.path)
    path.push_back(chart.toNormalized(rotation * p));
  IncisionPlan plan(std::move(path), {chart.centreTheta(), chart.centreZ()});
  plan.setProcedure(id_);
  plan.setGenerator(generator_);
  plan.setParameters(v);
  for (int vertex = 0; vertex < int(local.offsets.size()); ++vertex)
    if (!local.offsets[vertex].isZero())
      plan.offsetBorderPoint(vertex, rotation * local.offsets[vertex]);
  plan.setSutures(written_, woundLineNames_);
  plan.setUnderminingBand(undermining_.width(v));
  plan.setCutDepth(depth_);
  checkPlan(plan, skin);
  return plan;
}

ProcedureLibrary ProcedureLibrary::load(const fs::path& folder)
{
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    throw std::runtime_error("the procedures folder " + folder.string() +
                             " does not exist; set CAPS_DATA_DIR to the data folder of the CAPS sources");
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder))
    if (entry.is_regular_file() && entry.path().extension() == ".procedure")
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  ProcedureLibrary library;
  for (const auto& file : files)
  {
    try
    {
      ProcedureTemplate t = ProcedureTemplate::load(file);
      if (const ProcedureTemplate* other = library.find(t.id()))
        throw ProcedureFileError(
          file, 0, "procedure '" + t.id() + "' is already defined by " + other->file().filename().string());
      library.procedures_.push_back(std::move(t));
    }
    catch (const ProcedureFileError& e)
    {
      library.errors_.push_back(e.what());
    }
  }
  return library;
}

const ProcedureTemplate* ProcedureLibrary::find(const std::string& id) const
{
  for (const auto& t : procedures_)
    if (t.id() == id)
      return &t;
  return nullptr;
}

fs::path defaultProceduresFolder()
{
  if (const char* env = std::getenv("CAPS_DATA_DIR"))
    return fs::path(env) / "procedures";
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec)
  {
    const fs::path installed = exe.parent_path().parent_path() / "share" / "caps" / "data" / "procedures";
    if (fs::is_directory(installed, ec))
      return installed;
  }
  return fs::path(CAPS_SOURCE_DATA_DIR) / "procedures";
}

} // namespace caps::planning
