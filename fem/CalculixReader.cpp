#include "fem/CalculixReader.h"

#include "fem/ElementNumbering.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <set>
#include <span>
#include <string_view>
#include <system_error>
#include <unordered_map>

namespace caps::fem {

namespace {

std::string upper(std::string s)
{
  for (char& c : s)
    c = char(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

constexpr bool isSpace(char c)
{
  return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

std::string_view trimmed(std::string_view s)
{
  std::size_t b = 0, e = s.size();
  while (b < e && isSpace(s[b]))
    ++b;
  while (e > b && isSpace(s[e - 1]))
    --e;
  return s.substr(b, e - b);
}

std::string trim(const std::string& s)
{
  return std::string(trimmed(s));
}

/// The comma-separated fields of @a s, trimmed; a trailing comma gives a
/// last empty field; an empty line has none.
std::vector<std::string> split(const std::string& s)
{
  std::vector<std::string> out;
  if (s.empty())
    return out;
  const std::string_view v(s);
  std::size_t begin = 0;
  while (true)
  {
    const std::size_t comma = v.find(',', begin);
    out.emplace_back(
      trimmed(v.substr(begin, comma == std::string_view::npos ? std::string_view::npos : comma - begin)));
    if (comma == std::string_view::npos)
      break;
    begin = comma + 1;
  }
  return out;
}

/// One logical line: a keyword with its parameters, or a data line's fields.
struct Line
{
  int number = 0;
  std::string text;
};

class Parser
{
public:
  Parser(const std::string& text, std::string source, const CalculixReadOptions& options)
    : source_(std::move(source)), options_(options)
  {
    const std::string_view all(text);
    int number = 0;
    for (std::size_t at = 0; at < all.size();)
    {
      const std::size_t end = std::min(all.find('\n', at), all.size());
      const std::string_view raw = all.substr(at, end - at);
      at = end + 1;
      ++number;
      const std::string_view t = trimmed(raw);
      if (t.empty() || t.rfind("**", 0) == 0)
        continue;
      // A keyword line ending in a comma continues on the next line.
      if (!lines_.empty() && lines_.back().text[0] == '*' && lines_.back().text.back() == ',' && t[0] != '*')
      {
        lines_.back().text += t;
        continue;
      }
      lines_.push_back({number, std::string(t)});
    }
  }

  CalculixModel run()
  {
    std::size_t i = 0;
    while (i < lines_.size())
    {
      const Line& kw = lines_[i];
      if (kw.text[0] != '*')
        fail(kw.number, "data line outside a keyword: " + kw.text);
      std::vector<std::string> fields = split(kw.text);
      const std::string keyword = upper(fields[0]);
      std::map<std::string, std::string> params;
      for (std::size_t f = 1; f < fields.size(); ++f)
      {
        if (fields[f].empty())
          continue;
        const auto eq = fields[f].find('=');
        params[upper(trim(fields[f].substr(0, eq)))] =
          eq == std::string::npos ? "" : upper(trim(fields[f].substr(eq + 1)));
      }
      std::size_t end = i + 1;
      while (end < lines_.size() && lines_[end].text[0] != '*')
        ++end;
      const std::span<const Line> data(lines_.data() + i + 1, end - i - 1);
      line_ = kw.number;
      handle(keyword, params, data);
      i = end;
    }
    return finish();
  }

private:
  [[noreturn]] void fail(int line, const std::string& what) const { throw InputDeckError(source_, line, what); }

  double number(const std::string& s, int line) const
  {
    // The common case, a plain decimal: from_chars (correctly rounded, as strtod).
    double v = 0.0;
    const char* end = s.data() + s.size();
    if (auto r = std::from_chars(s.data(), end, v); r.ec == std::errc() && r.ptr == end && !s.empty())
      return v;
    // Fortran exponents (1.5D3), a leading '+', and the like: strtod's reading.
    std::string t = s;
    for (char& c : t)
      if (c == 'd' || c == 'D')
        c = 'e';
    char* stop = nullptr;
    v = std::strtod(t.c_str(), &stop);
    if (t.empty() || *stop != '\0')
      fail(line, "'" + s + "' is not a number");
    return v;
  }
  /// strtol's reading of @a s when all of it is read, false otherwise.
  static bool readInteger(const std::string& s, long& v)
  {
    const char* end = s.data() + s.size();
    if (auto r = std::from_chars(s.data(), end, v); r.ec == std::errc() && r.ptr == end && !s.empty())
      return true;
    char* stop = nullptr;
    v = std::strtol(s.c_str(), &stop, 10);
    return !s.empty() && *stop == '\0';
  }
  long integer(const std::string& s, int line) const
  {
    long v = 0;
    if (!readInteger(s, v))
      fail(line, "'" + s + "' is not an integer");
    return v;
  }
  /// True if @a s is wholly an integer: a node or element number, not a set
  /// name (set names may start with a digit, e.g. ELSET=1E).
  static bool isInteger(const std::string& s)
  {
    long v = 0;
    return readInteger(s, v);
  }

  std::string required(const std::map<std::string, std::string>& params, const std::string& name,
                       const std::string& keyword) const
  {
    auto it = params.find(name);
    if (it == params.end() || it->second.empty())
      fail(line_, keyword + " needs " + name + "=");
    return it->second;
  }

  /// Node numbers of a node number or NSET name.
  std::vector<long> nodesOf(const std::string& field, int line) const
  {
    if (isInteger(field))
      return {integer(field, line)};
    auto it = nsets_.find(upper(field));
    if (it == nsets_.end())
      fail(line, "unknown node set " + field);
    return it->second;
  }
  std::vector<long> elementsOf(const std::string& field, int line) const
  {
    if (isInteger(field))
      return {integer(field, line)};
    return elementSet(field, line);
  }
  /// The members of the element set named @a name (an ELSET= parameter is
  /// always a name, even if it looks like a number).
  const std::vector<long>& elementSet(const std::string& name, int line) const
  {
    auto it = elsets_.find(upper(name));
    if (it == elsets_.end())
      fail(line, "unknown element set " + name);
    return it->second;
  }
  int nodeIndex(long id, int line) const
  {
    auto it = nodeIndex_.find(id);
    if (it == nodeIndex_.end())
      fail(line, "node " + std::to_string(id) + " is not defined");
    return it->second;
  }

  void handle(const std::string& keyword, const std::map<std::string, std::string>& params, std::span<const Line> data)
  {
    if (keyword == "*HEADING" || keyword == "*NODE FILE" || keyword == "*EL FILE" || keyword == "*NODE PRINT" ||
        keyword == "*EL PRINT" || keyword == "*END STEP")
      return;
    // *CONTROLS changes how ccx converges, not what the model means.
    if (keyword == "*CONTROLS")
      return;
    // Every material here is isotropic, so a local material frame changes
    // nothing: *ORIENTATION is accepted (and named by *SOLID SECTION).
    if (keyword == "*ORIENTATION")
    {
      orientations_.insert(required(params, "NAME", keyword));
      return;
    }
    // Thermal expansion needs temperatures, which no accepted keyword gives.
    if (keyword == "*EXPANSION")
    {
      if (material_.empty())
        fail(line_, "*EXPANSION outside a *MATERIAL");
      return;
    }
    if (keyword == "*STEP")
      return readStep(params);
    if (keyword == "*STATIC")
      return readStatic(params, data);
    if (keyword == "*HYPERELASTIC")
      return readHyperelastic(params, data);
    if (keyword == "*NODE")
      return readNodes(params, data);
    if (keyword == "*ELEMENT")
      return readElements(params, data);
    if (keyword == "*NSET" || keyword == "*ELSET")
      return readSet(keyword, params, data);
    if (keyword == "*MATERIAL")
      return readMaterial(params, keyword);
    if (keyword == "*ELASTIC" || keyword == "*DENSITY")
      return readMaterialConstant(keyword, params, data);
    if (keyword == "*SOLID SECTION")
      return readSolidSection(params, keyword);
    if (keyword == "*BOUNDARY")
      return readBoundary(params, data);
    if (keyword == "*CLOAD")
      return readConcentratedLoads(data);
    if (keyword == "*DLOAD")
      return readDistributedLoads(data);
    if (keyword == "*EQUATION")
      return readEquations(data);
    fail(line_, "unsupported keyword " + keyword);
  }

  /// *STEP[, NLGEOM]: the one static step, large deformation or not.
  void readStep(const std::map<std::string, std::string>& params)
  {
    if (++steps_ > 1)
      fail(line_, "a second *STEP: only one static step is supported");
    if (params.count("NLGEOM"))
    {
      const std::string v = params.at("NLGEOM");
      if (v != "" && v != "YES" && v != "NO")
        fail(line_, "*STEP, NLGEOM=" + v + ": expected YES or NO");
      nlgeom_ = v != "NO";
    }
  }

  /// *MATERIAL, NAME=: the material the next *ELASTIC or *DENSITY describe.
  void readMaterial(const std::map<std::string, std::string>& params, const std::string& keyword)
  {
    material_ = required(params, "NAME", keyword);
    if (materialIndex_.count(material_))
      fail(line_, "material " + material_ + " is defined twice");
    materialIndex_[material_] = int(names_.size());
    names_.push_back(material_);
    materials_[int(names_.size()) - 1] = {};
  }

  /// *ELASTIC (isotropic E, nu) or *DENSITY of the current material.
  void readMaterialConstant(const std::string& keyword, const std::map<std::string, std::string>& params,
                            std::span<const Line> data)
  {
    if (material_.empty())
      fail(line_, keyword + " outside a *MATERIAL");
    if (keyword == "*ELASTIC" && hyperelastic_.count(materialIndex_[material_]))
      fail(line_, "material " + material_ + " has both *ELASTIC and *HYPERELASTIC");
    if (keyword == "*ELASTIC" && params.count("TYPE") && params.at("TYPE") != "ISO" && params.at("TYPE") != "ISOTROPIC")
      fail(line_, "*ELASTIC, TYPE=" + params.at("TYPE") + " is not supported (isotropic only)");
    if (data.size() != 1)
      fail(line_, keyword + " needs exactly one data line (temperature tables are not supported)");
    const auto f = split(data[0].text);
    LinearElasticMaterial& m = materials_[materialIndex_[material_]];
    if (keyword == "*ELASTIC")
    {
      elastic_.insert(materialIndex_[material_]);
      if (f.size() < 2)
        fail(data[0].number, "*ELASTIC needs E, nu");
      m.youngsModulus = number(f[0], data[0].number);
      m.poissonRatio = number(f[1], data[0].number);
    }
    else
    {
      m.density = number(f[0], data[0].number);
    }
  }

  /// *SOLID SECTION, ELSET=, MATERIAL=[, ORIENTATION=]: the elements' material.
  void readSolidSection(const std::map<std::string, std::string>& params, const std::string& keyword)
  {
    const std::string elset = required(params, "ELSET", keyword);
    const std::string material = required(params, "MATERIAL", keyword);
    auto m = materialIndex_.find(material);
    if (m == materialIndex_.end())
      fail(line_, "*SOLID SECTION names material " + material + ", which is not defined");
    if (params.count("ORIENTATION") && !orientations_.count(params.at("ORIENTATION")))
      fail(line_, "*SOLID SECTION names orientation " + params.at("ORIENTATION") + ", which is not defined");
    for (long e : elementSet(elset, line_))
      sections_[e] = m->second;
  }

  /// *CLOAD lines: node (or set), DOF, magnitude.
  void readConcentratedLoads(std::span<const Line> data)
  {
    for (const Line& l : data)
    {
      const auto f = split(l.text);
      if (f.size() < 3)
        fail(l.number, "*CLOAD needs node, DOF, magnitude");
      const long dof = integer(f[1], l.number);
      if (dof < 1 || dof > 3)
        fail(l.number, "*CLOAD on DOF " + f[1] + ": solids have DOFs 1..3");
      Eigen::Vector3d force = Eigen::Vector3d::Zero();
      force[dof - 1] = number(f[2], l.number);
      for (long n : nodesOf(f[0], l.number))
        forces_.push_back({nodeIndex(n, l.number), force});
    }
  }

  /// *DLOAD lines: gravity (GRAV) or a uniform pressure on an element face (P1..P6).
  void readDistributedLoads(std::span<const Line> data)
  {
    for (const Line& l : data)
    {
      const auto f = split(l.text);
      if (f.size() < 2)
        fail(l.number, "*DLOAD needs an element (set) and a load type");
      const std::string type = upper(f[1]);
      if (type.size() > 1 && type[0] == 'P' && type.find_first_not_of("0123456789", 1) == std::string::npos)
      {
        readFacePressure(f, type, l.number);
        continue;
      }
      if (type != "GRAV")
        fail(l.number, "*DLOAD type " + type + " is not supported (GRAV and uniform face pressure P1..P6 are)");
      if (f.size() < 6)
        fail(l.number, "*DLOAD GRAV needs magnitude, nx, ny, nz");
      const Eigen::Vector3d g = number(f[2], l.number) *
                                Eigen::Vector3d(number(f[3], l.number), number(f[4], l.number), number(f[5], l.number));
      for (long e : elementsOf(f[0], l.number))
        gravity_.emplace(e, Eigen::Vector3d::Zero()).first->second += g;
      gravityLine_ = l.number;
    }
  }

  /// *STATIC[, DIRECT] with the optional line: initial increment, step
  /// period, minimum and maximum increment (ccx's defaults for empty fields).
  void readStatic(const std::map<std::string, std::string>& params, std::span<const Line> data)
  {
    if (steps_ == 0)
      fail(line_, "*STATIC outside a *STEP");
    step_.direct = params.count("DIRECT") && params.at("DIRECT") != "NO";
    if (data.empty())
      return;
    if (data.size() > 1)
      fail(data[1].number, "*STATIC has one data line (initial, period, minimum, maximum)");
    const auto f = split(data[0].text);
    auto field = [&](std::size_t k, double fallback) {
      return k < f.size() && !f[k].empty() ? number(f[k], data[0].number) : fallback;
    };
    step_.initialIncrement = field(0, step_.initialIncrement);
    step_.period = field(1, step_.period);
    step_.minimumIncrement = field(2, step_.minimumIncrement);
    step_.maximumIncrement = field(3, step_.maximumIncrement);
    if (!(step_.period > 0.0) || !(step_.initialIncrement > 0.0) || !(step_.minimumIncrement > 0.0) ||
        !(step_.maximumIncrement > 0.0) || step_.minimumIncrement > step_.maximumIncrement)
      fail(data[0].number, "*STATIC increments must be positive, with minimum <= maximum (initial, period, "
                           "minimum, maximum)");
  }

  /// *HYPERELASTIC, NEO HOOKE (C10, D1) or MOONEY-RIVLIN (C10, C01, D1): the
  /// Abaqus/CalculiX data line order (checked against ccx 2.20: C10 = 1,
  /// D1 = 0.1 gives E = 5.806, nu = 0.4516).
  void readHyperelastic(const std::map<std::string, std::string>& params, std::span<const Line> data)
  {
    if (material_.empty())
      fail(line_, "*HYPERELASTIC outside a *MATERIAL");
    const int region = materialIndex_[material_];
    if (elastic_.count(region))
      fail(line_, "material " + material_ + " has both *ELASTIC and *HYPERELASTIC");
    static const std::set<std::string> kOtherTypes = {"POLYNOMIAL",   "REDUCED POLYNOMIAL", "OGDEN",     "YEOH",
                                                      "ARRUDA-BOYCE", "VAN DER WAALS",      "HYPERFOAM", "MARLOW"};
    std::string type;
    for (const auto& [name, value] : params)
    {
      if (name == "NEO HOOKE" || name == "MOONEY-RIVLIN")
        type = name;
      else if (kOtherTypes.count(name))
        fail(line_, "*HYPERELASTIC, " + name +
                      " is not supported (NEO HOOKE and MOONEY-RIVLIN are; "
                      "POLYNOMIAL, N=1 is MOONEY-RIVLIN)");
    }
    for (const auto& [name, value] : params)
      if (name != type)
        fail(line_, "*HYPERELASTIC, " + name + " is not supported");
    if (type.empty())
      fail(line_, "*HYPERELASTIC needs its type: NEO HOOKE or MOONEY-RIVLIN");
    if (data.size() != 1)
      fail(line_, "*HYPERELASTIC needs exactly one data line (temperature tables are not supported)");
    const auto f = split(data[0].text);
    const int at = data[0].number;
    const std::size_t needed = type == "NEO HOOKE" ? 2 : 3;
    for (std::size_t k = 0; k < needed; ++k)
      if (k >= f.size() || f[k].empty())
        fail(at, "*HYPERELASTIC, " + type + (needed == 2 ? " needs C10, D1" : " needs C10, C01, D1"));
    hyperelastic_[region] =
      needed == 2 ? HyperelasticMaterial::neoHookean(number(f[0], at), number(f[1], at))
                  : HyperelasticMaterial::mooneyRivlin(number(f[0], at), number(f[1], at), number(f[2], at));
    hyperelasticLine_[region] = at;
  }

  void readNodes(const std::map<std::string, std::string>& params, std::span<const Line> data)
  {
    std::vector<long>* set = params.count("NSET") ? &nsets_[params.at("NSET")] : nullptr;
    for (const Line& l : data)
    {
      const auto f = split(l.text);
      if (f.size() < 2)
        fail(l.number, "*NODE needs a number and coordinates");
      const long id = integer(f[0], l.number);
      if (nodeIndex_.count(id))
        fail(l.number, "node " + f[0] + " is defined twice");
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (std::size_t d = 0; d < 3 && d + 1 < f.size(); ++d)
        if (!f[d + 1].empty())
          x[Eigen::Index(d)] = number(f[d + 1], l.number);
      nodeIndex_[id] = int(coords_.size());
      coords_.push_back(x);
      nodeIds_.push_back(id);
      if (set)
        set->push_back(id);
    }
  }

  void readElements(const std::map<std::string, std::string>& params, std::span<const Line> data)
  {
    const std::string type = required(params, "TYPE", "*ELEMENT");
    int count = 0;
    if (type == "C3D20" || type == "C3D20R")
      count = 20;
    else if (type == "C3D15")
      count = 15;
    else if (type == "C3D8")
      count = 8;
    else
      fail(line_, "unsupported element type " + type + " (C3D20, C3D20R, C3D15 and C3D8 are)");
    // The rule ccx integrates each type with: C3D20 3x3x3, C3D20R 2x2x2
    // (reduced), C3D8 2x2x2 (its full rule), C3D15 the 9-point wedge rule
    // (wedgeRule(2)). A C3D15 read as a degenerate brick has no ccx
    // equivalent and takes the analysis's default.
    std::uint8_t points = 3;
    if (type == "C3D20R" || type == "C3D8")
      points = 2;
    else if (count == 15)
      points = options_.nativeWedges ? 2 : 0;
    std::vector<long>* set = params.count("ELSET") ? &elsets_[params.at("ELSET")] : nullptr;
    std::vector<std::string> tokens;
    int first = 0;
    for (const Line& l : data)
    {
      if (tokens.empty())
        first = l.number;
      for (const auto& t : split(l.text))
        if (!t.empty())
          tokens.push_back(t);
      if (int(tokens.size()) < count + 1)
        continue;
      if (int(tokens.size()) > count + 1)
        fail(first, type + " element " + tokens[0] + " has " + std::to_string(tokens.size() - 1) + " nodes, expected " +
                      std::to_string(count));
      const long id = integer(tokens[0], first);
      if (elementIds_.count(id))
        fail(first, "element " + tokens[0] + " is defined twice");
      std::vector<int> n;
      for (int k = 1; k <= count; ++k)
        n.push_back(nodeIndex(integer(tokens[std::size_t(k)], first), first));
      Element el;
      el.nodes.fill(-1);
      el.integrationPoints = points;
      if (count == 15 && options_.nativeWedges)
      {
        el.kind = ElementKind::Wedge15;
        for (int c = 0; c < 15; ++c)
          el.nodes[std::size_t(c3d15ToWedge15(c + 1))] = n[std::size_t(c)];
      }
      else if (count == 15)
      {
        // C3D15 -> degenerate C3D20 (Fig. 3.2): the edge 3-4 of each triangle face collapses.
        const int map[20] = {0, 1, 2, 2, 3, 4, 5, 5, 6, 7, 2, 8, 9, 10, 5, 11, 12, 13, 14, 14};
        for (int c = 0; c < 20; ++c)
          el.nodes[std::size_t(c3d20ToBathe(c + 1))] = n[std::size_t(map[c])];
      }
      else
      {
        for (int c = 0; c < count; ++c)
          el.nodes[std::size_t(c3d20ToBathe(c + 1))] = n[std::size_t(c)];
      }
      elementIds_[id] = int(elements_.size());
      elements_.push_back(el);
      elementNumbers_.push_back(id);
      elementLines_.push_back(first);
      elementNodeCounts_.push_back(count);
      if (set)
        set->push_back(id);
      tokens.clear();
    }
    if (!tokens.empty())
      fail(first, type + " element " + tokens[0] + " is incomplete (" + std::to_string(tokens.size() - 1) + " of " +
                    std::to_string(count) + " nodes)");
  }

  /// *DLOAD element (set), Pn, pressure: face n in the deck's numbering of
  /// the element's type, mapped onto the faces of our element.
  void readFacePressure(const std::vector<std::string>& f, const std::string& type, int line)
  {
    // More than three digits cannot be a face (and would overflow stoi).
    const int face = type.size() <= 4 ? std::stoi(type.substr(1)) : 0;
    if (f.size() < 3 || f[2].empty())
      fail(line, "*DLOAD " + type + " needs a pressure");
    const double p = number(f[2], line);
    if (!std::isfinite(p))
      fail(line, "*DLOAD " + type + " with a non-finite pressure");
    for (long id : elementsOf(f[0], line))
    {
      auto it = elementIds_.find(id);
      if (it == elementIds_.end())
        fail(line, "*DLOAD on element " + std::to_string(id) + ", which is not defined");
      const int e = it->second;
      const bool wedge = elementNodeCounts_[std::size_t(e)] == 15;
      const int faces = wedge ? 5 : 6;
      if (face < 1 || face > faces)
        fail(line, "*DLOAD " + type + " on element " + std::to_string(id) + ": a " +
                     (wedge ? "C3D15 wedge has faces P1..P5" : "hexahedron has faces P1..P6"));
      // A native wedge keeps the C3D15 numbering. In the degenerate brick
      // built in readElements, C3D15 faces 1-2-3, 4-5-6, 1-2-5-4, 2-3-6-5,
      // 3-1-4-6 are C3D20 faces 1, 2, 3, 4, 6 (face 5, 3-7-8-4, is the
      // collapsed edge).
      static constexpr int kWedgeToHexFace[5] = {1, 2, 3, 4, 6};
      const bool degenerate = wedge && elements_[std::size_t(e)].kind == ElementKind::Hex20;
      const int ourFace = degenerate ? kWedgeToHexFace[face - 1] : face;
      // Pressures repeated on one face add up, as in ccx 2.20 (measured).
      pressures_[{e, ourFace}] += p;
    }
  }

  void readSet(const std::string& keyword, const std::map<std::string, std::string>& params, std::span<const Line> data)
  {
    const bool nodes = keyword == "*NSET";
    const std::string name = required(params, nodes ? "NSET" : "ELSET", keyword);
    std::vector<long>& set = (nodes ? nsets_ : elsets_)[name];
    const bool generate = params.count("GENERATE") > 0;
    for (const Line& l : data)
    {
      const auto f = split(l.text);
      if (generate)
      {
        if (f.size() < 2)
          fail(l.number, keyword + ", GENERATE needs first, last[, step]");
        const long a = integer(f[0], l.number), b = integer(f[1], l.number);
        const long step = f.size() > 2 && !f[2].empty() ? integer(f[2], l.number) : 1;
        if (step <= 0 || b < a)
          fail(l.number, keyword + ", GENERATE with a bad range");
        for (long v = a; v <= b; v += step)
          set.push_back(v);
        continue;
      }
      for (const auto& t : f)
      {
        if (t.empty())
          continue;
        const auto members = nodes ? nodesOf(t, l.number) : elementsOf(t, l.number);
        set.insert(set.end(), members.begin(), members.end());
      }
    }
  }

  void readBoundary(const std::map<std::string, std::string>& params, std::span<const Line> data)
  {
    for (const auto& [name, value] : params)
      if (name != "OP")
        fail(line_, "*BOUNDARY, " + name + " is not supported");
    for (const Line& l : data)
    {
      const auto f = split(l.text);
      if (f.size() < 2)
        fail(l.number, "*BOUNDARY needs a node (set) and a DOF");
      long first = 0, last = 0;
      const std::string kind = upper(f[1]);
      if (kind == "ENCASTRE" || kind == "PINNED")
      {
        first = 1;
        last = 3;
      }
      else
      {
        first = integer(f[1], l.number);
        last = f.size() > 2 && !f[2].empty() ? integer(f[2], l.number) : first;
      }
      const double value = f.size() > 3 && !f[3].empty() ? number(f[3], l.number) : 0.0;
      if (first < 1 || last < first)
        fail(l.number, "*BOUNDARY with DOFs " + std::to_string(first) + " to " + std::to_string(last));
      for (long n : nodesOf(f[0], l.number))
        for (long d = first; d <= std::min(last, 3L); ++d)
          boundary_.push_back({nodeIndex(n, l.number), int(d - 1), value, l.number});
    }
  }

  /// *EQUATION: a line with the number of terms, then node, DOF,
  /// coefficient triples (up to four per line). The first term's DOF is the
  /// dependent one (ccx), so its coefficient must not be zero.
  void readEquations(std::span<const Line> data)
  {
    std::size_t i = 0;
    while (i < data.size())
    {
      const int at = data[i].number;
      const long terms = integer(split(data[i].text)[0], at);
      if (terms < 1)
        fail(at, "*EQUATION with " + std::to_string(terms) + " terms: it needs at least one");
      std::vector<std::string> tokens;
      for (++i; i < data.size() && long(tokens.size()) < 3 * terms; ++i)
        for (const auto& t : split(data[i].text))
          if (!t.empty())
            tokens.push_back(t);
      if (long(tokens.size()) != 3 * terms)
        fail(at, "*EQUATION of " + std::to_string(terms) + " terms: expected " + std::to_string(3 * terms) +
                   " entries (node, DOF, coefficient per term), found " + std::to_string(tokens.size()));
      Equation eq;
      eq.line = at;
      for (long t = 0; t < terms; ++t)
      {
        const long node = integer(tokens[std::size_t(3 * t)], at);
        const long dof = integer(tokens[std::size_t(3 * t + 1)], at);
        if (dof < 1 || dof > 3)
          fail(at, "*EQUATION on DOF " + std::to_string(dof) + " of node " + std::to_string(node) +
                     ": solids have DOFs 1..3");
        eq.terms.push_back({nodeIndex(node, at), int(dof - 1), number(tokens[std::size_t(3 * t + 2)], at)});
      }
      if (eq.terms[0].coefficient == 0.0)
        fail(at, "*EQUATION: the first term (the dependent DOF, node " + tokens[0] + " DOF " + tokens[1] +
                   ") has coefficient 0");
      equations_.push_back(std::move(eq));
    }
  }

  struct Equation
  {
    int line = 0;
    std::vector<ConstraintTerm> terms;
  };
  struct Boundary
  {
    int node, dof;
    double value;
    int line;
  };

  CalculixModel finish()
  {
    CalculixModel m;
    finishMesh(m);
    finishMaterials(m);
    finishConstraints(m);
    finishLoads(m);
    return m;
  }

  /// The mesh: nodes, elements and the material each element's section gives.
  void finishMesh(CalculixModel& m)
  {
    m.mesh.nodes.resize(3, Eigen::Index(coords_.size()));
    for (std::size_t i = 0; i < coords_.size(); ++i)
      m.mesh.nodes.col(Eigen::Index(i)) = coords_[i];
    m.nodeIds = nodeIds_;
    m.elementIds = elementNumbers_;
    m.materialNames = names_;
    m.materials = materials_;
    for (std::size_t e = 0; e < elements_.size(); ++e)
    {
      auto s = sections_.find(elementNumbers_[e]);
      if (s == sections_.end())
        fail(elementLines_[e],
             "element " + std::to_string(elementNumbers_[e]) + " has no *SOLID SECTION (no material)");
      elements_[e].region = s->second;
    }
    m.mesh.elements = elements_;
  }

  /// The materials, checked; a hyperelastic one with its small-strain limit
  /// as the linear material, and the step it makes nonlinear.
  void finishMaterials(CalculixModel& m)
  {
    // Hyperelastic materials: the table, and their small-strain limit as
    // the linear material (same density).
    for (auto& [region, h] : hyperelastic_)
    {
      h.density = materials_[region].density;
      try
      {
        h.validate("material " + names_[std::size_t(region)]);
      }
      catch (const std::invalid_argument& e)
      {
        fail(hyperelasticLine_[region], e.what());
      }
      m.materials[region] = h.smallStrainLimit();
    }
    m.hyperelastic = hyperelastic_;
    m.step = step_;
    m.step.nlgeom = nlgeom_;
    // ccx 2.20 solves a step with a hyperelastic material geometrically
    // nonlinear even without NLGEOM (measured: the same 50 % stretch of a
    // neo-Hookean cube with and without it), so the step is NLGEOM here too.
    for (const Element& el : elements_)
      if (hyperelastic_.count(el.region))
        m.step.nlgeom = true;
    for (const auto& [region, material] : m.materials)
    {
      const std::string context = "material " + names_[std::size_t(region)];
      material.validate(context.c_str());
    }
  }

  /// Prescribed displacements, sutures (ties recognised among the
  /// equations) and the other equations.
  void finishConstraints(CalculixModel& m)
  {
    for (const Boundary& b : boundary_)
      m.constraints.prescribe(b.node, b.dof, b.value);
    // Auxiliary nodes: prescribed to (1, 0, 0).
    std::map<std::pair<int, int>, double> prescribed;
    for (const Boundary& b : boundary_)
      prescribed[{b.node, b.dof}] = b.value;
    auto isAux = [&](int node) {
      for (int d = 0; d < 3; ++d)
      {
        auto it = prescribed.find({node, d});
        if (it == prescribed.end() || it->second != (d == 0 ? 1.0 : 0.0))
          return false;
      }
      return true;
    };
    // Sutures (the fast path): ties u(a, i) - u(b, i) [+ c u(aux, 1)] = 0 of
    // both nodes' three directions that make a end where b ends. Every other
    // equation is kept as the general constraint it is.
    std::map<std::pair<int, int>, std::vector<std::size_t>> ties; // (a, b) -> equations
    std::vector<char> tie(equations_.size(), 0);
    const double size = m.mesh.nodes.size() ? m.mesh.nodes.cwiseAbs().maxCoeff() : 1.0;
    for (std::size_t k = 0; k < equations_.size(); ++k)
    {
      const auto& t = equations_[k].terms;
      if (t.size() != 2 && t.size() != 3)
        continue;
      const int a = t[0].node, b = t[1].node, d = t[0].direction;
      if (a == b || t[1].direction != d ||
          std::abs(t[0].coefficient + t[1].coefficient) > 1e-12 * std::abs(t[0].coefficient))
        continue;
      double offset = 0.0; // u_a = u_b + offset
      if (t.size() == 3)
      {
        if (t[2].direction != 0 || !isAux(t[2].node))
          continue;
        offset = -t[2].coefficient / t[0].coefficient;
      }
      const double expected = m.mesh.nodes(d, b) - m.mesh.nodes(d, a);
      if (std::abs(offset - expected) > 1e-9 * std::max(1.0, size))
        continue;
      ties[{a, b}].push_back(k);
      tie[k] = 1;
    }
    for (const auto& [pair, members] : ties)
    {
      std::set<int> directions;
      for (std::size_t k : members)
        directions.insert(equations_[k].terms[0].direction);
      if (directions.size() == 3 && members.size() == 3)
      {
        m.constraints.suture(pair.first, pair.second);
      }
      else
      {
        for (std::size_t k : members)
          tie[k] = 0;
      }
    }
    for (std::size_t k = 0; k < equations_.size(); ++k)
    {
      if (tie[k])
        continue;
      LinearConstraint c;
      // Zero coefficients (ccx decks write them) constrain nothing.
      for (const ConstraintTerm& t : equations_[k].terms)
        if (t.coefficient != 0.0)
          c.terms.push_back(t);
      m.constraints.equation(std::move(c));
    }
  }

  /// Nodal forces, face pressures and the one gravity of the model.
  void finishLoads(CalculixModel& m)
  {
    m.load.nodalForces = forces_;
    for (const auto& [face, p] : pressures_)
      m.load.facePressures.push_back({face.first, face.second, p});
    // Gravity: one acceleration for every element with a density.
    bool have = false;
    for (std::size_t e = 0; e < elements_.size(); ++e)
    {
      if (m.materials.at(elements_[e].region).density <= 0.0)
        continue;
      auto it = gravity_.find(elementNumbers_[e]);
      const Eigen::Vector3d g = it == gravity_.end() ? Eigen::Vector3d::Zero() : it->second;
      if (!have)
        m.load.gravity = g;
      else if ((g - m.load.gravity).norm() > 1e-12 * std::max(1.0, g.norm()))
        fail(gravityLine_, "*DLOAD GRAV differs between elements (e.g. element " + std::to_string(elementNumbers_[e]) +
                             "): only one acceleration for the whole model is supported");
      have = true;
    }
  }

  std::string source_;
  CalculixReadOptions options_;
  std::vector<Line> lines_;
  int line_ = 0;
  int steps_ = 0;
  std::vector<Eigen::Vector3d> coords_;
  std::vector<long> nodeIds_;
  std::unordered_map<long, int> nodeIndex_;
  std::vector<Element> elements_;
  std::vector<long> elementNumbers_;
  std::vector<int> elementLines_;
  std::vector<int> elementNodeCounts_; ///< 20, 15 or 8: the deck's element type
  std::unordered_map<long, int> elementIds_;
  std::map<std::string, std::vector<long>> nsets_, elsets_;
  std::string material_;
  std::map<std::string, int> materialIndex_;
  std::vector<std::string> names_;
  MaterialTable materials_;
  std::map<long, int> sections_;
  std::vector<Boundary> boundary_;
  std::vector<std::pair<int, Eigen::Vector3d>> forces_;
  std::map<long, Eigen::Vector3d> gravity_;
  std::map<std::pair<int, int>, double> pressures_; ///< (element index, face 1..6) -> MPa
  int gravityLine_ = 0;
  std::vector<Equation> equations_;
  bool nlgeom_ = false;
  StaticStep step_;
  std::set<int> elastic_; ///< regions given by *ELASTIC
  std::set<std::string> orientations_;
  HyperelasticTable hyperelastic_;
  std::map<int, int> hyperelasticLine_;
};

} // namespace

CalculixModel parseCalculixInput(const std::string& text, const std::string& sourceName,
                                 const CalculixReadOptions& options)
{
  return Parser(text, sourceName, options).run();
}

CalculixModel readCalculixInput(const std::string& path, const CalculixReadOptions& options)
{
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f)
    throw std::runtime_error("cannot read the input deck " + path);
  std::string text;
  char buffer[1 << 16];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;)
    text.append(buffer, n);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed)
    throw std::runtime_error("cannot read the input deck " + path);
  return parseCalculixInput(text, path, options);
}

} // namespace caps::fem
