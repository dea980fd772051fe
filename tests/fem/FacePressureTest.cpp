// Pressure on element faces against independent answers: the CalculiX face
// table, p x area on flat and curved faces, the textbook -1/12, 1/3 split of
// an 8-node face, zero resultant and moment on closed bodies, degenerate
// wedge faces, Lamé's thick-walled cylinder, ccx on the same decks, and the
// *DLOAD Pn reader.

#include "fem/CalculixIO.h"
#include "fem/CalculixReader.h"
#include "fem/FacePressure.h"
#include "fem/StaticAnalysis.h"
#include "fem/StressRecovery.h"

#include "CcxRunner.h"
#include "FemTestMeshes.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <string>

namespace caps::fem {
namespace {

namespace fs = std::filesystem;
using test::boxMesh;
using test::wobble;

constexpr double kPi = 3.14159265358979323846;

/// Resultant force and moment about the origin of a load vector.
struct Resultant
{
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
};

Resultant resultantOf(const Mesh& mesh, const Eigen::VectorXd& r)
{
  Resultant out;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    out.force += r.segment<3>(3 * i);
    out.moment += mesh.nodes.col(i).cross(r.segment<3>(3 * i));
  }
  return out;
}

Eigen::VectorXd pressureLoad(const Mesh& mesh, int element, int face, double p)
{
  return assembleFacePressureLoad(mesh, {{element, face, p}});
}

/// Distinct corner nodes of face @a face of element @a e.
std::set<int> faceCorners(const Mesh& mesh, std::size_t e, int face)
{
  const Element& el = mesh.elements[e];
  const int corners = el.kind == ElementKind::Wedge15 ? kWedge15CornerCount : kHex20CornerCount;
  std::set<int> out;
  for (int k : faceNodes(el.kind, face))
    if (k < corners)
      out.insert(el.nodes[std::size_t(k)]);
  return out;
}

/// Faces of @a mesh on its boundary: faces (by their set of distinct corner
/// nodes) that belong to one element only. Collapsed faces are left out.
std::vector<FacePressure> boundaryFaces(const Mesh& mesh)
{
  std::map<std::set<int>, std::vector<FacePressure>> faces;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
    for (int f = 1; f <= faceCount(mesh.elements[e].kind); ++f)
    {
      const std::set<int> corners = faceCorners(mesh, e, f);
      if (corners.size() >= 3)
        faces[corners].push_back({int(e), f, 0.0});
    }
  std::vector<FacePressure> out;
  for (const auto& [corners, list] : faces)
    if (list.size() == 1)
      out.push_back(list[0]);
  return out;
}

ElementShape shapeOf(const Mesh& mesh, std::size_t e)
{
  return ElementShape::fromConnectivity(mesh.elements[e].kind, mesh.elements[e].nodes);
}

/// Quarter of a thick-walled tube, inner radius @a a, outer @a b, height
/// @a height: nr x nt curved 20-node bricks (mid-side nodes on the arcs),
/// natural r radial, s circumferential, t axial.
Mesh quarterTube(int nr, int nt, double a, double b, double height, int layers = 1)
{
  Mesh m = boxMesh(nr, nt, layers, b - a, kPi / 2, height, Eigen::Vector3d(a, 0, 0));
  for (Eigen::Index i = 0; i < m.nodeCount(); ++i)
  {
    const double r = m.nodes(0, i), theta = m.nodes(1, i);
    m.nodes(0, i) = r * std::cos(theta);
    m.nodes(1, i) = r * std::sin(theta);
  }
  return m;
}

/// Faces whose eight nodes all satisfy @a on.
template <class Predicate> std::vector<FacePressure> facesWhere(const Mesh& mesh, double p, Predicate on)
{
  std::vector<FacePressure> out;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
    for (int f = 1; f <= faceCount(mesh.elements[e].kind); ++f)
    {
      bool all = true;
      for (int k : faceNodes(mesh.elements[e].kind, f))
      {
        const int n = mesh.elements[e].nodes[std::size_t(k)];
        if (n >= 0 && !on(Eigen::Vector3d(mesh.nodes.col(n))))
          all = false;
      }
      if (all)
        out.push_back({int(e), f, p});
    }
  return out;
}

double radius(const Eigen::Vector3d& x)
{
  return std::hypot(x[0], x[1]);
}

// ---------------------------------------------------------------------------
// Face table and single faces

TEST(FacePressure, FaceNodesAndOrientationFollowTheCalculixManual)
{
  // ccx manual, *DLOAD: hexahedron faces by corner nodes (C3D20 numbering),
  // listed so that the right-hand rule gives the inward normal; mid-sides
  // 9..20 follow from the C3D20 edge table.
  const int corners[6][4] = {{1, 2, 3, 4}, {5, 8, 7, 6}, {1, 5, 6, 2}, {2, 6, 7, 3}, {3, 7, 8, 4}, {4, 8, 5, 1}};
  const std::set<int> midsides[6] = {{9, 10, 11, 12},  {13, 14, 15, 16}, {9, 13, 17, 18},
                                     {10, 14, 18, 19}, {11, 15, 19, 20}, {12, 16, 17, 20}};
  // One brick, 2 x 3 x 4 mm, sheared so that no face is axis-aligned.
  Mesh mesh = boxMesh(1, 1, 1, 2, 3, 4);
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    const Eigen::Vector3d x = mesh.nodes.col(i);
    mesh.nodes.col(i) = Eigen::Vector3d(x[0] + 0.3 * x[2], x[1] + 0.2 * x[0], x[2] + 0.1 * x[1]);
  }
  const Element& el = mesh.elements[0];
  for (int f = 1; f <= 6; ++f)
  {
    std::set<int> c3d;
    for (int k : faceNodes(ElementKind::Hex20, f))
      c3d.insert(batheToC3D20(k));
    std::set<int> expected(std::begin(corners[f - 1]), std::end(corners[f - 1]));
    expected.insert(midsides[f - 1].begin(), midsides[f - 1].end());
    EXPECT_EQ(c3d, expected) << "face " << f;

    auto at = [&](int c3dNode) {
      return Eigen::Vector3d(mesh.nodes.col(el.nodes[std::size_t(c3d20ToBathe(c3dNode))]));
    };
    const Eigen::Vector3d x1 = at(corners[f - 1][0]), x2 = at(corners[f - 1][1]), x3 = at(corners[f - 1][2]),
                          x4 = at(corners[f - 1][3]);
    // The faces are flat parallelograms: area vector = (x2 - x1) x (x4 - x1), inward by the manual's order.
    const Eigen::Vector3d inwardArea = (x2 - x1).cross(x4 - x1);
    const double p = 0.7;
    const Resultant r = resultantOf(mesh, pressureLoad(mesh, 0, f, p));
    EXPECT_LT((r.force - p * inwardArea).norm(), 1e-12 * p * inwardArea.norm()) << "face " << f;
    const ElementCoordinates xe = mesh.elementCoordinates(0);
    EXPECT_NEAR(elementFaceArea(Hex20Shape::fromConnectivity(el.nodes), xe, f, gaussLineRule(3)), inwardArea.norm(),
                1e-12 * inwardArea.norm());
    EXPECT_LT((x3 - x2 - (x4 - x1)).norm(), 1e-12); // parallelogram indeed
  }
}

