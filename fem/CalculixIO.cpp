#include "fem/CalculixIO.h"

#include "fem/ElementNumbering.h"
#include "fem/FacePressure.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

namespace caps::fem {

namespace {

std::string regionName(const char* prefix, int region)
{
  std::ostringstream name;
  name << prefix << (region < 0 ? "M" : "") << (region < 0 ? -region : region);
  return name.str();
}

/// *CONTROLS for tight Newton convergence in ccx: residual at most 1e-8 of
/// the average force (R_n, and R_p after I_P iterations) and correction at
/// most 1e-8 of the increment's displacement (C_n), where ccx's defaults
/// are 0.005 and 0.01; more iterations allowed before a cut-back.
constexpr const char* kTightControls = "*CONTROLS, PARAMETERS=FIELD\n1e-8, 1e-8, 0.01, , 1e-8, 1e-5, 1e-8, 1e-8\n"
                                       "*CONTROLS, PARAMETERS=TIME INCREMENTATION\n8, 10, 9, 30, 10, 4, , 5\n";

/// @a v as a ccx data field. ccx 2.20 reads at most 20 characters of a
/// field and silently drops the rest (-8.88178419700125e-16 was read as
/// -0.888), so 13 significant digits: "%.13g" is at most 20 characters with
/// sign, point and a three-digit exponent. Values within 1e-13 @a scale of
/// zero (e.g. 1e-16 rounding noise beside 100 mm coordinates) are written
/// as 0: they are below what 13 digits of the largest value resolve.
std::string ccxNumber(double v, double scale = 0.0)
{
  if (!std::isfinite(v))
    throw std::invalid_argument("CalculiX cannot read the non-finite number " + std::to_string(v));
  if (std::abs(v) <= 1e-13 * scale)
    v = 0.0;
  char text[32];
  std::snprintf(text, sizeof text, "%.13g", v);
  return text;
}

/// The material card of @a h: *HYPERELASTIC NEO HOOKE (C10, D1) or
/// MOONEY-RIVLIN (C10, C01, D1), or *ELASTIC for St. Venant-Kirchhoff
/// (ccx's *ELASTIC under NLGEOM is that law).
std::string hyperelasticLines(const HyperelasticMaterial& h, int region)
{
  switch (h.law)
  {
  case HyperelasticLaw::NeoHookean:
    return "*HYPERELASTIC, NEO HOOKE\n" + ccxNumber(h.c10) + ", " + ccxNumber(h.d1) + "\n";
  case HyperelasticLaw::MooneyRivlin:
    return "*HYPERELASTIC, MOONEY-RIVLIN\n" + ccxNumber(h.c10) + ", " + ccxNumber(h.c01) + ", " + ccxNumber(h.d1) +
           "\n";
  case HyperelasticLaw::StVenantKirchhoff:
    return "*ELASTIC\n" + ccxNumber(h.youngsModulus) + ", " + ccxNumber(h.poissonRatio) + "\n";
  default:
    throw std::invalid_argument(std::string("region ") + std::to_string(region) + " is " + lawName(h.law) +
                                ", which CalculiX has no keyword for (neo-Hookean, Mooney-Rivlin and St. "
                                "Venant-Kirchhoff can be exported)");
  }
}

/// *STEP and *STATIC: linear, or NLGEOM with the increment line when the
/// step asks for it or a material is hyperelastic (ccx would go nonlinear
/// anyway), and the tight *CONTROLS if asked.
std::string stepLines(const CalculixExportOptions& options, bool hyperelastic)
{
  const StaticStep& s = options.step;
  if (!s.nlgeom && !hyperelastic)
    return "*STEP\n*STATIC\n";
  // INC= allows every increment down to the minimum (ccx's default is 100).
  const double increments = std::ceil(s.period / std::max(s.minimumIncrement, 1e-12)) + 10.0;
  std::ostringstream o;
  o << "*STEP, NLGEOM, INC=" << long(std::clamp(increments, 1000.0, 1e7)) << "\n*STATIC" << (s.direct ? ", DIRECT" : "")
    << "\n"
    << ccxNumber(s.initialIncrement) << ", " << ccxNumber(s.period) << ", " << ccxNumber(s.minimumIncrement) << ", "
    << ccxNumber(s.maximumIncrement) << "\n";
  if (options.tightControls)
    o << kTightControls;
  return o.str();
}

/// One deck of calculixInput(), written step by step in the deck's order.
/// The steps share the resolved constraints, the representative DOF of
/// each reduced DOF, the equations' offsets and whether the auxiliary node
/// is needed.
struct DeckWriter
{
  DeckWriter(const Mesh& mesh, const MaterialTable& materials, const LoadCase& load,
             const CalculixExportOptions& options, const ConstraintMap& map)
    : mesh(mesh), materials(materials), load(load), options(options), map(map), n(mesh.nodeCount()), aux(n + 1)
  {
    // ccx reads at most 20 characters per field: 13 significant digits always
    // fit (-1.234567890123e-100 is 20), 14 do not. Fields written through
    // ccxNumber() also lose rounding noise.
    o.precision(13);
    for (const Element& el : mesh.elements)
      usedRegions.insert(el.region);
  }

