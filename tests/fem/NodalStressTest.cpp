// Nodal stresses extrapolated from Gauss points: exact for constant and
// linear (pure bending) stress fields.

#include "FemTestMeshes.h"
#include "fem/Constraints.h"
#include "fem/ElementGeometry.h"
#include "fem/ElementNumbering.h"
#include "fem/NodalStress.h"
#include "fem/StaticAnalysis.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

using namespace caps::fem;
using caps::fem::test::boxMesh;

namespace {

Eigen::VectorXd displacementField(const Mesh& mesh, const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& f)
{
  Eigen::VectorXd u(mesh.dofCount());
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    u.segment<3>(3 * i) = f(mesh.nodes.col(i));
  return u;
}

} // namespace

TEST(NodalStress, ExtrapolationRowsArePartitionsOfUnity)
{
  for (int n : {2, 3})
  {
    const Eigen::MatrixXd e = gaussToNodeExtrapolation(n);
    ASSERT_EQ(e.rows(), 20);
    ASSERT_EQ(e.cols(), n * n * n);
    EXPECT_LT((e.rowwise().sum() - Eigen::VectorXd::Ones(20)).cwiseAbs().maxCoeff(), 1e-13);
  }
  // 2x2x2: the corner weight of the nearest point is (1 + sqrt 3)^3 / 8.
  const Eigen::MatrixXd e2 = gaussToNodeExtrapolation(2);
  EXPECT_NEAR(e2.row(0).maxCoeff(), std::pow(1 + std::sqrt(3.0), 3) / 8, 1e-12);
  EXPECT_THROW(gaussToNodeExtrapolation(4), std::invalid_argument);
}

TEST(NodalStress, ConstantStressPatchIsExactOnDistortedHexesAndWedges)
{
  const Eigen::Matrix3d a = (Eigen::Matrix3d() << 1e-3, 2e-4, -3e-4, 5e-4, -2e-3, 1e-4, 0, 7e-4, 4e-4).finished();
  for (bool wedges : {false, true})
  {
    Mesh mesh = boxMesh(3, 2, 2, 30, 20, 10, Eigen::Vector3d::Zero(), wedges);
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      mesh.nodes.col(i) = caps::fem::test::wobble(mesh.nodes.col(i), 0.3);
    const MaterialTable materials{{0, {1000.0, 0.3, 0.0}}};
    const Eigen::VectorXd u = displacementField(mesh, [&](const Eigen::Vector3d& x) { return Eigen::Vector3d(a * x); });
    Vector6d strain;
    strain << a(0, 0), a(1, 1), a(2, 2), a(0, 1) + a(1, 0), a(1, 2) + a(2, 1), a(2, 0) + a(0, 2);
    const Vector6d exact = materials.at(0).elasticityMatrix() * strain;
    for (int n : {2, 3})
    {
      const NodalStressField f = recoverNodalStresses(mesh, materials, u, n);
      double worst = 0.0;
      for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
        worst = std::max(worst, (f.stress.col(i) - exact).cwiseAbs().maxCoeff());
      EXPECT_LT(worst / exact.cwiseAbs().maxCoeff(), 1e-10) << (wedges ? "wedges" : "hexes") << ", " << n << " points";
      EXPECT_NEAR(f.vonMises()[0], vonMisesStress(exact), 1e-9 * vonMisesStress(exact));
    }
  }
}