TEST(FacePressure, FlatFaceSplitsAsTheTextbookSerendipityLoads)
{
  // A rectangular 8-node face under uniform p: corners get -pA/12, mid-sides
  // +pA/3 (Zienkiewicz & Taylor, consistent loads of the serendipity quad);
  // a 4-node face (no mid-sides) gives pA/4 to each corner.
  const double p = 1.5, area = 2.0 * 3.0;
  const Mesh mesh = boxMesh(1, 1, 1, 2, 3, 4);
  const Element& el = mesh.elements[0];
  const Eigen::VectorXd r = pressureLoad(mesh, 0, 2, p); // t = +1, z = 4: pushes -z
  for (int k = 0; k < kHex20NodeCount; ++k)
  {
    const Eigen::Vector3d f = r.segment<3>(3 * el.nodes[std::size_t(k)]);
    const double expected = k < 4 ? p * area / 12.0 : (k >= 8 && k < 12 ? -p * area / 3.0 : 0.0);
    EXPECT_NEAR(f[2], expected, 1e-13) << "Bathe node " << k;
    EXPECT_NEAR(f.head<2>().norm(), 0.0, 1e-13);
  }
  Mesh linear = mesh;
  for (int k = kHex20CornerCount; k < kHex20NodeCount; ++k)
    linear.elements[0].nodes[std::size_t(k)] = -1;
  const Eigen::VectorXd r4 = pressureLoad(linear, 0, 2, p);
  for (int k = 0; k < 4; ++k)
    EXPECT_NEAR(r4[3 * el.nodes[std::size_t(k)] + 2], -p * area / 4.0, 1e-13);
  EXPECT_NEAR(r4.sum(), -p * area, 1e-12);
  // One mid-side absent: still the whole pA, nothing on the absent node.
  Mesh some = mesh;
  const int dropped = some.elements[0].nodes[9];
  some.elements[0].nodes[9] = -1;
  const Eigen::VectorXd r7 = pressureLoad(some, 0, 2, p);
  EXPECT_NEAR(r7.sum(), -p * area, 1e-12);
  EXPECT_EQ(r7.segment<3>(3 * dropped).norm(), 0.0);
}

TEST(FacePressure, FlatFaceWithAParabolicEdgeCarriesPTimesItsArea)
{
  // Bulge the mid-side node of one edge of the top face outwards (in plane)
  // by d: the edge is a parabola, the face gains 2/3 x chord x d.
  Mesh mesh = boxMesh(1, 1, 1, 2, 3, 4);
  const Element& el = mesh.elements[0];
  const double d = 0.4;
  const int mid = el.nodes[11]; // Bathe 11: r = +1, s = 0, t = +1, on x = 2 at z = 4
  ASSERT_NEAR(mesh.nodes(0, mid), 2.0, 1e-12);
  mesh.nodes(0, mid) += d;
  const double area = 2.0 * 3.0 + 2.0 / 3.0 * 3.0 * d, p = 0.25;
  const Resultant r = resultantOf(mesh, pressureLoad(mesh, 0, 2, p));
  EXPECT_NEAR(r.force[2], -p * area, 1e-12);
  EXPECT_NEAR(r.force.head<2>().norm(), 0.0, 1e-12);
  EXPECT_NEAR(elementFaceArea(Hex20Shape::fromConnectivity(el.nodes), mesh.elementCoordinates(0), 2, gaussLineRule(3)),
              area, 1e-12);
}

