#include "fem/CalculixReader.h"

#include "fem/ElementNumbering.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace caps::fem {

namespace {

std::string upper(std::string s) {
  for (char& c : s) c = char(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream in(s);
  while (std::getline(in, field, ',')) out.push_back(trim(field));
  if (!s.empty() && s.back() == ',') out.emplace_back();
  return out;
}

/// One logical line: a keyword with its parameters, or a data line's fields.
struct Line {
  int number = 0;
  std::string text;
};

class Parser {
public:
  Parser(const std::string& text, std::string source, const CalculixReadOptions& options)
      : source_(std::move(source)), options_(options) {
    std::istringstream in(text);
    std::string raw;
    int number = 0;
    while (std::getline(in, raw)) {
      ++number;
      const std::string t = trim(raw);
      if (t.empty() || t.rfind("**", 0) == 0) continue;
      // A keyword line ending in a comma continues on the next line.
      if (!lines_.empty() && lines_.back().text[0] == '*' && lines_.back().text.back() == ',' &&
          t[0] != '*') {
        lines_.back().text += t;
        continue;
      }
      lines_.push_back({number, t});
    }
  }

  CalculixModel run() {
    std::size_t i = 0;
    while (i < lines_.size()) {
      const Line& kw = lines_[i];
      if (kw.text[0] != '*') fail(kw.number, "data line outside a keyword: " + kw.text);
      std::vector<std::string> fields = split(kw.text);
      const std::string keyword = upper(fields[0]);
      std::map<std::string, std::string> params;
      for (std::size_t f = 1; f < fields.size(); ++f) {
        if (fields[f].empty()) continue;
        const auto eq = fields[f].find('=');
        params[upper(trim(fields[f].substr(0, eq)))] = eq == std::string::npos ? "" : upper(trim(fields[f].substr(eq + 1)));
      }
      std::size_t end = i + 1;
      while (end < lines_.size() && lines_[end].text[0] != '*') ++end;
      std::vector<Line> data(lines_.begin() + long(i + 1), lines_.begin() + long(end));
      line_ = kw.number;
      handle(keyword, params, data);
      i = end;
    }
    return finish();
  }

private:
  [[noreturn]] void fail(int line, const std::string& what) const { throw InputDeckError(source_, line, what); }

  double number(const std::string& s, int line) const {
    std::string t = s;
    for (char& c : t)
      if (c == 'd' || c == 'D') c = 'e';
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (t.empty() || *end != '\0') fail(line, "'" + s + "' is not a number");
    return v;
  }
  long integer(const std::string& s, int line) const {
    char* end = nullptr;
    const long v = std::strtol(s.c_str(), &end, 10);
    if (s.empty() || *end != '\0') fail(line, "'" + s + "' is not an integer");
    return v;
  }

  std::string required(const std::map<std::string, std::string>& params, const std::string& name,
                       const std::string& keyword) const {
    auto it = params.find(name);
    if (it == params.end() || it->second.empty()) fail(line_, keyword + " needs " + name + "=");
    return it->second;
  }

  /// Node numbers of a node number or NSET name.
  std::vector<long> nodesOf(const std::string& field, int line) const {
    if (!field.empty() && (std::isdigit(static_cast<unsigned char>(field[0])) || field[0] == '-'))
      return {integer(field, line)};
    auto it = nsets_.find(upper(field));
    if (it == nsets_.end()) fail(line, "unknown node set " + field);
    return it->second;
  }
  std::vector<long> elementsOf(const std::string& field, int line) const {
    if (!field.empty() && std::isdigit(static_cast<unsigned char>(field[0]))) return {integer(field, line)};
    auto it = elsets_.find(upper(field));
    if (it == elsets_.end()) fail(line, "unknown element set " + field);
    return it->second;
  }
  int nodeIndex(long id, int line) const {
    auto it = nodeIndex_.find(id);
    if (it == nodeIndex_.end()) fail(line, "node " + std::to_string(id) + " is not defined");
    return it->second;
  }

  void handle(const std::string& keyword, const std::map<std::string, std::string>& params,
              const std::vector<Line>& data) {
    if (keyword == "*HEADING" || keyword == "*NODE FILE" || keyword == "*EL FILE" || keyword == "*NODE PRINT" ||
        keyword == "*EL PRINT" || keyword == "*END STEP")
      return;
    if (keyword == "*STEP") {
      if (++steps_ > 1) fail(line_, "a second *STEP: only one static step is supported");
      if (params.count("NLGEOM") && params.at("NLGEOM") != "NO") fail(line_, "*STEP, NLGEOM is not supported (linear analysis only)");
      return;
    }
    if (keyword == "*STATIC") {
      if (steps_ == 0) fail(line_, "*STATIC outside a *STEP");
      return;
    }
    if (keyword == "*NODE") return readNodes(params, data);
    if (keyword == "*ELEMENT") return readElements(params, data);
    if (keyword == "*NSET" || keyword == "*ELSET") return readSet(keyword, params, data);
    if (keyword == "*MATERIAL") {
      material_ = required(params, "NAME", keyword);
      if (materialIndex_.count(material_)) fail(line_, "material " + material_ + " is defined twice");
      materialIndex_[material_] = int(names_.size());
      names_.push_back(material_);
      materials_[int(names_.size()) - 1] = {};
      return;
    }
    if (keyword == "*ELASTIC" || keyword == "*DENSITY") {
      if (material_.empty()) fail(line_, keyword + " outside a *MATERIAL");
      if (keyword == "*ELASTIC" && params.count("TYPE") && params.at("TYPE") != "ISO")
        fail(line_, "*ELASTIC, TYPE=" + params.at("TYPE") + " is not supported (isotropic only)");
      if (data.size() != 1) fail(line_, keyword + " needs exactly one data line (temperature tables are not supported)");
      const auto f = split(data[0].text);
      LinearElasticMaterial& m = materials_[materialIndex_[material_]];
      if (keyword == "*ELASTIC") {
        if (f.size() < 2) fail(data[0].number, "*ELASTIC needs E, nu");
        m.youngsModulus = number(f[0], data[0].number);
        m.poissonRatio = number(f[1], data[0].number);
      } else {
        m.density = number(f[0], data[0].number);
      }
      return;
    }
    if (keyword == "*SOLID SECTION") {
      const std::string elset = required(params, "ELSET", keyword);
      const std::string material = required(params, "MATERIAL", keyword);
      auto m = materialIndex_.find(material);
      if (m == materialIndex_.end()) fail(line_, "*SOLID SECTION names material " + material + ", which is not defined");
      for (long e : elementsOf(elset, line_)) sections_[e] = m->second;
      return;
    }
    if (keyword == "*BOUNDARY") return readBoundary(params, data);
    if (keyword == "*CLOAD") {
      for (const Line& l : data) {
        const auto f = split(l.text);
        if (f.size() < 3) fail(l.number, "*CLOAD needs node, DOF, magnitude");
        const long dof = integer(f[1], l.number);
        if (dof < 1 || dof > 3) fail(l.number, "*CLOAD on DOF " + f[1] + ": solids have DOFs 1..3");
        Eigen::Vector3d force = Eigen::Vector3d::Zero();
        force[dof - 1] = number(f[2], l.number);
        for (long n : nodesOf(f[0], l.number)) forces_.push_back({nodeIndex(n, l.number), force});
      }
      return;
    }
    if (keyword == "*DLOAD") {
      for (const Line& l : data) {
        const auto f = split(l.text);
        if (f.size() < 2) fail(l.number, "*DLOAD needs an element (set) and a load type");
        const std::string type = upper(f[1]);
        if (type.size() > 1 && type[0] == 'P' && type.find_first_not_of("0123456789", 1) == std::string::npos) {
          readFacePressure(f, type, l.number);
          continue;
        }
        if (type != "GRAV")
          fail(l.number, "*DLOAD type " + type + " is not supported (GRAV and uniform face pressure P1..P6 are)");
        if (f.size() < 6) fail(l.number, "*DLOAD GRAV needs magnitude, nx, ny, nz");
        const Eigen::Vector3d g = number(f[2], l.number) * Eigen::Vector3d(number(f[3], l.number), number(f[4], l.number),
                                                                         number(f[5], l.number));
        for (long e : elementsOf(f[0], l.number)) gravity_.emplace(e, Eigen::Vector3d::Zero()).first->second += g;
        gravityLine_ = l.number;
      }
      return;
    }
    if (keyword == "*EQUATION") return readEquations(data);
    fail(line_, "unsupported keyword " + keyword);
  }

  void readNodes(const std::map<std::string, std::string>& params, const std::vector<Line>& data) {
    std::vector<long>* set = params.count("NSET") ? &nsets_[params.at("NSET")] : nullptr;
    for (const Line& l : data) {
      const auto f = split(l.text);
      if (f.size() < 2) fail(l.number, "*NODE needs a number and coordinates");
      const long id = integer(f[0], l.number);
      if (nodeIndex_.count(id)) fail(l.number, "node " + f[0] + " is defined twice");
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (std::size_t d = 0; d < 3 && d + 1 < f.size(); ++d)
        if (!f[d + 1].empty()) x[Eigen::Index(d)] = number(f[d + 1], l.number);
      nodeIndex_[id] = int(coords_.size());
      coords_.push_back(x);
      nodeIds_.push_back(id);
      if (set) set->push_back(id);
    }
  }

  void readElements(const std::map<std::string, std::string>& params, const std::vector<Line>& data) {
    const std::string type = required(params, "TYPE", "*ELEMENT");
    int count = 0;
    if (type == "C3D20" || type == "C3D20R") count = 20;
    else if (type == "C3D15") count = 15;
    else if (type == "C3D8") count = 8;
    else fail(line_, "unsupported element type " + type + " (C3D20, C3D20R, C3D15 and C3D8 are)");
    std::vector<long>* set = params.count("ELSET") ? &elsets_[params.at("ELSET")] : nullptr;
    std::vector<std::string> tokens;
    int first = 0;
    for (const Line& l : data) {
      if (tokens.empty()) first = l.number;
      for (const auto& t : split(l.text))
        if (!t.empty()) tokens.push_back(t);
      if (int(tokens.size()) < count + 1) continue;
      if (int(tokens.size()) > count + 1)
        fail(first, type + " element " + tokens[0] + " has " + std::to_string(tokens.size() - 1) + " nodes, expected " +
                        std::to_string(count));
      const long id = integer(tokens[0], first);
      if (elementIds_.count(id)) fail(first, "element " + tokens[0] + " is defined twice");
      std::vector<int> n;
      for (int k = 1; k <= count; ++k) n.push_back(nodeIndex(integer(tokens[std::size_t(k)], first), first));
      Element el;
      el.nodes.fill(-1);
      if (count == 15 && options_.nativeWedges) {
        el.kind = ElementKind::Wedge15;
        for (int c = 0; c < 15; ++c) el.nodes[std::size_t(c3d15ToWedge15(c + 1))] = n[std::size_t(c)];
      } else if (count == 15) {
        // C3D15 -> degenerate C3D20 (Fig. 3.2): the edge 3-4 of each triangle face collapses.
        const int map[20] = {0, 1, 2, 2, 3, 4, 5, 5, 6, 7, 2, 8, 9, 10, 5, 11, 12, 13, 14, 14};
        for (int c = 0; c < 20; ++c) el.nodes[std::size_t(c3d20ToBathe(c + 1))] = n[std::size_t(map[c])];
      } else {
        for (int c = 0; c < count; ++c) el.nodes[std::size_t(c3d20ToBathe(c + 1))] = n[std::size_t(c)];
      }
      elementIds_[id] = int(elements_.size());
      elements_.push_back(el);
      elementNumbers_.push_back(id);
      elementLines_.push_back(first);
      elementNodeCounts_.push_back(count);
      if (set) set->push_back(id);
      tokens.clear();
    }
    if (!tokens.empty()) fail(first, type + " element " + tokens[0] + " is incomplete (" + std::to_string(tokens.size() - 1) + " of " + std::to_string(count) + " nodes)");
  }

  /// *DLOAD element (set), Pn, pressure: face n in the deck's numbering of
  /// the element's type, mapped onto the faces of our element.
  void readFacePressure(const std::vector<std::string>& f, const std::string& type, int line) {
    // More than three digits cannot be a face (and would overflow stoi).
    const int face = type.size() <= 4 ? std::stoi(type.substr(1)) : 0;
    if (f.size() < 3 || f[2].empty()) fail(line, "*DLOAD " + type + " needs a pressure");
    const double p = number(f[2], line);
    if (!std::isfinite(p)) fail(line, "*DLOAD " + type + " with a non-finite pressure");
    for (long id : elementsOf(f[0], line)) {
      auto it = elementIds_.find(id);
      if (it == elementIds_.end()) fail(line, "*DLOAD on element " + std::to_string(id) + ", which is not defined");
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

  void readSet(const std::string& keyword, const std::map<std::string, std::string>& params,
               const std::vector<Line>& data) {
    const bool nodes = keyword == "*NSET";
    const std::string name = required(params, nodes ? "NSET" : "ELSET", keyword);
    std::vector<long>& set = (nodes ? nsets_ : elsets_)[name];
    const bool generate = params.count("GENERATE") > 0;
    for (const Line& l : data) {
      const auto f = split(l.text);
      if (generate) {
        if (f.size() < 2) fail(l.number, keyword + ", GENERATE needs first, last[, step]");
        const long a = integer(f[0], l.number), b = integer(f[1], l.number);
        const long step = f.size() > 2 && !f[2].empty() ? integer(f[2], l.number) : 1;
        if (step <= 0 || b < a) fail(l.number, keyword + ", GENERATE with a bad range");
        for (long v = a; v <= b; v += step) set.push_back(v);
        continue;
      }
      for (const auto& t : f) {
        if (t.empty()) continue;
        const auto members = nodes ? nodesOf(t, l.number) : elementsOf(t, l.number);
        set.insert(set.end(), members.begin(), members.end());
      }
    }
  }

  void readBoundary(const std::map<std::string, std::string>& params, const std::vector<Line>& data) {
    for (const auto& [name, value] : params)
      if (name != "OP") fail(line_, "*BOUNDARY, " + name + " is not supported");
    for (const Line& l : data) {
      const auto f = split(l.text);
      if (f.size() < 2) fail(l.number, "*BOUNDARY needs a node (set) and a DOF");
      long first = 0, last = 0;
      const std::string kind = upper(f[1]);
      if (kind == "ENCASTRE" || kind == "PINNED") {
        first = 1;
        last = 3;
      } else {
        first = integer(f[1], l.number);
        last = f.size() > 2 && !f[2].empty() ? integer(f[2], l.number) : first;
      }
      const double value = f.size() > 3 && !f[3].empty() ? number(f[3], l.number) : 0.0;
      if (first < 1 || last < first) fail(l.number, "*BOUNDARY with DOFs " + std::to_string(first) + " to " + std::to_string(last));
      for (long n : nodesOf(f[0], l.number))
        for (long d = first; d <= std::min(last, 3L); ++d)
          boundary_.push_back({nodeIndex(n, l.number), int(d - 1), value, l.number});
    }
  }

  void readEquations(const std::vector<Line>& data) {
    std::size_t i = 0;
    while (i < data.size()) {
      const int at = data[i].number;
      const long terms = integer(split(data[i].text)[0], at);
      if (terms != 2 && terms != 3)
        fail(at, "*EQUATION with " + std::to_string(terms) + " terms is not supported (two-term ties only)");
      std::vector<std::string> tokens;
      for (++i; i < data.size() && long(tokens.size()) < 3 * terms; ++i)
        for (const auto& t : split(data[i].text))
          if (!t.empty()) tokens.push_back(t);
      if (long(tokens.size()) != 3 * terms) fail(at, "*EQUATION: expected " + std::to_string(3 * terms) + " entries");
      Equation eq;
      eq.line = at;
      for (long t = 0; t < terms; ++t) {
        eq.node[t] = nodeIndex(integer(tokens[std::size_t(3 * t)], at), at);
        eq.dof[t] = int(integer(tokens[std::size_t(3 * t + 1)], at)) - 1;
        eq.coef[t] = number(tokens[std::size_t(3 * t + 2)], at);
      }
      eq.terms = int(terms);
      equations_.push_back(eq);
    }
  }

  struct Equation {
    int line = 0, terms = 0;
    int node[3]{}, dof[3]{};
    double coef[3]{};
  };
  struct Boundary {
    int node, dof;
    double value;
    int line;
  };

  CalculixModel finish() {
    CalculixModel m;
    m.mesh.nodes.resize(3, Eigen::Index(coords_.size()));
    for (std::size_t i = 0; i < coords_.size(); ++i) m.mesh.nodes.col(Eigen::Index(i)) = coords_[i];
    m.nodeIds = nodeIds_;
    m.elementIds = elementNumbers_;
    m.materialNames = names_;
    m.materials = materials_;
    for (std::size_t e = 0; e < elements_.size(); ++e) {
      auto s = sections_.find(elementNumbers_[e]);
      if (s == sections_.end())
        fail(elementLines_[e], "element " + std::to_string(elementNumbers_[e]) + " has no *SOLID SECTION (no material)");
      elements_[e].region = s->second;
    }
    m.mesh.elements = elements_;
    for (const auto& [region, material] : m.materials) {
      const std::string context = "material " + names_[std::size_t(region)];
      material.validate(context.c_str());
    }
    for (const Boundary& b : boundary_) m.constraints.prescribe(b.node, b.dof, b.value);
    // Auxiliary nodes: prescribed to (1, 0, 0).
    std::map<std::pair<int, int>, double> prescribed;
    for (const Boundary& b : boundary_) prescribed[{b.node, b.dof}] = b.value;
    auto isAux = [&](int node) {
      for (int d = 0; d < 3; ++d) {
        auto it = prescribed.find({node, d});
        if (it == prescribed.end() || it->second != (d == 0 ? 1.0 : 0.0)) return false;
      }
      return true;
    };
    // Group ties by node pair; a suture needs all three directions.
    std::map<std::pair<int, int>, std::set<int>> ties;
    std::map<std::pair<int, int>, int> tieLine;
    const double size = m.mesh.nodes.size() ? m.mesh.nodes.cwiseAbs().maxCoeff() : 1.0;
    for (const Equation& eq : equations_) {
      const int a = eq.node[0], b = eq.node[1], d = eq.dof[0];
      if (eq.dof[1] != d || std::abs(eq.coef[0] + eq.coef[1]) > 1e-12 * std::abs(eq.coef[0]) || eq.coef[0] == 0.0 || d < 0 || d > 2)
        fail(eq.line, "*EQUATION: only ties u(a, i) - u(b, i) = 0 of the same direction are supported");
      double offset = 0.0;  // u_a = u_b + offset
      if (eq.terms == 3) {
        if (eq.dof[2] != 0 || !isAux(eq.node[2]))
          fail(eq.line, "*EQUATION: a third term must be DOF 1 of an auxiliary node prescribed to (1, 0, 0)");
        offset = -eq.coef[2] / eq.coef[0];
      }
      const double expected = m.mesh.nodes(d, b) - m.mesh.nodes(d, a);
      if (std::abs(offset - expected) > 1e-9 * std::max(1.0, size))
        fail(eq.line, "*EQUATION: node " + std::to_string(nodeIds_[std::size_t(a)]) + " would not end where node " +
                          std::to_string(nodeIds_[std::size_t(b)]) +
                          " ends (only sutures are supported: equal displacement of coincident nodes)");
      ties[{a, b}].insert(d);
      tieLine[{a, b}] = eq.line;
    }
    for (const auto& [pair, dofs] : ties) {
      if (dofs.size() != 3)
        fail(tieLine[pair], "*EQUATION ties node " + std::to_string(nodeIds_[std::size_t(pair.first)]) + " to node " +
                                std::to_string(nodeIds_[std::size_t(pair.second)]) +
                                " in some directions only: a suture needs all three");
      m.constraints.suture(pair.first, pair.second);
    }
    m.load.nodalForces = forces_;
    for (const auto& [face, p] : pressures_) m.load.facePressures.push_back({face.first, face.second, p});
    // Gravity: one acceleration for every element with a density.
    bool have = false;
    for (std::size_t e = 0; e < elements_.size(); ++e) {
      if (m.materials.at(elements_[e].region).density <= 0.0) continue;
      auto it = gravity_.find(elementNumbers_[e]);
      const Eigen::Vector3d g = it == gravity_.end() ? Eigen::Vector3d::Zero() : it->second;
      if (!have) m.load.gravity = g;
      else if ((g - m.load.gravity).norm() > 1e-12 * std::max(1.0, g.norm()))
        fail(gravityLine_, "*DLOAD GRAV differs between elements (e.g. element " + std::to_string(elementNumbers_[e]) +
                               "): only one acceleration for the whole model is supported");
      have = true;
    }
    return m;
  }

  std::string source_;
  CalculixReadOptions options_;
  std::vector<Line> lines_;
  int line_ = 0;
  int steps_ = 0;
  std::vector<Eigen::Vector3d> coords_;
  std::vector<long> nodeIds_;
  std::map<long, int> nodeIndex_;
  std::vector<Element> elements_;
  std::vector<long> elementNumbers_;
  std::vector<int> elementLines_;
  std::vector<int> elementNodeCounts_;  ///< 20, 15 or 8: the deck's element type
  std::map<long, int> elementIds_;
  std::map<std::string, std::vector<long>> nsets_, elsets_;
  std::string material_;
  std::map<std::string, int> materialIndex_;
  std::vector<std::string> names_;
  MaterialTable materials_;
  std::map<long, int> sections_;
  std::vector<Boundary> boundary_;
  std::vector<std::pair<int, Eigen::Vector3d>> forces_;
  std::map<long, Eigen::Vector3d> gravity_;
  std::map<std::pair<int, int>, double> pressures_;  ///< (element index, face 1..6) -> MPa
  int gravityLine_ = 0;
  std::vector<Equation> equations_;
};

}  // namespace

CalculixModel parseCalculixInput(const std::string& text, const std::string& sourceName,
                                 const CalculixReadOptions& options) {
  return Parser(text, sourceName, options).run();
}

CalculixModel readCalculixInput(const std::string& path, const CalculixReadOptions& options) {
  std::ifstream f(path);
  if (!f) throw std::runtime_error("cannot read the input deck " + path);
  std::ostringstream s;
  s << f.rdbuf();
  return parseCalculixInput(s.str(), path, options);
}

}  // namespace caps::fem