// Pure bending of a 40 x 6 x 10 beam: the exact elasticity solution
// u = (k x z, -nu k y z, -k/2 (x^2 + nu (z^2 - y^2))) has sigma_xx = E k z and
// all other stresses zero. It is quadratic, so the 20-node elements carry it
// exactly, the Gauss stresses are exact, and the extrapolation (exact for
// linear fields) must reproduce sigma_xx = E k z at every node to rounding.
TEST(NodalStress, PureBendingIsReproducedAtNodes)
{
  const double k = 1e-4, nu = 0.3, e = 2000.0;
  for (bool sheared : {false, true})
  {
    Mesh mesh = boxMesh(4, 1, 2, 40, 6, 10, Eigen::Vector3d(0, -3, -5));
    if (sheared) // an affine distortion keeps the field exact in the elements
      for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
        mesh.nodes(0, i) += 0.4 * mesh.nodes(2, i) + 0.2 * mesh.nodes(1, i);
    const MaterialTable materials{{0, {e, nu, 0.0}}};
    const Eigen::VectorXd u = displacementField(mesh, [&](const Eigen::Vector3d& x) {
      return Eigen::Vector3d(k * x[0] * x[2], -nu * k * x[1] * x[2],
                             -0.5 * k * (x[0] * x[0] + nu * (x[2] * x[2] - x[1] * x[1])));
    });
    const double peak = e * k * 5.0;
    for (int n : {2, 3})
    {
      const NodalStressField f = recoverNodalStresses(mesh, materials, u, n);
      double worst = 0.0;
      for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      {
        Vector6d exact = Vector6d::Zero();
        exact[0] = e * k * mesh.nodes(2, i);
        worst = std::max(worst, (f.stress.col(i) - exact).cwiseAbs().maxCoeff());
      }
      std::cout << "pure bending, " << (sheared ? "sheared" : "regular") << " mesh, " << n
                << " points: worst nodal stress error / peak " << worst / peak << "\n";
      EXPECT_LT(worst / peak, 1e-9);
    }
  }
}

TEST(NodalStress, PrincipalStressesAndVonMises)
{
  Vector6d s;
  s << 10, 0, 0, 0, 0, 0;
  EXPECT_NEAR(vonMisesStress(s), 10.0, 1e-12);
  s << 0, 0, 0, 5, 0, 0; // pure shear: principal +5, 0, -5; von Mises 5 sqrt 3
  const Eigen::Vector3d p = principalStresses(s);
  EXPECT_NEAR(p[0], 5.0, 1e-12);
  EXPECT_NEAR(p[1], 0.0, 1e-12);
  EXPECT_NEAR(p[2], -5.0, 1e-12);
  EXPECT_NEAR(vonMisesStress(s), 5.0 * std::sqrt(3.0), 1e-12);
  s << 1, 2, 3, 0.5, -0.7, 0.2; // trace and invariants survive
  const Eigen::Vector3d q = principalStresses(s);
  EXPECT_NEAR(q.sum(), 6.0, 1e-12);
  EXPECT_GE(q[0], q[1]);
  EXPECT_GE(q[1], q[2]);
}