TEST(FacePressure, CurvedCylindricalFaceGivesPTimesProjectedArea)
{
  // One brick of a tube, radii 10..14, 60 degrees, height 5. The inner face
  // r = 10 is curved; pressure on it pushes outward with resultant
  // p x (projected area 2 a sin(60°/2) h) along the bisector, whatever the
  // arc interpolation, because the vector area depends only on its edges.
  const double a = 10.0, b = 14.0, h = 5.0, span = kPi / 3, p = 2.0;
  Mesh mesh = boxMesh(1, 1, 1, b - a, span, h, Eigen::Vector3d(a, 0, 0));
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    const double r = mesh.nodes(0, i), th = mesh.nodes(1, i);
    mesh.nodes(0, i) = r * std::cos(th);
    mesh.nodes(1, i) = r * std::sin(th);
  }
  const int inner = 6; // natural r = -1 is the radius a
  const Resultant r = resultantOf(mesh, pressureLoad(mesh, 0, inner, p));
  const Eigen::Vector3d bisector(std::cos(span / 2), std::sin(span / 2), 0.0);
  const double projected = 2.0 * a * std::sin(span / 2) * h;
  EXPECT_LT((r.force - p * projected * bisector).norm(), 1e-12 * p * projected);
  // By symmetry the moment about the tube axis vanishes.
  EXPECT_NEAR(r.moment[2], 0.0, 1e-11 * p * projected * a);
  // The true area a·span·h, up to the parabolic approximation of a 60° arc.
  const double area = elementFaceArea(Hex20Shape::fromConnectivity(mesh.elements[0].nodes), mesh.elementCoordinates(0),
                                      inner, gaussLineRule(3));
  std::cout << "60 degree arc face: area " << area << " mm^2, cylinder " << a * span * h << " mm^2, relative "
            << area / (a * span * h) - 1 << "\n";
  EXPECT_NEAR(area, a * span * h, 2e-3 * a * span * h);
}

TEST(FacePressure, ClosedBodiesHaveZeroResultantAndMoment)
{
  // A distorted block of curved bricks, of degenerate wedges, and of native
  // wedges: equal pressure on the whole boundary is in equilibrium
  // (∮ n dA = 0, ∮ x × n dA = 0), and the rules integrate both exactly
  // (see FacePressure.h).
  for (const char* kind : {"bricks", "wedges", "native wedges"})
  {
    const bool wedges = kind[0] != 'b', native = kind[0] == 'n';
    Mesh mesh = boxMesh(3, 2, 2, 30, 20, 10, Eigen::Vector3d(5, -3, 2), wedges);
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      mesh.nodes.col(i) = wobble(mesh.nodes.col(i));
    if (native)
      mesh = withNativeWedges(mesh);
    std::vector<FacePressure> faces = boundaryFaces(mesh);
    // 2 (3·2 + 3·2 + 2·2) quads; wedges: 2·2·6 triangles and 2 (3·2 + 2·2) quads.
    ASSERT_EQ(faces.size(), wedges ? 44u : 32u);
    double area = 0.0;
    for (auto& f : faces)
    {
      f.pressure = 0.3;
      area += elementFaceArea(shapeOf(mesh, std::size_t(f.element)), mesh.elementCoordinates(std::size_t(f.element)),
                              f.face, gaussLineRule(3));
    }
    const Eigen::VectorXd r = assembleFacePressureLoad(mesh, faces);
    const Resultant res = resultantOf(mesh, r);
    std::cout << kind << ": boundary area " << area << " mm^2, |resultant| " << res.force.norm() << " N, |moment| "
              << res.moment.norm() << " N mm\n";
    EXPECT_GT(area, 2 * (30 * 20 + 30 * 10 + 20 * 10) * 0.95);
    EXPECT_LT(res.force.norm(), 1e-12 * 0.3 * area);
    EXPECT_LT(res.moment.norm(), 1e-12 * 0.3 * area * 40.0);
    // Every face of every element loaded: the shared faces cancel node by node too.
    std::vector<FacePressure> all;
    for (std::size_t e = 0; e < mesh.elements.size(); ++e)
      for (int f = 1; f <= faceCount(mesh.elements[e].kind); ++f)
        all.push_back({int(e), f, 0.3});
    const Eigen::VectorXd rAll = assembleFacePressureLoad(mesh, all);
    EXPECT_LT((rAll - r).cwiseAbs().maxCoeff(), 1e-12 * r.cwiseAbs().maxCoeff());
  }
}

