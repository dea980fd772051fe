// Body coordinates (thesis §4.2.4, eq. 4.13-4.15): world and displaced
// world points of (e, r, s, t), and the inverse by Newton iteration, on
// curved and distorted 20-node bricks and degenerate wedges.

#include "fem/BodyCoordinates.h"

#include "FemTestMeshes.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <random>
#include <string>

namespace caps::fem {
namespace {

using test::boxMesh;

// Strong smooth distortion of every node (mid-sides too): curved edges and
// faces, elements far from parallelepipeds, all Jacobians still positive.
Eigen::Vector3d bend(const Eigen::Vector3d& x)
{
  return x + Eigen::Vector3d(1.6 * std::sin(0.21 * x[1] + 0.13 * x[2]) + 0.04 * x[1] * x[1] / 10.0,
                             1.4 * std::sin(0.17 * x[0] + 0.25 * x[2]), 1.2 * std::sin(0.19 * x[0] + 0.11 * x[1]));
}

enum class Kind
{
  Bricks,
  DegenerateWedges,
  NativeWedges
};
const char* name(Kind kind)
{
  return kind == Kind::Bricks ? "bricks" : kind == Kind::DegenerateWedges ? "degenerate wedges" : "native wedges";
}

Mesh curvedMesh(Kind kind)
{
  Mesh mesh = boxMesh(4, 3, 3, 30.0, 24.0, 18.0, Eigen::Vector3d(-5.0, 3.0, 40.0), kind != Kind::Bricks);
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = bend(mesh.nodes.col(i));
  return kind == Kind::NativeWedges ? withNativeWedges(mesh) : mesh;
}

// A natural point strictly inside element @a e (margin @a m), uniform-ish.
Eigen::Vector3d insidePoint(const Mesh& mesh, int e, std::mt19937& random, double m)
{
  std::uniform_real_distribution<double> natural(-1.0 + m, 1.0 - m);
  Eigen::Vector3d rst(natural(random), natural(random), natural(random));
  if (mesh.elements[std::size_t(e)].kind == ElementKind::Wedge15)
  {
    // Fold the square onto the triangle r, s >= m, r + s <= 1 - m.
    double r = 0.5 * (rst[0] + 1.0), s = 0.5 * (rst[1] + 1.0);
    if (r + s > 1.0)
      r = 1.0 - r, s = 1.0 - s;
    rst[0] = m + (1.0 - 3.0 * m) * r;
    rst[1] = m + (1.0 - 3.0 * m) * s;
  }
  return rst;
}

void roundTrip(Kind kind)
{
  const Mesh mesh = curvedMesh(kind);
  ASSERT_EQ(mesh.elements[0].kind, kind == Kind::NativeWedges ? ElementKind::Wedge15 : ElementKind::Hex20);
  const BodyCoordinateLocator locator(mesh);
  std::mt19937 random(7);
  std::uniform_int_distribution<int> element(0, int(mesh.elements.size()) - 1);
  double worstNatural = 0.0, worstWorld = 0.0;
  for (int i = 0; i < 2000; ++i)
  {
    BodyPoint p{element(random), Eigen::Vector3d::Zero()};
    p.rst = insidePoint(mesh, p.element, random, 0.005);
    // s = +1 is the collapsed edge of a degenerate wedge: there r is not unique.
    if (kind == Kind::DegenerateWedges)
      p.rst[1] = std::min(p.rst[1], 0.9);
    const Eigen::Vector3d x = worldPoint(mesh, p);
    const BodyPoint found = locator.locate(x);
    ASSERT_EQ(found.element, p.element) << "point " << i;
    worstNatural = std::max(worstNatural, (found.rst - p.rst).cwiseAbs().maxCoeff());
    worstWorld = std::max(worstWorld, (worldPoint(mesh, found) - x).norm());
  }
  std::cout << "[ measured ] round trip " << name(kind) << ": natural " << worstNatural << ", world " << worstWorld
            << " mm\n";
  EXPECT_LT(worstNatural, 1e-10);
  EXPECT_LT(worstWorld, 1e-10);
}

TEST(BodyCoordinates, RoundTripOnCurvedBricks)
{
  roundTrip(Kind::Bricks);
}
TEST(BodyCoordinates, RoundTripOnCurvedDegenerateWedges)
{
  roundTrip(Kind::DegenerateWedges);
}
TEST(BodyCoordinates, RoundTripOnCurvedNativeWedges)
{
  roundTrip(Kind::NativeWedges);
}

// Points on faces, edges and nodes belong to several elements: any one will
// do as long as it maps back to the same world point.
TEST(BodyCoordinates, PointsOnSharedFacesAndNodes)
{
  const Mesh mesh = curvedMesh(Kind::Bricks);
  const BodyCoordinateLocator locator(mesh);
  std::mt19937 random(11);
  std::uniform_real_distribution<double> natural(-1.0, 1.0);
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
    for (int face = 0; face < 6; ++face)
    {
      Eigen::Vector3d rst(natural(random), natural(random), natural(random));
      rst[face / 2] = face % 2 ? 1.0 : -1.0;
      const Eigen::Vector3d x = worldPoint(mesh, {int(e), rst});
      const BodyPoint found = locator.locate(x);
      EXPECT_LT((worldPoint(mesh, found) - x).norm(), 1e-10) << "element " << e << " face " << face;
    }
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
  {
    const BodyPoint found = locator.locate(mesh.nodes.col(i));
    EXPECT_LT((worldPoint(mesh, found) - mesh.nodes.col(i)).norm(), 1e-10) << "node " << i;
  }
}

// The interpolation functions reproduce linear fields, so eq. 4.15 moves
// each point exactly by u(x) = u0 + A x on curved elements.
TEST(BodyCoordinates, LinearDisplacementMapsExactly)
{
  for (Kind kind : {Kind::Bricks, Kind::DegenerateWedges, Kind::NativeWedges})
  {
    const Mesh mesh = curvedMesh(kind);
    Eigen::Matrix3d a;
    a << 0.02, -0.05, 0.01, 0.03, 0.04, -0.02, -0.01, 0.06, 0.03;
    const Eigen::Vector3d u0(0.7, -1.1, 0.4);
    Eigen::VectorXd u(mesh.dofCount());
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      u.segment<3>(3 * i) = u0 + a * mesh.nodes.col(i);
    std::mt19937 random(3);
    for (int i = 0; i < 500; ++i)
    {
      BodyPoint p{int(i % mesh.elements.size()), Eigen::Vector3d::Zero()};
      p.rst = insidePoint(mesh, p.element, random, 0.0);
      const Eigen::Vector3d x = worldPoint(mesh, p);
      EXPECT_LT((displacementAt(mesh, u, p) - (u0 + a * x)).norm(), 1e-12);
      EXPECT_LT((displacedWorldPoint(mesh, u, p) - (x + u0 + a * x)).norm(), 1e-12);
    }
  }
}

// Outside: beyond every element, in the notch of an L-shaped block (inside
// the mesh's bounding box but in no element), and just off a curved face.
TEST(BodyCoordinates, PointOutsideIsReported)
{
  const Mesh mesh = curvedMesh(Kind::Bricks);
  const BodyCoordinateLocator locator(mesh);
  EXPECT_FALSE(locator.find(Eigen::Vector3d(500.0, 0.0, 0.0)));
  try
  {
    locator.locate(Eigen::Vector3d(500.0, 0.0, 0.0));
    ADD_FAILURE() << "no error";
  }
  catch (const std::out_of_range& e)
  {
    EXPECT_NE(std::string(e.what()).find("(500, 0, 0) mm lies outside the mesh"), std::string::npos) << e.what();
  }
  // Just off the curved face r = +1 of a boundary element, along its normal.
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    PointGeometry g;
    const Hex20Shape shape = Hex20Shape::fromConnectivity(mesh.elements[e].nodes);
    const Eigen::Vector3d rst(1.0, 0.3, -0.4);
    evaluateGeometry(shape, mesh.elementCoordinates(e), rst, int(e), g);
    const Eigen::Vector3d normal = g.jacobian.row(1).cross(g.jacobian.row(2)).normalized();
    const Eigen::Vector3d outside = g.world + 0.01 * normal, inside = g.world - 0.01 * normal;
    if (locator.find(outside))
      continue; // an inner face: the neighbour holds it
    try
    {
      locator.locate(outside);
      ADD_FAILURE() << "no error";
    }
    catch (const std::out_of_range& error)
    {
      EXPECT_NE(std::string(error.what()).find("mm from element " + std::to_string(e)), std::string::npos)
        << error.what();
    }
    const auto in = locator.find(inside);
    ASSERT_TRUE(in) << "element " << e;
    EXPECT_EQ(in->element, int(e));
    EXPECT_LT((worldPoint(mesh, *in) - inside).norm(), 1e-10);
  }

