// Display surfaces (thesis §4.7): element faces subdivided in body
// coordinates, checked against analytic displacement and stress fields,
// the vertex-count formulas, Euler's formula for closed surfaces and an
// independent evaluation of the body coordinates (BodyCoordinates.h) and
// of the nodal stresses (NodalStress.h).

#include "FemTestMeshes.h"
#include "fem/BodyCoordinates.h"
#include "fem/DisplaySurface.h"
#include "fem/NodalStress.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <numeric>
#include <set>
#include <utility>

using namespace caps::fem;
using caps::fem::test::boxMesh;

namespace {

using Field = std::function<Eigen::Vector3d(const Eigen::Vector3d&)>;

Eigen::VectorXd nodalField(const Mesh& mesh, const Field& f)
{
  Eigen::VectorXd u(mesh.dofCount());
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    u.segment<3>(3 * i) = f(mesh.nodes.col(i));
  return u;
}

std::vector<int> allNodes(const Mesh& mesh)
{
  std::vector<int> nodes(std::size_t(mesh.nodeCount()));
  std::iota(nodes.begin(), nodes.end(), 0);
  return nodes;
}

/// One 20-node brick mapped affinely, x = A (r, s, t) + b: any field
/// quadratic in x is then quadratic in (r, s, t), which the element holds exactly.
struct AffineHex
{
  Eigen::Matrix3d a = (Eigen::Matrix3d() << 6.0, 1.0, 0.5, -0.5, 4.0, 0.8, 0.3, -0.2, 3.0).finished();
  Eigen::Vector3d b{10.0, -4.0, 25.0};
  Mesh mesh;
  AffineHex()
  {
    mesh.nodes.resize(3, kHex20NodeCount);
    Element el;
    for (int k = 0; k < kHex20NodeCount; ++k)
    {
      mesh.nodes.col(k) = world(batheNaturalCoordinates(k));
      el.nodes[std::size_t(k)] = k;
    }
    mesh.elements.push_back(el);
  }
  Eigen::Vector3d world(const Eigen::Vector3d& rst) const { return a * rst + b; }
};

/// A quadratic displacement field (mm), large enough to matter.
Eigen::Vector3d quadraticField(const Eigen::Vector3d& x)
{
  return {0.01 * x[0] * x[1] - 0.002 * x[2] * x[2] + 0.3, 0.004 * x[0] * x[0] + 0.02 * x[1] * x[2] - 0.1 * x[0],
          -0.003 * x.squaredNorm() + 0.05 * x[1]};
}

/// Right-hand (Newell) normal of a polygon.
Eigen::Vector3d polygonNormal(const Eigen::Matrix3Xd& x, const std::vector<int>& polygon)
{
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < polygon.size(); ++k)
    n += x.col(polygon[k]).cross(x.col(polygon[(k + 1) % polygon.size()]));
  return n;
}

Eigen::Vector3d polygonCentre(const Eigen::Matrix3Xd& x, const std::vector<int>& polygon)
{
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int v : polygon)
    c += x.col(v);
  return c / double(polygon.size());
}

Eigen::Vector3d elementCentroid(const Mesh& mesh, int e)
{
  std::set<int> nodes;
  for (int n : mesh.elements[std::size_t(e)].nodes)
    if (n >= 0)
      nodes.insert(n);
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int n : nodes)
    c += mesh.nodes.col(n);
  return c / double(nodes.size());
}

/// Polygons whose right-hand normal points away from their element's centroid.
int outwardPolygons(const Mesh& mesh, const DisplaySurface& s)
{
  int out = 0;
  for (std::size_t p = 0; p < s.polygons().size(); ++p)
  {
    const int e = s.faces()[std::size_t(s.polygonFace()[p])].element;
    const Eigen::Vector3d n = polygonNormal(s.undeformedPositions(), s.polygons()[p]);
    if (n.dot(polygonCentre(s.undeformedPositions(), s.polygons()[p]) - elementCentroid(mesh, e)) > 0)
      ++out;
  }
  return out;
}