// A 40 x 8 x 6 bar of two materials side by side (y < 4: E = 0.15 MPa, the
// skin; y > 4: E = 0.01 MPa, the fat; the same nu = 0.45), its ends pulled
// apart by 1 % with lateral contraction free. Closed form: u = (e x,
// -nu e y, -nu e z) in both halves (continuous at y = 4, traction-free there
// and on the sides), so sigma_xx = E_i e in region i and every other stress
// zero. The nodes of the interface y = 4 carry both values, one per region;
// the old mean over all elements gave (E_0 + E_1) e / 2 at them.
TEST(NodalStress, ABarOfTwoMaterialsSideBySideKeepsEachRegionsStressAtTheInterface)
{
  const double length = 40, width = 8, height = 6, strain = 0.01, nu = 0.45;
  const double stiff = 0.15, soft = 0.01;
  for (bool wedges : {false, true})
  {
    Mesh mesh = boxMesh(4, 2, 1, length, width, height, Eigen::Vector3d::Zero(), wedges);
    for (Element& el : mesh.elements)
    {
      double y = 0; // the element's centroid side
      int count = 0;
      for (int n : el.nodes)
        if (n >= 0)
        {
          y += mesh.nodes(1, n);
          ++count;
        }
      el.region = y / count < width / 2 ? 0 : 1;
    }
    const MaterialTable materials{{0, {stiff, nu, 0.0}}, {1, {soft, nu, 0.0}}};
    Constraints c;
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    {
      const Eigen::Vector3d x = mesh.nodes.col(i);
      if (x[0] < 1e-9)
        c.fix(int(i), 0);
      if (x[0] > length - 1e-9)
        c.prescribe(int(i), 0, strain * length);
      if (x[0] < 1e-9 && x[1] < 1e-9 && x[2] < 1e-9)
      {
        c.fix(int(i), 1);
        c.fix(int(i), 2);
      }
      if (x[0] < 1e-9 && x[1] > width - 1e-9 && x[2] < 1e-9)
        c.fix(int(i), 2);
    }
    LinearStaticAnalysis analysis(mesh, materials, c);
    ASSERT_EQ(analysis.prepare(), SolverStatus::Success) << analysis.message();
    const Eigen::VectorXd u = analysis.solve(LoadCase{});
    for (int n : {2, 3})
    {
      const NodalStressField f = recoverNodalStresses(mesh, materials, u, n);
      const std::string what = std::string(wedges ? "wedges" : "hexes") + ", " + std::to_string(n) + " points";
      ASSERT_EQ(f.regionStress.cols(), f.layout.size());
      int interface = 0;
      double worst = 0;
      for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      {
        const double y = mesh.nodes(1, i);
        const bool onInterface = std::abs(y - width / 2) < 1e-9;
        const int columns = f.layout.firstColumn[i + 1] - f.layout.firstColumn[i];
        EXPECT_EQ(columns, onInterface ? 2 : 1) << what << ", node " << i;
        for (int col = f.layout.firstColumn[i]; col < f.layout.firstColumn[i + 1]; ++col)
        {
          const int region = f.layout.regionOf[col];
          EXPECT_EQ(f.layout.nodeOf[col], i);
          EXPECT_EQ(region, y < width / 2 - 1e-9 ? 0 : y > width / 2 + 1e-9 ? 1 : region) << what;
          Vector6d exact = Vector6d::Zero();
          exact[0] = (region == 0 ? stiff : soft) * strain;
          worst = std::max(worst, (f.valueAt(region, int(i)) - exact).cwiseAbs().maxCoeff());
        }
        if (onInterface)
        {
          ++interface;
          EXPECT_NEAR(f.valueAt(0, int(i))[0], stiff * strain, 1e-9 * stiff * strain) << what;
          EXPECT_NEAR(f.valueAt(1, int(i))[0], soft * strain, 1e-9 * stiff * strain) << what;
          // One value per node: the stiffer region's.
          EXPECT_EQ(f.regionAt(int(i)), 0);
          EXPECT_EQ(f.stress.col(i), f.valueAt(0, int(i)));
          EXPECT_EQ(f.elementCount[i], f.layout.elementCount[f.layout.column(0, int(i))]);
        }
        else
        {
          EXPECT_EQ(f.stress.col(i), f.regionStress.col(f.layout.firstColumn[i])) << what;
        }
      }
      EXPECT_GE(interface, 9) << what;
      EXPECT_LT(worst / (stiff * strain), 1e-9) << what;
      for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i) // the side y = 0 lies in the stiff half only
        if (mesh.nodes(1, i) < 1e-9)
          EXPECT_THROW(f.valueAt(1, int(i)), std::out_of_range) << i;
      EXPECT_NEAR(f.vonMises().maxCoeff(), stiff * strain, 1e-9 * stiff * strain);
    }
  }
}

TEST(NodalStress, TheLayoutCountsEachRegionsElementsAtANodeOnce)
{
  // 2 x 2 x 1 bricks, regions by quadrant {0, 1; 1, 2}; the centre line
  // x = 10, y = 10 touches all four elements: regions 0, 1 (twice), 2.
  Mesh mesh = boxMesh(2, 2, 1, 20, 20, 5);
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    double x = 0, y = 0;
    for (int n : mesh.elements[e].nodes)
    {
      x += mesh.nodes(0, n);
      y += mesh.nodes(1, n);
    }
    mesh.elements[e].region = (x / 20 < 10 ? 0 : 1) + (y / 20 < 10 ? 0 : 1);
  }
  // Region 2 the stiffest, then 0; region 1 has no stiffness given (ranks 0).
  const RegionNodeLayout layout = RegionNodeLayout::of(mesh, {{0, 1.0}, {2, 5.0}});
  int centre = -1;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    if (std::abs(mesh.nodes(0, i) - 10) < 1e-9 && std::abs(mesh.nodes(1, i) - 10) < 1e-9 && mesh.nodes(2, i) < 1e-9)
      centre = int(i);
  ASSERT_GE(centre, 0);
  ASSERT_EQ(layout.firstColumn[centre + 1] - layout.firstColumn[centre], 3);
  for (int r = 0; r < 3; ++r)
  {
    const int c = layout.column(r, centre);
    ASSERT_GE(c, 0);
    EXPECT_EQ(layout.regionOf[c], r);
    EXPECT_EQ(layout.elementCount[c], r == 1 ? 2 : 1);
  }
  EXPECT_EQ(layout.regionOf[layout.representative[centre]], 2);
  EXPECT_EQ(layout.column(3, centre), -1);
  EXPECT_EQ(layout.firstColumn[mesh.nodeCount()], layout.size());
}

