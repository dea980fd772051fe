// Cross-checks LinearStaticAnalysis against CalculiX: each model is exported
// as a .inp, solved by ccx (Debian calculix-ccx; CI installs it, and a missing
// ccx FAILS these tests), and the displacements read back from the .frd
// (6 significant digits) and the .dat (7 digits) are compared with ours.

#include "fem/CalculixIO.h"
#include "fem/StaticAnalysis.h"

#include "CcxRunner.h"
#include "FemTestMeshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

namespace caps::fem {
namespace {

namespace fs = std::filesystem;
using test::boxMesh;
using test::wobble;

void compareWithCcx(const std::string& name, const Mesh& mesh, const MaterialTable& materials, const Constraints& c,
                    const LoadCase& load)
{
  ASSERT_TRUE(test::ccxAvailable()) << "CalculiX 'ccx' was not found on PATH: install Debian package "
                                       "calculix-ccx (these comparisons must not be skipped)";
  LinearStaticAnalysis analysis(mesh, materials, c);
  ASSERT_EQ(analysis.prepare(), SolverStatus::Success) << analysis.message();
  const Eigen::VectorXd u = analysis.solve(load);
  const test::CcxResult r = test::runCcx(name, calculixInput(mesh, materials, c, load), mesh.nodeCount(), true);
  const double dat = test::relativeDifference(r.dat, u), frd = test::relativeDifference(r.frd, u);
  std::cout << "ccx " << name << ": " << mesh.elements.size() << " elements, max |u| " << u.cwiseAbs().maxCoeff()
            << " mm, relative difference .dat " << dat << ", .frd " << frd << "\n";
  EXPECT_LT(dat, 1e-6) << name;
  EXPECT_LT(frd, 1e-5) << name << " (.frd keeps 6 significant digits)";
}

TEST(Calculix, DistortedHexCantileverWithPrescribedDisplacement)
{
  Mesh mesh = boxMesh(4, 2, 2, 40, 10, 10);
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = wobble(mesh.nodes.col(i));
  Constraints c;
  LoadCase load;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    if (mesh.nodes(0, i) < 0.5)
      c.fixNode(int(i));
    if (mesh.nodes(0, i) > 39.0)
      load.nodalForces.push_back({int(i), Eigen::Vector3d(0.1, -0.2, 0.5)});
  }
  c.prescribe(int(mesh.nodeCount()) - 1, 1, 0.05);
  compareWithCcx("hex", mesh, {{0, {10.0, 0.3, 1e-9}}}, c, load);
}

TEST(Calculix, WedgesUnderGravity)
{
  Mesh mesh = boxMesh(3, 2, 2, 30, 20, 10, Eigen::Vector3d::Zero(), true);
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = wobble(mesh.nodes.col(i));
  Constraints c;
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    if (mesh.nodes(2, i) < 0.5 && mesh.nodes(0, i) < 15.0)
      c.fixNode(int(i));
  LoadCase load;
  load.gravity = Eigen::Vector3d(1000.0, -2000.0, -9810.0);
  compareWithCcx("wedge", mesh, {{0, {0.05, 0.45, 1.05e-9}}}, c, load);
}

TEST(Calculix, MixedHexWedgeTwoRegionsWithSuturesAndGravity)
{
  Mesh mesh = boxMesh(2, 2, 2, 20, 20, 10);
  Mesh wedges = boxMesh(2, 2, 1, 20, 20, 5, Eigen::Vector3d(0.5, 1.0, 10.7), true);
  for (auto& e : wedges.elements)
    e.region = 2;
  const int w0 = test::appendMesh(mesh, wedges);
  Mesh loose = boxMesh(1, 2, 2, 10, 20, 10, Eigen::Vector3d(21.0, 0.0, 0.0));
  for (auto& e : loose.elements)
    e.region = 2;
  const int l0 = test::appendMesh(mesh, loose);
  Constraints c;
  LoadCase load;
  for (int i = 0; i < w0; ++i)
  {
    const Eigen::Vector3d x = mesh.nodes.col(i);
    if (x[2] < 1e-9)
      c.fixNode(i);
    // Wedge layer's bottom face sutured onto the hex top face (offset 0.5, 1.0, 0.7).
    if (std::abs(x[2] - 10.0) < 1e-9)
      for (int j = w0; j < l0; ++j)
        if ((mesh.nodes.col(j) - x - Eigen::Vector3d(0.5, 1.0, 0.7)).norm() < 1e-9)
          c.suture(j, i);
    // Loose block's face x = 21 sutured onto the hex face x = 20 (a 1 mm gap closed).
    if (std::abs(x[0] - 20.0) < 1e-9)
      for (int j = l0; j < int(mesh.nodeCount()); ++j)
        if ((mesh.nodes.col(j) - x - Eigen::Vector3d(1.0, 0, 0)).norm() < 1e-9)
          c.suture(j, i);
  }
  ASSERT_GT(c.sutures.size(), 40u);
  load.gravity = Eigen::Vector3d(0, -9810.0, -9810.0);
  load.nodalForces.push_back({w0 + 2, Eigen::Vector3d(0.0, 0.0, 0.001)});
  compareWithCcx("sutures", mesh, {{0, {0.02, 0.3, 1e-9}}, {2, {0.1, 0.48, 1.1e-9}}}, c, load);
}

TEST(Calculix, ExportTranslatesNodeOrderAndWritesKeywords)
{
  const Mesh mesh = boxMesh(1, 1, 1, 2, 2, 2);
  Constraints c;
  c.fixNode(0);
  c.suture(1, 2);
  LoadCase load;
  load.gravity = Eigen::Vector3d(0, 0, -9810);
  load.nodalForces.push_back({3, Eigen::Vector3d(1, 0, 0)});
  const std::string deck = calculixInput(mesh, {{0, {1.0, 0.3, 1e-9}}}, c, load);
  for (const char* key :
       {"*ELEMENT, TYPE=C3D20", "*BOUNDARY", "*CLOAD", "*DLOAD", "GRAV", "*EQUATION", "*NODE FILE", "*SOLID SECTION"})
    EXPECT_NE(deck.find(key), std::string::npos) << key;
  // C3D20 node 1 is Bathe node 6 (natural -1,-1,-1), i.e. our node at the origin.
  const auto& el = mesh.elements[0];
  const std::string first = "\n1, " + std::to_string(el.nodes[6] + 1) + ", " + std::to_string(el.nodes[7] + 1);
  EXPECT_NE(deck.find(first), std::string::npos) << deck;
  EXPECT_TRUE(mesh.nodes.col(el.nodes[6]).isZero());
}

TEST(Calculix, ElementWithSomeMidsideNodesIsRefusedClearly)
{
  Mesh mesh = boxMesh(1, 1, 1, 2, 2, 2);
  mesh.elements[0].nodes[9] = -1;
  const MaterialTable materials{{0, {1.0, 0.3, 0.0}}};
  try
  {
    calculixInput(mesh, materials, Constraints{}, LoadCase{});
    FAIL() << "no error";
  }
  catch (const std::invalid_argument& e)
  {
    EXPECT_NE(std::string(e.what()).find("element 0 has 11 of 12 mid-side nodes"), std::string::npos) << e.what();
  }
}

TEST(Calculix, FrdReaderFailsClearlyOnMissingFile)
{
  EXPECT_THROW(readFrdDisplacements("/nonexistent/job.frd", 3), std::runtime_error);
}

} // namespace
} // namespace caps::fem
