// The native 15-node wedge against independent answers: partition of unity,
// the Kronecker property, finite differences, exact integrals and volumes,
// the constant-strain patch test on a distorted mixed mesh, gravity; then
// the same problems solved with the degenerate 20-node wedge of thesis
// Fig. 3.2 and with the native wedge (beam theory, a fine reference mesh for
// nearly incompressible tissue), and CalculiX's C3D15 on the exported decks.

#include "fem/Assembly.h"
#include "fem/CalculixIO.h"
#include "fem/CalculixReader.h"
#include "fem/ElasticityIntegrator.h"
#include "fem/ElementGeometry.h"
#include "fem/NodalStress.h"
#include "fem/Quadrature.h"
#include "fem/StaticAnalysis.h"
#include "fem/StressRecovery.h"
#include "fem/VtuWriter.h"
#include "fem/Wedge15Shape.h"

#include "CcxRunner.h"
#include "FemTestMeshes.h"

#include <Eigen/Eigenvalues>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <iostream>
#include <random>
#include <set>
#include <string>

#include <unistd.h>

namespace caps::fem {
namespace {

using test::boxMesh;
using test::wobble;

std::vector<Eigen::Vector3d> wedgePoints()
{
  std::vector<Eigen::Vector3d> p;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 30; ++i)
  {
    double r = u(rng), s = u(rng);
    if (r + s > 1.0)
    {
      r = 1.0 - r;
      s = 1.0 - s;
    }
    p.emplace_back(r, s, 2.0 * u(rng) - 1.0);
  }
  p.emplace_back(0.0, 0.0, 1.0);
  p.emplace_back(1.0 / 3.0, 1.0 / 3.0, 0.0);
  return p;
}

// ---- Interpolation functions ----

TEST(Wedge15Shape, PartitionOfUnityAndZeroDerivativeSum)
{
  const Wedge15Shape shape;
  for (const auto& p : wedgePoints())
  {
    ShapeVector h;
    ShapeDerivatives dh;
    shape.evaluate(p, h, dh);
    EXPECT_NEAR(h.sum(), 1.0, 1e-14);
    EXPECT_LT(dh.colwise().sum().norm(), 1e-13);
    EXPECT_EQ(h.tail<5>().norm(), 0.0);
    EXPECT_EQ(dh.bottomRows<5>().norm(), 0.0);
  }
}

TEST(Wedge15Shape, KroneckerPropertyAtTheFifteenNodes)
{
  const Wedge15Shape shape;
  for (int node = 0; node < kWedge15NodeCount; ++node)
  {
    ShapeVector h;
    shape.values(wedge15NaturalCoordinates(node), h);
    for (int k = 0; k < kHex20NodeCount; ++k)
      EXPECT_NEAR(h[k], k == node ? 1.0 : 0.0, 1e-15) << node << " h_" << k;
  }
}

TEST(Wedge15Shape, DerivativesMatchFiniteDifferences)
{
  const Wedge15Shape shape;
  const double eps = 1e-6;
  for (const auto& p : wedgePoints())
  {
    ShapeVector h;
    ShapeDerivatives dh;
    shape.evaluate(p, h, dh);
    for (int d = 0; d < 3; ++d)
    {
      ShapeVector hp, hm;
      Eigen::Vector3d pp = p, pm = p;
      pp[d] += eps;
      pm[d] -= eps;
      shape.values(pp, hp);
      shape.values(pm, hm);
      EXPECT_LT(((hp - hm) / (2 * eps) - dh.col(d)).cwiseAbs().maxCoeff(), 1e-9) << "direction " << d;
    }
  }
}

// The 15 functions span {1, r, s, r^2, rs, s^2} x {1, t} + {1, r, s} t^2, so
// any such field is reproduced exactly from its nodal values.
TEST(Wedge15Shape, ReproducesItsPolynomialSpace)
{
  const Wedge15Shape shape;
  auto f = [](const Eigen::Vector3d& x) {
    const double r = x[0], s = x[1], t = x[2];
    return 0.3 - r + 2 * s + 0.7 * r * r - 1.1 * r * s + 0.4 * s * s +
           t * (0.2 + 0.5 * r - s + 0.9 * r * r + 0.3 * r * s - 0.6 * s * s) + t * t * (0.8 - 0.2 * r + 0.1 * s);
  };
  ShapeVector nodal = ShapeVector::Zero();
  for (int k = 0; k < kWedge15NodeCount; ++k)
    nodal[k] = f(wedge15NaturalCoordinates(k));
  for (const auto& p : wedgePoints())
  {
    ShapeVector h;
    shape.values(p, h);
    EXPECT_NEAR(h.dot(nodal), f(p), 1e-14);
  }
}

TEST(Wedge15Numbering, CalculixTranslationKeepsNaturalCoordinates)
{
  // ccx shape15w: nodes 1..3 at zeta = -1 (0,0), (1,0), (0,1); 4..6 above; 7..9 / 10..12 mid-edges; 13..15 along zeta.
  const double ccx[15][3] = {{0, 0, -1},  {1, 0, -1},  {0, 1, -1},   {0, 0, 1},   {1, 0, 1},
                             {0, 1, 1},   {.5, 0, -1}, {.5, .5, -1}, {0, .5, -1}, {.5, 0, 1},
                             {.5, .5, 1}, {0, .5, 1},  {0, 0, 0},    {1, 0, 0},   {0, 1, 0}};
  for (int c = 1; c <= 15; ++c)
  {
    const int w = c3d15ToWedge15(c);
    EXPECT_EQ(wedge15ToC3D15(w), c);
    EXPECT_EQ(wedge15NaturalCoordinates(w), Eigen::Vector3d(ccx[c - 1][0], ccx[c - 1][1], ccx[c - 1][2])) << c;
  }
  EXPECT_THROW(wedge15ToC3D15(15), std::out_of_range);
  EXPECT_THROW(c3d15ToWedge15(0), std::out_of_range);
}

// ---- Integration rules ----

double factorial(int n)
{
  return n <= 1 ? 1.0 : n * factorial(n - 1);
}

TEST(WedgeRule, IntegratesPolynomialsExactly)
{
  // Over the triangle: int r^i s^j = i! j! / (i + j + 2)!; along t: 2 / (k + 1) for even k.
  for (int level : {2, 3})
  {
    const IntegrationRule& rule = wedgeRule(level);
    ASSERT_EQ(rule.size(), level == 2 ? 9u : 18u);
    const int triangleDegree = level == 2 ? 2 : 4;
    for (int i = 0; i <= triangleDegree; ++i)
      for (int j = 0; i + j <= triangleDegree; ++j)
        for (int k = 0; k <= 5; ++k)
        {
          double sum = 0.0;
          for (std::size_t q = 0; q < rule.size(); ++q)
          {
            const auto& p = rule.points[q];
            sum += rule.weights[q] * std::pow(p[0], i) * std::pow(p[1], j) * std::pow(p[2], k);
          }
          const double exact = factorial(i) * factorial(j) / factorial(i + j + 2) * (k % 2 ? 0.0 : 2.0 / (k + 1));
          EXPECT_NEAR(sum, exact, 1e-15) << "level " << level << ": r^" << i << " s^" << j << " t^" << k;
        }
  }
  EXPECT_THROW(wedgeRule(1), std::invalid_argument);
  EXPECT_THROW(wedgeRule(4), std::invalid_argument);
  EXPECT_EQ(&integrationRule(ElementKind::Hex20, 3), &gaussRule(3));
  EXPECT_EQ(&integrationRule(ElementKind::Wedge15, 2), &wedgeRule(2));
}

// Node positions of a wedge mapped by @a f from its natural coordinates (slots 15..19 zero).
ElementCoordinates mappedWedge(const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& f)
{
  ElementCoordinates x = ElementCoordinates::Zero();
  for (int k = 0; k < kWedge15NodeCount; ++k)
    x.row(k) = f(wedge15NaturalCoordinates(k)).transpose();
  return x;
}

// A sheared wedge with curved triangles: x = (a r + d s t, b s, H/2 t (1 + g r^2 + e s)),
// inside the element's space, so the isoparametric map is exactly this one.
// det J = a b H/2 (1 + g r^2 + e s) - b H g d r s t, and the odd t term
// integrates to zero: V = a b H (1/2 + g/12 + e/6).
TEST(Wedge15Geometry, VolumeOfADistortedWedgeMatchesTheAnalyticIntegral)
{
  const double a = 3.0, b = 2.0, height = 5.0, d = 0.4, g = 0.5, e = -0.3;
  const ElementCoordinates x = mappedWedge([&](const Eigen::Vector3d& n) {
    const double r = n[0], s = n[1], t = n[2];
    return Eigen::Vector3d(a * r + d * s * t, b * s, 0.5 * height * t * (1 + g * r * r + e * s));
  });
  const double exact = a * b * height * (0.5 + g / 12 + e / 6);
  for (int level : {2, 3})
  {
    const double v = elementVolume(ElementShape::wedge15(), x, wedgeRule(level), 0);
    EXPECT_NEAR(v, exact, 1e-13 * exact) << level;
  }
  // World derivatives: the gradient of the field x itself is the identity.
  PointGeometry pg;
  evaluateGeometry(ElementShape::wedge15(), x, Eigen::Vector3d(0.2, 0.3, -0.4), 0, pg);
  EXPECT_TRUE((x.transpose() * pg.dhWorld).isApprox(Eigen::Matrix3d::Identity(), 1e-13));
}

TEST(Wedge15Geometry, InvertedWedgeIsNamedWithItsNaturalPoint)
{
  // Top and bottom triangles swapped: left-handed.
  const ElementCoordinates x = mappedWedge([](const Eigen::Vector3d& n) { return Eigen::Vector3d(n[0], n[1], -n[2]); });
  PointGeometry g;
  try
  {
    evaluateGeometry(ElementShape::wedge15(), x, wedgeRule(3).points[0], 17, g);
    FAIL() << "no error";
  }
  catch (const ElementError& e)
  {
    EXPECT_EQ(e.element(), 17);
    const std::string m = e.what();
    EXPECT_NE(m.find("element 17 is inverted"), std::string::npos) << m;
    EXPECT_NE(m.find("natural point (r, s, t)"), std::string::npos) << m;
    EXPECT_NE(m.find("wedge numbering"), std::string::npos) << m;
  }
  // Flattened: collapsed.
  const ElementCoordinates flat = mappedWedge([](const Eigen::Vector3d& n) { return Eigen::Vector3d(n[0], n[1], 0); });
  EXPECT_THROW(evaluateGeometry(ElementShape::wedge15(), flat, Eigen::Vector3d(0.2, 0.2, 0), 3, g), ElementError);
}

// Both rules give exactly the six rigid-body modes; 3 x 2 points could not.
TEST(Wedge15Stiffness, OnlyRigidBodyModesHaveZeroEnergy)
{
  const ElementCoordinates x = mappedWedge([](const Eigen::Vector3d& n) {
    return Eigen::Vector3d(2.0 * n[0] + 0.3 * n[1], 1.5 * n[1], 0.8 * n[2] + 0.1 * n[0]);
  });
  for (int level : {2, 3})
  {
    ElementMatrix ke;
    assembleElementStiffness(ElementShape::wedge15(), x, {1.0, 0.3, 0.0}, wedgeRule(level), 0, ke);
    const Eigen::MatrixXd k = ke.topLeftCorner(45, 45);
    EXPECT_EQ(ke.bottomRows(15).norm(), 0.0);
    const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(k).eigenvalues();
    int zero = 0;
    for (Eigen::Index i = 0; i < ev.size(); ++i)
      zero += std::abs(ev[i]) < 1e-10 * ev.maxCoeff();
    EXPECT_EQ(zero, 6) << "level " << level << ", smallest deformation eigenvalue " << ev[6] / ev.maxCoeff();
  }
}

// ---- Meshes of wedges ----

Eigen::Vector3d smoothDistortion(const Eigen::Vector3d& x)
{
  return x + 0.35 * Eigen::Vector3d(std::sin(0.7 * x[1] + 0.3 * x[2]), std::sin(0.5 * x[0] + 0.9 * x[2]),
                                    std::sin(0.6 * x[0] + 0.4 * x[1]));
}

int countKind(const Mesh& mesh, ElementKind kind)
{
  int n = 0;
  for (const Element& e : mesh.elements)
    n += e.kind == kind;
  return n;
}

TEST(NativeWedges, ConversionKeepsNodesRegionsAndVolume)
{
  test::MeshBuilder b(Eigen::Vector3d(1.0, 1.5, 2.0));
  b.addHex(0, 0, 0, 1);
  b.addWedgePair(1, 0, 0, 2);
  b.addWedgePair(0, 1, 0, 3);
  b.addHex(1, 1, 0, 1);
  const Mesh degenerate = b.build();
  const Mesh native = withNativeWedges(degenerate);
  ASSERT_EQ(native.elements.size(), 6u);
  EXPECT_EQ(countKind(native, ElementKind::Wedge15), 4);
  EXPECT_EQ(native.nodes, degenerate.nodes);
  for (std::size_t e = 0; e < native.elements.size(); ++e)
  {
    EXPECT_EQ(native.elements[e].region, degenerate.elements[e].region);
    const double v0 = elementVolume(ElementShape::fromConnectivity(ElementKind::Hex20, degenerate.elements[e].nodes),
                                    degenerate.elementCoordinates(e), gaussRule(3), int(e));
    const double v1 = elementVolume(ElementShape::fromConnectivity(native.elements[e].kind, native.elements[e].nodes),
                                    native.elementCoordinates(e), integrationRule(native.elements[e].kind, 3), int(e));
    EXPECT_NEAR(v1, v0, 1e-12) << e;
    // The same 15 nodes, each once.
    std::set<int> a(degenerate.elements[e].nodes.begin(), degenerate.elements[e].nodes.end());
    std::set<int> c(native.elements[e].nodes.begin(), native.elements[e].nodes.begin() + kWedge15NodeCount);
    if (native.elements[e].kind == ElementKind::Hex20)
      c.insert(native.elements[e].nodes.begin(), native.elements[e].nodes.end());
    a.erase(-1);
    EXPECT_EQ(a, c);
  }
  validateMesh(native, {{1, {1, 0.3, 0}}, {2, {1, 0.3, 0}}, {3, {1, 0.3, 0}}});
  // A native wedge needs all 15 nodes and no more.
  Mesh bad = native;
  bad.elements[1].nodes[9] = -1;
  EXPECT_THROW(validateMesh(bad, {{1, {1, 0.3, 0}}, {2, {1, 0.3, 0}}, {3, {1, 0.3, 0}}}), std::invalid_argument);
  bad = native;
  bad.elements[1].nodes[17] = 0;
  EXPECT_THROW(validateMesh(bad, {{1, {1, 0.3, 0}}, {2, {1, 0.3, 0}}, {3, {1, 0.3, 0}}}), std::invalid_argument);
}

// Patch test: a linear displacement prescribed on the boundary of a
// distorted mesh of bricks and native wedges is reproduced inside, with the
// constant strain at every Gauss point, for both wedge rules.
TEST(NativeWedges, PatchTestOnDistortedMixedMesh)
{
  const Eigen::Vector3d size(4.0, 3.0, 2.0);
  test::MeshBuilder b(Eigen::Vector3d(size[0] / 8, size[1] / 6, size[2] / 4));
  // Whole columns of bricks among columns of wedges: a brick face cannot
  // meet the two triangles of a wedge pair (their diagonal node).
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 4; ++i)
      {
        if ((i + j) % 3 == 0)
          b.addHex(i, j, k);
        else
          b.addWedgePair(i, j, k);
      }
  const Mesh straight = withNativeWedges(b.build());
  ASSERT_GT(countKind(straight, ElementKind::Wedge15), 20);
  ASSERT_GT(countKind(straight, ElementKind::Hex20), 5);
  // Level 3 integrates exactly what the patch test needs even on curved
  // elements; ccx's 9 points (level 2) only on straight-sided ones, so it
  // gets an affine distortion (on the curved mesh it is off by ~3e-5, as
  // the brick's 2x2x2 rule is on a curved brick mesh).
  Mesh curved = straight, skewed = straight;
  Eigen::Matrix3d skew;
  skew << 1.0, 0.3, -0.2, 0.1, 0.9, 0.25, -0.15, 0.2, 1.1;
  for (Eigen::Index i = 0; i < straight.nodeCount(); ++i)
  {
    curved.nodes.col(i) = smoothDistortion(straight.nodes.col(i));
    skewed.nodes.col(i) = skew * straight.nodes.col(i);
  }