  void writeNodes();
  void chooseRepresentatives();
  void computeGeneralOffsets();
  void writeAuxiliaryNode();
  void writeElements();
  void writeMaterials();
  void writeSutureEquations();
  void writeGeneralEquations();
  void writeBoundaries();
  void writeNodalForces();
  void writeGravity();
  void writeFacePressures();

  const Mesh& mesh;
  const MaterialTable& materials;
  const LoadCase& load;
  const CalculixExportOptions& options;
  const ConstraintMap& map;
  const Eigen::Index n;
  const Eigen::Index aux;
  std::ostringstream o;
  std::set<int> usedRegions;
  std::vector<int> representative;
  std::vector<double> generalBeta;
  bool needAux = false;
  bool anyHyperelastic = false;
  bool equationHeader = false;
};

void DeckWriter::writeNodes()
{
  o << "*HEADING\nCAPS finite element model (Bathe 8-to-20 node elements as C3D20)\n";
  o << "*NODE, NSET=NALLNODES\n";
  const double extent = mesh.nodes.size() ? mesh.nodes.cwiseAbs().maxCoeff() : 0.0;
  for (Eigen::Index i = 0; i < n; ++i)
    o << i + 1 << ", " << ccxNumber(mesh.nodes(0, i), extent) << ", " << ccxNumber(mesh.nodes(1, i), extent) << ", "
      << ccxNumber(mesh.nodes(2, i), extent) << "\n";
}

void DeckWriter::chooseRepresentatives()
{
  // Representative DOF of each reduced DOF in the *EQUATIONs. ccx 2.20
  // mis-assembles an equation whose dependent DOF belongs to a node repeated
  // in a degenerate (wedge) C3D20, so such a node is made the independent one.
  std::vector<char> repeated(std::size_t(n), 0);
  for (const Element& el : mesh.elements)
    for (int a = 0; a < kHex20NodeCount; ++a)
      for (int b = a + 1; b < kHex20NodeCount; ++b)
        if (el.nodes[a] >= 0 && el.nodes[a] == el.nodes[b])
          repeated[std::size_t(el.nodes[a])] = 1;
  representative = map.masterOf;
  for (std::size_t d = 0; d < map.reduced.size(); ++d)
  {
    const int r = map.reduced[d];
    if (r >= 0 && repeated[d / 3] && !repeated[std::size_t(representative[std::size_t(r)] / 3)])
      representative[std::size_t(r)] = int(d);
  }
  for (std::size_t d = 0; d < map.reduced.size(); ++d)
  {
    const int r = map.reduced[d];
    if (r >= 0 && representative[std::size_t(r)] != int(d) &&
        map.offset[Eigen::Index(d)] != map.offset[representative[std::size_t(r)]])
      needAux = true;
  }
}

void DeckWriter::computeGeneralOffsets()
{
  // General rows of T (equations), u_d = sum c_k Ubar_k + g_d, written over
  // the representatives: u_d - sum c_k u_rep(k) - beta u_aux = 0 with
  // beta = g_d - sum c_k g_rep(k). A row without terms is a *BOUNDARY.
  generalBeta.assign(map.general.size(), 0.0);
  for (std::size_t g = 0; g < map.general.size(); ++g)
  {
    double beta = map.offset[map.general[g]];
    for (int e = map.generalStart[g]; e < map.generalStart[g + 1]; ++e)
      beta -= map.generalCoefficient[std::size_t(e)] *
              map.offset[representative[std::size_t(map.generalIndex[std::size_t(e)])]];
    generalBeta[g] = beta;
    if (beta != 0.0 && map.generalStart[g + 1] > map.generalStart[g])
      needAux = true;
  }
}

void DeckWriter::writeAuxiliaryNode()
{
  if (needAux)
    o << aux << ", " << mesh.nodes(0, 0) << ", " << mesh.nodes(1, 0) << ", " << mesh.nodes(2, 0) << "\n";
}

void DeckWriter::writeElements()
{
  // Elements, grouped by region and type.
  // Type 20 is C3D20 (3x3x3), 21 C3D20R (2x2x2, ccx's reduced brick), 15
  // C3D15 (ccx's 9 points, whatever the element's rule), 8 C3D8 (ccx's 2x2x2).
  std::map<std::pair<int, int>, std::vector<std::size_t>> groups; // (region, type) -> elements
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Element& el = mesh.elements[e];
    if (el.kind == ElementKind::Wedge15)
    {
      groups[{el.region, 15}].push_back(e);
      continue;
    }
    const bool reduced = integrationPointsOf(el, options.defaultIntegrationPoints) == 2;
    int present = 0;
    for (int k = kHex20CornerCount; k < kHex20NodeCount; ++k)
      present += el.nodes[k] >= 0;
    if (present != 0 && present != 12)
      throw std::invalid_argument("element " + std::to_string(e) + " has " + std::to_string(present) +
                                  " of 12 mid-side nodes; CalculiX needs all (C3D20) or none (C3D8)");
    groups[{el.region, present == 12 ? (reduced ? 21 : 20) : 8}].push_back(e);
  }
  const auto& toC3D20 = batheToC3D20Table();
  for (const auto& [key, elements] : groups)
  {
    const int count = key.second == 21 ? 20 : key.second;
    o << "*ELEMENT, TYPE=C3D" << count << (key.second == 21 ? "R" : "") << ", ELSET=" << regionName("R", key.first)
      << "\n";
    for (std::size_t e : elements)
    {
      const Element& el = mesh.elements[e];
      int c3d[kHex20NodeCount];
      for (int k = 0; k < count; ++k)
      {
        const int number = count == kWedge15NodeCount ? wedge15ToC3D15(k) : toC3D20[std::size_t(k)];
        c3d[number - 1] = el.nodes[std::size_t(k)] + 1;
      }
      // At most 16 entries per line; a trailing comma continues the record.
      o << e + 1;
      for (int j = 0; j < count; ++j)
        o << (j == 15 ? ",\n" : ", ") << c3d[j];
      o << "\n";
    }
  }
}

void DeckWriter::writeMaterials()
{
  for (int region : usedRegions)
    anyHyperelastic = anyHyperelastic || options.hyperelastic.count(region);
  for (int region : usedRegions)
  {
    const LinearElasticMaterial& m = materials.at(region);
    o << "*MATERIAL, NAME=" << regionName("M", region) << "\n";
    const auto h = options.hyperelastic.find(region);
    if (h == options.hyperelastic.end())
      o << "*ELASTIC\n" << ccxNumber(m.youngsModulus) << ", " << ccxNumber(m.poissonRatio) << "\n";
    else
      o << hyperelasticLines(h->second, region);
    if (m.density > 0.0)
      o << "*DENSITY\n" << ccxNumber(m.density) << "\n";
    o << "*SOLID SECTION, ELSET=" << regionName("R", region) << ", MATERIAL=" << regionName("M", region) << "\n";
  }
}

void DeckWriter::writeSutureEquations()
{
  // Sutures (resolved): u_i - u_m - beta u_aux = 0, beta = g_i - g_m.
  for (std::size_t d = 0; d < map.reduced.size(); ++d)
  {
    if (map.reduced[d] < 0)
      continue;
    const int master = representative[std::size_t(map.reduced[d])];
    if (master == int(d))
      continue;
    if (!equationHeader)
      o << "*EQUATION\n";
    equationHeader = true;
    const double beta = map.offset[Eigen::Index(d)] - map.offset[master];
    o << (beta != 0.0 ? 3 : 2) << "\n"
      << d / 3 + 1 << ", " << d % 3 + 1 << ", 1.0, " << master / 3 + 1 << ", " << master % 3 + 1 << ", -1.0";
    if (beta != 0.0)
      o << ", " << aux << ", 1, " << -beta;
    o << "\n";
  }
}

void DeckWriter::writeGeneralEquations()
{
  // Equations (resolved, so no dependent DOF appears in another equation):
  // ccx reads at most 4 terms (12 fields) per line. The ccx 2.20 fault above
  // also hits an equation whose dependent DOF is on a repeated node, and no
  // choice of dependent DOF avoids it when all terms are that node's (u . n =
  // 0): ccx then solves another model (giving the second occurrence its own
  // coincident node, tied to the first, avoids it; that is the element
  // writer's part).
  for (std::size_t g = 0; g < map.general.size(); ++g)
  {
    const int first = map.generalStart[g], last = map.generalStart[g + 1];
    if (first == last)
      continue;
    if (!equationHeader)
      o << "*EQUATION\n";
    equationHeader = true;
    const int d = map.general[g];
    const double beta = generalBeta[g];
    o << 1 + (last - first) + (beta != 0.0 ? 1 : 0) << "\n" << d / 3 + 1 << ", " << d % 3 + 1 << ", 1.0";
    int written = 1;
    const auto term = [this, &written](long node, int direction, double coefficient) {
      o << (written % 4 == 0 ? "\n" : ", ") << node << ", " << direction << ", " << coefficient;
      ++written;
    };
    for (int e = first; e < last; ++e)
    {
      const int rep = representative[std::size_t(map.generalIndex[std::size_t(e)])];
      term(rep / 3 + 1, rep % 3 + 1, -map.generalCoefficient[std::size_t(e)]);
    }
    if (beta != 0.0)
      term(long(aux), 1, -beta);
    o << "\n";
  }
}

void DeckWriter::writeBoundaries()
{
  o << stepLines(options, anyHyperelastic) << "*BOUNDARY\n";
  if (needAux)
    o << aux << ", 1, 1, 1.0\n" << aux << ", 2, 3, 0.0\n";
  for (std::size_t d = 0, g = 0; d < map.reduced.size(); ++d)
  {
    if (map.reduced[d] >= 0)
      continue;
    if (g < map.general.size() && map.general[g] == int(d))
    {
      const bool hasTerms = map.generalStart[g + 1] > map.generalStart[g];
      ++g;
      if (hasTerms)
        continue; // written as an *EQUATION
    }
    o << d / 3 + 1 << ", " << d % 3 + 1 << ", " << d % 3 + 1 << ", " << map.offset[Eigen::Index(d)] << "\n";
  }
}

void DeckWriter::writeNodalForces()
{
  if (load.nodalForces.empty() && load.muscles.empty())
    return;
  // Sum forces per node so each (node, direction) appears once.
  std::map<int, Eigen::Vector3d> forces;
  for (const auto& [node, f] : load.nodalForces)
  {
    if (node < 0 || node >= n)
      throw std::invalid_argument("a nodal force is applied to node " + std::to_string(node) + ", outside the mesh");
    auto it = forces.emplace(node, Eigen::Vector3d::Zero()).first;
    it->second += f;
  }
  // ccx has no spherical body force: muscles go in as their consistent nodal loads.
  if (!load.muscles.empty())
  {
    const Eigen::VectorXd muscle = assembleMuscleLoad(mesh, load.muscles).load;
    for (Eigen::Index i = 0; i < n; ++i)
      if (!muscle.segment<3>(3 * i).isZero(0.0))
        forces.emplace(int(i), Eigen::Vector3d::Zero()).first->second += muscle.segment<3>(3 * i);
  }
  o << "*CLOAD\n";
  for (const auto& [node, f] : forces)
    for (int d = 0; d < 3; ++d)
      if (f[d] != 0.0)
        o << node + 1 << ", " << d + 1 << ", " << ccxNumber(f[d]) << "\n";
}

void DeckWriter::writeGravity()
{
  const double g = load.gravity.norm();
  if (g <= 0.0)
    return;
  const Eigen::Vector3d dir = load.gravity / g;
  bool header = false;
  for (int region : usedRegions)
  {
    if (materials.at(region).density <= 0.0)
      continue;
    if (!header)
      o << "*DLOAD\n";
    header = true;
    o << regionName("R", region) << ", GRAV, " << ccxNumber(g) << ", " << ccxNumber(dir[0], 1.0) << ", "
      << ccxNumber(dir[1], 1.0) << ", " << ccxNumber(dir[2], 1.0) << "\n";
  }
}

void DeckWriter::writeFacePressures()
{
  if (load.facePressures.empty())
    return;
  validateFacePressures(mesh, load.facePressures);
  // Our face numbers are CalculiX's for each type written: C3D20 and C3D8
  // (also a wedge written as a degenerate C3D20), C3D15 for a native
  // wedge. Pressures on the same face add up in ccx as in LoadCase; one
  // line per face keeps the deck plain.
  std::map<std::pair<int, int>, double> pressures;
  for (const FacePressure& p : load.facePressures)
    pressures[{p.element, p.face}] += p.pressure;
  o << "*DLOAD\n";
  for (const auto& [face, p] : pressures)
    if (p != 0.0)
      o << face.first + 1 << ", P" << face.second << ", " << ccxNumber(p) << "\n";
}

} // namespace