/// Closed, consistently oriented 2-manifold: every directed edge once and its
/// reverse once; returns the Euler characteristic V - E + F.
struct Topology
{
  bool closed = true;
  bool oriented = true;
  long euler = 0;
};
Topology topology(const DisplaySurface& s)
{
  std::map<std::pair<int, int>, int> directed;
  for (const auto& p : s.polygons())
    for (std::size_t k = 0; k < p.size(); ++k)
      ++directed[{p[k], p[(k + 1) % p.size()]}];
  Topology t;
  long edges = 0;
  for (const auto& [e, count] : directed)
  {
    if (count != 1)
      t.oriented = false;
    const auto reverse = directed.find({e.second, e.first});
    if (reverse == directed.end())
      t.closed = false;
    if (e.first < e.second || reverse == directed.end())
      ++edges;
  }
  t.euler = long(s.vertexCount()) - edges + long(s.polygons().size());
  return t;
}

bool onGrid(double value, int n)
{
  const double k = (value + 1.0) * n / 2.0;
  return std::abs(k - std::round(k)) < 1e-12;
}

} // namespace

TEST(DisplaySurface, QuadraticFieldOnABrickIsExactAtEveryVertex)
{
  const AffineHex hex;
  const std::vector<ElementFace> faces = boundaryFacesOnNodes(hex.mesh, allNodes(hex.mesh));
  ASSERT_EQ(faces.size(), 6u);
  const Eigen::VectorXd u = nodalField(hex.mesh, quadraticField);
  for (int n : {1, 2, 5})
  {
    DisplaySurface s(hex.mesh, faces, n);
    s.setSolution(u, {{0, {1.0, 0.3, 0.0}}});
    // Euler on the subdivided cube: 6 n^2 quadrilaterals, 12 n^2 edges, 6 n^2 + 2 vertices.
    EXPECT_EQ(long(s.vertexCount()), 6L * n * n + 2) << "n = " << n;
    EXPECT_EQ(long(s.polygons().size()), 6L * n * n);
    const Eigen::Matrix3Xd after = s.positions({1.0, false});
    const Eigen::Matrix3Xd halfway = s.positions({0.5, false});
    double worstPlace = 0.0, worstAfter = 0.0, worstHalf = 0.0;
    for (Eigen::Index v = 0; v < s.vertexCount(); ++v)
    {
      const BodyPoint& p = s.bodyPoints()[std::size_t(v)];
      // On the face (one natural coordinate ±1) at the equal steps of Table 4.8.
      EXPECT_EQ(p.element, 0);
      EXPECT_NEAR(p.rst.cwiseAbs().maxCoeff(), 1.0, 1e-15);
      for (int i = 0; i < 3; ++i)
        EXPECT_TRUE(onGrid(p.rst[i], n)) << p.rst.transpose();
      const Eigen::Vector3d x = hex.world(p.rst);
      worstPlace = std::max(worstPlace, (s.undeformedPositions().col(v) - x).norm());
      worstAfter = std::max(worstAfter, (after.col(v) - x - quadraticField(x)).norm());
      worstHalf = std::max(worstHalf, (halfway.col(v) - x - 0.5 * quadraticField(x)).norm());
    }
    EXPECT_LT(worstPlace, 1e-12) << "n = " << n;
    EXPECT_LT(worstAfter, 1e-12) << "n = " << n;
    EXPECT_LT(worstHalf, 1e-12) << "n = " << n;
    // Every grid point of every face is there exactly once.
    std::set<std::array<long, 3>> distinct;
    for (const BodyPoint& p : s.bodyPoints())
      distinct.insert({std::lround(p.rst[0] * n), std::lround(p.rst[1] * n), std::lround(p.rst[2] * n)});
    EXPECT_EQ(long(distinct.size()), long(s.vertexCount()));
    EXPECT_EQ(outwardPolygons(hex.mesh, s), int(s.polygons().size())) << "n = " << n;
    const Topology t = topology(s);
    EXPECT_TRUE(t.closed && t.oriented);
    EXPECT_EQ(t.euler, 2);
  }
}