TEST(FacePressure, NativeAndDegenerateWedgesCarryTheSameFaceResultants)
{
  // The resultant of a uniform pressure is p times the vector area, fixed by
  // the face's boundary; the edges are the same parabolas in both forms of
  // the wedge, so every face (matched by its corners) carries the same force
  // and moment, though the split between the nodes differs on the triangles.
  Mesh degenerate = boxMesh(2, 2, 1, 20, 20, 10, Eigen::Vector3d::Zero(), true);
  for (Eigen::Index i = 0; i < degenerate.nodeCount(); ++i)
    degenerate.nodes.col(i) = wobble(degenerate.nodes.col(i));
  const Mesh native = withNativeWedges(degenerate);
  int compared = 0;
  for (std::size_t e = 0; e < native.elements.size(); ++e)
  {
    ASSERT_EQ(native.elements[e].kind, ElementKind::Wedge15);
    for (int f = 1; f <= 5; ++f)
    {
      const std::set<int> corners = faceCorners(native, e, f);
      for (int g = 1; g <= 6; ++g)
      {
        if (faceCorners(degenerate, e, g) != corners)
          continue;
        const Resultant a = resultantOf(native, pressureLoad(native, int(e), f, 0.2));
        const Resultant b = resultantOf(degenerate, pressureLoad(degenerate, int(e), g, 0.2));
        EXPECT_LT((a.force - b.force).norm(), 1e-12 * b.force.norm()) << "element " << e << " face " << f;
        EXPECT_LT((a.moment - b.moment).norm(), 1e-12 * b.moment.norm()) << "element " << e << " face " << f;
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, int(native.elements.size()) * 5);
}

TEST(FacePressure, NativeWedgeFacesFollowTheCalculixManual)
{
  // ccx manual, *DLOAD: wedge faces 1-2-3, 4-5-6, 1-2-5-4, 2-3-6-5, 3-1-4-6
  // (C3D15 numbering, right-hand rule inward), mid-sides from the C3D15
  // edge table.
  const std::vector<std::set<int>> expected{{1, 2, 3, 7, 8, 9},
                                            {4, 5, 6, 10, 11, 12},
                                            {1, 2, 5, 4, 7, 10, 13, 14},
                                            {2, 3, 6, 5, 8, 11, 14, 15},
                                            {3, 1, 4, 6, 9, 12, 13, 15}};
  for (int f = 1; f <= 5; ++f)
  {
    std::set<int> c3d;
    for (int k : faceNodes(ElementKind::Wedge15, f))
      c3d.insert(wedge15ToC3D15(k));
    EXPECT_EQ(c3d, expected[std::size_t(f - 1)]) << "face " << f;
  }
}

TEST(FacePressure, DegenerateWedgeFaces)
{
  // Cell (0..2) x (0..2) x (0..3) split along its diagonal; the first wedge
  // has corners (2,2) twice, (0,0), (2,0): the face s = +1 (5) is collapsed.
  test::MeshBuilder builder(Eigen::Vector3d(1.0, 1.0, 1.5));
  builder.addWedgePair(0, 0, 0);
  const Mesh mesh = builder.build();
  const Hex20Shape shape = Hex20Shape::fromConnectivity(mesh.elements[0].nodes);
  const ElementCoordinates x = mesh.elementCoordinates(0);
  const double p = 0.5, h = 3.0, leg = 2.0;
  const std::map<int, Eigen::Vector3d> inwardArea{
    {1, Eigen::Vector3d(0, 0, 0.5 * leg * leg)},  // bottom triangle, z = 0
    {2, Eigen::Vector3d(0, 0, -0.5 * leg * leg)}, // top triangle, z = 3
    {3, Eigen::Vector3d(0, leg * h, 0)},          // y = 0
    {4, Eigen::Vector3d(-leg * h, 0, 0)},         // x = 2
    {5, Eigen::Vector3d::Zero()},                 // collapsed edge at (2, 2)
    {6, Eigen::Vector3d(leg * h, -leg * h, 0)},   // the diagonal y = x
  };
  for (const auto& [face, inward] : inwardArea)
  {
    const Eigen::VectorXd r = pressureLoad(mesh, 0, face, p);
    const Resultant res = resultantOf(mesh, r);
    EXPECT_LT((res.force - p * inward).norm(), 1e-12) << "face " << face;
    EXPECT_NEAR(elementFaceArea(shape, x, face, gaussLineRule(3)), inward.norm(), 1e-12) << "face " << face;
    if (face == 5)
    {
      EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-15); // rounding only
    }
  }
  // The triangle's load acts at its centroid (2/3·2, 1/3·2): moment about the origin.
  const Resultant top = resultantOf(mesh, pressureLoad(mesh, 0, 2, p));
  const Eigen::Vector3d centroid(4.0 / 3.0, 2.0 / 3.0, 3.0);
  EXPECT_LT((top.moment - centroid.cross(top.force)).norm(), 1e-12);
}

TEST(FacePressure, BadLoadsAreRefusedNamingTheCulprit)
{
  const Mesh mesh = boxMesh(2, 1, 1, 2, 1, 1);
  auto message = [&](const FacePressure& l) -> std::string {
    try
    {
      assembleFacePressureLoad(mesh, {{0, 1, 1.0}, l});
    }
    catch (const std::invalid_argument& e)
    {
      return e.what();
    }
    return "no error";
  };
  EXPECT_NE(message({2, 1, 1.0}).find("face pressure 1 is applied to element 2, but the mesh has elements 0..1"),
            std::string::npos)
    << message({2, 1, 1.0});
  EXPECT_NE(message({-1, 1, 1.0}).find("element -1"), std::string::npos);
  EXPECT_NE(message({1, 7, 1.0}).find("names face 7: a hexahedron has faces 1..6"), std::string::npos)
    << message({1, 7, 1.0});
  EXPECT_NE(message({1, 0, 1.0}).find("face 0"), std::string::npos);
  EXPECT_NE(message({1, 3, std::nan("")}).find("non-finite pressure"), std::string::npos);
  EXPECT_NE(message({1, 3, std::numeric_limits<double>::infinity()}).find("non-finite pressure"), std::string::npos);
  EXPECT_THROW(faceNodes(ElementKind::Hex20, 7), std::invalid_argument);
  EXPECT_THROW(faceNodes(ElementKind::Wedge15, 6), std::invalid_argument);
  EXPECT_THROW(faceNodes(ElementKind::Hex20, 0), std::invalid_argument);
  const Mesh native = withNativeWedges(boxMesh(1, 1, 1, 2, 2, 2, Eigen::Vector3d::Zero(), true));
  ASSERT_EQ(native.elements[1].kind, ElementKind::Wedge15);
  try
  {
    assembleFacePressureLoad(native, {{1, 6, 1.0}});
    ADD_FAILURE() << "no error";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("names face 6: a native wedge has faces 1..5"), std::string::npos) << e.what();
  }
  // Through the analysis as well.
  LinearStaticAnalysis analysis(mesh, {{0, {1.0, 0.3, 0.0}}}, Constraints{});
  LoadCase load;
  load.facePressures.push_back({5, 1, 1.0});
  EXPECT_THROW(analysis.loadVector(load), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// Lamé's thick-walled cylinder

/// Plane-strain Lamé solution for internal pressure p on radii a..b.
struct Lame
{
  double a, b, p, e, nu;
  double A() const { return p * a * a / (b * b - a * a); }
  double B() const { return p * a * a * b * b / (b * b - a * a); }
  double radialStress(double r) const { return A() - B() / (r * r); }
  double hoopStress(double r) const { return A() + B() / (r * r); }
  double radialDisplacement(double r) const { return (1 + nu) / e * ((1 - 2 * nu) * A() * r + B() / r); }
};

struct LameErrors
{
  double displacement = 0.0; ///< max |u_r - exact| at the nodes / u_r(a)
  double tangential = 0.0;   ///< max |u_theta| / u_r(a)
  double stress = 0.0;       ///< max |sigma_r, sigma_theta - exact| at the 3x3x3 Gauss points / p
  double stressBarlow = 0.0; ///< the same at the 2x2x2 (Barlow) points
  double axialStress = 0.0;  ///< max |sigma_z - nu (sigma_r + sigma_theta)| / p
};

LameErrors solveLame(const Lame& lame, int nr, int nt)
{
  const Mesh mesh = quarterTube(nr, nt, lame.a, lame.b, 2.0);
  const MaterialTable materials{{0, {lame.e, lame.nu, 0.0}}};
  Constraints c;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    c.fix(int(i), 2); // plane strain: no axial motion anywhere
    if (std::abs(mesh.nodes(1, i)) < 1e-9)
      c.fix(int(i), 1); // symmetry plane y = 0
    if (std::abs(mesh.nodes(0, i)) < 1e-9)
      c.fix(int(i), 0); // symmetry plane x = 0
  }
  LoadCase load;
  load.facePressures =
    facesWhere(mesh, lame.p, [&](const Eigen::Vector3d& x) { return std::abs(radius(x) - lame.a) < 1e-9; });
  EXPECT_EQ(int(load.facePressures.size()), nt);
  LinearStaticAnalysis analysis(mesh, materials, c);
  EXPECT_EQ(analysis.prepare(), SolverStatus::Success) << analysis.message();
  const Eigen::VectorXd u = analysis.solve(load);

  LameErrors err;
  const double scale = lame.radialDisplacement(lame.a);
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    const Eigen::Vector3d x = mesh.nodes.col(i);
    const double r = radius(x);
    const Eigen::Vector2d er(x[0] / r, x[1] / r), et(-x[1] / r, x[0] / r);
    const Eigen::Vector2d ui = u.segment<2>(3 * i);
    err.displacement = std::max(err.displacement, std::abs(ui.dot(er) - lame.radialDisplacement(r)) / scale);
    err.tangential = std::max(err.tangential, std::abs(ui.dot(et)) / scale);
  }
  for (int points : {3, 2})
    for (std::size_t e = 0; e < mesh.elements.size(); ++e)
      for (const StressPoint& s : recoverStressAtGaussPoints(mesh, materials, u, int(e), points))
      {
        const double r = radius(s.world);
        const Eigen::Vector2d n(s.world[0] / r, s.world[1] / r);
        Eigen::Matrix2d sigma;
        sigma << s.stress[0], s.stress[3], s.stress[3], s.stress[1];
        const double sr = n.dot(sigma * n), st = sigma.trace() - sr;
        double& worst = points == 3 ? err.stress : err.stressBarlow;
        worst =
          std::max({worst, std::abs(sr - lame.radialStress(r)) / lame.p, std::abs(st - lame.hoopStress(r)) / lame.p});
        err.axialStress = std::max(err.axialStress, std::abs(s.stress[2] - lame.nu * sigma.trace()) / lame.p);
      }
  return err;
}

