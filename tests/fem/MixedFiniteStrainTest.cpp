// The mixed u/p/J finite-strain element (near incompressibility without
// locking), checked against independent references: finite differences of
// its condensed forces, the displacement element on homogeneous
// deformations, closed forms of a uniaxial stretch and of the expansion of
// an incompressible thick-walled cylinder.

#include "fem/FiniteStrainIntegrator.h"
#include "fem/HyperelasticMaterial.h"
#include "fem/MixedFiniteStrainIntegrator.h"
#include "fem/NonlinearStaticAnalysis.h"

#include "FemTestMeshes.h"
#include "FiniteStrainCases.h"

#include <Eigen/LU>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace caps::fem {
namespace {

using test::boxMesh;
using test::elementCases;
using test::MeshBuilder;
using test::wobble;

/// Nearly incompressible tissue: E = 0.1 MPa, nu = 0.49.
const LinearElasticMaterial kTissue{0.1, 0.49, 1e-9};

std::vector<std::pair<std::string, HyperelasticMaterial>> splitMaterials()
{
  return {{"NeoHookean", HyperelasticMaterial::fromLinear(HyperelasticLaw::NeoHookean, kTissue)},
          {"MooneyRivlin", HyperelasticMaterial::fromLinear(HyperelasticLaw::MooneyRivlin, kTissue)},
          {"MooneyRivlin, nu = 0.3", HyperelasticMaterial::mooneyRivlin(0.012, 0.006, 1.2)},
          {"VerondaWestmann", HyperelasticMaterial::fromLinear(HyperelasticLaw::VerondaWestmann, kTissue, 4.0)}};
}

TEST(HyperelasticMaterial, DeviatoricAndVolumetricPartsSumToTheResponse)
{
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> d(-0.3, 0.3);
  for (const auto& [name, m] : splitMaterials())
  {
    for (int sample = 0; sample < 5; ++sample)
    {
      Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
      for (int i = 0; i < 9; ++i)
        f(i / 3, i % 3) += d(rng);
      const double j = f.determinant();
      ASSERT_GT(j, 0.0);
      const Eigen::Matrix3d c = f.transpose() * f, ci = c.inverse();
      const MaterialResponse all = m.response(c, j), dev = m.deviatoricResponse(c, j);
      const VolumetricResponse vol = m.volumetricResponse(j);
      // S_vol = U' J C^-1; D_vol = (U'' J^2 + U' J) Ci(x)Ci - U' J (Ci_ik Ci_jl + Ci_il Ci_jk).
      const int pair[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {1, 2}, {2, 0}};
      Vector6d sVol;
      Matrix6d dVol;
      for (int a = 0; a < 6; ++a)
      {
        const int p = pair[a][0], q = pair[a][1];
        sVol[a] = vol.pressure * j * ci(p, q);
        for (int b = 0; b < 6; ++b)
        {
          const int k = pair[b][0], l = pair[b][1];
          dVol(a, b) = (vol.stiffness * j * j + vol.pressure * j) * ci(p, q) * ci(k, l) -
                       vol.pressure * j * (ci(p, k) * ci(q, l) + ci(p, l) * ci(q, k));
        }
      }
      EXPECT_LT((dev.stress + sVol - all.stress).norm(), 1e-12 * all.stress.norm()) << name;
      EXPECT_LT((dev.tangent + dVol - all.tangent).norm(), 1e-12 * all.tangent.norm()) << name;
      EXPECT_NEAR(dev.energy + vol.energy, all.energy, 1e-14 * std::abs(all.energy)) << name;
    }
  }
  const HyperelasticMaterial svk = HyperelasticMaterial::fromLinear(HyperelasticLaw::StVenantKirchhoff, kTissue);
  EXPECT_FALSE(svk.hasVolumetricSplit());
  EXPECT_THROW(svk.deviatoricResponse(Eigen::Matrix3d::Identity(), 1.0), std::invalid_argument);
}

ElementDisplacements slotsOf(const Element& el, const Eigen::Matrix3Xd& nodal)
{
  ElementDisplacements u = ElementDisplacements::Zero();
  for (int a = 0; a < kHex20NodeCount; ++a)
    if (el.nodes[std::size_t(a)] >= 0)
      u.row(a) = nodal.col(el.nodes[std::size_t(a)]).transpose();
  return u;
}

TEST(MixedFiniteStrainElement, CondensedTangentIsTheDerivativeOfTheCondensedForces)
{
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> d(-0.2, 0.2);
  for (const auto& c : elementCases())
  {
    const Element& el = c.mesh.elements[0];
    const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
    const ElementCoordinates x = c.mesh.elementCoordinates(0);
    for (int points : {2, 3})
    {
      const IntegrationRule& rule = integrationRule(el.kind, points);
      for (const auto& [name, m] : splitMaterials())
      {
        Eigen::Matrix3Xd nodal(3, c.mesh.nodeCount());
        for (Eigen::Index i = 0; i < nodal.cols(); ++i)
          for (int k = 0; k < 3; ++k)
            nodal(k, i) = d(rng);
        const ElementDisplacements u = slotsOf(el, nodal);
        ElementVector f;
        ElementMatrix k;
        FiniteStrainElementCheck check;
        MixedElementFields fields;
        assembleElementMixedFiniteStrain(shape, x, u, m, rule, 0, f, &k, check, &fields);
        ASSERT_GT(check.minDetF, 0.0);
        // Per node DOF (all slots of a repeated node together), central differences.
        const double h = 1e-6;
        double worst = 0;
        for (Eigen::Index node = 0; node < c.mesh.nodeCount(); ++node)
          for (int dir = 0; dir < 3; ++dir)
          {
            Eigen::Matrix3Xd np = nodal, nm = nodal;
            np(dir, node) += h;
            nm(dir, node) -= h;
            ElementVector fp, fm;
            assembleElementMixedFiniteStrain(shape, x, slotsOf(el, np), m, rule, 0, fp, nullptr, check);
            assembleElementMixedFiniteStrain(shape, x, slotsOf(el, nm), m, rule, 0, fm, nullptr, check);
            ElementVector column = (fp - fm) / (2 * h), analytic = ElementVector::Zero();
            for (int a = 0; a < kHex20NodeCount; ++a)
              if (el.nodes[std::size_t(a)] == node)
                analytic += k.col(3 * a + dir);
            worst = std::max(worst, (column - analytic).norm());
          }
        EXPECT_LT(worst, 1e-6 * k.norm()) << c.name << ", " << name << ", " << points << " points";
        EXPECT_LT((k - k.transpose()).norm(), 1e-13 * k.norm()) << c.name << ", " << name;
      }
    }
  }
}

TEST(MixedFiniteStrainElement, UnderAHomogeneousDeformationItIsTheDisplacementElement)
{
  // J is uniform, so J~ = J and p~ = U'(J): the same forces and tangent.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> d(-0.3, 0.3);
  for (const auto& c : elementCases())
  {
    const Element& el = c.mesh.elements[0];
    const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
    const ElementCoordinates x = c.mesh.elementCoordinates(0);
    for (const auto& [name, m] : splitMaterials())
    {
      Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
      for (int i = 0; i < 9; ++i)
        f(i / 3, i % 3) += d(rng);
      ASSERT_GT(f.determinant(), 0.0);
      const Eigen::Matrix3Xd nodal = (f - Eigen::Matrix3d::Identity()) * c.mesh.nodes;
      const ElementDisplacements u = slotsOf(el, nodal);
      ElementVector fMixed, fPlain;
      ElementMatrix kMixed, kPlain;
      FiniteStrainElementCheck cMixed, cPlain;
      MixedElementFields fields;
      assembleElementMixedFiniteStrain(shape, x, u, m, integrationRule(el.kind, 3), 0, fMixed, &kMixed, cMixed,
                                       &fields);
      assembleElementFiniteStrain(shape, x, u, m, integrationRule(el.kind, 3), 0, fPlain, &kPlain, cPlain);
      EXPECT_LT((fMixed - fPlain).norm(), 1e-10 * fPlain.norm()) << c.name << ", " << name;
      // The tangents differ (the mixed one sees the projected dilatation
      // only), but not along a homogeneous increment, whose dJ is uniform.
      Eigen::Matrix3d df;
      for (int i = 0; i < 9; ++i)
        df(i / 3, i % 3) = d(rng);
      const ElementDisplacements du = slotsOf(el, df * c.mesh.nodes);
      const ElementVector flat =
        Eigen::Map<const ElementVector>(Eigen::Matrix<double, 3, kHex20NodeCount>(du.transpose()).data());
      EXPECT_LT((kMixed * flat - kPlain * flat).norm(), 1e-10 * (kPlain * flat).norm()) << c.name << ", " << name;
      EXPECT_NEAR(cMixed.energy, cPlain.energy, 1e-10 * cPlain.energy) << c.name << ", " << name;
      EXPECT_NEAR(fields.dilatation[0], f.determinant(), 1e-12) << c.name;
      EXPECT_LT(fields.dilatation.tail<3>().norm(), 1e-12) << c.name;
      EXPECT_NEAR(fields.pressure[0], m.volumetricResponse(f.determinant()).pressure,
                  1e-10 * std::abs(m.volumetricResponse(f.determinant()).pressure))
        << c.name;
    }
  }
}

/// Principal nominal stresses dW/dlambda_i of a neo-Hookean or Mooney-Rivlin
/// law at principal stretches @a l, from the invariants' derivatives.
Eigen::Vector3d principalNominalStress(const HyperelasticMaterial& m, const Eigen::Vector3d& l)
{
  const double j = l.prod(), i1 = l.squaredNorm();
  const double i2 = l[0] * l[0] * l[1] * l[1] + l[1] * l[1] * l[2] * l[2] + l[2] * l[2] * l[0] * l[0];
  const double jm23 = std::pow(j, -2.0 / 3.0), jm43 = jm23 * jm23;
  Eigen::Vector3d p;
  for (int i = 0; i < 3; ++i)
  {
    const double di1b = jm23 * (2 * l[i] - (2.0 / 3.0) * i1 / l[i]);
    const double di2b = jm43 * (2 * l[i] * (i1 - l[i] * l[i]) - (4.0 / 3.0) * i2 / l[i]);
    p[i] = m.c10 * di1b + m.c01 * di2b + (2 * (j - 1) / m.d1) * j / l[i];
  }
  return p;
}

TEST(MixedNonlinearStaticAnalysis, UniaxialStretchToTwiceTheLengthMeetsTheClosedForm)
{
  // The block of FiniteStrainTest, of bricks and of native wedges: the
  // deformation is homogeneous, so the mixed element is exact as well.
  const double length = 10, side = 4, stretch = 2.0;
  for (bool wedges : {false, true})
    for (const HyperelasticMaterial& m :
         {HyperelasticMaterial::fromLinear(HyperelasticLaw::NeoHookean, kTissue),
          HyperelasticMaterial::fromLinear(HyperelasticLaw::MooneyRivlin, {0.1, 0.499, 0.0})})
    {
      Mesh mesh = boxMesh(2, 1, 1, length, side, side, Eigen::Vector3d::Zero(), wedges);
      if (wedges)
        mesh = withNativeWedges(mesh);
      const Constraints c = test::uniaxialStretch(mesh, length, side, stretch);
      AssemblyOptions options;
      options.volumetric = VolumetricFormulation::MixedPressure;
      NonlinearStaticAnalysis analysis(mesh, {{0, m}}, c, options);
      IncrementControl control;
      control.initial = 0.25;
      NewtonOptions newton;
      newton.residualTolerance = 1e-10;
      const NonlinearResult r = analysis.solve(LoadCase{}, control, newton);
      const std::string what = std::string(lawName(m.law)) + (wedges ? ", wedges" : ", bricks");
      ASSERT_EQ(r.status, NonlinearStatus::Converged) << what << ": " << r.message;

      // Closed form: the lateral stretch l makes the lateral stress vanish.
      double lo = 0.3, hi = 1.0;
      for (int i = 0; i < 200; ++i)
      {
        const double mid = 0.5 * (lo + hi);
        (principalNominalStress(m, Eigen::Vector3d(stretch, mid, mid))[1] > 0 ? hi : lo) = mid;
      }
      const double lateral = 0.5 * (lo + hi);
      const double nominal = principalNominalStress(m, Eigen::Vector3d(stretch, lateral, lateral))[0];

      double worst = 0;
      for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      {
        const Eigen::Vector3d x = mesh.nodes.col(i), u = r.displacements.segment<3>(3 * i);
        worst = std::max({worst, std::abs(u[1] - (lateral - 1) * x[1]), std::abs(u[2] - (lateral - 1) * x[2]),
                          std::abs(u[0] - (stretch - 1) * x[0])});
      }
      EXPECT_LT(worst, 1e-8 * length) << what << ": lateral stretch " << lateral;
      const Eigen::VectorXd f = analysis.internalForces(r.displacements);
      double force = 0;
      for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
        if (mesh.nodes(0, i) > length - 1e-9)
          force += f[3 * i];
      EXPECT_NEAR(force / (side * side), nominal, 1e-8 * std::abs(nominal)) << what;
      EXPECT_NEAR(r.check.minDetF, stretch * lateral * lateral, 1e-8) << what;
    }
}

TEST(MixedNonlinearStaticAnalysis, TheStVenantKirchhoffMaterialIsRefusedByName)
{
  AssemblyOptions options;
  options.volumetric = VolumetricFormulation::MixedPressure;
  Mesh mesh = boxMesh(1, 1, 1, 1, 1, 1);
  Constraints c;
  c.fixNode(0);
  NonlinearStaticAnalysis analysis(
    mesh, {{0, HyperelasticMaterial::fromLinear(HyperelasticLaw::StVenantKirchhoff, kTissue)}}, c, options);
  try
  {
    analysis.solve(LoadCase{});
    FAIL();
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("St. Venant-Kirchhoff"), std::string::npos) << e.what();
  }
}