std::string calculixInput(const Mesh& mesh, const MaterialTable& materials, const Constraints& constraints,
                          const LoadCase& load, const CalculixExportOptions& options)
{
  validateMesh(mesh, materials);
  const ConstraintMap map = resolveConstraints(mesh, constraints);
  DeckWriter deck(mesh, materials, load, options, map);
  deck.writeNodes();
  deck.chooseRepresentatives();
  deck.computeGeneralOffsets();
  deck.writeAuxiliaryNode();
  deck.writeElements();
  deck.writeMaterials();
  deck.writeSutureEquations();
  deck.writeGeneralEquations();
  deck.writeBoundaries();
  deck.writeNodalForces();
  deck.writeGravity();
  deck.writeFacePressures();
  deck.o << "*NODE FILE\nU\n*NODE PRINT, NSET=NALLNODES\nU\n*END STEP\n";
  return deck.o.str();
}

std::string calculixInput(const Mesh& mesh, const MaterialTable& materials, const Constraints& constraints,
                          const LoadCase& load)
{
  return calculixInput(mesh, materials, constraints, load, CalculixExportOptions{});
}

void writeCalculixInput(const std::string& path, const Mesh& mesh, const MaterialTable& materials,
                        const Constraints& constraints, const LoadCase& load, const CalculixExportOptions& options)
{
  const std::string text = calculixInput(mesh, materials, constraints, load, options);
  std::ofstream f(path);
  if (!f)
    throw std::runtime_error("cannot write the CalculiX input " + path);
  f << text;
  if (!f)
    throw std::runtime_error("error while writing the CalculiX input " + path);
}