TEST(DisplaySurface, OneFaceHasTheGridsVertexCount)
{
  const AffineHex hex;
  for (int face = 1; face <= 6; ++face)
  {
    const DisplaySurface s(hex.mesh, {{0, face}}, 4);
    EXPECT_EQ(s.vertexCount(), 25);
    EXPECT_EQ(s.polygons().size(), 16u);
    EXPECT_EQ(outwardPolygons(hex.mesh, s), 16) << "face " << face;
  }
  // A triangle of a native wedge: (n + 1)(n + 2) / 2 vertices, n^2 triangles.
  const Mesh wedges = withNativeWedges(boxMesh(1, 1, 1, 10, 10, 10, Eigen::Vector3d::Zero(), true));
  ASSERT_EQ(wedges.elements[0].kind, ElementKind::Wedge15);
  for (int n : {1, 3, 6})
    for (int face : {1, 2})
    {
      const DisplaySurface s(wedges, {{0, face}}, n);
      EXPECT_EQ(long(s.vertexCount()), long((n + 1) * (n + 2) / 2));
      EXPECT_EQ(long(s.polygons().size()), long(n * n));
      EXPECT_EQ(outwardPolygons(wedges, s), n * n);
    }
}

TEST(DisplaySurface, UniformStrainGivesTheAnalyticStressAtEveryVertex)
{
  const Eigen::Matrix3d g = (Eigen::Matrix3d() << 2e-3, 5e-4, -1e-3, 3e-4, -1.5e-3, 6e-4, -2e-4, 8e-4, 1e-3).finished();
  Vector6d strain;
  strain << g(0, 0), g(1, 1), g(2, 2), g(0, 1) + g(1, 0), g(1, 2) + g(2, 1), g(2, 0) + g(0, 2);
  const LinearElasticMaterial material{0.15, 0.45, 0.0};
  const Vector6d stress = material.elasticityMatrix() * strain;
  const double vonMises = vonMisesStress(stress), mean = (stress[0] + stress[1] + stress[2]) / 3;
  const double volumetric = strain[0] + strain[1] + strain[2];
  // sqrt(2/3 e':e') from the tensor, written out independently.
  Eigen::Matrix3d e = 0.5 * (g + g.transpose());
  const Eigen::Matrix3d deviator = e - volumetric / 3 * Eigen::Matrix3d::Identity();
  const double equivalent = std::sqrt(2.0 / 3.0 * (deviator.array() * deviator.array()).sum());

  for (bool wedges : {false, true})
  {
    Mesh mesh = boxMesh(2, 2, 1, 20, 16, 8, Eigen::Vector3d(5, -3, 40), wedges);
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      mesh.nodes.col(i) = test::wobble(mesh.nodes.col(i), 0.4);
    if (wedges)
      mesh = withNativeWedges(mesh);
    DisplaySurface s(mesh, boundaryFacesOnNodes(mesh, allNodes(mesh)), 3);
    s.setSolution(nodalField(mesh, [&](const Eigen::Vector3d& x) { return Eigen::Vector3d(g * x); }), {{0, material}});
    double worst = 0.0, worstScalar = 0.0;
    const Eigen::VectorXd vm = s.vonMises(), ms = s.meanStress(), vs = s.volumetricStrain(), es = s.equivalentStrain();
    for (Eigen::Index v = 0; v < s.vertexCount(); ++v)
    {
      worst = std::max(worst, (s.stresses().col(v) - stress).cwiseAbs().maxCoeff() / stress.cwiseAbs().maxCoeff());
      worst = std::max(worst, (s.strains().col(v) - strain).cwiseAbs().maxCoeff() / strain.cwiseAbs().maxCoeff());
      worstScalar =
        std::max({worstScalar, std::abs(vm[v] - vonMises) / vonMises, std::abs(ms[v] - mean) / std::abs(mean),
                  std::abs(vs[v] - volumetric) / std::abs(volumetric), std::abs(es[v] - equivalent) / equivalent});
    }
    std::printf("[uniform strain, %s] %ld vertices: largest relative error of strain/stress %.2g, "
                "of the scalars %.2g\n",
                wedges ? "native wedges" : "bricks", long(s.vertexCount()), worst, worstScalar);
    EXPECT_LT(worst, 1e-10);
    EXPECT_LT(worstScalar, 1e-10);
    EXPECT_EQ(outwardPolygons(mesh, s), int(s.polygons().size()));
  }
}

