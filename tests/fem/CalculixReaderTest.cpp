// The .inp importer: round trip through calculixInput(), hand-written decks,
// and clear errors.

#include "FemTestMeshes.h"
#include "fem/CalculixIO.h"
#include "fem/CalculixReader.h"

#include <gtest/gtest.h>

using namespace caps::fem;
using caps::fem::test::boxMesh;

namespace {

Eigen::VectorXd solve(const Mesh& mesh, const MaterialTable& m, const Constraints& c, const LoadCase& load) {
  LinearStaticAnalysis a(mesh, m, c);
  EXPECT_EQ(a.prepare(), SolverStatus::Success) << a.message();
  return a.solve(load);
}

std::string errorOf(const std::string& deck) {
  try {
    parseCalculixInput(deck, "deck.inp");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

const char* kNodes8 =
    "*NODE, NSET=ALL\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n5, 0, 0, 1\n6, 1, 0, 1\n7, 1, 1, 1\n8, 0, 1, 1\n";

}  // namespace

TEST(CalculixReader, RoundTripMixedModelWithSuturesGravityAndLoads) {
  Mesh mesh = boxMesh(2, 2, 2, 20, 20, 10);
  Mesh wedges = boxMesh(2, 2, 1, 20, 20, 5, Eigen::Vector3d(0.5, 1.0, 10.7), true);
  for (auto& e : wedges.elements) e.region = 2;
  const int w0 = test::appendMesh(mesh, wedges);
  const MaterialTable materials{{0, {10.0, 0.3, 1e-9}}, {2, {3.0, 0.45, 2e-9}}};
  Constraints c;
  LoadCase load;
  load.gravity = Eigen::Vector3d(100, -200, -9810);
  for (Eigen::Index i = 0; i < w0; ++i)
    if (mesh.nodes(2, i) < 0.5) c.fixNode(int(i));
  // Suture the bottom of the wedge layer onto the top of the block (offset 0.7 in z, chains).
  int sutured = 0;
  for (Eigen::Index i = w0; i < mesh.nodeCount(); ++i) {
    if (std::abs(mesh.nodes(2, i) - 10.7) > 1e-9) continue;
    for (Eigen::Index j = 0; j < w0; ++j)
      if ((mesh.nodes.col(j) - mesh.nodes.col(i) + Eigen::Vector3d(0, 0, 0.7)).norm() < 1.2 && sutured < 6 &&
          std::abs(mesh.nodes(2, j) - 10) < 1e-9) {
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

TEST(CalculixReader, HandWrittenDeckWithSetsGenerateContinuationAndComments) {
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
  for (int k = 8; k < 20; ++k) EXPECT_EQ(m.mesh.elements[0].nodes[std::size_t(k)], -1);
  EXPECT_EQ(m.constraints.prescribed.size(), 12u);
  EXPECT_EQ(m.load.nodalForces.size(), 4u);
  EXPECT_DOUBLE_EQ(m.materials.at(0).density, 7.85e-9);
  const Eigen::VectorXd u = solve(m.mesh, m.materials, m.constraints, m.load);
  // Uniaxial compression of a unit cube under 100 N: u_z = -100 / E at the top (nu lets it bulge).
  EXPECT_NEAR(u[3 * 4 + 2], -100.0 / 210000.0, 0.3 * 100.0 / 210000.0);
}

TEST(CalculixReader, C3D15BecomesADegenerateWedgeWithPositiveJacobian) {
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

TEST(CalculixReader, ClearErrorsNamingKeywordAndLine) {
  const std::string base = std::string(kNodes8) + "*ELEMENT, TYPE=C3D8, ELSET=E\n1,1,2,3,4,5,6,7,8\n";
  EXPECT_NE(errorOf(base + "*AMPLITUDE, NAME=A\n0,0\n").find("deck.inp:12: unsupported keyword *AMPLITUDE"),
            std::string::npos)
      << errorOf(base + "*AMPLITUDE, NAME=A\n0,0\n");
  EXPECT_NE(errorOf(base + "*DLOAD\nE, P7, 1.0\n").find("deck.inp:13: *DLOAD P7 on element 1: a hexahedron has faces P1..P6"),
            std::string::npos)
      << errorOf(base + "*DLOAD\nE, P7, 1.0\n");
  EXPECT_NE(errorOf(std::string(kNodes8) + "*ELEMENT, TYPE=C3D4\n1,1,2,3,4\n").find("unsupported element type C3D4"),
            std::string::npos);
  EXPECT_NE(errorOf(std::string(kNodes8) + "*ELEMENT, TYPE=C3D8\n1,1,2,3,4,5,6,7,99\n").find("node 99 is not defined"),
            std::string::npos);
  EXPECT_NE(errorOf(base).find("element 1 has no *SOLID SECTION"), std::string::npos) << errorOf(base);
  EXPECT_NE(errorOf(base + "*MATERIAL,NAME=M\n*ELASTIC\n-5, 0.3\n*SOLID SECTION,ELSET=E,MATERIAL=M\n").find("M"),
            std::string::npos);
  EXPECT_NE(errorOf(base + "*MATERIAL,NAME=M\n*ELASTIC\n5, 0.5\n*SOLID SECTION,ELSET=E,MATERIAL=M\n").find("material M"),
            std::string::npos);
  EXPECT_NE(errorOf(base + "*MATERIAL,NAME=M\n*ELASTIC\n5, 0.3\n*SOLID SECTION,ELSET=E,MATERIAL=M\n*EQUATION\n2\n1,1,1.0,2,1,-1.0\n").find("*EQUATION"), std::string::npos);
  EXPECT_NE(errorOf(base + "*BOUNDARY\nNOSUCH,1,3\n").find("unknown node set NOSUCH"), std::string::npos);
  EXPECT_NE(errorOf(std::string(kNodes8) + "1, 2, 3\n*NODE\n1,0,0,0\n").find("defined twice"), std::string::npos);
}