// The stresses of every element on several threads are those of one
// element at a time, bit for bit, and so are nodal stresses averaged from
// them; the first bad element (lowest index) is the one reported.
TEST(NodalStress, EveryElementOnThreadsIsOneElementAtATimeBitForBit)
{
  Mesh mesh = boxMesh(8, 6, 4, 80, 60, 40, Eigen::Vector3d::Zero(), true);
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = caps::fem::test::wobble(mesh.nodes.col(i), 0.3);
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
    mesh.elements[e].region = int(e % 2);
  const MaterialTable materials{{0, {1000.0, 0.3, 0.0}}, {1, {300.0, 0.45, 0.0}}};
  const Eigen::VectorXd u = Eigen::VectorXd::Random(mesh.dofCount()) * 1e-2;
  ASSERT_GT(mesh.elements.size(), 128u); // enough for more than one thread
  for (int points : {2, 3})
  {
    std::vector<std::vector<StressPoint>> one;
    for (std::size_t e = 0; e < mesh.elements.size(); ++e)
      one.push_back(recoverStressAtGaussPoints(mesh, materials, u, int(e), points));
    for (int threads : {1, 2, 3})
    {
      const auto all = recoverStressAtAllGaussPoints(mesh, materials, u, points, threads);
      ASSERT_EQ(all.size(), one.size());
      for (std::size_t e = 0; e < all.size(); ++e)
      {
        ASSERT_EQ(all[e].size(), one[e].size());
        for (std::size_t p = 0; p < all[e].size(); ++p)
        {
          EXPECT_EQ(all[e][p].stress, one[e][p].stress) << e << ", " << p;
          EXPECT_EQ(all[e][p].strain, one[e][p].strain);
          EXPECT_EQ(all[e][p].world, one[e][p].world);
          EXPECT_EQ(all[e][p].natural, one[e][p].natural);
        }
      }
      // One point at a time (recoverStress) gives the same too.
      EXPECT_EQ(recoverStress(mesh, materials, u, 7, one[7][1].natural).stress, one[7][1].stress);
      const NodalStressField f = recoverNodalStresses(mesh, materials, u, points, threads);
      const NodalStressField g = nodalStressesFromGaussPoints(mesh, materials, one, points);
      EXPECT_EQ(f.regionStress, g.regionStress);
      EXPECT_EQ(f.stress, g.stress);
      EXPECT_EQ(f.elementCount, g.elementCount);
    }
  }
  // Two inverted elements: the lower one is named, on any number of threads.
  // (Inverted: each node slot takes the node of its mirror image in t.)
  Mesh bad = boxMesh(8, 6, 4, 80, 60, 40);
  for (int e : {150, 40})
  {
    Element& el = bad.elements[std::size_t(e)];
    const auto nodes = el.nodes;
    for (int k = 0; k < kHex20NodeCount; ++k)
      for (int j = 0; j < kHex20NodeCount; ++j)
        if (batheNaturalCoordinates(j) == batheNaturalCoordinates(k).cwiseProduct(Eigen::Vector3d(1, 1, -1)))
          el.nodes[std::size_t(k)] = nodes[std::size_t(j)];
  }
  for (int threads : {1, 2, 3})
  {
    try
    {
      recoverStressAtAllGaussPoints(bad, materials, Eigen::VectorXd::Zero(bad.dofCount()), 2, threads);
      ADD_FAILURE() << "no error on " << threads << " threads";
    }
    catch (const ElementError& e)
    {
      EXPECT_EQ(e.element(), 40) << threads << " threads";
    }
  }
  EXPECT_THROW(nodalStressesFromGaussPoints(mesh, materials, {}, 2), std::invalid_argument);
}