TEST(DisplaySurface, AHomogeneousLargeDeformationGivesTheNeoHookeanCauchyStressAtEveryVertex)
{
  // x -> F X with a large F (stretches 1.4, 0.8, 0.95, rotated): the
  // quadratic elements represent it exactly, so every vertex has the
  // closed-form Cauchy stress of the compressible neo-Hookean law,
  // sigma = 2 C10 / J dev(J^(-2/3) F F^T) + 2 / D1 (J - 1) I, written out
  // here without the material class, and the Green-Lagrange strain.
  const Eigen::Matrix3d rotation =
    Eigen::AngleAxisd(0.5, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
  const Eigen::Matrix3d f = rotation * Eigen::Vector3d(1.4, 0.8, 0.95).asDiagonal();
  const double c10 = 0.025, d1 = 1.2;
  const double j = f.determinant();
  const Eigen::Matrix3d bBar = std::pow(j, -2.0 / 3.0) * f * f.transpose();
  const Eigen::Matrix3d sigma = 2.0 * c10 / j * (bBar - bBar.trace() / 3.0 * Eigen::Matrix3d::Identity()) +
                                2.0 / d1 * (j - 1.0) * Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d e = 0.5 * (f.transpose() * f - Eigen::Matrix3d::Identity());
  Vector6d stress, strain;
  stress << sigma(0, 0), sigma(1, 1), sigma(2, 2), sigma(0, 1), sigma(1, 2), sigma(2, 0);
  strain << e(0, 0), e(1, 1), e(2, 2), 2 * e(0, 1), 2 * e(1, 2), 2 * e(2, 0);
  for (bool wedges : {false, true})
  {
    Mesh mesh = boxMesh(2, 2, 1, 20, 16, 8, Eigen::Vector3d(5, -3, 40), wedges);
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      mesh.nodes.col(i) = test::wobble(mesh.nodes.col(i), 0.4);
    if (wedges)
      mesh = withNativeWedges(mesh);
    DisplaySurface s(mesh, boundaryFacesOnNodes(mesh, allNodes(mesh)), 3);
    s.setSolution(
      nodalField(mesh,
                 [&](const Eigen::Vector3d& x) { return Eigen::Vector3d((f - Eigen::Matrix3d::Identity()) * x); }),
      HyperelasticTable{{0, HyperelasticMaterial::neoHookean(c10, d1)}});
    double worstStress = 0.0, worstStrain = 0.0;
    for (Eigen::Index v = 0; v < s.vertexCount(); ++v)
    {
      worstStress = std::max(worstStress, (s.stresses().col(v) - stress).cwiseAbs().maxCoeff());
      worstStrain = std::max(worstStrain, (s.strains().col(v) - strain).cwiseAbs().maxCoeff());
    }
    std::printf("[homogeneous large deformation, %s] %ld vertices: largest error of the Cauchy stress %.2g MPa "
                "(of %.3g), of the Green-Lagrange strain %.2g\n",
                wedges ? "native wedges" : "bricks", long(s.vertexCount()), worstStress, stress.cwiseAbs().maxCoeff(),
                worstStrain);
    EXPECT_LT(worstStress, 1e-10 * stress.cwiseAbs().maxCoeff());
    EXPECT_LT(worstStrain, 1e-10);
  }
  // A region without a material is refused, as for the linear solution.
  const Mesh cube = boxMesh(1, 1, 1, 10, 10, 10);
  DisplaySurface s(cube, boundaryFacesOnNodes(cube, allNodes(cube)), 1);
  EXPECT_THROW(s.setSolution(Eigen::VectorXd::Zero(cube.dofCount()),
                             HyperelasticTable{{1, HyperelasticMaterial::neoHookean(c10, d1)}}),
               std::invalid_argument);
}

TEST(DisplaySurface, EquivalentStrainIsTheStretchOfUniaxialIncompressibleStretch)
{
  // e_xx = 0.01, e_yy = e_zz = -0.005: equivalent strain 0.01.
  const AffineHex hex;
  DisplaySurface s(hex.mesh, {{0, 2}}, 1);
  s.setSolution(
    nodalField(hex.mesh,
               [](const Eigen::Vector3d& x) { return Eigen::Vector3d(0.01 * x[0], -0.005 * x[1], -0.005 * x[2]); }),
    {{0, {1.0, 0.3, 0.0}}});
  EXPECT_NEAR(s.equivalentStrain()[0], 0.01, 1e-14);
  EXPECT_NEAR(s.volumetricStrain()[0], 0.0, 1e-15);
}

TEST(DisplaySurface, StressIsTheNodalAverageInterpolatedAndContinuous)
{
  // Two materials in two layers (z < 5 and z > 5, as skin over fat) and a
  // field that is not linear: at vertices on mesh nodes the stress is
  // recoverNodalStresses' average there within the vertex's region (a node
  // of the interface z = 5 has one value per layer), and a vertex on an edge
  // between two elements of a region gets the same value from either.
  Mesh mesh = boxMesh(2, 2, 2, 20, 20, 10);
  for (Element& el : mesh.elements)
  {
    double z = 0;
    for (int n : el.nodes)
      z += mesh.nodes(2, n);
    el.region = z / kHex20NodeCount < 5 ? 0 : 1;
  }
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = test::wobble(mesh.nodes.col(i), 0.5);
  const MaterialTable materials{{0, {0.15, 0.45, 0.0}}, {1, {0.01, 0.45, 0.0}}};
  const Eigen::VectorXd u = nodalField(mesh, [](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(0.1 * std::sin(0.2 * x[1]), 0.002 * x[0] * x[2], 0.05 * std::cos(0.1 * x[0] * x[1] / 10));
  });
  DisplaySurface s(mesh, boundaryFacesOnNodes(mesh, allNodes(mesh)), 4);
  s.setSolution(u, materials);
  const NodalStressField nodal = recoverNodalStresses(mesh, materials, u, 2);
  const double scale = nodal.stress.cwiseAbs().maxCoeff();
  int onNodes = 0, onInterface = 0;
  double worst = 0.0;
  for (Eigen::Index v = 0; v < s.vertexCount(); ++v)
  {
    const BodyPoint& p = s.bodyPoints()[std::size_t(v)];
    // Corners of the element: exactly on a node.
    if ((p.rst.cwiseAbs() - Eigen::Vector3d::Ones()).cwiseAbs().maxCoeff() > 0)
      continue;
    for (int k = 0; k < kHex20CornerCount; ++k)
      if (batheNaturalCoordinates(k) == p.rst)
      {
        const Element& own = mesh.elements[std::size_t(p.element)];
        const int node = own.nodes[std::size_t(k)];
        worst = std::max(worst, (s.stresses().col(v) - nodal.valueAt(own.region, node)).cwiseAbs().maxCoeff() / scale);
        ++onNodes;
        if (nodal.layout.column(1 - own.region, node) >= 0)
        {
          ++onInterface; // the other layer's value differs: the jump is kept
          EXPECT_GT((nodal.valueAt(1 - own.region, node) - s.stresses().col(v)).cwiseAbs().maxCoeff(), 1e-3 * scale);
        }
      }
  }
  EXPECT_GT(onNodes, 20);
  EXPECT_GT(onInterface, 4);
  EXPECT_LT(worst, 1e-12);

  // The same vertex seen from the other element: the boundary faces of
  // element 0 and element 1 meet on the plane x = 10 (wobbled).
  const Eigen::VectorXd displayed = s.vonMises();
  double jump = 0.0;
  int shared = 0;
  for (Eigen::Index v = 0; v < s.vertexCount(); ++v)
  {
    const BodyPoint& p = s.bodyPoints()[std::size_t(v)];
    if (p.element != 0 || std::abs(p.rst[0] - 1.0) > 0)
      continue; // r = +1 of element 0 is the side it shares
    // Other element holding the same material point: interpolate the nodal
    // field with its own shape functions.
    for (std::size_t e = 1; e < mesh.elements.size(); ++e)
    {
      const Element& el = mesh.elements[e];
      // Mirror r across the shared face: the neighbour in +x has r = -1 there.
      const Element& own = mesh.elements[0];
      if (el.nodes[1] != own.nodes[0] || el.nodes[2] != own.nodes[3])
        continue;
      const Eigen::Vector3d other(-1.0, p.rst[1], p.rst[2]);
      ShapeVector h;
      ElementShape::fromConnectivity(el.kind, el.nodes).values(other, h);
      Vector6d sigma = Vector6d::Zero();
      for (int k = 0; k < kHex20NodeCount; ++k)
        sigma += h[k] * nodal.valueAt(el.region, el.nodes[std::size_t(k)]);
      EXPECT_LT((worldPoint(mesh, {int(e), other}) - s.undeformedPositions().col(v)).norm(), 1e-12);
      jump = std::max(jump, std::abs(vonMisesStress(sigma) - displayed[v]) / displayed.maxCoeff());
      ++shared;
    }
  }
  EXPECT_GT(shared, 0);
  EXPECT_LT(jump, 1e-12);
}

TEST(DisplaySurface, SharedEdgesAreWeldedIntoOneClosedSurface)
{
  for (int n : {1, 2, 4})
  {
    // Two bricks side by side: 10 boundary faces, 10 n^2 + 2 vertices.
    const Mesh two = boxMesh(2, 1, 1, 20, 10, 10);
    const std::vector<ElementFace> faces = boundaryFacesOnNodes(two, allNodes(two));
    ASSERT_EQ(faces.size(), 10u);
    const DisplaySurface s(two, faces, n);
    EXPECT_EQ(long(s.vertexCount()), 10L * n * n + 2);
    EXPECT_EQ(long(s.polygons().size()), 10L * n * n);
    const Topology t = topology(s);
    EXPECT_TRUE(t.closed) << "n = " << n;
    EXPECT_TRUE(t.oriented) << "n = " << n;
    EXPECT_EQ(t.euler, 2);
    EXPECT_EQ(outwardPolygons(two, s), int(s.polygons().size()));
    // The ring where the two elements meet (x = 10): 4 n vertices, none twice.
    std::set<std::array<long, 3>> ring;
    int onRing = 0;
    for (Eigen::Index v = 0; v < s.vertexCount(); ++v)
    {
      const Eigen::Vector3d x = s.undeformedPositions().col(v);
      if (std::abs(x[0] - 10.0) > 1e-9)
        continue;
      ++onRing;
      ring.insert({std::lround(x[0] * 1e6), std::lround(x[1] * 1e6), std::lround(x[2] * 1e6)});
    }
    EXPECT_EQ(onRing, 4 * n);
    EXPECT_EQ(int(ring.size()), onRing);

    // Native wedges (triangles and quadrilaterals together) and Fig. 3.2's
    // degenerate 20-node wedges: closed and outward too.
    for (bool native : {true, false})
    {
      Mesh w = boxMesh(2, 1, 1, 20, 10, 10, Eigen::Vector3d::Zero(), true);
      for (Eigen::Index i = 0; i < w.nodeCount(); ++i)
        w.nodes.col(i) = test::wobble(w.nodes.col(i), 0.3);
      if (native)
        w = withNativeWedges(w);
      const DisplaySurface ws(w, boundaryFacesOnNodes(w, allNodes(w)), n);
      const Topology wt = topology(ws);
      EXPECT_TRUE(wt.closed && wt.oriented) << (native ? "native" : "degenerate") << " wedges, n = " << n;
      EXPECT_EQ(wt.euler, 2);
      EXPECT_EQ(outwardPolygons(w, ws), int(ws.polygons().size()));
      // No two vertices in one place.
      std::set<std::array<long, 3>> places;
      for (Eigen::Index v = 0; v < ws.vertexCount(); ++v)
      {
        const Eigen::Vector3d x = ws.undeformedPositions().col(v);
        places.insert({std::lround(x[0] * 1e6), std::lround(x[1] * 1e6), std::lround(x[2] * 1e6)});
      }
      EXPECT_EQ(long(places.size()), long(ws.vertexCount()));
    }
  }
}

TEST(DisplaySurface, ScaleZeroIsUndeformedAndScaleOneIsDeformed)
{
  Mesh mesh = boxMesh(3, 2, 1, 30, 20, 6);
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = test::wobble(mesh.nodes.col(i), 0.5);
  const Eigen::VectorXd u = nodalField(mesh, [](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(0.2 * std::sin(0.3 * x[1]), 0.1 * std::cos(0.2 * x[0]), 0.01 * x[0] * x[1] / 10);
  });
  // The top (z = 6) faces only, as the skin would be.
  std::vector<int> top;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    if (mesh.nodes(2, i) > 4.0)
      top.push_back(int(i)); // z = 6 moved by at most 0.5
  const std::vector<ElementFace> faces = boundaryFacesOnNodes(mesh, top);
  ASSERT_EQ(faces.size(), 6u);
  for (const ElementFace& f : faces)
    EXPECT_EQ(f.face, 2); // t = +1
  DisplaySurface s(mesh, faces, 5);
  s.setSolution(u, {{0, {1.0, 0.3, 0.0}}});
  EXPECT_EQ(s.positions({0.0, false}), s.undeformedPositions());
  const Eigen::Matrix3Xd after = s.positions({1.0, false});
  double worstBefore = 0.0, worstAfter = 0.0;
  for (Eigen::Index v = 0; v < s.vertexCount(); ++v)
  {
    const BodyPoint& p = s.bodyPoints()[std::size_t(v)];
    worstBefore = std::max(worstBefore, (s.undeformedPositions().col(v) - worldPoint(mesh, p)).norm());
    worstAfter = std::max(worstAfter, (after.col(v) - displacedWorldPoint(mesh, u, p)).norm());
  }
  EXPECT_LT(worstBefore, 1e-12);
  EXPECT_LT(worstAfter, 1e-12);
  // An open sheet of 3 x 2 faces: (3n + 1)(2n + 1) vertices.
  EXPECT_EQ(long(s.vertexCount()), (3L * 5 + 1) * (2L * 5 + 1));

  // Range detail rides with the vertex.
  Eigen::Matrix3Xd detail = Eigen::Matrix3Xd::Random(3, s.vertexCount()) * 0.1;
  s.setRangeDetail(detail);
  EXPECT_LT((s.positions({1.0, true}) - after - detail).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((s.positions({0.0, true}) - s.undeformedPositions() - detail).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_THROW(s.setRangeDetail(Eigen::Matrix3Xd::Zero(3, 2)), std::invalid_argument);
  Eigen::Matrix3Xd wrong(3, 1);
  EXPECT_THROW(s.positions({1.0, false}, wrong), std::invalid_argument);
}

TEST(DisplaySurface, RefusesBadFacesResolutionsAndSolutions)
{
  const AffineHex hex;
  EXPECT_THROW(DisplaySurface(hex.mesh, {{0, 2}}, 0), std::invalid_argument);
  EXPECT_THROW(DisplaySurface(hex.mesh, {{1, 2}}, 2), std::invalid_argument);
  EXPECT_THROW(DisplaySurface(hex.mesh, {{0, 7}}, 2), std::invalid_argument);
  DisplaySurface s(hex.mesh, {{0, 2}}, 2);
  EXPECT_THROW(s.setSolution(Eigen::VectorXd::Zero(3), {{0, {1.0, 0.3, 0.0}}}), std::invalid_argument);
  EXPECT_THROW(s.setSolution(Eigen::VectorXd::Zero(60), {{1, {1.0, 0.3, 0.0}}}), std::invalid_argument);
}

TEST(DisplaySurface, NewScaleAndNewSolutionDoNotRedoTheSubdivision)
{
  // A skin-sized sheet: 30 x 30 elements over 3 layers, top faces at n = 4.
  Mesh mesh = boxMesh(30, 30, 3, 60, 60, 9);
  std::vector<int> top;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    if (mesh.nodes(2, i) > 9.0 - 1e-9)
      top.push_back(int(i));
  const MaterialTable materials{{0, {0.15, 0.45, 0.0}}};
  const Eigen::VectorXd u = nodalField(mesh, [](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(0.1 * std::sin(0.1 * x[1]), 0.0, 0.05 * std::cos(0.1 * x[0]));
  });
  using clock = std::chrono::steady_clock;
  auto seconds = [](clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); };
  auto t0 = clock::now();
  DisplaySurface s(mesh, boundaryFacesOnNodes(mesh, top), 4);
  const double build = seconds(t0);
  t0 = clock::now();
  s.setSolution(u, materials);
  const double solution = seconds(t0);
  Eigen::Matrix3Xd x(3, s.vertexCount());
  t0 = clock::now();
  const int frames = 100;
  for (int f = 0; f < frames; ++f)
    s.positions({double(f) / (frames - 1), false}, x);
  const double frame = seconds(t0) / frames;
  std::printf("[display timing] %zu faces, %ld vertices: subdivision %.2f ms, new solution %.2f ms, "
              "new scale %.3f ms per frame\n",
              s.faces().size(), long(s.vertexCount()), 1e3 * build, 1e3 * solution, 1e3 * frame);
  EXPECT_EQ(long(s.vertexCount()), (30L * 4 + 1) * (30L * 4 + 1));
  EXPECT_LT((x - s.undeformedPositions() - s.displacements()).cwiseAbs().maxCoeff(), 1e-12);
}