  Eigen::Matrix3d a;
  a << 1e-3, 2e-4, -3e-4, 5e-4, -2e-3, 1e-4, -4e-4, 3e-4, 1.5e-3;
  const Eigen::Vector3d u0(0.01, -0.02, 0.03);
  const MaterialTable materials{{0, {2.0, 0.3, 0.0}}};
  Vector6d strain;
  strain << a(0, 0), a(1, 1), a(2, 2), a(0, 1) + a(1, 0), a(1, 2) + a(2, 1), a(2, 0) + a(0, 2);
  for (int level : {3, 2})
  {
    const Mesh& mesh = level == 3 ? curved : skewed;
    Eigen::VectorXd exact(mesh.dofCount());
    Constraints c;
    int interior = 0;
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    {
      exact.segment<3>(3 * i) = u0 + a * mesh.nodes.col(i);
      const Eigen::Vector3d x = straight.nodes.col(i);
      bool boundary = false;
      for (int d = 0; d < 3; ++d)
        boundary = boundary || std::abs(x[d]) < 1e-9 || std::abs(x[d] - size[d]) < 1e-9;
      if (boundary)
        for (int d = 0; d < 3; ++d)
          c.prescribe(int(i), d, exact[3 * i + d]);
      else
        ++interior;
    }
    ASSERT_GE(interior, 20);
    AssemblyOptions options;
    options.gaussPointsPerDirection = level;
    LinearStaticAnalysis analysis(mesh, materials, c, options);
    ASSERT_EQ(analysis.prepare(), SolverStatus::Success) << analysis.message();
    const Eigen::VectorXd u = analysis.solve(LoadCase{});
    const double err = (u - exact).cwiseAbs().maxCoeff() / exact.cwiseAbs().maxCoeff();
    double worst = 0.0;
    for (int e = 0; e < int(mesh.elements.size()); ++e)
      for (const StressPoint& p : recoverStressAtGaussPoints(mesh, materials, u, e, level))
        worst = std::max(worst, (p.strain - strain).norm() / strain.norm());
    std::cout << "native wedge patch test (level " << level << (level == 3 ? ", curved" : ", skewed")
              << "): nodal error " << err << ", Gauss-point strain error " << worst << "\n";
    EXPECT_LT(err, 1e-10);
    EXPECT_LT(worst, 1e-10);
    // Nodal stresses: the constant stress at every node.
    const Vector6d stress = materials.at(0).elasticityMatrix() * strain;
    const NodalStressField f = recoverNodalStresses(mesh, materials, u, level);
    double nodal = 0.0;
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      nodal = std::max(nodal, (f.stress.col(i) - stress).norm());
    EXPECT_LT(nodal / stress.norm(), 1e-10) << level;
  }
}

