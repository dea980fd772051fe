// VTU export: the file parses, cells carry VTK's node order (checked by
// natural coordinates against VTK's documented order) and the data arrays.

#include "FemTestMeshes.h"
#include "fem/VtuWriter.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <map>
#include <sstream>

using namespace caps::fem;
using caps::fem::test::boxMesh;

namespace {

// VTK's documented parametric coordinates (vtkQuadraticHexahedron), mapped
// to [-1, 1]: corners (-1,-1,-1), (1,-1,-1), (1,1,-1), (-1,1,-1), then the
// top; mid-edges of the bottom (0,1), (1,2), (2,3), (3,0), of the top, then
// the vertical edges (0,4), (1,5), (2,6), (3,7).
const int kVtkHex[20][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1},  {-1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1},
                            {-1, 1, 1},   {0, -1, -1}, {1, 0, -1},  {0, 1, -1},  {-1, 0, -1}, {0, -1, 1}, {1, 0, 1},
                            {0, 1, 1},    {-1, 0, 1},  {-1, -1, 0}, {1, -1, 0},  {1, 1, 0},   {-1, 1, 0}};

// A tiny XML scan: every element's name and attributes, and the text of the
// DataArray elements; checks that tags nest.
struct XmlElement
{
  std::string name;
  std::map<std::string, std::string> attributes;
  std::string text;
};