  test::MeshBuilder b(Eigen::Vector3d(5.0, 5.0, 5.0));
  b.addHex(0, 0, 0);
  b.addHex(1, 0, 0);
  b.addHex(0, 1, 0);
  Mesh l = b.build();
  for (Eigen::Index i = 0; i < l.nodeCount(); ++i)
    l.nodes.col(i) = bend(l.nodes.col(i));
  const BodyCoordinateLocator lLocator(l);
  // The centre of the missing cell (1, 1) moved like its neighbours.
  EXPECT_FALSE(lLocator.find(bend(Eigen::Vector3d(15.0, 15.0, 5.0))));
  EXPECT_TRUE(lLocator.find(bend(Eigen::Vector3d(5.0, 15.0, 5.0))));
}

TEST(BodyCoordinates, RefusesBadBodyPoints)
{
  const Mesh mesh = boxMesh(1, 1, 1, 10.0, 10.0, 10.0);
  EXPECT_THROW(worldPoint(mesh, {1, Eigen::Vector3d::Zero()}), std::invalid_argument);
  EXPECT_THROW(worldPoint(mesh, {-1, Eigen::Vector3d::Zero()}), std::invalid_argument);
  EXPECT_THROW(worldPoint(mesh, {0, Eigen::Vector3d(1.5, 0.0, 0.0)}), std::invalid_argument);
  EXPECT_THROW(worldPoint(mesh, {0, Eigen::Vector3d(std::nan(""), 0.0, 0.0)}), std::invalid_argument);
  EXPECT_THROW(displacedWorldPoint(mesh, Eigen::VectorXd::Zero(3), {0, Eigen::Vector3d::Zero()}),
               std::invalid_argument);
  Mesh broken = mesh;
  broken.elements[0].nodes[3] = 99;
  EXPECT_THROW(BodyCoordinateLocator{broken}, std::invalid_argument);
  const Mesh wedges = curvedMesh(Kind::NativeWedges);
  EXPECT_NO_THROW(worldPoint(wedges, {0, Eigen::Vector3d(0.5, 0.5, 1.0)}));
  EXPECT_THROW(worldPoint(wedges, {0, Eigen::Vector3d(0.6, 0.5, 0.0)}), std::invalid_argument);
  EXPECT_THROW(worldPoint(wedges, {0, Eigen::Vector3d(-0.1, 0.5, 0.0)}), std::invalid_argument);
  EXPECT_NEAR((worldPoint(mesh, {0, Eigen::Vector3d(1.0, -1.0, 0.0)}) - Eigen::Vector3d(10.0, 0.0, 5.0)).norm(), 0.0,
              1e-14);
}

// Carrying skin points: many queries on a larger mesh stay fast.
TEST(BodyCoordinates, LocatesManyPointsQuickly)
{
  Mesh mesh = boxMesh(20, 20, 4, 100.0, 100.0, 12.0);
  for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    mesh.nodes.col(i) = bend(mesh.nodes.col(i));
  const auto t0 = std::chrono::steady_clock::now();
  const BodyCoordinateLocator locator(mesh);
  const auto t1 = std::chrono::steady_clock::now();
  std::mt19937 random(5);
  std::uniform_real_distribution<double> natural(-1.0, 1.0);
  std::uniform_int_distribution<int> element(0, int(mesh.elements.size()) - 1);
  const int count = 20000;
  for (int i = 0; i < count; ++i)
  {
    const BodyPoint p{element(random), Eigen::Vector3d(natural(random), natural(random), 1.0)};
    const Eigen::Vector3d x = worldPoint(mesh, p);
    ASSERT_LT((worldPoint(mesh, locator.locate(x)) - x).norm(), 1e-10);
  }
  const auto t2 = std::chrono::steady_clock::now();
  const double build = std::chrono::duration<double>(t1 - t0).count();
  const double each = std::chrono::duration<double>(t2 - t1).count() / count;
  std::cout << "[ measured ] locator over " << mesh.elements.size() << " elements: built in " << build << " s, "
            << each * 1e6 << " us per point\n";
}

} // namespace
} // namespace caps::fem