TEST(FacePressure, ThickWalledCylinderMatchesLame)
{
  // Quarter tube, radii 10..20 mm, plane strain (u_z = 0 everywhere is the
  // exact plane-strain field), symmetry on x = 0 and y = 0, p = 0.01 MPa
  // inside, E = 0.1 MPa, nu = 0.45 (soft tissue), meshes of 2 x 4, 4 x 8 and
  // 8 x 16 curved bricks (45-, 22.5- and 11.25-degree arcs).
  //
  // Expected discretisation error of quadratic elements: nodal
  // displacements O(h^3) or better (nodes are superconvergent), stresses
  // O(h^2) at the 3x3x3 Gauss points and about O(h^3) at the 2x2x2 Barlow
  // points. Measured: u_r 0.29 %, 0.022 %, 0.0015 % of u_r(a); stresses
  // 21, 7.2, 2.3 % of p at the 3x3x3 points (the steep 1/r^2 field next to
  // the bore, amplified by lambda at nu = 0.45) and 1.0, 0.21, 0.035 % of p
  // at the Barlow points. The thresholds below leave about 2x margin.
  const Lame lame{10.0, 20.0, 0.01, 0.1, 0.45};
  const int meshes[3][2] = {{2, 4}, {4, 8}, {8, 16}};
  LameErrors err[3];
  for (int m = 0; m < 3; ++m)
  {
    err[m] = solveLame(lame, meshes[m][0], meshes[m][1]);
    std::cout << "Lame " << meshes[m][0] << " x " << meshes[m][1] << " elements: u_r error "
              << 100 * err[m].displacement << " %, u_theta " << 100 * err[m].tangential << " %, stress error "
              << 100 * err[m].stress << " % of p (2x2x2 points " << 100 * err[m].stressBarlow << " %), sigma_z "
              << 100 * err[m].axialStress << " % of p\n";
  }
  EXPECT_LT(err[0].displacement, 5e-3); // even the coarse mesh is inside 0.5 %
  EXPECT_LT(err[1].displacement, 5e-4); // the moderate mesh inside 0.05 %
  EXPECT_LT(err[1].stressBarlow, 5e-3);
  EXPECT_LT(err[1].stress, 0.15);
  for (int m = 0; m < 3; ++m)
  {
    EXPECT_LT(err[m].tangential, 1e-9);  // every element is a rotated copy: the field stays radial
    EXPECT_LT(err[m].axialStress, 1e-9); // plane strain holds exactly
  }
  // Convergence under halving h: displacements by >= 2^3 (measured 13, 15),
  // Barlow-point stresses by >= 2^2 (4.8, 6.0), 3x3x3-point stresses
  // approaching 2^2 from below (2.9, 3.2: not yet asymptotic).
  for (int m = 0; m + 1 < 3; ++m)
  {
    EXPECT_GT(err[m].displacement / err[m + 1].displacement, 8.0) << m;
    EXPECT_GT(err[m].stressBarlow / err[m + 1].stressBarlow, 4.0) << m;
    EXPECT_GT(err[m].stress / err[m + 1].stress, 2.5) << m;
  }
}