TEST(NativeWedges, ExtrapolationReproducesLinearStressAtNodes)
{
  for (int level : {2, 3})
  {
    const Eigen::MatrixXd e = gaussToNodeExtrapolation(ElementKind::Wedge15, level);
    const IntegrationRule& rule = wedgeRule(level);
    ASSERT_EQ(e.rows(), 20);
    ASSERT_EQ(e.cols(), Eigen::Index(rule.size()));
    EXPECT_EQ(e.bottomRows(5).norm(), 0.0);
    auto f = [&](const Eigen::Vector3d& p) {
      const double linear = 0.4 - 1.3 * p[0] + 0.7 * p[1] + 2.1 * p[2] + 0.5 * p[0] * p[2];
      return level == 3 ? linear + 0.8 * p[0] * p[1] - 0.6 * p[2] * p[2] * p[1] : linear;
    };
    Eigen::VectorXd g(Eigen::Index(rule.size()));
    for (std::size_t q = 0; q < rule.size(); ++q)
      g[Eigen::Index(q)] = f(rule.points[q]);
    const Eigen::VectorXd atNodes = e * g;
    for (int k = 0; k < kWedge15NodeCount; ++k)
      EXPECT_NEAR(atNodes[k], f(wedge15NaturalCoordinates(k)), 1e-13) << k;
  }
}

