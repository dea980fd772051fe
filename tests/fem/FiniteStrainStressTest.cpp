// Stress output of the large-deformation path (FiniteStrainStress.h): Cauchy
// and PK2 stress, det F and stretches at the Gauss points and at the nodes,
// averaged within each region, against closed forms derived from the strain
// energy and exact rigid motions.

#include "fem/FiniteStrainStress.h"
#include "fem/NonlinearStaticAnalysis.h"

#include "FemTestMeshes.h"
#include "FiniteStrainCases.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace caps::fem {
namespace {

using test::boxMesh;
using test::wobble;

/// Neo-Hookean strain energy of the principal stretches straight from its
/// definition, W = C10 (J^(-2/3) I1 - 3) + (J - 1)^2 / D1.
double neoHookeanEnergy(double c10, double d1, double l1, double l2, double l3)
{
  const double j = l1 * l2 * l3;
  return c10 * (std::pow(j, -2.0 / 3.0) * (l1 * l1 + l2 * l2 + l3 * l3) - 3) + (j - 1) * (j - 1) / d1;
}

/// Uniaxial stretch @a stretch of the neo-Hookean solid: the lateral stretch
/// l with dW/dl = 0 at (stretch, l, l) (bisection on central differences of
/// W), and the nominal stress P = dW/dlambda there.
struct UniaxialClosedForm
{
  double lateral = 1.0, nominal = 0.0;
};

UniaxialClosedForm uniaxial(double c10, double d1, double stretch)
{
  const double h = 1e-6;
  auto dWdl = [&](double l) {
    return (neoHookeanEnergy(c10, d1, stretch, l + h, l + h) - neoHookeanEnergy(c10, d1, stretch, l - h, l - h)) /
           (2 * h);
  };
  double lo = 0.3, hi = 1.0;
  for (int i = 0; i < 200; ++i)
    (dWdl(0.5 * (lo + hi)) > 0 ? hi : lo) = 0.5 * (lo + hi);
  UniaxialClosedForm out;
  out.lateral = 0.5 * (lo + hi);
  out.nominal = (neoHookeanEnergy(c10, d1, stretch + h, out.lateral, out.lateral) -
                 neoHookeanEnergy(c10, d1, stretch - h, out.lateral, out.lateral)) /
                (2 * h);
  return out;
}

TEST(FiniteStrainStress, UniaxialStretchToTwiceTheLengthInTwoMaterialsMeetsTheClosedFormAtEveryNode)
{
  // A 10 x 4 x 4 mm block, x = 0 held in x, x = 10 pulled to x = 20. The half
  // y > 2 is a neo-Hookean solid 15 times the half y < 2 (C10 x 15,
  // D1 / 15): W_1 = 15 W_0, so both take the same lateral stretch l, the
  // deformation stays homogeneous (the interface is traction-free in y) and
  // every stress of region 1 is 15 times region 0's. Closed form from W:
  // P = dW/dlambda (nominal), sigma_xx = lambda P / J with J = lambda l^2,
  // S_xx = P / lambda; every other component zero.
  const double length = 10, side = 4, stretch = 2.0, ratio = 15.0;
  const double c10 = 0.002, d1 = 20.0; // fat-like: mu = 4 kPa, K = 0.1 MPa
  Mesh mesh = boxMesh(2, 2, 1, length, side, side);
  for (Element& el : mesh.elements)
  {
    double y = 0;
    for (int n : el.nodes)
      y += mesh.nodes(1, n);
    el.region = y / kHex20NodeCount < side / 2 ? 0 : 1;
  }
  const HyperelasticTable materials{{0, HyperelasticMaterial::neoHookean(c10, d1)},
                                    {1, HyperelasticMaterial::neoHookean(ratio * c10, d1 / ratio)}};
  const Constraints c = test::uniaxialStretch(mesh, length, side, stretch);
  NonlinearStaticAnalysis analysis(mesh, materials, c);
  IncrementControl control;
  control.initial = 0.25;
  NewtonOptions full; // ends far below the tolerance: the checks below are the closed form's
  full.tangentUpdate = TangentUpdate::EveryIteration;
  const NonlinearResult r = analysis.solve(LoadCase{}, control, full);
  ASSERT_EQ(r.status, NonlinearStatus::Converged) << r.message;

  const UniaxialClosedForm closed = uniaxial(c10, d1, stretch);
  const double j = stretch * closed.lateral * closed.lateral;
  const double cauchy = stretch * closed.nominal / j, pk2 = closed.nominal / stretch;
  std::printf("[finite-strain stress] uniaxial 2x: l = %.6f, J = %.6f, P = %.6g, sigma_xx = %.6g, S_xx = %.6g MPa\n",
              closed.lateral, j, closed.nominal, cauchy, pk2);
  ASSERT_GT(cauchy, 0.0);
  auto expected = [&](int region, double value) {
    Vector6d s = Vector6d::Zero();
    s[0] = (region == 1 ? ratio : 1.0) * value;
    return s;
  };
  const double scale = ratio * cauchy;

  // At the Gauss points of every element (both rules).
  for (int n : {2, 3})
    for (std::size_t e = 0; e < mesh.elements.size(); ++e)
      for (const FiniteStrainPoint& q : recoverFiniteStrainAtGaussPoints(mesh, materials, r.displacements, int(e), n))
      {
        const int region = mesh.elements[e].region;
        EXPECT_LT((q.cauchy - expected(region, cauchy)).cwiseAbs().maxCoeff(), 1e-6 * scale) << e;
        EXPECT_LT((q.secondPiolaKirchhoff - expected(region, pk2)).cwiseAbs().maxCoeff(), 1e-6 * scale) << e;
        EXPECT_NEAR(q.detF, j, 1e-7);
      }

  for (int n : {2, 3})
  {
    const FiniteStrainNodalField f = recoverFiniteStrainNodalField(mesh, materials, r.displacements, n);
    ASSERT_EQ(f.cauchy.cols(), mesh.nodeCount());
    int interface = 0;
    double worst = 0;
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    {
      for (int col = f.layout.firstColumn[i]; col < f.layout.firstColumn[i + 1]; ++col)
      {
        const int region = f.layout.regionOf[col];
        worst = std::max({worst, (f.regionCauchy.col(col) - expected(region, cauchy)).cwiseAbs().maxCoeff(),
                          (f.regionSecondPiolaKirchhoff.col(col) - expected(region, pk2)).cwiseAbs().maxCoeff()});
      }
      const bool onInterface = std::abs(mesh.nodes(1, i) - side / 2) < 1e-9;
      if (onInterface)
      {
        ++interface;
        ASSERT_EQ(f.layout.firstColumn[i + 1] - f.layout.firstColumn[i], 2);
        EXPECT_NEAR(f.cauchyAt(0, int(i))[0], cauchy, 1e-6 * scale);
        EXPECT_NEAR(f.cauchyAt(1, int(i))[0], ratio * cauchy, 1e-6 * scale);
      }
      // One value per node: the stiffer region's where two meet.
      const int region = f.layout.regionOf[f.layout.representative[i]];
      EXPECT_EQ(region, onInterface ? 1 : mesh.nodes(1, i) < side / 2 ? 0 : 1);
      EXPECT_LT((f.cauchy.col(i) - expected(region, cauchy)).cwiseAbs().maxCoeff(), 1e-6 * scale);
      EXPECT_NEAR(f.vonMises()[i], expected(region, cauchy)[0], 1e-6 * scale);
      EXPECT_NEAR(f.principalCauchy()(0, i), expected(region, cauchy)[0], 1e-6 * scale);
      EXPECT_NEAR(f.principalCauchy()(1, i), 0.0, 1e-6 * scale);
      EXPECT_NEAR(f.principalCauchy()(2, i), 0.0, 1e-6 * scale);
      EXPECT_NEAR(f.detF[i], j, 1e-7);
      EXPECT_NEAR(f.maxStretch()[i], stretch, 1e-7);
      EXPECT_NEAR(f.principalStretches(1, i), closed.lateral, 1e-7);
      EXPECT_NEAR(f.principalStretches(2, i), closed.lateral, 1e-7);
    }
    EXPECT_GE(interface, 5);
    EXPECT_LT(worst, 1e-6 * scale) << n << " points";
  }
}

TEST(FiniteStrainStress, ABlockTurnedRigidlyBy60DegreesIsStressFreeAtTheNodes)
{
  // The boundary nodes of a distorted block are prescribed onto its rigid
  // rotation; the free interior nodes follow, so F = R everywhere: sigma = S
  // = 0, J = 1, every stretch 1, and the nodal F is the rotation itself.
  Mesh mesh = boxMesh(2, 2, 2, 6, 5, 4);
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = wobble(mesh.nodes.col(i), 0.2);
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
    mesh.elements[e].region = int(e % 2);
  const Eigen::Matrix3d rotation =
    Eigen::AngleAxisd(M_PI / 3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d centre(3, 2.5, 2);
  const std::vector<char> outer = test::outerNodes(mesh);
  Constraints c;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    if (outer[std::size_t(i)])
    {
      const Eigen::Vector3d x = mesh.nodes.col(i);
      const Eigen::Vector3d u = rotation * (x - centre) + centre - x;
      for (int d = 0; d < 3; ++d)
        c.prescribe(int(i), d, u[d]);
    }
  const HyperelasticTable materials{{0, HyperelasticMaterial::neoHookean(0.02, 2.0)},
                                    {1, HyperelasticMaterial::neoHookean(0.3, 2.0 / 15)}};
  NonlinearStaticAnalysis analysis(mesh, materials, c);
  IncrementControl control;
  control.initial = 0.25;
  const NonlinearResult r = analysis.solve(LoadCase{}, control);
  ASSERT_EQ(r.status, NonlinearStatus::Converged) << r.message;

  const double mu = materials.at(1).shearModulus();
  const FiniteStrainNodalField f = recoverFiniteStrainNodalField(mesh, materials, r.displacements);
  EXPECT_GT(f.layout.size(), mesh.nodeCount()); // the regions alternate: nodes between them have two columns
  EXPECT_LT(f.regionCauchy.cwiseAbs().maxCoeff(), 1e-10 * mu);
  EXPECT_LT(f.regionSecondPiolaKirchhoff.cwiseAbs().maxCoeff(), 1e-10 * mu);
  EXPECT_LT(f.cauchy.cwiseAbs().maxCoeff(), 1e-10 * mu);
  EXPECT_LT(f.secondPiolaKirchhoff.cwiseAbs().maxCoeff(), 1e-10 * mu);
  EXPECT_LT(f.vonMises().maxCoeff(), 1e-10 * mu);
  EXPECT_LT((f.detF.array() - 1.0).abs().maxCoeff(), 1e-10);
  EXPECT_LT((f.principalStretches.array() - 1.0).abs().maxCoeff(), 1e-10);
  double worstRotation = 0;
  for (Eigen::Index col = 0; col < f.layout.size(); ++col)
    worstRotation = std::max(
      worstRotation,
      (f.deformationGradientAt(f.layout.regionOf[col], f.layout.nodeOf[col]) - rotation).cwiseAbs().maxCoeff());
  EXPECT_LT(worstRotation, 1e-10);
}

TEST(FiniteStrainStress, AStretchThenARotationTurnsTheCauchyStressButNotThePK2)
{
  // u = R diag(2, l, l) X - X imposed at every node (a homogeneous field the
  // quadratic elements carry exactly, even distorted): S is the unrotated
  // uniaxial PK2 diag(P / 2, 0, 0) and sigma = R diag(2 P / J, 0, 0) R^T.
  // Its lateral stretch is the uniaxial one, so the closed form holds.
  const double c10 = 0.02, d1 = 2.0, stretch = 2.0;
  const UniaxialClosedForm closed = uniaxial(c10, d1, stretch);
  const double j = stretch * closed.lateral * closed.lateral;
  Mesh mesh = boxMesh(2, 1, 1, 10, 4, 4, Eigen::Vector3d::Zero(), true); // wedges
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = wobble(mesh.nodes.col(i), 0.2);
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(-1, 0.5, 2).normalized()).toRotationMatrix();
  const Eigen::Matrix3d f0 = rotation * Eigen::Vector3d(stretch, closed.lateral, closed.lateral).asDiagonal();
  Eigen::VectorXd u(mesh.dofCount());
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    u.segment<3>(3 * i) = f0 * mesh.nodes.col(i) - mesh.nodes.col(i);
  const HyperelasticTable materials{{0, HyperelasticMaterial::neoHookean(c10, d1)}};
  const FiniteStrainNodalField f = recoverFiniteStrainNodalField(mesh, materials, u);

  const Eigen::Matrix3d sigma =
    rotation * Eigen::Vector3d(stretch * closed.nominal / j, 0, 0).asDiagonal() * rotation.transpose();
  Vector6d cauchy, pk2 = Vector6d::Zero();
  cauchy << sigma(0, 0), sigma(1, 1), sigma(2, 2), sigma(0, 1), sigma(1, 2), sigma(2, 0);
  pk2[0] = closed.nominal / stretch;
  const double scale = cauchy.cwiseAbs().maxCoeff();
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    EXPECT_LT((f.cauchy.col(i) - cauchy).cwiseAbs().maxCoeff(), 1e-6 * scale) << i;
    EXPECT_LT((f.secondPiolaKirchhoff.col(i) - pk2).cwiseAbs().maxCoeff(), 1e-6 * scale) << i;
    EXPECT_NEAR(f.vonMises()[i], stretch * closed.nominal / j, 1e-6 * scale);
    EXPECT_NEAR(f.detF[i], j, 1e-9);
    EXPECT_NEAR(f.maxStretch()[i], stretch, 1e-9);
  }
}

TEST(FiniteStrainStress, BadInputIsRefusedWithItsName)
{
  Mesh mesh = boxMesh(1, 1, 1, 1, 1, 1);
  const HyperelasticTable materials{{0, HyperelasticMaterial::neoHookean(0.02, 2.0)}};
  EXPECT_THROW(recoverFiniteStrainNodalField(mesh, materials, Eigen::VectorXd::Zero(3)), std::invalid_argument);
  EXPECT_THROW(recoverFiniteStrainNodalField(mesh, {{1, materials.at(0)}}, Eigen::VectorXd::Zero(mesh.dofCount())),
               std::invalid_argument);
  // Inverted: every node mirrored through the plane x = 0.
  Eigen::VectorXd u = Eigen::VectorXd::Zero(mesh.dofCount());
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    u[3 * i] = -2 * mesh.nodes(0, i);
  EXPECT_THROW(recoverFiniteStrainNodalField(mesh, materials, u), InvertedElementError);
}

} // namespace
} // namespace caps::fem