// ---------------------------------------------------------------------------
// CalculiX

/// Max |ours - ccx| / max |ours| for the exported model (also printed).
double ccxDifference(const std::string& name, const Mesh& mesh, const MaterialTable& materials, const Constraints& c,
                     const LoadCase& load, const AssemblyOptions& options = {})
{
  if (!test::ccxAvailable())
    throw std::runtime_error("CalculiX 'ccx' was not found on PATH: install Debian package calculix-ccx");
  LinearStaticAnalysis analysis(mesh, materials, c, options);
  if (analysis.prepare() != SolverStatus::Success)
    throw std::runtime_error(analysis.message());
  const Eigen::VectorXd u = analysis.solve(load);
  const double diff =
    test::relativeDifference(test::runCcx(name, calculixInput(mesh, materials, c, load), mesh.nodeCount()).dat, u);
  std::cout << "ccx " << name << ": " << mesh.elements.size() << " elements, " << load.facePressures.size()
            << " loaded faces, max |u| " << u.cwiseAbs().maxCoeff() << " mm, relative difference (.dat) " << diff
            << "\n";
  return diff;
}

void compareWithCcx(const std::string& name, const Mesh& mesh, const MaterialTable& materials, const Constraints& c,
                    const LoadCase& load)
{
  EXPECT_LT(ccxDifference(name, mesh, materials, c, load), 1e-6) << name;
}

TEST(FacePressure, CalculixAgreesOnACurvedTubeUnderPressure)
{
  // Three layers of curved bricks, free to stretch axially: inner pressure,
  // a smaller outer pressure and an axial pressure on the top; bottom held
  // in z only.
  const Mesh mesh = quarterTube(3, 6, 10.0, 20.0, 9.0, 3);
  Constraints c;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    if (std::abs(mesh.nodes(2, i)) < 1e-9)
      c.fix(int(i), 2);
    if (std::abs(mesh.nodes(1, i)) < 1e-9)
      c.fix(int(i), 1);
    if (std::abs(mesh.nodes(0, i)) < 1e-9)
      c.fix(int(i), 0);
  }
  LoadCase load;
  for (const auto& [p, on] : std::vector<std::pair<double, std::function<bool(const Eigen::Vector3d&)>>>{
         {0.01, [](const Eigen::Vector3d& x) { return std::abs(radius(x) - 10.0) < 1e-9; }},
         {0.002, [](const Eigen::Vector3d& x) { return std::abs(radius(x) - 20.0) < 1e-9; }},
         {0.004, [](const Eigen::Vector3d& x) { return std::abs(x[2] - 9.0) < 1e-9; }}})
  {
    const auto faces = facesWhere(mesh, p, on);
    load.facePressures.insert(load.facePressures.end(), faces.begin(), faces.end());
  }
  ASSERT_EQ(load.facePressures.size(), std::size_t(6 * 3 + 6 * 3 + 3 * 6));
  compareWithCcx("tube", mesh, {{0, {0.1, 0.45, 0.0}}}, c, load);
}

TEST(FacePressure, CalculixAgreesOnDistortedWedgesWithPressureOnEveryKindOfFace)
{
  // Degenerate wedges (written as degenerate C3D20): pressures varying from
  // face to face on the whole boundary, triangles, rectangles, diagonals, and
  // on collapsed faces (zero area: no load in either program).
  Mesh mesh = boxMesh(3, 2, 2, 30, 20, 10, Eigen::Vector3d::Zero(), true);
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = wobble(mesh.nodes.col(i));
  Constraints c;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    if (mesh.nodes(2, i) < 0.5 && mesh.nodes(0, i) < 15.0)
      c.fixNode(int(i));
  LoadCase load;
  int k = 0;
  for (FacePressure f : boundaryFaces(mesh))
  {
    f.pressure = 0.001 * (1 + (k++ % 5)) * (f.face == 2 ? -1.0 : 1.0); // suction on the tops
    load.facePressures.push_back(f);
  }
  for (int e = 0; e < 4; ++e)
    load.facePressures.push_back({e, 5, 0.05}); // collapsed
  compareWithCcx("wedges", mesh, {{0, {0.05, 0.45, 0.0}}}, c, load);
}