// Block 10 x 10 x 50 mm of native wedges fixed at z = 0 under its own weight,
// nu = 0: u_z = -(rho g / E) (H z - z^2 / 2) is quadratic, so exact.
TEST(NativeWedges, GravityColumnMatchesOneDimensionalSolution)
{
  const double height = 50.0, e = 0.02, rho = 1.1e-9, g = 9810.0;
  const Mesh mesh = withNativeWedges(boxMesh(1, 1, 5, 10.0, 10.0, height, Eigen::Vector3d::Zero(), true));
  ASSERT_EQ(countKind(mesh, ElementKind::Wedge15), 10);
  Constraints c;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    if (mesh.nodes(2, i) < 1e-9)
      c.fixNode(int(i));
  const MaterialTable materials{{0, {e, 0.0, rho}}};
  LoadCase load;
  load.gravity = Eigen::Vector3d(0, 0, -g);
  for (int level : {3, 2})
  {
    AssemblyOptions options;
    options.gaussPointsPerDirection = level;
    LinearStaticAnalysis analysis(mesh, materials, c, options);
    ASSERT_EQ(analysis.prepare(), SolverStatus::Success) << analysis.message();
    EXPECT_NEAR(analysis.loadVector(load).sum(), -rho * g * 10 * 10 * height, 1e-15);
    const Eigen::VectorXd u = analysis.solve(load);
    double err = 0.0, tip = 0.0;
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    {
      const double z = mesh.nodes(2, i);
      const double exact = -(rho * g / e) * (height * z - 0.5 * z * z);
      tip = std::min(tip, exact);
      err = std::max({err, std::abs(u[3 * i + 2] - exact), std::abs(u[3 * i]), std::abs(u[3 * i + 1])});
    }
    EXPECT_LT(err / std::abs(tip), 1e-10) << level;
    const StressPoint p = recoverStress(mesh, materials, u, 0, Eigen::Vector3d(0.2, 0.5, 0.1));
    EXPECT_NEAR(p.stress[2], -rho * g * (height - p.world[2]), 1e-12);
  }
}

// ---- The same problems with degenerate and native wedges ----