std::vector<XmlElement> scanXml(const std::string& s)
{
  std::vector<XmlElement> all;
  std::vector<std::size_t> open;
  std::size_t i = 0;
  while ((i = s.find('<', i)) != std::string::npos)
  {
    const std::size_t end = s.find('>', i);
    if (end == std::string::npos)
      throw std::runtime_error("unterminated tag");
    std::string tag = s.substr(i + 1, end - i - 1);
    if (tag[0] == '?')
    {
      i = end + 1;
      continue;
    }
    if (tag[0] == '/')
    {
      if (open.empty() || all[open.back()].name != tag.substr(1))
        throw std::runtime_error("mismatched </" + tag);
      open.pop_back();
      i = end + 1;
      continue;
    }
    const bool selfClosing = tag.back() == '/';
    if (selfClosing)
      tag.pop_back();
    XmlElement el;
    std::istringstream in(tag);
    in >> el.name;
    std::string rest((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::size_t p = 0;
    while ((p = rest.find('=', p)) != std::string::npos)
    {
      std::size_t k = rest.rfind(' ', p);
      const std::string key = rest.substr(k + 1, p - k - 1);
      const std::size_t q1 = rest.find('"', p), q2 = rest.find('"', q1 + 1);
      el.attributes[key] = rest.substr(q1 + 1, q2 - q1 - 1);
      p = q2 + 1;
    }
    const std::size_t next = s.find('<', end);
    el.text = s.substr(end + 1, next - end - 1);
    all.push_back(el);
    if (!selfClosing)
      open.push_back(all.size() - 1);
    i = end + 1;
  }
  if (!open.empty())
    throw std::runtime_error("unclosed <" + all[open.back()].name + ">");
  return all;
}

std::vector<double> numbers(const std::string& text)
{
  std::istringstream in(text);
  std::vector<double> v;
  double x;
  while (in >> x)
    v.push_back(x);
  return v;
}

const XmlElement& array(const std::vector<XmlElement>& xml, const std::string& name)
{
  for (const auto& e : xml)
    if (e.name == "DataArray" && e.attributes.count("Name") && e.attributes.at("Name") == name)
      return e;
  throw std::runtime_error("no DataArray " + name);
}

} // namespace

TEST(Vtu, QuadraticHexOrderMatchesVtkByNaturalCoordinates)
{
  const auto& toBathe = vtkQuadraticHexToBathe();
  for (int i = 0; i < 20; ++i)
  {
    const Eigen::Vector3d n = batheNaturalCoordinates(toBathe[std::size_t(i)]);
    EXPECT_EQ(n, Eigen::Vector3d(kVtkHex[i][0], kVtkHex[i][1], kVtkHex[i][2])) << "VTK point " << i;
  }
}

TEST(Vtu, WedgeCellsAreVtkQuadraticWedgesWithVtkOrientation)
{
  const Mesh mesh = boxMesh(1, 1, 1, 2, 2, 2, Eigen::Vector3d(-1, -1, -1), true);
  ASSERT_EQ(mesh.elements.size(), 2u);
  for (const Element& el : mesh.elements)
  {
    const VtkCell cell = vtkCell(el, mesh.nodes);
    ASSERT_EQ(cell.type, kVtkQuadraticWedge);
    ASSERT_EQ(cell.nodes.size(), 15u);
    auto x = [&](int i) { return Eigen::Vector3d(mesh.nodes.col(cell.nodes[std::size_t(i)])); };
    // Two triangles, one above the other (same z on each), six distinct corners.
    for (int i = 0; i < 3; ++i)
    {
      EXPECT_NEAR(x(i)[2], -1.0, 1e-12);
      EXPECT_NEAR(x(i + 3)[2], 1.0, 1e-12);
      EXPECT_LT((x(i + 3) - x(i) - Eigen::Vector3d(0, 0, 2)).norm(), 1e-12);
    }
    // vtkWedge: (0, 1, 2) by the right-hand rule points away from (3, 4, 5).
    EXPECT_LT((x(1) - x(0)).cross(x(2) - x(0)).dot(x(3) - x(0)), 0.0);
    // Mid-edge points at the middle of VTK's edges.
    const int edges[9][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {0, 3}, {1, 4}, {2, 5}};
    for (int m = 0; m < 9; ++m)
      EXPECT_LT((x(6 + m) - 0.5 * (x(edges[m][0]) + x(edges[m][1]))).norm(), 1e-12) << "mid-edge " << 6 + m;
  }
}

TEST(Vtu, DocumentParsesWithPointAndCellData)
{
  Mesh mesh = boxMesh(2, 1, 1, 20, 10, 10);
  const Mesh wedges = boxMesh(1, 1, 1, 10, 10, 10, Eigen::Vector3d(20, 0, 0), true);
  caps::fem::test::appendMesh(mesh, wedges);
  mesh.elements.back().region = 3;
  Element linear = mesh.elements[0]; // a corner-only copy -> VTK_HEXAHEDRON
  for (int k = 8; k < 20; ++k)
    linear.nodes[std::size_t(k)] = -1;
  mesh.elements.push_back(linear);
  const Eigen::Index n = mesh.nodeCount();
  Eigen::MatrixXd u = Eigen::MatrixXd::Random(3, n), s = Eigen::MatrixXd::Random(6, n);
  const std::string doc = vtuDocument(mesh, {{"displacement", u}, {"stress", s}, {"von_mises", s.row(0)}});
  const auto xml = scanXml(doc);
  ASSERT_EQ(xml[0].name, "VTKFile");
  EXPECT_EQ(xml[0].attributes.at("type"), "UnstructuredGrid");
  const XmlElement* piece = nullptr;
  for (const auto& e : xml)
    if (e.name == "Piece")
      piece = &e;
  ASSERT_NE(piece, nullptr);
  EXPECT_EQ(piece->attributes.at("NumberOfPoints"), std::to_string(n));
  EXPECT_EQ(piece->attributes.at("NumberOfCells"), std::to_string(mesh.elements.size()));
  const auto types = numbers(array(xml, "types").text);
  EXPECT_EQ(types, (std::vector<double>{25, 25, 26, 26, 12}));
  const auto offsets = numbers(array(xml, "offsets").text);
  EXPECT_EQ(offsets, (std::vector<double>{20, 40, 55, 70, 78}));
  const auto connectivity = numbers(array(xml, "connectivity").text);
  ASSERT_EQ(connectivity.size(), 78u);
  // The first cell's points, by natural coordinates: VTK point i of cell 0 is
  // the node at kVtkHex[i] of element 0 (box from (0,0,0) to (10,10,10)).
  for (int i = 0; i < 20; ++i)
  {
    const Eigen::Vector3d expected =
      5.0 * (Eigen::Vector3d(kVtkHex[i][0], kVtkHex[i][1], kVtkHex[i][2]) + Eigen::Vector3d::Ones());
    EXPECT_LT((mesh.nodes.col(Eigen::Index(connectivity[std::size_t(i)])) - expected).norm(), 1e-12) << "point " << i;
  }
  const auto points = numbers(array(xml, "Points").text);
  ASSERT_EQ(points.size(), std::size_t(3 * n));
  EXPECT_DOUBLE_EQ(points[3], mesh.nodes(0, 1));
  const auto disp = numbers(array(xml, "displacement").text);
  ASSERT_EQ(disp.size(), std::size_t(3 * n));
  EXPECT_DOUBLE_EQ(disp[3 * n - 1], u(2, n - 1));
  EXPECT_EQ(array(xml, "stress").attributes.at("NumberOfComponents"), "6");
  EXPECT_EQ(numbers(array(xml, "stress").text).size(), std::size_t(6 * n));
  EXPECT_EQ(numbers(array(xml, "region").text), (std::vector<double>{0, 0, 0, 3, 0}));
  EXPECT_THROW(vtuDocument(mesh, {{"bad", Eigen::MatrixXd::Zero(1, n - 1)}}), std::invalid_argument);
}

TEST(Vtu, NumbersAreWrittenAsAnOstreamWithPrecision17WritesThem)
{
  // The writer formats with std::to_chars; the bytes are those of the
  // ostream it replaced (and every double reads back exactly).
  const Mesh mesh = boxMesh(1, 1, 1, 10, 10, 10);
  const Eigen::Index n = mesh.nodeCount();
  Eigen::MatrixXd v = Eigen::MatrixXd::Random(1, n);
  const double tricky[] = {
    0.0, -0.0, 0.1, 1e-5, -2.5e-300, 1e21, 123456789012345678.0, 1.0 / 3.0, 2.2250738585072014e-308, 100.0};
  for (std::size_t k = 0; k < std::size(tricky); ++k)
    v(0, Eigen::Index(k)) = tricky[k];
  const std::string doc = vtuDocument(mesh, {{"values", v}});
  std::ostringstream expected;
  expected.precision(17);
  for (Eigen::Index j = 0; j < n; ++j)
    expected << "          " << v(0, j) << '\n';
  const std::string text = array(scanXml(doc), "values").text;
  EXPECT_EQ(text.substr(text.find('\n') + 1, expected.str().size()), expected.str());
  const auto back = numbers(text);
  ASSERT_EQ(back.size(), std::size_t(n));
  for (Eigen::Index j = 0; j < n; ++j)
    EXPECT_EQ(back[std::size_t(j)], v(0, j)) << j;
  std::ostringstream points;
  points.precision(17);
  for (Eigen::Index j = 0; j < n; ++j)
    points << "         " << ' ' << mesh.nodes(0, j) << ' ' << mesh.nodes(1, j) << ' ' << mesh.nodes(2, j) << '\n';
  const std::string pointText = array(scanXml(doc), "Points").text;
  EXPECT_EQ(pointText.substr(pointText.find('\n') + 1, points.str().size()), points.str());
}
