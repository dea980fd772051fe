// The large-deformation solver (NonlinearStaticAnalysis) against CalculiX:
// the same exported deck (calculixInput with *STEP, NLGEOM, the law as
// *HYPERELASTIC or *ELASTIC, tight *CONTROLS) solved by ccx and by us, the
// same integration rule, both converged tightly. Hyperelastic end states do
// not depend on the load path (no instability on the way), so the two
// solvers' increments need not match; the end displacements must agree to
// 1e-5 of the largest (ccx's .dat holds 7 significant digits). A missing
// ccx FAILS these tests (CcxRunner.h).

#include "fem/CalculixIO.h"
#include "fem/HyperelasticMaterial.h"
#include "fem/NonlinearStaticAnalysis.h"
#include "fem/StaticAnalysis.h"

#include "CcxRunner.h"
#include "FemTestMeshes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <iostream>
#include <string>
#include <tuple>
#include <vector>

namespace caps::fem {
namespace {

using test::boxMesh;

constexpr double kAgreement = 1e-5; // max |ccx - ours| / max |ours|

void requireCcx()
{
  ASSERT_TRUE(test::ccxAvailable()) << "CalculiX 'ccx' was not found on PATH: install Debian package calculix-ccx";
}

double secondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// One model solved by both: the mesh (one region 0), its law, constraints,
/// load, the rule of its elements and the increments both solvers start with.
struct Model
{
  std::string name;
  Mesh mesh;
  HyperelasticMaterial material;
  Constraints constraints;
  LoadCase load;
  int integrationPoints = 3; ///< 3: C3D20, 2: C3D20R (native wedges are C3D15, 9 points, set per element)
  double initialIncrement = 0.1;
  double maximumIncrement = 0.25;
};

struct Comparison
{
  double relativeDifference = 0.0;
  double maxDisplacement = 0.0; ///< largest |u| component of ours, mm
  /// ccx against the small-strain solve of the same model: how far from
  /// linear the case is, i.e. what the agreement above resolves.
  double linearDifference = 0.0;
  Eigen::VectorXd ours;
  Eigen::Matrix3Xd ccx;
};

/// Exports @a m, runs ccx and our solver on it, prints and returns the difference.
Comparison compare(const Model& m)
{
  Comparison out;
  const MaterialTable linear{{0, m.material.smallStrainLimit()}};
  CalculixExportOptions options;
  options.defaultIntegrationPoints = m.integrationPoints;
  options.step.nlgeom = true;
  options.step.initialIncrement = m.initialIncrement;
  options.step.maximumIncrement = m.maximumIncrement;
  options.hyperelastic[0] = m.material;
  options.tightControls = true;
  const std::string deck = calculixInput(m.mesh, linear, m.constraints, m.load, options);
  EXPECT_NE(deck.find("*STEP, NLGEOM"), std::string::npos) << m.name;

  auto start = std::chrono::steady_clock::now();
  NonlinearStaticAnalysis analysis(m.mesh, {{0, m.material}}, m.constraints, AssemblyOptions{2, m.integrationPoints});
  IncrementControl control;
  control.initial = m.initialIncrement;
  control.maximum = m.maximumIncrement;
  NewtonOptions newton;
  newton.residualTolerance = 1e-10;
  const NonlinearResult r = analysis.solve(m.load, control, newton);
  const double oursSeconds = secondsSince(start);
  EXPECT_EQ(r.status, NonlinearStatus::Converged) << m.name << ": " << r.message;
  out.ours = r.displacements;

  start = std::chrono::steady_clock::now();
  out.ccx = test::runCcx(m.name, deck, m.mesh.nodeCount()).dat; // throws if ccx did not finish
  const double ccxSeconds = secondsSince(start);

  out.relativeDifference = test::relativeDifference(out.ccx, out.ours);

  // Full Newton (a tangent per iteration) reaches the same state as the
  // modified Newton above, which keeps factorizations while they contract.
  NewtonOptions full = newton;
  full.tangentUpdate = TangentUpdate::EveryIteration;
  const NonlinearResult f = analysis.solve(m.load, control, full);
  EXPECT_EQ(f.status, NonlinearStatus::Converged) << m.name << ": " << f.message;
  const double newtonDifference =
    (f.displacements - r.displacements).cwiseAbs().maxCoeff() / r.displacements.cwiseAbs().maxCoeff();
  EXPECT_LT(newtonDifference, 1e-7) << m.name << ": full and modified Newton disagree";
  // The states on the way converged only to 1e-3 of the forces: the same
  // end state (the path leaves no trace in a hyperelastic body), in fewer
  // iterations.
  NewtonOptions loosePath = newton;
  loosePath.pathResidualTolerance = 1e-3;
  const NonlinearResult p = analysis.solve(m.load, control, loosePath);
  EXPECT_EQ(p.status, NonlinearStatus::Converged) << m.name << ": " << p.message;
  const double pathDifference =
    (p.displacements - r.displacements).cwiseAbs().maxCoeff() / r.displacements.cwiseAbs().maxCoeff();
  EXPECT_LT(pathDifference, 1e-7) << m.name << ": a loose path changed the end state";
  EXPECT_LT(test::relativeDifference(out.ccx, p.displacements), kAgreement) << m.name << ": the loose path against ccx";
  EXPECT_LE(p.iterations.size(), r.iterations.size()) << m.name;
  std::cout << m.name << ": modified Newton " << r.iterations.size() << " iterations, " << r.factorizations
            << " factorizations; full Newton " << f.iterations.size() << " iterations; difference " << newtonDifference
            << "; loose path " << p.iterations.size() << " iterations, " << p.factorizations
            << " factorizations, difference " << pathDifference << "\n";
  LinearStaticAnalysis small(m.mesh, linear, m.constraints, AssemblyOptions{2, m.integrationPoints});
  EXPECT_EQ(small.prepare(), SolverStatus::Success) << m.name << ": " << small.message();
  out.linearDifference = test::relativeDifference(out.ccx, small.solve(m.load));
  out.maxDisplacement = out.ours.cwiseAbs().maxCoeff();
  int accepted = 0;
  for (const IncrementRecord& inc : r.increments)
    accepted += inc.accepted;
  std::cout << m.name << ": max |u| " << out.maxDisplacement << " mm, relative difference to ccx "
            << out.relativeDifference << ", small-strain solve to ccx " << out.linearDifference << " (ours " << accepted
            << " increments, " << r.iterations.size() << " iterations, " << oursSeconds << " s; ccx " << ccxSeconds
            << " s; min det F " << r.check.minDetF << ", stretches " << r.check.minStretch << " .. "
            << r.check.maxStretch << ")\n";
  EXPECT_GT(out.linearDifference, 100.0 * kAgreement) << m.name << ": too close to linear to test the nonlinear path";
  return out;
}

bool near(double a, double b)
{
  return std::abs(a - b) < 1e-9;
}

/// Nodes with coordinate @a axis equal to @a value.
std::vector<int> nodesOn(const Mesh& mesh, int axis, double value)
{
  std::vector<int> nodes;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    if (near(mesh.nodes(axis, i), value))
      nodes.push_back(int(i));
  return nodes;
}

/// Node nearest to @a x.
int nodeNearest(const Mesh& mesh, const Eigen::Vector3d& x)
{
  Eigen::Index best = 0;
  (mesh.nodes.colwise() - x).colwise().squaredNorm().minCoeff(&best);
  return int(best);
}

/// The cantilever: @a length x 5 x 5 mm, x = 0 clamped, @a tipForce spread
/// evenly over the nodes of the end face x = @a length (a dead load in ccx
/// as in ours).
Model cantilever(const std::string& name, Mesh mesh, double length, const HyperelasticMaterial& material,
                 const Eigen::Vector3d& tipForce)
{
  Model m;
  m.name = name;
  m.material = material;
  for (int i : nodesOn(mesh, 0, 0.0))
    m.constraints.fixNode(i);
  const std::vector<int> tip = nodesOn(mesh, 0, length);
  for (int i : tip)
    m.load.nodalForces.push_back({i, tipForce / double(tip.size())});
  m.mesh = std::move(mesh);
  return m;
}

/// Tip deflection of the cantilever's end-face centre (|u|, mm).
double tipMotion(const Model& m, const Eigen::VectorXd& u, double length)
{
  const int tip = nodeNearest(m.mesh, Eigen::Vector3d(length, 2.5, 2.5));
  return u.segment<3>(3 * tip).norm();
}

// 1. Neo-Hookean block 20 x 10 x 10 mm, x = 0 clamped, x = 20 clamped to a
//    rigid plate moved 10 mm along x (50 %) and 4 mm along y (shear): the
//    free sides neck unevenly.
TEST(NonlinearCalculix, NeoHookeanBlockStretchedHalfAndShearedMatchesCcx)
{
  requireCcx();
  Model m;
  m.name = "neo-Hookean block, 50 % stretch + shear";
  m.mesh = boxMesh(4, 2, 2, 20, 10, 10);
  m.material = HyperelasticMaterial::neoHookean(0.5, 0.04);
  for (int i : nodesOn(m.mesh, 0, 0.0))
    m.constraints.fixNode(i);
  for (int i : nodesOn(m.mesh, 0, 20.0))
  {
    m.constraints.prescribe(i, 0, 10.0);
    m.constraints.prescribe(i, 1, 4.0);
    m.constraints.fix(i, 2);
  }
  const Comparison c = compare(m);
  EXPECT_NEAR(c.maxDisplacement, 10.0, 1e-12);
  EXPECT_LT(c.relativeDifference, kAgreement);
}

// 2. Neo-Hookean C3D20 cantilever 40 x 5 x 5 mm (8 x 1 x 1) bent by a dead
//    tip load until the tip has moved about 40 % of its length.
TEST(NonlinearCalculix, NeoHookeanCantileverAtLargeRotationMatchesCcx)
{
  requireCcx();
  Model m = cantilever("neo-Hookean cantilever C3D20", boxMesh(8, 1, 1, 40, 5, 5), 40.0,
                       HyperelasticMaterial::neoHookean(0.5, 0.1), Eigen::Vector3d(0, 0, -0.15));
  m.initialIncrement = 0.05;
  m.maximumIncrement = 0.1;
  const Comparison c = compare(m);
  const double tip = tipMotion(m, c.ours, 40.0);
  std::cout << "  tip moved " << tip << " mm (" << 100.0 * tip / 40.0 << " % of the length)\n";
  EXPECT_GT(tip, 0.3 * 40.0);
  EXPECT_LT(c.relativeDifference, kAgreement);
}

/// Merges coincident nodes for which @a merge holds (the later one onto the
/// earlier) and drops the nodes no element uses any more, renumbering.
Mesh mergeNodes(const Mesh& mesh, const std::function<bool(const Eigen::Vector3d&)>& merge)
{
  const Eigen::Index n = mesh.nodeCount();
  std::vector<int> target(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i)
  {
    target[std::size_t(i)] = int(i);
    if (!merge(mesh.nodes.col(i)))
      continue;
    for (Eigen::Index j = 0; j < i; ++j)
      if ((mesh.nodes.col(j) - mesh.nodes.col(i)).norm() < 1e-9)
      {
        target[std::size_t(i)] = int(j);
        break;
      }
  }
  std::vector<int> number(static_cast<std::size_t>(n), -1);
  int count = 0;
  for (Eigen::Index i = 0; i < n; ++i)
    if (target[std::size_t(i)] == int(i))
      number[std::size_t(i)] = count++;
  Mesh out;
  out.nodes.resize(3, count);
  for (Eigen::Index i = 0; i < n; ++i)
    if (number[std::size_t(i)] >= 0)
      out.nodes.col(number[std::size_t(i)]) = mesh.nodes.col(i);
  for (Element el : mesh.elements)
  {
    for (int& node : el.nodes)
      if (node >= 0)
        node = number[std::size_t(target[std::size_t(node)])];
    out.elements.push_back(el);
  }
  return out;
}

// 3. A slab 20 x 10 x 4 mm with a V-shaped slit from the edge y = 10 down to
//    y = 5 along x = 10 (3 mm wide at the edge), its two faces pulled
//    together by sutures (each node of the left face onto its partner on the
//    right face: *EQUATION with the auxiliary node, whose prescribed 1 ccx
//    ramps over the step as we ramp the gap); the ends x = 0, 20 clamped.
TEST(NonlinearCalculix, NeoHookeanSlitClosedBySuturesMatchesCcx)
{
  requireCcx();
  const double half = 1.5; // half the slit's width at y = 10
  Mesh mesh = boxMesh(2, 2, 1, 10, 10, 4);
  const int leftNodes = int(mesh.nodeCount());
  test::appendMesh(mesh, boxMesh(2, 2, 1, 10, 10, 4, Eigen::Vector3d(10, 0, 0)));
  // Joined along x = 10 below the slit (y <= 5); the slit's faces stay apart.
  // Only right-half nodes merge, so nodes 0 .. leftNodes-1 stay the left half.
  mesh = mergeNodes(mesh, [](const Eigen::Vector3d& x) { return near(x[0], 10.0) && x[1] < 5.0 + 1e-9; });
  Model m;
  m.name = "neo-Hookean slit closed by sutures";
  m.material = HyperelasticMaterial::neoHookean(0.5, 0.1);
  int sutures = 0;
  for (int i = 0; i < leftNodes; ++i)
  {
    if (!near(mesh.nodes(0, i), 10.0) || mesh.nodes(1, i) < 5.0 + 1e-9)
      continue;
    for (Eigen::Index j = leftNodes; j < mesh.nodeCount(); ++j)
      if ((mesh.nodes.col(j) - mesh.nodes.col(i)).norm() < 1e-9)
      {
        m.constraints.suture(i, int(j));
        ++sutures;
      }
  }
  ASSERT_EQ(sutures, 5); // y = 7.5 (z = 0, 4) and y = 10 (z = 0, 2, 4)
  // Open the slit: bilinear in each half, zero on x = 0, 20 and for y <= 5.
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    auto x = mesh.nodes.col(i);
    if (x[1] <= 5.0)
      continue;
    const double opening = half * (x[1] - 5.0) / 5.0;
    x[0] += i < leftNodes ? -opening * x[0] / 10.0 : opening * (20.0 - x[0]) / 10.0;
  }
  for (int i : nodesOn(mesh, 0, 0.0))
    m.constraints.fixNode(i);
  for (int i : nodesOn(mesh, 0, 20.0))
    m.constraints.fixNode(i);
  m.mesh = mesh;
  const Comparison c = compare(m);
  // Closed: each sutured pair ends at one place.
  for (const Suture& s : m.constraints.sutures)
  {
    const Eigen::Vector3d a = m.mesh.nodes.col(s.node) + c.ours.segment<3>(3 * s.node);
    const Eigen::Vector3d b = m.mesh.nodes.col(s.target) + c.ours.segment<3>(3 * s.target);
    EXPECT_LT((a - b).norm(), 1e-9);
  }
  EXPECT_LT(c.relativeDifference, kAgreement);
}

// 4. The cantilever of 4a native 15-node wedges (C3D15, ccx's 9 points) and
//    4b degenerate 20-node wedges (C3D20, 3x3x3): each hex cell split along
//    a diagonal of its xy face. Only *BOUNDARY and *CLOAD, no *EQUATION (ccx
//    2.20 mis-assembles equations on nodes a degenerate C3D20 repeats).
TEST(NonlinearCalculix, NeoHookeanWedgeCantileversMatchCcx)
{
  requireCcx();
  const Mesh degenerate = boxMesh(8, 1, 1, 40, 5, 5, Eigen::Vector3d::Zero(), true);
  Mesh native = withNativeWedges(degenerate);
  for (Element& el : native.elements)
  {
    ASSERT_EQ(el.kind, ElementKind::Wedge15);
    el.integrationPoints = 2; // ccx's C3D15 rule
  }
  const HyperelasticMaterial material = HyperelasticMaterial::neoHookean(0.5, 0.1);
  const Eigen::Vector3d force(0, 0, -0.15);
  for (auto [name, mesh, points] :
       {std::tuple<const char*, Mesh, int>{"neo-Hookean cantilever C3D15", native, 2},
        std::tuple<const char*, Mesh, int>{"neo-Hookean cantilever degenerate C3D20", degenerate, 3}})
  {
    Model m = cantilever(name, mesh, 40.0, material, force);
    m.integrationPoints = points;
    m.initialIncrement = 0.05;
    m.maximumIncrement = 0.1;
    const Comparison c = compare(m);
    const double tip = tipMotion(m, c.ours, 40.0);
    std::cout << "  tip moved " << tip << " mm (" << 100.0 * tip / 40.0 << " % of the length)\n";
    EXPECT_GT(tip, 0.2 * 40.0) << name;
    EXPECT_LT(c.relativeDifference, kAgreement) << name;
  }
}

// 5. Mooney-Rivlin (C10 and C01 both non-zero) block 10 x 10 x 10 mm of
//    C3D20R (2x2x2), z = 0 clamped, z = 10 clamped to a plate pushed down
//    3 mm (30 % compression) and 2 mm along x (shear).
TEST(NonlinearCalculix, MooneyRivlinBlockCompressedAndShearedMatchesCcx)
{
  requireCcx();
  Model m;
  m.name = "Mooney-Rivlin block C3D20R, 30 % compression + shear";
  m.mesh = boxMesh(2, 2, 2, 10, 10, 10);
  m.integrationPoints = 2;
  m.material = HyperelasticMaterial::mooneyRivlin(0.3, 0.1, 0.1);
  for (int i : nodesOn(m.mesh, 2, 0.0))
    m.constraints.fixNode(i);
  for (int i : nodesOn(m.mesh, 2, 10.0))
  {
    m.constraints.prescribe(i, 0, 2.0);
    m.constraints.fix(i, 1);
    m.constraints.prescribe(i, 2, -3.0);
  }
  const Comparison c = compare(m);
  EXPECT_NEAR(c.maxDisplacement, 3.0, 1e-12);
  EXPECT_LT(c.relativeDifference, kAgreement);
}

// 6. St. Venant-Kirchhoff (*ELASTIC under NLGEOM) on the C3D20 cantilever at
//    moderate rotation (tip about 15 % of the length).
TEST(NonlinearCalculix, StVenantKirchhoffCantileverMatchesCcx)
{
  requireCcx();
  Model m = cantilever("St. Venant-Kirchhoff cantilever C3D20", boxMesh(8, 1, 1, 40, 5, 5), 40.0,
                       HyperelasticMaterial::stVenantKirchhoff(3.0, 0.3), Eigen::Vector3d(0, 0, -0.045));
  const Comparison c = compare(m);
  const double tip = tipMotion(m, c.ours, 40.0);
  std::cout << "  tip moved " << tip << " mm (" << 100.0 * tip / 40.0 << " % of the length)\n";
  EXPECT_GT(tip, 0.1 * 40.0);
  EXPECT_LT(c.relativeDifference, kAgreement);
}

} // namespace
} // namespace caps::fem