TEST(FacePressure, CalculixAgreesOnNativeWedgesAsC3D15)
{
  // Native wedges are written as C3D15 and the face numbers go through
  // unchanged. ccx integrates C3D15 with the 9-point rule (wedgeRule(2)), so
  // ours uses it too. A sheared block has flat faces, where ccx's face rules
  // and ours are both exact. On curved faces ccx integrates C3D15 faces less
  // accurately than our exact rule (measured 2.4e-4 of max |u| here); given
  // our consistent loads as nodal forces it agrees again, so the face
  // numbering and orientation are the same there too.
  for (bool curved : {false, true})
  {
    Mesh mesh = boxMesh(3, 2, 2, 30, 20, 10, Eigen::Vector3d::Zero(), true);
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    {
      const Eigen::Vector3d x = mesh.nodes.col(i);
      mesh.nodes.col(i) = curved ? wobble(x) : Eigen::Vector3d(x[0] + 0.2 * x[1] + 0.1 * x[2], x[1] - 0.1 * x[2], x[2]);
    }
    mesh = withNativeWedges(mesh);
    Constraints c;
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      if (mesh.nodes(2, i) < 0.5 && mesh.nodes(0, i) < 15.0)
        c.fixNode(int(i));
    LoadCase load;
    int k = 0;
    for (FacePressure f : boundaryFaces(mesh))
    {
      f.pressure = 0.001 * (1 + (k++ % 5)) * (f.face == 2 ? -1.0 : 1.0);
      load.facePressures.push_back(f);
    }
    AssemblyOptions options;
    options.gaussPointsPerDirection = 2;
    const MaterialTable materials{{0, {0.05, 0.45, 0.0}}};
    const double diff = ccxDifference(curved ? "native_curved" : "native", mesh, materials, c, load, options);
    if (!curved)
    {
      EXPECT_LT(diff, 1e-6);
      continue;
    }
    EXPECT_LT(diff, 1e-3);
    LoadCase nodal;
    const Eigen::VectorXd r = assembleFacePressureLoad(mesh, load.facePressures);
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      if (!r.segment<3>(3 * i).isZero(0.0))
        nodal.nodalForces.push_back({int(i), r.segment<3>(3 * i)});
    EXPECT_LT(ccxDifference("native_curved_nodal", mesh, materials, c, nodal, options), 1e-6);
  }
}

// ---------------------------------------------------------------------------
// Reader

std::string errorOf(const std::string& deck)
{
  try
  {
    parseCalculixInput(deck, "deck.inp");
  }
  catch (const std::exception& e)
  {
    return e.what();
  }
  return "no error";
}

/// The deck of @a mesh without loads, a *DLOAD block inserted before the output requests.
std::string deckWithDload(const Mesh& mesh, const MaterialTable& materials, const Constraints& c,
                          const std::string& dload)
{
  std::string deck = calculixInput(mesh, materials, c, LoadCase{});
  const auto at = deck.find("*NODE FILE");
  return deck.insert(at, dload);
}

TEST(FacePressure, ReaderTakesDloadP3AndSolvesLikeTheModelInMemory)
{
  // Two bricks in x; P3 (s = -1, the y = 0 side) on both, and P4 (r = +1,
  // x = 4) twice on the second: the two add up, as in ccx (checked below by
  // running ccx on the same deck).
  const Mesh mesh = boxMesh(2, 1, 1, 4, 1, 1);
  const MaterialTable materials{{0, {1.0, 0.3, 0.0}}};
  Constraints c;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    if (mesh.nodes(0, i) < 1e-9)
      c.fixNode(int(i));
  const std::string deck =
    deckWithDload(mesh, materials, c, "*DLOAD\n1, P3, 0.02\n2, P3, 0.02\n2, p4, 0.5\n2, P4, -0.01\n");
  const CalculixModel m = parseCalculixInput(deck, "deck.inp");
  ASSERT_EQ(m.load.facePressures.size(), 3u);
  LoadCase load;
  load.facePressures = {{0, 3, 0.02}, {1, 3, 0.02}, {1, 4, 0.5}, {1, 4, -0.01}};
  const Eigen::VectorXd r = assembleFacePressureLoad(mesh, load.facePressures);
  const Eigen::VectorXd rDeck = assembleFacePressureLoad(m.mesh, m.load.facePressures);
  EXPECT_LT((rDeck.head(r.size()) - r).cwiseAbs().maxCoeff(), 1e-15);
  // P3 pushes the y = 0 side in +y with 0.02 x 4 mm^2; P4 pushes x = 4 in -x with 0.49 x 1 mm^2.
  const Resultant res = resultantOf(mesh, r);
  EXPECT_LT((res.force - Eigen::Vector3d(-0.49, 0.08, 0.0)).norm(), 1e-14);

  LinearStaticAnalysis ours(mesh, materials, c), read(m.mesh, m.materials, m.constraints);
  ASSERT_EQ(ours.prepare(), SolverStatus::Success);
  ASSERT_EQ(read.prepare(), SolverStatus::Success);
  const Eigen::VectorXd u = ours.solve(load), v = read.solve(m.load);
  EXPECT_LT((v.head(u.size()) - u).cwiseAbs().maxCoeff(), 1e-12 * u.cwiseAbs().maxCoeff());
  ASSERT_TRUE(test::ccxAvailable()) << "CalculiX 'ccx' was not found on PATH: install Debian package calculix-ccx";
  const double diff = test::relativeDifference(test::runCcx("p3deck", deck, mesh.nodeCount()).dat, u);
  std::cout << "ccx on the hand-edited P3/P4 deck: relative difference (.dat) " << diff << "\n";
  EXPECT_LT(diff, 1e-6);
}