/// Inner pressure of a quarter ring A..B of @a nr x @a nt elements, one thick, in plane strain,
/// whose inner radius is taken to @a a by prescribed radial displacement:
/// sum over the inner nodes of the radial reaction, divided by the deformed
/// inner area (pi/2) a h. That sum is d(energy)/da, so it is the pressure
/// doing the same work.
struct RingResult
{
  double pressure = 0.0; ///< MPa, at the last converged state
  bool converged = false;
  double loadFraction = 0.0;
  int increments = 0;
};

RingResult ringPressure(int nr, int nt, bool wedges, VolumetricFormulation formulation, const HyperelasticMaterial& m,
                        double ra, double rb, double a)
{
  const double h = 2.0, quarter = M_PI / 2;
  MeshBuilder b(Eigen::Vector3d((rb - ra) / (2 * nr), quarter / (2 * nt), h / 2), Eigen::Vector3d(ra, 0, 0));
  for (int j = 0; j < nt; ++j)
    for (int i = 0; i < nr; ++i)
    {
      if (wedges)
        b.addWedgePair(i, j, 0);
      else
        b.addHex(i, j, 0);
    }
  b.distort(
    [](const Eigen::Vector3d& p) { return Eigen::Vector3d(p[0] * std::cos(p[1]), p[0] * std::sin(p[1]), p[2]); });
  Mesh mesh = b.build();
  if (wedges)
    mesh = withNativeWedges(mesh);
  Constraints c;
  std::vector<int> inner;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    const Eigen::Vector3d x = mesh.nodes.col(i);
    const double radius = std::hypot(x[0], x[1]);
    c.fix(int(i), 2); // plane strain
    if (std::abs(radius - ra) < 1e-9)
    {
      inner.push_back(int(i));
      c.prescribe(int(i), 0, (a - ra) * x[0] / radius);
      c.prescribe(int(i), 1, (a - ra) * x[1] / radius);
      continue;
    }
    if (std::abs(x[0]) < 1e-9)
      c.fix(int(i), 0); // symmetry planes
    if (std::abs(x[1]) < 1e-9)
      c.fix(int(i), 1);
  }
  AssemblyOptions options;
  options.volumetric = formulation;
  NonlinearStaticAnalysis analysis(mesh, {{0, m}}, c, options);
  IncrementControl control;
  control.initial = 0.1;
  control.maximum = 0.25;
  const NonlinearResult r = analysis.solve(LoadCase{}, control);
  RingResult out;
  out.converged = r.status == NonlinearStatus::Converged;
  out.loadFraction = r.loadFraction;
  out.increments = int(r.increments.size());
  const Eigen::VectorXd f = analysis.internalForces(r.displacements);
  double radial = 0;
  for (int n : inner)
  {
    const Eigen::Vector3d x = mesh.nodes.col(n);
    radial += (f[3 * n] * x[0] + f[3 * n + 1] * x[1]) / std::hypot(x[0], x[1]);
  }
  out.pressure = radial / (quarter * (ra + r.loadFraction * (a - ra)) * h);
  return out;
}

