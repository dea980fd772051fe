#include "fem/VtuWriter.h"

#include <Eigen/Geometry>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <system_error>
#include <type_traits>

namespace caps::fem {

namespace {

constexpr std::array<int, kHex20NodeCount> kVtkHexToBathe{6,  7,  4,  5,  2, 3, 0,  1,  14, 15,
                                                          12, 13, 10, 11, 8, 9, 18, 19, 16, 17};

bool allMidsides(const Element& el, const std::vector<int>& batheNodes)
{
  for (int k : batheNodes)
    if (el.nodes[std::size_t(k)] < 0)
      return false;
  return true;
}

/// The document as it grows: numbers formatted by std::to_chars, which gives
/// the bytes of an ostream with precision(17) (printf's %.17g) at a tenth
/// of the cost.
class Text
{
public:
  Text& operator<<(const char* s)
  {
    text_ += s;
    return *this;
  }
  Text& operator<<(const std::string& s)
  {
    text_ += s;
    return *this;
  }
  Text& operator<<(char c)
  {
    text_ += c;
    return *this;
  }
  Text& operator<<(double v)
  {
    char buffer[32];
    const auto r = std::to_chars(buffer, buffer + sizeof buffer, v, std::chars_format::general, 17);
    text_.append(buffer, r.ptr);
    return *this;
  }
  template <class Integer, class = std::enable_if_t<std::is_integral_v<Integer>>> Text& operator<<(Integer v)
  {
    char buffer[24];
    const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
    text_.append(buffer, r.ptr);
    return *this;
  }
  void reserve(std::size_t n) { text_.reserve(n); }
  std::string take() { return std::move(text_); }

private:
  std::string text_;
};

void writeArray(Text& o, const VtuArray& a)
{
  o << "        <DataArray type=\"Float64\" Name=\"" << a.name << "\" NumberOfComponents=\"" << a.values.rows()
    << "\" format=\"ascii\">\n";
  for (Eigen::Index j = 0; j < a.values.cols(); ++j)
  {
    o << "         ";
    for (Eigen::Index i = 0; i < a.values.rows(); ++i)
      o << ' ' << a.values(i, j);
    o << '\n';
  }
  o << "        </DataArray>\n";
}

} // namespace

const std::array<int, kHex20NodeCount>& vtkQuadraticHexToBathe()
{
  return kVtkHexToBathe;
}

VtkCell vtkCell(const Element& el, const Eigen::Matrix3Xd& nodes)
{
  VtkCell cell;
  // The wedge numbering is VTK's quadratic wedge order (ElementNumbering.h).
  if (el.kind == ElementKind::Wedge15)
  {
    cell.type = kVtkQuadraticWedge;
    cell.nodes.assign(el.nodes.begin(), el.nodes.begin() + kWedge15NodeCount);
    return cell;
  }
  std::array<int, kWedge15NodeCount> slots{};
  if (degenerateWedgeSlots(el, nodes, slots))
  {
    const std::vector<int> mids(slots.begin() + kWedge15CornerCount, slots.end());
    cell.type = allMidsides(el, mids) ? kVtkQuadraticWedge : kVtkWedge;
    const int count = cell.type == kVtkQuadraticWedge ? kWedge15NodeCount : kWedge15CornerCount;
    for (int k = 0; k < count; ++k)
      cell.nodes.push_back(el.nodes[std::size_t(slots[std::size_t(k)])]);
    return cell;
  }
  std::vector<int> mids;
  for (int k = kHex20CornerCount; k < kHex20NodeCount; ++k)
    mids.push_back(k);
  cell.type = allMidsides(el, mids) ? kVtkQuadraticHexahedron : kVtkHexahedron;
  const int count = cell.type == kVtkQuadraticHexahedron ? kHex20NodeCount : kHex20CornerCount;
  for (int i = 0; i < count; ++i)
    cell.nodes.push_back(el.nodes[std::size_t(kVtkHexToBathe[std::size_t(i)])]);
  return cell;
}

std::string vtuDocument(const Mesh& mesh, const std::vector<VtuArray>& pointData, const std::vector<VtuArray>& cellData)
{
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
  Text o;
  std::size_t values = std::size_t(mesh.nodes.size());
  for (const auto& a : pointData)
    values += std::size_t(a.values.size());
  for (const auto& a : cellData)
    values += std::size_t(a.values.size());
  o.reserve(24 * values + 140 * std::size_t(m) + 4096);
  o << "<?xml version=\"1.0\"?>\n"
    << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
    << "  <UnstructuredGrid>\n"
    << "    <Piece NumberOfPoints=\"" << n << "\" NumberOfCells=\"" << m << "\">\n";
  o << "      <PointData>\n";
  for (const auto& a : pointData)
    writeArray(o, a);
  o << "      </PointData>\n      <CellData>\n";
  o << "        <DataArray type=\"Int32\" Name=\"region\" format=\"ascii\">\n         ";
  for (Eigen::Index e = 0; e < m; ++e)
    o << ' ' << mesh.elements[std::size_t(e)].region;
  o << "\n        </DataArray>\n";
  for (const auto& a : cellData)
    writeArray(o, a);
  o << "      </CellData>\n";
  o << "      <Points>\n";
  writeArray(o, {"Points", mesh.nodes});
  o << "      </Points>\n      <Cells>\n";
  std::vector<VtkCell> cells;
  cells.reserve(mesh.elements.size());
  for (const Element& el : mesh.elements)
    cells.push_back(vtkCell(el, mesh.nodes));
  o << "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (const VtkCell& cell : cells)
  {
    o << "         ";
    for (int id : cell.nodes)
      o << ' ' << id;
    o << '\n';
  }
  o << "        </DataArray>\n"
    << "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n         ";
  long offset = 0;
  for (const VtkCell& cell : cells)
  {
    offset += long(cell.nodes.size());
    o << ' ' << offset;
  }
  o << "\n        </DataArray>\n"
    << "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n         ";
  for (const VtkCell& cell : cells)
    o << ' ' << cell.type;
  o << "\n        </DataArray>\n";
  o << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
  return o.take();
}

void writeVtu(const std::string& path, const Mesh& mesh, const std::vector<VtuArray>& pointData,
              const std::vector<VtuArray>& cellData)
{
  const std::string text = vtuDocument(mesh, pointData, cellData);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f)
    throw std::runtime_error("cannot write the VTU file " + path);
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  if (std::fclose(f) != 0 || !written)
    throw std::runtime_error("error while writing the VTU file " + path);
}

} // namespace caps::fem