TEST(FacePressure, ReaderRoundTripsExportedPressuresOnBricksAndWedges)
{
  Mesh mesh = boxMesh(2, 2, 1, 20, 20, 5);
  test::appendMesh(mesh, boxMesh(2, 2, 1, 20, 20, 5, Eigen::Vector3d(0, 0, 5), true));
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = wobble(mesh.nodes.col(i));
  LoadCase load;
  int k = 0;
  for (FacePressure f : boundaryFaces(mesh))
  {
    f.pressure = 0.01 * (k++ % 7 - 3);
    load.facePressures.push_back(f);
  }
  load.facePressures.push_back(load.facePressures[0]); // twice: summed on export
  const MaterialTable materials{{0, {1.0, 0.3, 0.0}}};
  const CalculixModel m = parseCalculixInput(calculixInput(mesh, materials, Constraints{}, load));
  const Eigen::VectorXd r = assembleFacePressureLoad(mesh, load.facePressures);
  const Eigen::VectorXd rDeck = assembleFacePressureLoad(m.mesh, m.load.facePressures);
  EXPECT_LT((rDeck.head(r.size()) - r).cwiseAbs().maxCoeff(), 1e-12 * r.cwiseAbs().maxCoeff());
}

TEST(FacePressure, ReaderMapsC3D15FacesOntoDegenerateAndNativeWedges)
{
  // Wedge: triangle (0,0)-(1,0)-(0,1) at z = 0 and z = 2.
  const std::string model =
    "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,2\n5,1,0,2\n6,0,1,2\n"
    "7,.5,0,0\n8,.5,.5,0\n9,0,.5,0\n10,.5,0,2\n11,.5,.5,2\n12,0,.5,2\n13,0,0,1\n14,1,0,1\n15,0,1,1\n"
    "*ELEMENT, TYPE=C3D15, ELSET=W\n1, 1,2,3,4,5,6,7,8,9,10,\n11,12,13,14,15\n"
    "*MATERIAL, NAME=M\n*ELASTIC\n100, 0.25\n*SOLID SECTION, ELSET=W, MATERIAL=M\n*STEP\n*STATIC\n";
  // ccx manual: wedge faces 1-2-3, 4-5-6, 1-2-5-4, 2-3-6-5, 3-1-4-6; inward area vectors.
  const Eigen::Vector3d inward[5] = {{0, 0, 0.5}, {0, 0, -0.5}, {0, 2, 0}, {-2, -2, 0}, {2, 0, 0}};
  for (bool native : {false, true})
  {
    CalculixReadOptions options;
    options.nativeWedges = native;
    for (int face = 1; face <= 5; ++face)
    {
      const CalculixModel m =
        parseCalculixInput(model + "*DLOAD\nW, P" + std::to_string(face) + ", 3.0\n*END STEP\n", "wedge.inp", options);
      ASSERT_EQ(m.mesh.elements[0].kind, native ? ElementKind::Wedge15 : ElementKind::Hex20);
      ASSERT_EQ(m.load.facePressures.size(), 1u);
      EXPECT_EQ(m.load.facePressures[0].face, native || face < 5 ? face : 6);
      const Resultant res = resultantOf(m.mesh, assembleFacePressureLoad(m.mesh, m.load.facePressures));
      EXPECT_LT((res.force - 3.0 * inward[face - 1]).norm(), 1e-12) << "C3D15 face " << face << " native " << native;
    }
  }
  const std::string bad = errorOf(model + "*DLOAD\nW, P6, 3.0\n*END STEP\n");
  const long line = long(std::count(model.begin(), model.end(), '\n')) + 2;
  EXPECT_NE(bad.find("deck.inp:" + std::to_string(line) + ": *DLOAD P6 on element 1: a C3D15 wedge has faces P1..P5"),
            std::string::npos)
    << bad;
}

TEST(FacePressure, ReaderRefusesBadFaceLoadsNamingTheLine)
{
  const Mesh mesh = boxMesh(1, 1, 1, 1, 1, 1);
  const MaterialTable materials{{0, {1.0, 0.3, 0.0}}};
  const std::string deck = calculixInput(mesh, materials, Constraints{}, LoadCase{});
  const int line = int(std::count(deck.begin(), deck.begin() + long(deck.find("*NODE FILE")), '\n')) + 2;
  auto error = [&](const std::string& dload) { return errorOf(deckWithDload(mesh, materials, Constraints{}, dload)); };
  const std::string at = "deck.inp:" + std::to_string(line) + ": ";
  EXPECT_NE(error("*DLOAD\n1, P7, 1.0\n").find(at + "*DLOAD P7 on element 1: a hexahedron has faces P1..P6"),
            std::string::npos)
    << error("*DLOAD\n1, P7, 1.0\n");
  EXPECT_NE(error("*DLOAD\n1, P0, 1.0\n").find(at + "*DLOAD P0"), std::string::npos);
  EXPECT_NE(error("*DLOAD\n1, P12345, 1.0\n").find(at + "*DLOAD P12345 on element 1"), std::string::npos);
  EXPECT_NE(error("*DLOAD\n1, P2\n").find(at + "*DLOAD P2 needs a pressure"), std::string::npos);
  EXPECT_NE(error("*DLOAD\n9, P2, 1.0\n").find(at + "*DLOAD on element 9, which is not defined"), std::string::npos);
  EXPECT_NE(error("*DLOAD\n1, P2NU, 1.0\n").find(at + "*DLOAD type P2NU is not supported"), std::string::npos);
  EXPECT_NE(error("*DLOAD\n1, P2, abc\n").find(at + "'abc' is not a number"), std::string::npos);
}

} // namespace
} // namespace caps::fem