TEST(MixedNonlinearStaticAnalysis, AThickCylinderExpandedNearlyIncompressiblyMeetsTheClosedForm)
{
  // Plane strain quarter ring A = 10, B = 20 mm of 2 x 3 elements (radial x
  // around), inner radius taken to a = 15 mm. Incompressible neo-Hookean:
  // b^2 = a^2 + B^2 - A^2 and
  //   p = mu [ln(la / lb) + (lb^-2 - la^-2) / 2],  la = a / A, lb = b / B.
  // nu = 0.499 (the tissue's) and 0.4999; the displacement element on the
  // same mesh, for comparison, locks (measured, not asserted beyond being worse).
  const double ra = 10, rb = 20, a = 15;
  const int nr = 2, nt = 3;
  const double b = std::sqrt(a * a + rb * rb - ra * ra), la = a / ra, lb = b / rb;
  for (double nu : {0.499, 0.4999})
  {
    const HyperelasticMaterial m = HyperelasticMaterial::fromLinear(HyperelasticLaw::NeoHookean, {3.0, nu, 0.0});
    const double exact = m.shearModulus() * (std::log(la / lb) + 0.5 * (1 / (lb * lb) - 1 / (la * la)));
    for (bool wedges : {false, true})
    {
      const std::string what = std::string(wedges ? "wedges" : "bricks") + ", nu = " + std::to_string(nu);
      const RingResult mixed = ringPressure(nr, nt, wedges, VolumetricFormulation::MixedPressure, m, ra, rb, a);
      const RingResult plain = ringPressure(nr, nt, wedges, VolumetricFormulation::Displacement, m, ra, rb, a);
      ASSERT_TRUE(mixed.converged) << what;
      const double errMixed = mixed.pressure / exact - 1, errPlain = plain.pressure / exact - 1;
      const std::string suffix = plain.converged ? std::string()
                                                 : ", did NOT converge: stopped at " +
                                                     std::to_string(100 * plain.loadFraction) + " % of the expansion";
      std::printf("[ cylinder ] %s, nu = %g: closed form p = %.6f MPa; mixed %.6f (%+.3f %%, %d increments), "
                  "displacement %.6f (%+.3f %%, %d increments)%s\n",
                  wedges ? "Wedge15" : "Hex20", nu, exact, mixed.pressure, 100 * errMixed, mixed.increments,
                  plain.pressure, 100 * errPlain, plain.increments, suffix.c_str());
      EXPECT_LT(std::abs(errMixed), 0.01) << what;
      if (plain.converged)
      {
        EXPECT_LT(std::abs(errMixed), std::abs(errPlain)) << what;
      }
    }
  }
}

} // namespace
} // namespace caps::fem