// Cantilever L x h x h clamped at x = 0 with a shear load P along @a axis
// (1: y, in the plane of the wedges' triangles; 2: z, along their extrusion)
// spread over the tip face as a uniform traction (consistent loads: corners
// -1/12, mid-sides 1/3 of each face's share). Returns the mean tip deflection.
double cantileverTip(const Mesh& mesh, int ny, int nz, double length, double h, double nu, int axis,
                     int gaussPoints = 3)
{
  const double e = 1000.0, p = -1.0;
  Constraints c;
  LoadCase load;
  const double dy = h / (2 * ny), dz = h / (2 * nz), share = p / (ny * nz);
  std::vector<int> tip;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    const Eigen::Vector3d x = mesh.nodes.col(i);
    if (x[0] < 1e-9)
      c.fixNode(int(i));
    if (std::abs(x[0] - length) > 1e-9)
      continue;
    tip.push_back(int(i));
    const int jy = int(std::lround(x[1] / dy)), jz = int(std::lround(x[2] / dz));
    double f = 0.0;
    for (int fy = 0; fy < ny; ++fy)
      for (int fz = 0; fz < nz; ++fz)
      {
        const int ly = jy - 2 * fy, lz = jz - 2 * fz;
        if (ly < 0 || ly > 2 || lz < 0 || lz > 2 || (ly == 1 && lz == 1))
          continue;
        f += (ly == 1 || lz == 1) ? share / 3.0 : -share / 12.0;
      }
    Eigen::Vector3d force = Eigen::Vector3d::Zero();
    force[axis] = f;
    load.nodalForces.push_back({int(i), force});
  }
  AssemblyOptions options;
  options.gaussPointsPerDirection = gaussPoints;
  LinearStaticAnalysis analysis(mesh, {{0, {e, nu, 0.0}}}, c, options);
  EXPECT_EQ(analysis.prepare(), SolverStatus::Success) << analysis.message();
  const Eigen::VectorXd u = analysis.solve(load);
  double mean = 0.0;
  for (int i : tip)
    mean += u[3 * i + axis];
  return mean / double(tip.size());
}

struct BeamErrors
{
  double degenerate = 0.0, native = 0.0;
};

// Relative tip-deflection errors of the split-brick meshes against @a reference.
BeamErrors wedgeBeamErrors(int nx, int nyz, double nu, int axis, double reference, int gaussPoints = 3)
{
  const double l = 200.0, h = 10.0;
  const Mesh degenerate = boxMesh(nx, nyz, nyz, l, h, h, Eigen::Vector3d::Zero(), true);
  const Mesh native = withNativeWedges(degenerate);
  return {cantileverTip(degenerate, nyz, nyz, l, h, nu, axis, gaussPoints) / reference - 1.0,
          cantileverTip(native, nyz, nyz, l, h, nu, axis, gaussPoints) / reference - 1.0};
}

// L/h = 20, nu = 0: Timoshenko's tip deflection P L^3 / (3 E I) + P L / (k G A),
// k = 5/6, is the reference (a 40 x 4 x 4 brick mesh agrees with it to 0.1 %).
TEST(WedgeComparison, CantileverBendingAgainstBeamTheory)
{
  const double l = 200.0, h = 10.0, e = 1000.0, p = -1.0, inertia = h * h * h * h / 12.0;
  const double timoshenko = p * l * l * l / (3 * e * inertia) + p * l / (5.0 / 6.0 * 0.5 * e * h * h);
  const double fine = cantileverTip(boxMesh(40, 4, 4, l, h, h), 4, 4, l, h, 0.0, 2);
  std::cout << "cantilever L/h = 20, nu = 0: Timoshenko " << timoshenko << " mm, 40x4x4 bricks "
            << 100 * (fine / timoshenko - 1) << " %\n";
  EXPECT_NEAR(fine / timoshenko, 1.0, 1e-3);
  for (int nx : {10, 20})
    for (int axis : {1, 2})
    {
      const BeamErrors err = wedgeBeamErrors(nx, 2, 0.0, axis, timoshenko);
      const BeamErrors lower = wedgeBeamErrors(nx, 2, 0.0, axis, timoshenko, 2);
      const double bricks = cantileverTip(boxMesh(nx, 2, 2, l, h, h), 2, 2, l, h, 0.0, axis) / timoshenko - 1.0;
      std::cout << "cantilever " << nx << "x2x2 bricks split in " << 8 * nx << " wedges, load along "
                << "xyz"[axis] << ": degenerate " << 100 * err.degenerate << " % (2x2x2: " << 100 * lower.degenerate
                << " %), native " << 100 * err.native << " % (9 points: " << 100 * lower.native
                << " %); unsplit bricks " << 100 * bricks << " %\n";
      EXPECT_LT(std::abs(err.native), 0.1 * std::abs(err.degenerate)) << nx << " " << axis;
      EXPECT_LT(std::abs(err.native), nx == 10 ? 2e-3 : 3e-4);
      EXPECT_LT(std::abs(lower.native), nx == 10 ? 2e-3 : 3e-4);
    }
}

// Nearly incompressible tissue: the same clamped cantilever at nu = 0.45 and
// 0.49 against a 40 x 4 x 4 brick mesh with reduced 2x2x2 integration (the
// least locking reference; its 3x3x3 twin is 0.4 % / 0.75 % stiffer). The
// clamp restrains the Poisson contraction, so beam theory is no reference.
TEST(WedgeComparison, NearlyIncompressibleCantileverAgainstFineMesh)
{
  const double l = 200.0, h = 10.0;
  for (double nu : {0.45, 0.49})
  {
    const double fine = cantileverTip(boxMesh(40, 4, 4, l, h, h), 4, 4, l, h, nu, 2, 2);
    const double fineFull = cantileverTip(boxMesh(40, 4, 4, l, h, h), 4, 4, l, h, nu, 2, 3);
    const double bricks = cantileverTip(boxMesh(10, 2, 2, l, h, h), 2, 2, l, h, nu, 2, 3) / fine - 1.0;
    std::cout << "nu = " << nu << ": fine reference (40x4x4, 2x2x2) " << fine << " mm, its 3x3x3 twin "
              << 100 * (fineFull / fine - 1) << " %; unsplit 10x2x2 bricks " << 100 * bricks << " %\n";
    EXPECT_NEAR(fineFull / fine, 1.0, 0.01);
    for (int axis : {1, 2})
      for (int level : {3, 2})
      {
        const BeamErrors err = wedgeBeamErrors(10, 2, nu, axis, fine, level);
        std::cout << "  10x2x2 split, load along "
                  << "xyz"[axis] << ", rule level " << level << ": degenerate " << 100 * err.degenerate << " %, native "
                  << 100 * err.native << " %\n";
        // Measured: native 3.3-4.8 % stiff at 0.45, 5.7-9.5 % at 0.49;
        // degenerate 29-58 %.
        EXPECT_LT(std::abs(err.native), nu < 0.46 ? 0.055 : 0.10) << nu << " " << axis << " " << level;
        EXPECT_LT(std::abs(err.native), 0.25 * std::abs(err.degenerate)) << nu << " " << axis << " " << level;
      }
  }
}

