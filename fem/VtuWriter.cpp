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

bool allMidsides(const Element& el, const std::vector<int>& batheNodes) {
  for (int k : batheNodes)
    if (el.nodes[std::size_t(k)] < 0) return false;
  return true;
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
  VtkCell cell;
  // The wedge numbering is VTK's quadratic wedge order (ElementNumbering.h).
  if (el.kind == ElementKind::Wedge15) {
    cell.type = kVtkQuadraticWedge;
    cell.nodes.assign(el.nodes.begin(), el.nodes.begin() + kWedge15NodeCount);
    return cell;
  }
  std::array<int, kWedge15NodeCount> slots{};
  if (degenerateWedgeSlots(el, nodes, slots)) {
    const std::vector<int> mids(slots.begin() + kWedge15CornerCount, slots.end());
    cell.type = allMidsides(el, mids) ? kVtkQuadraticWedge : kVtkWedge;
    const int count = cell.type == kVtkQuadraticWedge ? kWedge15NodeCount : kWedge15CornerCount;
    for (int k = 0; k < count; ++k) cell.nodes.push_back(el.nodes[std::size_t(slots[std::size_t(k)])]);
    return cell;
  }
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
