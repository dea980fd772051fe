// Nodal stresses extrapolated from Gauss points: exact for constant and
// linear (pure bending) stress fields.

#include "FemTestMeshes.h"
#include "fem/NodalStress.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

using namespace caps::fem;
using caps::fem::test::boxMesh;

namespace {

Eigen::VectorXd displacementField(const Mesh& mesh, const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& f) {
  Eigen::VectorXd u(mesh.dofCount());
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i) u.segment<3>(3 * i) = f(mesh.nodes.col(i));
  return u;
}

}  // namespace

TEST(NodalStress, ExtrapolationRowsArePartitionsOfUnity) {
  for (int n : {2, 3}) {
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

TEST(NodalStress, ConstantStressPatchIsExactOnDistortedHexesAndWedges) {
  const Eigen::Matrix3d a = (Eigen::Matrix3d() << 1e-3, 2e-4, -3e-4, 5e-4, -2e-3, 1e-4, 0, 7e-4, 4e-4).finished();
  for (bool wedges : {false, true}) {
    Mesh mesh = boxMesh(3, 2, 2, 30, 20, 10, Eigen::Vector3d::Zero(), wedges);
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i) mesh.nodes.col(i) = caps::fem::test::wobble(mesh.nodes.col(i), 0.3);
    const MaterialTable materials{{0, {1000.0, 0.3, 0.0}}};
    const Eigen::VectorXd u = displacementField(mesh, [&](const Eigen::Vector3d& x) { return Eigen::Vector3d(a * x); });
    Vector6d strain;
    strain << a(0, 0), a(1, 1), a(2, 2), a(0, 1) + a(1, 0), a(1, 2) + a(2, 1), a(2, 0) + a(0, 2);
    const Vector6d exact = materials.at(0).elasticityMatrix() * strain;
    for (int n : {2, 3}) {
      const NodalStressField f = recoverNodalStresses(mesh, materials, u, n);
      double worst = 0.0;
      for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i) worst = std::max(worst, (f.stress.col(i) - exact).cwiseAbs().maxCoeff());
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
TEST(NodalStress, PureBendingIsReproducedAtNodes) {
  const double k = 1e-4, nu = 0.3, e = 2000.0;
  for (bool sheared : {false, true}) {
    Mesh mesh = boxMesh(4, 1, 2, 40, 6, 10, Eigen::Vector3d(0, -3, -5));
    if (sheared)  // an affine distortion keeps the field exact in the elements
      for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i) mesh.nodes(0, i) += 0.4 * mesh.nodes(2, i) + 0.2 * mesh.nodes(1, i);
    const MaterialTable materials{{0, {e, nu, 0.0}}};
    const Eigen::VectorXd u = displacementField(mesh, [&](const Eigen::Vector3d& x) {
      return Eigen::Vector3d(k * x[0] * x[2], -nu * k * x[1] * x[2],
                             -0.5 * k * (x[0] * x[0] + nu * (x[2] * x[2] - x[1] * x[1])));
    });
    const double peak = e * k * 5.0;
    for (int n : {2, 3}) {
      const NodalStressField f = recoverNodalStresses(mesh, materials, u, n);
      double worst = 0.0;
      for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i) {
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

TEST(NodalStress, PrincipalStressesAndVonMises) {
  Vector6d s;
  s << 10, 0, 0, 0, 0, 0;
  EXPECT_NEAR(vonMisesStress(s), 10.0, 1e-12);
  s << 0, 0, 0, 5, 0, 0;  // pure shear: principal +5, 0, -5; von Mises 5 sqrt 3
  const Eigen::Vector3d p = principalStresses(s);
  EXPECT_NEAR(p[0], 5.0, 1e-12);
  EXPECT_NEAR(p[1], 0.0, 1e-12);
  EXPECT_NEAR(p[2], -5.0, 1e-12);
  EXPECT_NEAR(vonMisesStress(s), 5.0 * std::sqrt(3.0), 1e-12);
  s << 1, 2, 3, 0.5, -0.7, 0.2;  // trace and invariants survive
  const Eigen::Vector3d q = principalStresses(s);
  EXPECT_NEAR(q.sum(), 6.0, 1e-12);
  EXPECT_GE(q[0], q[1]);
  EXPECT_GE(q[1], q[2]);
}