// Bending stress at the nodes (recoverNodalStresses, default 9-point
// extrapolation for wedges) on the top fibre at x = 100 mm of the 10 x 2 x 2
// split cantilever, nu = 0: sigma_xx = P (L - x) c / I.
TEST(WedgeComparison, NodalBendingStressAgainstBeamTheory)
{
  const double l = 200.0, h = 10.0, x0 = 100.0;
  const double expected = (l - x0) * (h / 2) / (h * h * h * h / 12.0);
  const MaterialTable materials{{0, {1000.0, 0.0, 0.0}}};
  const Mesh degenerate = boxMesh(10, 2, 2, l, h, h, Eigen::Vector3d::Zero(), true);
  for (int axis : {1, 2})
  {
    double errors[2] = {0.0, 0.0};
    for (int native : {0, 1})
    {
      const Mesh mesh = native ? withNativeWedges(degenerate) : degenerate;
      Constraints c;
      LoadCase load;
      int tipNodes = 0;
      for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      {
        if (mesh.nodes(0, i) < 1e-9)
          c.fixNode(int(i));
        if (std::abs(mesh.nodes(0, i) - l) < 1e-9)
          ++tipNodes;
      }
      for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
        if (std::abs(mesh.nodes(0, i) - l) < 1e-9)
        {
          Eigen::Vector3d f = Eigen::Vector3d::Zero();
          f[axis] = -1.0 / tipNodes;
          load.nodalForces.push_back({int(i), f});
        }
      LinearStaticAnalysis analysis(mesh, materials, c);
      ASSERT_EQ(analysis.prepare(), SolverStatus::Success) << analysis.message();
      const NodalStressField f = recoverNodalStresses(mesh, materials, analysis.solve(load));
      double worst = 0.0;
      int count = 0;
      for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
        if (std::abs(mesh.nodes(0, i) - x0) < 1e-9 && std::abs(mesh.nodes(axis, i) - h) < 1e-9)
        {
          worst = std::max(worst, std::abs(f.stress(0, i) / expected - 1.0));
          ++count;
        }
      ASSERT_EQ(count, 5);
      errors[native] = worst;
    }
    std::cout << "top-fibre nodal sigma_xx at x = 100, load along "
              << "xyz"[axis] << ": worst error degenerate " << 100 * errors[0] << " %, native " << 100 * errors[1]
              << " %\n";
    EXPECT_LT(errors[1], 0.03);
    EXPECT_LT(errors[1], errors[0]);
  }
}

// ---- Export and import ----

TEST(NativeWedges, VtuCellIsTheQuadraticWedgeOfTheDegenerateElement)
{
  const Mesh degenerate = boxMesh(2, 1, 1, 2, 2, 2, Eigen::Vector3d(-1, -1, -1), true);
  const Mesh native = withNativeWedges(degenerate);
  for (std::size_t e = 0; e < native.elements.size(); ++e)
  {
    const VtkCell cell = vtkCell(native.elements[e], native.nodes);
    EXPECT_EQ(cell.type, kVtkQuadraticWedge);
    EXPECT_EQ(cell.nodes, std::vector<int>(native.elements[e].nodes.begin(), native.elements[e].nodes.begin() + 15));
    EXPECT_EQ(cell.nodes, vtkCell(degenerate.elements[e], degenerate.nodes).nodes);
    // vtkWedge: (0, 1, 2) by the right-hand rule points away from (3, 4, 5).
    auto x = [&](int i) { return Eigen::Vector3d(native.nodes.col(cell.nodes[std::size_t(i)])); };
    EXPECT_LT((x(1) - x(0)).cross(x(2) - x(0)).dot(x(3) - x(0)), 0.0);
  }
  const std::string doc = vtuDocument(native, {});
  EXPECT_NE(doc.find(" 26 26 26 26"), std::string::npos);
}

const char* kC3D15Deck =
  "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n5,1,0,1\n6,0,1,1\n"
  "7,.5,0,0\n8,.5,.5,0\n9,0,.5,0\n10,.5,0,1\n11,.5,.5,1\n12,0,.5,1\n13,0,0,.5\n14,1,0,.5\n15,0,1,.5\n"
  "*ELEMENT, TYPE=C3D15, ELSET=W\n1, 1,2,3,4,5,6,7,8,9,10,\n11,12,13,14,15\n"
  "*MATERIAL, NAME=M\n*ELASTIC\n100, 0.25\n*SOLID SECTION, ELSET=W, MATERIAL=M\n"
  "*BOUNDARY\n1,1,3\n2,1,3\n3,1,3\n7,1,3\n8,1,3\n9,1,3\n*STEP\n*STATIC\n*CLOAD\n4,3,1.0\n*END STEP\n";

