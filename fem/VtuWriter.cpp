#include "fem/VtuWriter.h"

#include <Eigen/Geometry>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace caps::fem {

namespace {

constexpr std::array<int, kHex20NodeCount> kVtkHexToBathe{6,  7,  4,  5,  2,  3,  0,  1,  14, 15,
                                                          12, 13, 10, 11, 8,  9,  18, 19, 16, 17};

/// Bathe node at natural coordinates @a c (each -1, 0 or 1).
int batheAt(const std::array<int, 3>& c) {
  for (int k = 0; k < kHex20NodeCount; ++k) {
    const Eigen::Vector3d n = batheNaturalCoordinates(k);
    if (int(n[0]) == c[0] && int(n[1]) == c[1] && int(n[2]) == c[2]) return k;
  }
  throw std::logic_error("no Bathe node at these natural coordinates");
}

/// Natural coordinates with value @a va on axis a, @a vb on axis b, @a vc on axis c.
std::array<int, 3> on(int a, int va, int b, int vb, int c, int vc) {
  std::array<int, 3> x{};
  x[std::size_t(a)] = va;
  x[std::size_t(b)] = vb;
  x[std::size_t(c)] = vc;
  return x;
}

bool allMidsides(const Element& el, const std::vector<int>& batheNodes) {
  for (int k : batheNodes)
    if (el.nodes[std::size_t(k)] < 0) return false;
  return true;
}

/// The wedge cell of a degenerate element, or an empty cell if it is none.
VtkCell wedgeCell(const Element& el, const Eigen::Matrix3Xd& x) {
  auto node = [&](const std::array<int, 3>& c) { return el.nodes[std::size_t(batheAt(c))]; };
  for (int a = 0; a < 3; ++a)  // axis along which two edges collapse
    for (int b = 0; b < 3; ++b) {
      if (b == a) continue;
      const int c = 3 - a - b;  // extrusion axis
      for (int beta : {-1, 1}) {
        // Edges along a at b = beta, on the faces c = -1 and c = +1, collapsed.
        bool collapsed = true;
        for (int gamma : {-1, 1})
          collapsed = collapsed && node(on(a, -1, b, beta, c, gamma)) == node(on(a, 1, b, beta, c, gamma));
        if (!collapsed) continue;
        // The other four corners distinct from each other and from the apexes.
        std::vector<int> corners;
        for (int gamma : {-1, 1})
          for (int alpha : {-1, 1, 0}) {
            corners.push_back(alpha == 0 ? node(on(a, -1, b, beta, c, gamma)) : node(on(a, alpha, b, -beta, c, gamma)));
          }
        bool distinct = true;
        for (std::size_t i = 0; i < corners.size(); ++i)
          for (std::size_t j = i + 1; j < corners.size(); ++j) distinct = distinct && corners[i] != corners[j];
        if (!distinct) continue;
        // Triangle on face c = gamma: apex P (b = beta), Q (a = -1, b = -beta), R (a = +1, b = -beta).
        int qa = -1, ra = 1;
        {
          const Eigen::Vector3d p = x.col(node(on(a, -1, b, beta, c, -1)));
          const Eigen::Vector3d q = x.col(node(on(a, qa, b, -beta, c, -1)));
          const Eigen::Vector3d r = x.col(node(on(a, ra, b, -beta, c, -1)));
          const Eigen::Vector3d top = x.col(node(on(a, -1, b, beta, c, 1)));
          // VTK: normal of (0, 1, 2) points away from (3, 4, 5).
          if ((q - p).cross(r - p).dot(top - p) > 0) std::swap(qa, ra);
        }
        // Natural coordinates of the six corners and nine mid-edges in VTK order.
        auto corner = [&](int i, int gamma) {
          return i == 0 ? on(a, -1, b, beta, c, gamma) : on(a, i == 1 ? qa : ra, b, -beta, c, gamma);
        };
        VtkCell cell;
        for (int gamma : {-1, 1})
          for (int i = 0; i < 3; ++i) cell.nodes.push_back(node(corner(i, gamma)));
        std::vector<std::array<int, 3>> mids;
        for (int gamma : {-1, 1}) {
          mids.push_back(on(a, qa, b, 0, c, gamma));   // P-Q
          mids.push_back(on(a, 0, b, -beta, c, gamma)); // Q-R
          mids.push_back(on(a, ra, b, 0, c, gamma));   // R-P
        }
        mids.push_back(on(a, -1, b, beta, c, 0));  // P vertical (either collapsed slot)
        mids.push_back(on(a, qa, b, -beta, c, 0));
        mids.push_back(on(a, ra, b, -beta, c, 0));
        std::vector<int> midBathe;
        for (const auto& m : mids) midBathe.push_back(batheAt(m));
        if (allMidsides(el, midBathe)) {
          cell.type = kVtkQuadraticWedge;
          for (int k : midBathe) cell.nodes.push_back(el.nodes[std::size_t(k)]);
        } else {
          cell.type = kVtkWedge;
        }
        return cell;
      }
    }
  return {};
}

void writeArray(std::ostream& o, const VtuArray& a) {
  o << "        <DataArray type=\"Float64\" Name=\"" << a.name << "\" NumberOfComponents=\"" << a.values.rows()
    << "\" format=\"ascii\">\n";
  for (Eigen::Index j = 0; j < a.values.cols(); ++j) {
    o << "         ";
    for (Eigen::Index i = 0; i < a.values.rows(); ++i) o << ' ' << a.values(i, j);
    o << '\n';
  }
  o << "        </DataArray>\n";
}

}  // namespace

