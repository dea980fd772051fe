// The .inp importer: round trip through calculixInput(), hand-written decks,
// and clear errors.

#include "FemTestMeshes.h"
#include "fem/CalculixIO.h"
#include "fem/CalculixReader.h"

#include <gtest/gtest.h>

using namespace caps::fem;
using caps::fem::test::boxMesh;

namespace {

Eigen::VectorXd solve(const Mesh& mesh, const MaterialTable& m, const Constraints& c, const LoadCase& load)
{
  LinearStaticAnalysis a(mesh, m, c);
  EXPECT_EQ(a.prepare(), SolverStatus::Success) << a.message();
  return a.solve(load);
}

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

const char* kNodes8 =
  "*NODE, NSET=ALL\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n5, 0, 0, 1\n6, 1, 0, 1\n7, 1, 1, 1\n8, 0, 1, 1\n";

} // namespace

TEST(CalculixReader, RoundTripMixedModelWithSuturesGravityAndLoads)
{
  Mesh mesh = boxMesh(2, 2, 2, 20, 20, 10);
  Mesh wedges = boxMesh(2, 2, 1, 20, 20, 5, Eigen::Vector3d(0.5, 1.0, 10.7), true);
  for (auto& e : wedges.elements)
    e.region = 2;
  const int w0 = test::appendMesh(mesh, wedges);
  const MaterialTable materials{{0, {10.0, 0.3, 1e-9}}, {2, {3.0, 0.45, 2e-9}}};
  Constraints c;
  LoadCase load;
  load.gravity = Eigen::Vector3d(100, -200, -9810);
  for (Eigen::Index i = 0; i < w0; ++i)
    if (mesh.nodes(2, i) < 0.5)
      c.fixNode(int(i));
  // Suture the bottom of the wedge layer onto the top of the block (offset 0.7 in z, chains).
  int sutured = 0;
  for (Eigen::Index i = w0; i < mesh.nodeCount(); ++i)
  {
    if (std::abs(mesh.nodes(2, i) - 10.7) > 1e-9)
      continue;
    for (Eigen::Index j = 0; j < w0; ++j)
      if ((mesh.nodes.col(j) - mesh.nodes.col(i) + Eigen::Vector3d(0, 0, 0.7)).norm() < 1.2 && sutured < 6 &&
          std::abs(mesh.nodes(2, j) - 10) < 1e-9)
      {
        c.suture(int(i), int(j));
        ++sutured;
        break;
      }
  }
  load.nodalForces.push_back({int(mesh.nodeCount()) - 1, Eigen::Vector3d(0.1, 0.2, -0.3)});
  const Eigen::VectorXd u = solve(mesh, materials, c, load);

  const CalculixModel m = parseCalculixInput(calculixInput(mesh, materials, c, load));
  ASSERT_GE(m.mesh.nodeCount(), mesh.nodeCount());
  ASSERT_EQ(m.mesh.elements.size(), mesh.elements.size());
  EXPECT_LT((m.mesh.nodes.leftCols(mesh.nodeCount()) - mesh.nodes).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(m.materials.size(), 2u);
  EXPECT_LT((m.load.gravity - load.gravity).norm(), 1e-9);
  // The auxiliary node (if any) is prescribed in the deck.
  const Eigen::VectorXd v = solve(m.mesh, m.materials, m.constraints, m.load);
  const double diff = (v.head(u.size()) - u).cwiseAbs().maxCoeff() / u.cwiseAbs().maxCoeff();
  std::cout << "round trip: " << m.constraints.sutures.size() << " sutures read back, relative difference " << diff
            << "\n";
  EXPECT_GT(m.constraints.sutures.size(), 0u);
  EXPECT_LT(diff, 1e-10);
}

TEST(CalculixReader, HandWrittenDeckWithSetsGenerateContinuationAndComments)
{
  const std::string deck = std::string("** a unit cube of one C3D8\n*heading\ncube\n") + kNodes8 +
                           "*Element, type=C3D8,\n ELSET=EALL\n1, 1, 2, 3, 4, 5, 6, 7, 8\n"
                           "*NSET, NSET=BOTTOM, GENERATE\n1, 4\n*nset, nset=TOP\n5, 6\n7, 8\n"
                           "*MATERIAL, NAME=steel\n*ELASTIC\n210000, 0.3\n*DENSITY\n7.85D-9\n"
                           "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n"
                           "*STEP\n*STATIC\n*BOUNDARY\nBOTTOM, 1, 3\n*CLOAD\nTOP, 3, -25.\n"
                           "*NODE FILE\nU\n*EL FILE\nS\n*NODE PRINT, NSET=ALL\nU\n*END STEP\n";
  const CalculixModel m = parseCalculixInput(deck);
  EXPECT_EQ(m.mesh.nodeCount(), 8);
  ASSERT_EQ(m.mesh.elements.size(), 1u);
  for (int k = 8; k < 20; ++k)
    EXPECT_EQ(m.mesh.elements[0].nodes[std::size_t(k)], -1);
  EXPECT_EQ(m.constraints.prescribed.size(), 12u);
  EXPECT_EQ(m.load.nodalForces.size(), 4u);
  EXPECT_DOUBLE_EQ(m.materials.at(0).density, 7.85e-9);
  const Eigen::VectorXd u = solve(m.mesh, m.materials, m.constraints, m.load);
  // Uniaxial compression of a unit cube under 100 N: u_z = -100 / E at the top (nu lets it bulge).
  EXPECT_NEAR(u[3 * 4 + 2], -100.0 / 210000.0, 0.3 * 100.0 / 210000.0);
}

TEST(CalculixReader, C3D15BecomesADegenerateWedgeWithPositiveJacobian)
{
  // A wedge: triangle (0,0)-(1,0)-(0,1) at z = 0 and z = 1.
  const std::string deck =
    "*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n4,0,0,1\n5,1,0,1\n6,0,1,1\n"
    "7,.5,0,0\n8,.5,.5,0\n9,0,.5,0\n10,.5,0,1\n11,.5,.5,1\n12,0,.5,1\n13,0,0,.5\n14,1,0,.5\n15,0,1,.5\n"
    "*ELEMENT, TYPE=C3D15, ELSET=W\n1, 1,2,3,4,5,6,7,8,9,10,\n11,12,13,14,15\n"
    "*MATERIAL, NAME=M\n*ELASTIC\n100, 0.25\n*SOLID SECTION, ELSET=W, MATERIAL=M\n"
    "*BOUNDARY\n1,1,3\n2,1,3\n3,1,3\n7,1,3\n8,1,3\n9,1,3\n*STEP\n*STATIC\n*CLOAD\n4,3,1.0\n*END STEP\n";
  const CalculixModel m = parseCalculixInput(deck);
  const Eigen::VectorXd u = solve(m.mesh, m.materials, m.constraints, m.load);
  EXPECT_GT(u[3 * 3 + 2], 0.0);
}

TEST(CalculixReader, ClearErrorsNamingKeywordAndLine)
{
  const std::string base = std::string(kNodes8) + "*ELEMENT, TYPE=C3D8, ELSET=E\n1,1,2,3,4,5,6,7,8\n";
  EXPECT_NE(errorOf(base + "*AMPLITUDE, NAME=A\n0,0\n").find("deck.inp:12: unsupported keyword *AMPLITUDE"),
            std::string::npos)
    << errorOf(base + "*AMPLITUDE, NAME=A\n0,0\n");
  EXPECT_NE(
    errorOf(base + "*DLOAD\nE, P7, 1.0\n").find("deck.inp:13: *DLOAD P7 on element 1: a hexahedron has faces P1..P6"),
    std::string::npos)
    << errorOf(base + "*DLOAD\nE, P7, 1.0\n");
  EXPECT_NE(errorOf(std::string(kNodes8) + "*ELEMENT, TYPE=C3D4\n1,1,2,3,4\n").find("unsupported element type C3D4"),
            std::string::npos);
  EXPECT_NE(errorOf(std::string(kNodes8) + "*ELEMENT, TYPE=C3D8\n1,1,2,3,4,5,6,7,99\n").find("node 99 is not defined"),
            std::string::npos);
  EXPECT_NE(errorOf(base).find("element 1 has no *SOLID SECTION"), std::string::npos) << errorOf(base);
  EXPECT_NE(errorOf(base + "*MATERIAL,NAME=M\n*ELASTIC\n-5, 0.3\n*SOLID SECTION,ELSET=E,MATERIAL=M\n").find("M"),
            std::string::npos);
  EXPECT_NE(
    errorOf(base + "*MATERIAL,NAME=M\n*ELASTIC\n5, 0.5\n*SOLID SECTION,ELSET=E,MATERIAL=M\n").find("material M"),
    std::string::npos);
  EXPECT_NE(
    errorOf(base +
            "*MATERIAL,NAME=M\n*ELASTIC\n5, 0.3\n*SOLID SECTION,ELSET=E,MATERIAL=M\n*EQUATION\n2\n1,4,1.0,2,1,-1.0\n")
      .find("*EQUATION on DOF 4 of node 1"),
    std::string::npos);
  EXPECT_NE(errorOf(base + "*BOUNDARY\nNOSUCH,1,3\n").find("unknown node set NOSUCH"), std::string::npos);
  EXPECT_NE(errorOf(std::string(kNodes8) + "1, 2, 3\n*NODE\n1,0,0,0\n").find("defined twice"), std::string::npos);
}

namespace {

/// kNodes8 and four more on top (z = 2), two C3D8 cubes, the bottom fixed.
std::string twoCubes(const std::string& material, const std::string& elset = "E", const std::string& nset = "TOP")
{
  return std::string(kNodes8) + "9, 0, 0, 2\n10, 1, 0, 2\n11, 1, 1, 2\n12, 0, 1, 2\n" +
         "*ELEMENT, TYPE=C3D8, ELSET=" + elset + "\n1,1,2,3,4,5,6,7,8\n2,5,6,7,8,9,10,11,12\n" + "*NSET, NSET=" + nset +
         "\n9, 10\n11, 12\n" + material + "*SOLID SECTION, ELSET=" + elset + ", MATERIAL=M\n";
}

} // namespace

TEST(CalculixReader, ElementTypesCarryTheRuleCcxIntegratesThemWith)
{
  const std::string deck = std::string(kNodes8) +
                           "9,2,0,0\n10,2,1,0\n11,2,0,1\n12,2,1,1\n*ELEMENT, TYPE=C3D8, ELSET=E\n1,1,2,3,4,5,6,7,8\n"
                           "*ELEMENT, TYPE=C3D15, ELSET=E\n2,2,9,3,6,11,7,2,9,3,6,11,7,2,9,3\n"
                           "*MATERIAL,NAME=M\n*ELASTIC\n5, 0.3\n*SOLID SECTION,ELSET=E,MATERIAL=M\n";
  // Only the element types matter here (the C3D15 is not a valid wedge: it is never solved).
  const CalculixModel m = parseCalculixInput(deck);
  EXPECT_EQ(m.mesh.elements[0].integrationPoints, 2); // C3D8: ccx's full 2x2x2
  EXPECT_EQ(m.mesh.elements[1].integrationPoints, 2); // C3D15: ccx's 9 points, wedgeRule(2)
  CalculixReadOptions degenerate;
  degenerate.nativeWedges = false;
  EXPECT_EQ(parseCalculixInput(deck, "deck", degenerate).mesh.elements[1].integrationPoints, 0);

  // The same 20-node brick as C3D20 and C3D20R.
  const Mesh brick = boxMesh(1, 1, 1, 1, 1, 1);
  const std::string full = calculixInput(brick, {{0, {5.0, 0.3, 0.0}}}, Constraints{}, LoadCase{});
  ASSERT_NE(full.find("TYPE=C3D20,"), std::string::npos);
  EXPECT_EQ(parseCalculixInput(full).mesh.elements[0].integrationPoints, 3);
  std::string reduced = full;
  reduced.replace(reduced.find("TYPE=C3D20,"), 11, "TYPE=C3D20R,");
  EXPECT_EQ(parseCalculixInput(reduced).mesh.elements[0].integrationPoints, 2);
}

TEST(CalculixReader, SetNamesMayStartWithADigit)
{
  const std::string material = "*MATERIAL, NAME=M\n*ELASTIC\n100, 0.3\n*DENSITY\n1e-9\n";
  // Element set e, node sets n (top), b (bottom) and t (the set of the set n).
  auto deck = [&](const std::string& e, const std::string& n, const std::string& b, const std::string& t) {
    return twoCubes(material, e, n) + "*NSET, NSET=" + b + "\n1, 2, 3, 4\n*NSET, NSET=" + t + "\n" + n +
           "\n*STEP\n*STATIC\n*BOUNDARY\n" + b + ", 1, 3\n*CLOAD\n" + t + ", 1, 0.5\n*DLOAD\n" + e +
           ", GRAV, 9810, 0, 0, -1\n" + e + ", P2, 0.25\n*END STEP\n";
  };
  const CalculixModel digits = parseCalculixInput(deck("1E", "2N", "1B", "3T"));
  const CalculixModel letters = parseCalculixInput(deck("EALL", "NTOP", "NBOTTOM", "NT"));
  EXPECT_EQ(digits.constraints.prescribed.size(), 12u);
  EXPECT_EQ(digits.load.nodalForces.size(), 4u);
  EXPECT_EQ(digits.load.facePressures.size(), 2u);
  const Eigen::VectorXd u = solve(digits.mesh, digits.materials, digits.constraints, digits.load);
  const Eigen::VectorXd v = solve(letters.mesh, letters.materials, letters.constraints, letters.load);
  EXPECT_GT(u.cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_LT((u - v).cwiseAbs().maxCoeff(), 1e-14);
  // A field that is wholly an integer is still a node number, and an unknown name is named.
  EXPECT_NE(errorOf(twoCubes(material) + "*BOUNDARY\n1X, 1, 3\n").find("unknown node set 1X"), std::string::npos);
}

TEST(CalculixReader, EquationsOfAnyNumberOfTerms)
{
  const std::string material = "*MATERIAL, NAME=M\n*ELASTIC\n100, 0.3\n";
  // Nodes 13 and 14 coincide with 9 and 10 (a suture of 13 onto 9 in all three directions).
  const std::string deck = twoCubes(material) +
                           "*NODE\n13, 0, 0, 2\n14, 1, 0, 2\n"
                           "*EQUATION\n2\n13,1,1.,9,1,-1.\n2\n13,2,1.,9,2,-1.\n2\n13,3,1.,9,3,-1.\n"
                           "1\n10, 3, 2.5,\n"
                           "3\n11, 1, 1., 12, 2, -0.5, 10, 1, 0.25\n"
                           "4\n12, 3, -0.577, 12, 1, 0.0, 12, 2, 0.577,\n 14, 3, 1.\n"
                           "2\n14, 1, 1., 10, 1, -1.\n";
  const CalculixModel m = parseCalculixInput(deck);
  ASSERT_EQ(m.constraints.sutures.size(), 1u);
  EXPECT_EQ(m.constraints.sutures[0].node, 12);
  EXPECT_EQ(m.constraints.sutures[0].target, 8);
  // A tie in one direction only is an equation, not a suture.
  ASSERT_EQ(m.constraints.equations.size(), 4u);
  const auto& one = m.constraints.equations[0];
  ASSERT_EQ(one.terms.size(), 1u);
  EXPECT_EQ(one.terms[0].node, 9);
  EXPECT_EQ(one.terms[0].direction, 2);
  EXPECT_EQ(one.terms[0].coefficient, 2.5);
  EXPECT_EQ(m.constraints.equations[1].terms.size(), 3u);
  const auto& four = m.constraints.equations[2]; // its zero coefficient is dropped
  ASSERT_EQ(four.terms.size(), 3u);
  EXPECT_EQ(four.terms[0].node, 11);
  EXPECT_EQ(four.terms[0].direction, 2);
  EXPECT_EQ(four.terms[0].coefficient, -0.577);
  EXPECT_EQ(four.terms[2].node, 13);
  EXPECT_EQ(four.terms[2].coefficient, 1.0);
  EXPECT_EQ(m.constraints.equations[3].terms.size(), 2u);
  for (const auto& eq : m.constraints.equations)
    EXPECT_EQ(eq.value, 0.0);
  EXPECT_NE(errorOf(twoCubes(material) + "*EQUATION\n2\n9, 1, 0., 10, 1, 1.\n").find("coefficient 0"),
            std::string::npos);
  EXPECT_NE(errorOf(twoCubes(material) + "*EQUATION\n3\n9, 1, 1., 10, 1, 1.\n").find("expected 9 entries"),
            std::string::npos);
}

TEST(CalculixReader, LargeDeformationStepAndHyperelasticMaterials)
{
  const std::string tail = "*STEP, NLGEOM, INC=500\n*STATIC, DIRECT\n0.1, 1., 1e-4, 0.2\n"
                           "*CONTROLS, PARAMETERS=FIELD\n1e-8, 1e-8\n*BOUNDARY\n1, 1, 3\n*END STEP\n";
  const CalculixModel neo =
    parseCalculixInput(twoCubes("*MATERIAL, NAME=M\n*HYPERELASTIC, NEO HOOKE\n0.5, 0.04\n*DENSITY\n1e-9\n") + tail);
  EXPECT_TRUE(neo.step.nlgeom);
  EXPECT_TRUE(neo.step.direct);
  EXPECT_EQ(neo.step.initialIncrement, 0.1);
  EXPECT_EQ(neo.step.period, 1.0);
  EXPECT_EQ(neo.step.minimumIncrement, 1e-4);
  EXPECT_EQ(neo.step.maximumIncrement, 0.2);
  ASSERT_EQ(neo.hyperelastic.count(0), 1u);
  const HyperelasticMaterial& h = neo.hyperelastic.at(0);
  EXPECT_EQ(h.law, HyperelasticLaw::NeoHookean);
  EXPECT_EQ(h.c10, 0.5);
  EXPECT_EQ(h.d1, 0.04);
  EXPECT_EQ(h.density, 1e-9);
  // The linear table holds the small-strain limit: mu = 2 C10 = 1, K = 2 / D1 = 50.
  const LinearElasticMaterial& lin = neo.materials.at(0);
  EXPECT_NEAR(lin.youngsModulus, 9.0 * 50.0 * 1.0 / (3.0 * 50.0 + 1.0), 1e-12);
  EXPECT_NEAR(lin.poissonRatio, (3.0 * 50.0 - 2.0) / (2.0 * (3.0 * 50.0 + 1.0)), 1e-12);
  EXPECT_EQ(lin.density, 1e-9);

  const CalculixModel mr =
    parseCalculixInput(twoCubes("*MATERIAL, NAME=M\n*HYPERELASTIC, MOONEY-RIVLIN\n0.3, 0.2, 0.04\n") +
                       "*STEP\n*STATIC\n*BOUNDARY\n1, 1, 3\n*END STEP\n");
  EXPECT_EQ(mr.hyperelastic.at(0).law, HyperelasticLaw::MooneyRivlin);
  EXPECT_EQ(mr.hyperelastic.at(0).c10, 0.3);
  EXPECT_EQ(mr.hyperelastic.at(0).c01, 0.2);
  EXPECT_EQ(mr.hyperelastic.at(0).d1, 0.04);
  // ccx solves a hyperelastic material nonlinearly even without NLGEOM.
  EXPECT_TRUE(mr.step.nlgeom);
  EXPECT_FALSE(mr.step.direct);

  const CalculixModel linear =
    parseCalculixInput(twoCubes("*MATERIAL, NAME=M\n*ELASTIC\n5, 0.3\n") + "*STEP, NLGEOM=NO\n*STATIC\n*END STEP\n");
  EXPECT_FALSE(linear.step.nlgeom);
  EXPECT_TRUE(linear.hyperelastic.empty());

  const std::string ogden = errorOf(twoCubes("*MATERIAL, NAME=M\n*HYPERELASTIC, OGDEN, N=1\n1, 2, 0.1\n"));
  EXPECT_NE(ogden.find("*HYPERELASTIC, "), std::string::npos) << ogden;
  EXPECT_NE(ogden.find("is not supported (NEO HOOKE and MOONEY-RIVLIN are"), std::string::npos) << ogden;
  EXPECT_NE(errorOf(twoCubes("*MATERIAL, NAME=M\n*HYPERELASTIC, POLYNOMIAL\n1, 2, 0.1\n")).find("POLYNOMIAL"),
            std::string::npos);
  EXPECT_NE(errorOf(twoCubes("*MATERIAL, NAME=M\n*ELASTIC\n5, 0.3\n*HYPERELASTIC, NEO HOOKE\n1, 0.1\n"))
              .find("both *ELASTIC and *HYPERELASTIC"),
            std::string::npos);
  EXPECT_NE(errorOf(twoCubes("*MATERIAL, NAME=M\n*HYPERELASTIC, NEO HOOKE\n1\n")).find("needs C10, D1"),
            std::string::npos);
  EXPECT_NE(errorOf(twoCubes("*MATERIAL, NAME=M\n*HYPERELASTIC, NEO HOOKE\n-1, 0.1\n")).find("deck.inp:22: "),
            std::string::npos)
    << errorOf(twoCubes("*MATERIAL, NAME=M\n*HYPERELASTIC, NEO HOOKE\n-1, 0.1\n"));
}

TEST(CalculixReader, OrientationAndExpansionOfIsotropicMaterialsChangeNothing)
{
  const std::string material = "*ORIENTATION, NAME=S0, DEFINITION=COORDINATES, SYSTEM=RECTANGULAR\n0,1,0,-1,0,0\n"
                               "*MATERIAL, NAME=M\n*ELASTIC, TYPE=ISOTROPIC\n100, 0.3\n*EXPANSION, TYPE=ISO\n1.2e-5\n";
  const std::string load = "*STEP\n*STATIC\n*BOUNDARY\n1,1,3\n2,1,3\n3,1,3\n4,1,3\n*CLOAD\n9,1,0.5\n*END STEP\n";
  std::string oriented = twoCubes(material) + load;
  const std::string section = "MATERIAL=M\n";
  oriented.replace(oriented.find(section), section.size(), "MATERIAL=M, ORIENTATION=S0\n");
  const CalculixModel a = parseCalculixInput(oriented);
  const CalculixModel b = parseCalculixInput(twoCubes("*MATERIAL, NAME=M\n*ELASTIC\n100, 0.3\n") + load);
  EXPECT_LT((solve(a.mesh, a.materials, a.constraints, a.load) - solve(b.mesh, b.materials, b.constraints, b.load))
              .cwiseAbs()
              .maxCoeff(),
            1e-15);
  std::string unknown = oriented;
  unknown.replace(unknown.find("ORIENTATION=S0"), 14, "ORIENTATION=S1");
  EXPECT_NE(errorOf(unknown).find("orientation S1, which is not defined"), std::string::npos) << errorOf(unknown);
}

TEST(CalculixReader, NumbersAreReadAsStrtodReadsThemInAnyLineEnding)
{
  // CRLF line endings, a '+' sign, Fortran exponents, a leading dot, tabs.
  const std::string deck = "*NODE\r\n1, 0, 0, 0\r\n2, +1.0, 0, 0\r\n3, 1.D0, 1d0, 0\r\n4, 0, .1, 0\r\n"
                           "5, 0, 0, 1\r\n6, 1, 0, 0.1E+1\r\n7, 1, 1, 1\r\n8,\t-0.25E+1 ,\t1, 1\r\n"
                           "*ELEMENT, TYPE=C3D8, ELSET=E\r\n+1, 1, 2, 3, 4, 5, 6, 7, 8\r\n"
                           "*MATERIAL, NAME=M\r\n*ELASTIC\r\n7.5D2, 3.D-1\r\n*SOLID SECTION, ELSET=E, MATERIAL=M\r\n";
  const CalculixModel m = parseCalculixInput(deck);
  ASSERT_EQ(m.mesh.nodeCount(), 8);
  EXPECT_EQ(m.mesh.nodes(0, 1), 1.0);
  EXPECT_EQ(m.mesh.nodes(1, 2), 1.0);
  EXPECT_EQ(m.mesh.nodes(1, 3), std::strtod("0.1", nullptr));
  EXPECT_EQ(m.mesh.nodes(2, 5), 1.0);
  EXPECT_EQ(m.mesh.nodes(0, 7), -2.5);
  EXPECT_EQ(m.elementIds, std::vector<long>{1});
  EXPECT_EQ(m.materials.at(0).youngsModulus, 750.0);
  EXPECT_EQ(m.materials.at(0).poissonRatio, std::strtod("3e-1", nullptr));
  const std::string base = std::string(kNodes8) + "*ELEMENT, TYPE=C3D8, ELSET=E\n1,1,2,3,4,5,6,7,8\n";
  EXPECT_NE(errorOf(base + "*MATERIAL,NAME=M\n*ELASTIC\n5x, 0.3\n").find("deck.inp:14: '5x' is not a number"),
            std::string::npos)
    << errorOf(base + "*MATERIAL,NAME=M\n*ELASTIC\n5x, 0.3\n");
  EXPECT_NE(
    errorOf(std::string(kNodes8) + "*ELEMENT, TYPE=C3D8\n1,1,2,3,4,5,6,7,8.5\n").find("'8.5' is not an integer"),
    std::string::npos);
}