TEST(NativeWedges, ReaderKeepsC3D15NativeOrDegenerateByOption)
{
  const CalculixModel native = parseCalculixInput(kC3D15Deck, "deck.inp"); // the default
  CalculixReadOptions options;
  options.nativeWedges = false;
  const CalculixModel degenerate = parseCalculixInput(kC3D15Deck, "deck.inp", options);
  ASSERT_EQ(native.mesh.elements.size(), 1u);
  const Element& el = native.mesh.elements[0];
  EXPECT_EQ(el.kind, ElementKind::Wedge15);
  EXPECT_EQ(degenerate.mesh.elements[0].kind, ElementKind::Hex20);
  // Each node sits at its natural coordinates (the deck's triangle (0,0)-(1,0)-(0,1), z = (t + 1) / 2).
  for (int k = 0; k < kWedge15NodeCount; ++k)
  {
    const Eigen::Vector3d n = wedge15NaturalCoordinates(k);
    EXPECT_LT((native.mesh.nodes.col(el.nodes[std::size_t(k)]) - Eigen::Vector3d(n[0], n[1], 0.5 * (n[2] + 1))).norm(),
              1e-15)
      << k;
  }
  for (int k = kWedge15NodeCount; k < kHex20NodeCount; ++k)
    EXPECT_EQ(el.nodes[std::size_t(k)], -1);
  // The degenerate import converts to the same element (numbered from
  // another corner: a wedge has six right-handed numberings), so the same
  // displacements.
  Mesh converted = withNativeWedges(degenerate.mesh);
  ASSERT_EQ(converted.elements[0].kind, ElementKind::Wedge15);
  // The deck's native C3D15 carries ccx's 9-point rule; the converted one the analysis's: compare like with like.
  EXPECT_EQ(el.integrationPoints, 2);
  converted.elements[0].integrationPoints = el.integrationPoints;
  EXPECT_EQ(std::set<int>(converted.elements[0].nodes.begin(), converted.elements[0].nodes.end()),
            std::set<int>(el.nodes.begin(), el.nodes.end()));
  LinearStaticAnalysis a(native.mesh, native.materials, native.constraints);
  LinearStaticAnalysis b(converted, native.materials, native.constraints);
  ASSERT_EQ(a.prepare(), SolverStatus::Success) << a.message();
  ASSERT_EQ(b.prepare(), SolverStatus::Success) << b.message();
  const Eigen::VectorXd u = a.solve(native.load);
  EXPECT_GT(u[3 * 3 + 2], 0.0);
  EXPECT_LT((b.solve(native.load) - u).norm(), 1e-12 * u.norm());
}

TEST(NativeWedges, ExportIsC3D15AndReadsBackIdentically)
{
  Mesh mesh = withNativeWedges(boxMesh(2, 1, 2, 20, 10, 10, Eigen::Vector3d::Zero(), true));
  test::appendMesh(mesh, boxMesh(1, 1, 1, 10, 10, 10, Eigen::Vector3d(0, 0, 20)));
  const MaterialTable materials{{0, {1.0, 0.3, 1e-9}}};
  Constraints c;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    if (mesh.nodes(2, i) < 1e-9)
      c.fixNode(int(i));
  LoadCase load;
  load.gravity = Eigen::Vector3d(0, 0, -9810);
  const std::string deck = calculixInput(mesh, materials, c, load);
  EXPECT_NE(deck.find("*ELEMENT, TYPE=C3D15"), std::string::npos);
  EXPECT_NE(deck.find("*ELEMENT, TYPE=C3D20"), std::string::npos);
  // C3D15 node 1 is wedge node 3 (r = s = 0, t = -1).
  const Element& w = mesh.elements[0];
  EXPECT_NE(deck.find("\n1, " + std::to_string(w.nodes[3] + 1) + ", " + std::to_string(w.nodes[4] + 1) + ", " +
                      std::to_string(w.nodes[5] + 1) + ", " + std::to_string(w.nodes[0] + 1) + ","),
            std::string::npos)
    << deck;
  CalculixReadOptions options;
  options.nativeWedges = true;
  const CalculixModel m = parseCalculixInput(deck, "export.inp", options);
  ASSERT_EQ(m.mesh.elements.size(), mesh.elements.size());
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    EXPECT_EQ(m.mesh.elements[e].kind, mesh.elements[e].kind);
    EXPECT_EQ(m.mesh.elements[e].nodes, mesh.elements[e].nodes);
  }
}

// ---- CalculiX ----

// Displacements ccx computes for the exported deck (.dat, 7 digits).
Eigen::VectorXd ccxDisplacements(const std::string& name, const Mesh& mesh, const MaterialTable& materials,
                                 const Constraints& c, const LoadCase& load)
{
  const Eigen::Matrix3Xd u = test::runCcx(name, calculixInput(mesh, materials, c, load), mesh.nodeCount()).dat;
  return Eigen::Map<const Eigen::VectorXd>(u.data(), u.size());
}

// Ours with @a level against ccx; returns max |difference| / max |u|.
double differenceFromCcx(const std::string& name, const Mesh& mesh, const MaterialTable& materials,
                         const Constraints& c, const LoadCase& load, int level = 2)
{
  AssemblyOptions options;
  options.gaussPointsPerDirection = level;
  LinearStaticAnalysis analysis(mesh, materials, c, options);
  EXPECT_EQ(analysis.prepare(), SolverStatus::Success) << analysis.message();
  const Eigen::VectorXd u = analysis.solve(load);
  const Eigen::VectorXd v = ccxDisplacements(name, mesh, materials, c, load);
  return (u - v).cwiseAbs().maxCoeff() / u.cwiseAbs().maxCoeff();
}