const std::array<int, kHex20NodeCount>& vtkQuadraticHexToBathe() { return kVtkHexToBathe; }

VtkCell vtkCell(const Element& el, const Eigen::Matrix3Xd& nodes) {
  int distinct = 0;
  for (int k = 0; k < kHex20CornerCount; ++k) {
    bool first = true;
    for (int j = 0; j < k; ++j) first = first && el.nodes[std::size_t(j)] != el.nodes[std::size_t(k)];
    distinct += first;
  }
  if (distinct == 6) {
    VtkCell w = wedgeCell(el, nodes);
    if (!w.nodes.empty()) return w;
  }
  VtkCell cell;
  std::vector<int> mids;
  for (int k = kHex20CornerCount; k < kHex20NodeCount; ++k) mids.push_back(k);
  cell.type = allMidsides(el, mids) ? kVtkQuadraticHexahedron : kVtkHexahedron;
  const int count = cell.type == kVtkQuadraticHexahedron ? kHex20NodeCount : kHex20CornerCount;
  for (int i = 0; i < count; ++i) cell.nodes.push_back(el.nodes[std::size_t(kVtkHexToBathe[std::size_t(i)])]);
  return cell;
}

std::string vtuDocument(const Mesh& mesh, const std::vector<VtuArray>& pointData,
                        const std::vector<VtuArray>& cellData) {
  const Eigen::Index n = mesh.nodeCount();
  const Eigen::Index m = Eigen::Index(mesh.elements.size());
  for (const auto& a : pointData)
    if (a.values.cols() != n)
      throw std::invalid_argument("point array '" + a.name + "' has " + std::to_string(a.values.cols()) +
                                  " columns, but the mesh has " + std::to_string(n) + " nodes");
  for (const auto& a : cellData)
    if (a.values.cols() != m)
      throw std::invalid_argument("cell array '" + a.name + "' has " + std::to_string(a.values.cols()) +
                                  " columns, but the mesh has " + std::to_string(m) + " elements");
  std::ostringstream o;
  o.precision(17);
  o << "<?xml version=\"1.0\"?>\n"
    << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
    << "  <UnstructuredGrid>\n"
    << "    <Piece NumberOfPoints=\"" << n << "\" NumberOfCells=\"" << m << "\">\n";
  o << "      <PointData>\n";
  for (const auto& a : pointData) writeArray(o, a);
  o << "      </PointData>\n      <CellData>\n";
  o << "        <DataArray type=\"Int32\" Name=\"region\" format=\"ascii\">\n         ";
  for (Eigen::Index e = 0; e < m; ++e) o << ' ' << mesh.elements[std::size_t(e)].region;
  o << "\n        </DataArray>\n";
  for (const auto& a : cellData) writeArray(o, a);
  o << "      </CellData>\n";
  o << "      <Points>\n";
  writeArray(o, {"Points", mesh.nodes});
  o << "      </Points>\n      <Cells>\n";
  std::ostringstream connectivity, offsets, types;
  long offset = 0;
  for (const Element& el : mesh.elements) {
    const VtkCell cell = vtkCell(el, mesh.nodes);
    connectivity << "         ";
    for (int id : cell.nodes) connectivity << ' ' << id;
    connectivity << '\n';
    offset += long(cell.nodes.size());
    offsets << ' ' << offset;
    types << ' ' << cell.type;
  }
  o << "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n"
    << connectivity.str() << "        </DataArray>\n"
    << "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n         " << offsets.str()
    << "\n        </DataArray>\n"
    << "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n         " << types.str()
    << "\n        </DataArray>\n";
  o << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
  return o.str();
}

void writeVtu(const std::string& path, const Mesh& mesh, const std::vector<VtuArray>& pointData,
              const std::vector<VtuArray>& cellData) {
  const std::string text = vtuDocument(mesh, pointData, cellData);
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write the VTU file " + path);
  f << text;
  if (!f) throw std::runtime_error("error while writing the VTU file " + path);
}

}  // namespace caps::fem