namespace {

Eigen::Matrix3Xd collect(const std::map<long, Eigen::Vector3d>& values, Eigen::Index nodeCount, const std::string& path)
{
  Eigen::Matrix3Xd u(3, nodeCount);
  for (Eigen::Index i = 0; i < nodeCount; ++i)
  {
    auto it = values.find(long(i + 1));
    if (it == values.end())
      throw std::runtime_error(path + " has no displacement for node " + std::to_string(i + 1) + " (CAPS node " +
                               std::to_string(i) + ")");
    u.col(i) = it->second;
  }
  return u;
}

} // namespace

Eigen::Matrix3Xd readFrdDisplacements(const std::string& path, Eigen::Index nodeCount)
{
  std::ifstream f(path);
  if (!f)
    throw std::runtime_error("cannot read the CalculiX result " + path);
  std::map<long, Eigen::Vector3d> last, current;
  bool inDisp = false, found = false;
  std::string line;
  while (std::getline(f, line))
  {
    if (line.rfind(" -4", 0) == 0)
    {
      inDisp = line.find("DISP") != std::string::npos;
      if (inDisp)
        current.clear();
      continue;
    }
    if (!inDisp)
      continue;
    if (line.rfind(" -3", 0) == 0)
    {
      last = current;
      found = true;
      inDisp = false;
      continue;
    }
    if (line.rfind(" -1", 0) != 0)
      continue;
    // Fixed format: " -1", I10 node, then 12-character E12.5 fields.
    if (line.size() < 13 + 36)
      throw std::runtime_error(path + ": short displacement line: " + line);
    const long node = std::strtol(line.substr(3, 10).c_str(), nullptr, 10);
    Eigen::Vector3d v;
    for (int d = 0; d < 3; ++d)
      v[d] = std::strtod(line.substr(13 + 12 * std::size_t(d), 12).c_str(), nullptr);
    current[node] = v;
  }
  if (!found)
    throw std::runtime_error(path + " has no DISP block (was *NODE FILE U requested?)");
  return collect(last, nodeCount, path);
}

Eigen::Matrix3Xd readDatDisplacements(const std::string& path, Eigen::Index nodeCount)
{
  std::ifstream f(path);
  if (!f)
    throw std::runtime_error("cannot read the CalculiX result " + path);
  std::map<long, Eigen::Vector3d> values;
  bool inTable = false, found = false;
  std::string line;
  while (std::getline(f, line))
  {
    if (line.find("displacements (vx,vy,vz)") != std::string::npos)
    {
      inTable = true;
      found = true;
      values.clear();
      continue;
    }
    if (!inTable)
      continue;
    std::istringstream s(line);
    long node;
    Eigen::Vector3d v;
    if (s >> node >> v[0] >> v[1] >> v[2])
    {
      values[node] = v;
    }
    else if (line.find_first_not_of(" \t\r") != std::string::npos)
    {
      inTable = false;
    }
  }
  if (!found)
    throw std::runtime_error(path + " has no displacement table (was *NODE PRINT U requested?)");
  return collect(values, nodeCount, path);
}

} // namespace caps::fem