// ccx integrates C3D15 with the 9 points of wedgeRule(2): the same element
// must give the same displacements (the .dat has 7 significant digits).
TEST(WedgeCalculix, DistortedNativeWedgesUnderGravityAndLoadsAgreeWithC3D15)
{
  ASSERT_TRUE(test::ccxAvailable()) << "CalculiX 'ccx' was not found on PATH (Debian package calculix-ccx)";
  Mesh mesh = withNativeWedges(boxMesh(3, 2, 2, 30, 20, 10, Eigen::Vector3d::Zero(), true));
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = wobble(mesh.nodes.col(i));
  Constraints c;
  LoadCase load;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    if (mesh.nodes(2, i) < 0.5 && mesh.nodes(0, i) < 15.0)
      c.fixNode(int(i));
    if (mesh.nodes(0, i) > 29.0)
      load.nodalForces.push_back({int(i), Eigen::Vector3d(0.001, -0.002, 0.003)});
  }
  c.prescribe(int(mesh.nodeCount()) - 1, 1, 0.05);
  load.gravity = Eigen::Vector3d(1000.0, -2000.0, -9810.0);
  const MaterialTable materials{{0, {0.05, 0.45, 1.05e-9}}};
  const double lower = differenceFromCcx("gravity", mesh, materials, c, load, 2);
  const double full = differenceFromCcx("gravity18", mesh, materials, c, load, 3);
  std::cout << "native wedges vs ccx C3D15: relative difference " << lower << " (9-point rule, ccx's), " << full
            << " (18-point rule)\n";
  EXPECT_LT(lower, 1e-6);
}

// Sutures whose dependent nodes belong to native wedges: ccx 2.20 mishandles
// *EQUATION on nodes repeated in a degenerate C3D20 (CalculixIO.h); a C3D15
// repeats no node, so the equations must hold as written.
TEST(WedgeCalculix, SuturedNativeWedgeBlocksAgreeWithC3D15)
{
  ASSERT_TRUE(test::ccxAvailable()) << "CalculiX 'ccx' was not found on PATH (Debian package calculix-ccx)";
  Mesh mesh = withNativeWedges(boxMesh(2, 2, 1, 20, 20, 10, Eigen::Vector3d::Zero(), true));
  const int top =
    test::appendMesh(mesh, withNativeWedges(boxMesh(2, 2, 1, 20, 20, 5, Eigen::Vector3d(0.5, 1.0, 10.7), true)));
  for (std::size_t e = mesh.elements.size() / 2; e < mesh.elements.size(); ++e)
    mesh.elements[e].region = 2;
  Constraints c;
  int sutures = 0;
  for (int i = 0; i < top; ++i)
  {
    if (mesh.nodes(2, i) < 1e-9)
      c.fixNode(i);
    if (std::abs(mesh.nodes(2, i) - 10.0) > 1e-9)
      continue;
    for (int j = top; j < int(mesh.nodeCount()); ++j)
      if ((mesh.nodes.col(j) - mesh.nodes.col(i) - Eigen::Vector3d(0.5, 1.0, 0.7)).norm() < 1e-9)
      {
        c.suture(j, i); // the upper block's node depends on the lower one's
        ++sutures;
      }
  }
  ASSERT_EQ(sutures, 25); // the 5 x 5 doubled grid of the interface (cell centres: diagonal mid-edges)
  LoadCase load;
  load.gravity = Eigen::Vector3d(0, -9810.0, -9810.0);
  load.nodalForces.push_back({top + 2, Eigen::Vector3d(0.0, 0.0, 0.001)});
  const MaterialTable materials{{0, {0.02, 0.3, 1e-9}}, {2, {0.1, 0.48, 1.1e-9}}};
  const double diff = differenceFromCcx("sutures", mesh, materials, c, load);
  std::cout << "sutured native wedge blocks vs ccx C3D15: relative difference " << diff << "\n";
  EXPECT_LT(diff, 1e-6);
}

// The split-brick cantilever through ccx: its own C3D20 collapsed into
// wedges is as stiff as ours, its C3D15 as accurate, so the gap is the
// element's, not our implementation's.
TEST(WedgeCalculix, CantileverDegenerateAndNativeWedgesInCcx)
{
  ASSERT_TRUE(test::ccxAvailable()) << "CalculiX 'ccx' was not found on PATH (Debian package calculix-ccx)";
  const double l = 200.0, h = 10.0, e = 1000.0, inertia = h * h * h * h / 12.0;
  const double timoshenko = -l * l * l / (3 * e * inertia) - l / (5.0 / 6.0 * 0.5 * e * h * h);
  const Mesh degenerate = boxMesh(10, 2, 2, l, h, h, Eigen::Vector3d::Zero(), true);
  for (const Mesh& mesh : {degenerate, withNativeWedges(degenerate)})
  {
    Constraints c;
    LoadCase load;
    std::vector<int> tip;
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    {
      if (mesh.nodes(0, i) < 1e-9)
        c.fixNode(int(i));
      if (std::abs(mesh.nodes(0, i) - l) < 1e-9)
        tip.push_back(int(i));
    }
    // Tip load on the neutral-axis nodes (only the mean tip deflection is compared).
    int axisNodes = 0;
    for (int i : tip)
      axisNodes += std::abs(mesh.nodes(2, i) - 5.0) < 1e-9;
    for (int i : tip)
      if (std::abs(mesh.nodes(2, i) - 5.0) < 1e-9)
        load.nodalForces.push_back({i, Eigen::Vector3d(0, 0, -1.0 / axisNodes)});
    const Eigen::VectorXd v = ccxDisplacements("cantilever", mesh, {{0, {e, 0.0, 0.0}}}, c, load);
    double mean = 0.0;
    for (int i : tip)
      mean += v[3 * i + 2];
    mean /= double(tip.size());
    const bool native = mesh.elements[0].kind == ElementKind::Wedge15;
    std::cout << "ccx cantilever 10x2x2 split, " << (native ? "C3D15" : "degenerate C3D20") << ": "
              << 100 * (mean / timoshenko - 1) << " % vs Timoshenko\n";
    if (native)
      EXPECT_NEAR(mean / timoshenko, 1.0, 0.01);
    else
      EXPECT_LT(mean / timoshenko, 0.7);
  }
}

} // namespace
} // namespace caps::fem
