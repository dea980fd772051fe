// Whether a deformed body passes through itself (checkSurfaceCrossings):
// against configurations whose overlap is known in closed form. Two blocks
// pushed together overlap exactly when the push exceeds the gap between
// them; a strip rolled into a spiral passes through itself exactly when the
// spiral's pitch is less than the strip's thickness, with det F > 0 at every
// point either way (which is why the element check cannot see it).

#include "fem/SurfaceCrossing.h"

#include "fem/DisplaySurface.h"
#include "fem/FiniteStrainStress.h"

#include "FemTestMeshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

namespace caps::fem {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::vector<ElementFace> boundaryOf(const Mesh& mesh)
{
  std::vector<int> all(std::size_t(mesh.nodeCount()));
  std::iota(all.begin(), all.end(), 0);
  return boundaryFacesOnNodes(mesh, all);
}

/// Two 10 x 10 x 4 blocks, the second 2 mm beyond the first along x and
/// offset by @a offset across; @a second the second block's first node.
Mesh twoBlocks(const Eigen::Vector3d& offset, int& second)
{
  Mesh mesh = test::boxMesh(2, 2, 1, 10.0, 10.0, 4.0);
  second = test::appendMesh(mesh, test::boxMesh(2, 2, 1, 10.0, 10.0, 4.0, Eigen::Vector3d(12.0, 0.0, 0.0) + offset));
  return mesh;
}

/// The second block moved by @a push towards the first, and by @a across.
Eigen::VectorXd pushed(const Mesh& mesh, int second, double push,
                       const Eigen::Vector3d& across = Eigen::Vector3d::Zero())
{
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3 * mesh.nodeCount());
  for (Eigen::Index n = second; n < mesh.nodeCount(); ++n)
    u.segment<3>(3 * n) = Eigen::Vector3d(-push, 0.0, 0.0) + across;
  return u;
}

TEST(SurfaceCrossing, TwoBlocksCrossExactlyWhenPushedFartherThanTheGap)
{
  int second = 0;
  const Mesh mesh = twoBlocks(Eigen::Vector3d(0.0, 3.0, 1.0), second);
  const std::vector<ElementFace> faces = boundaryOf(mesh);
  EXPECT_EQ(checkSurfaceCrossings(mesh, faces, pushed(mesh, second, 0.0)).crossingPairs, 0);
  EXPECT_EQ(checkSurfaceCrossings(mesh, faces, pushed(mesh, second, 1.9)).crossingPairs, 0);
  const SurfaceCrossingCheck into = checkSurfaceCrossings(mesh, faces, pushed(mesh, second, 2.5));
  EXPECT_GT(into.crossingPairs, 0);
  EXPECT_GT(into.triangles, 0);
  // The crossing is where the blocks overlap: x in [9.5, 10], y in [3, 10], z in [1, 4].
  EXPECT_GE(into.where.x(), 9.5 - 1e-9);
  EXPECT_LE(into.where.x(), 10.0 + 1e-9);
  EXPECT_GE(into.where.y(), 3.0 - 1e-9);
  EXPECT_LE(into.where.y(), 10.0 + 1e-9);
  EXPECT_GE(into.where.z(), 1.0 - 1e-9);
  EXPECT_LE(into.where.z(), 4.0 + 1e-9);
  EXPECT_GE(into.faceA, 0);
  EXPECT_GE(into.faceB, 0);
  EXPECT_NE(mesh.elements[std::size_t(faces[std::size_t(into.faceA)].element)].nodes[0] < second,
            mesh.elements[std::size_t(faces[std::size_t(into.faceB)].element)].nodes[0] < second)
    << "a crossing pair has one face on each block";
}

// The sides of a closed wound meet point for point (the sutures bring them
// together exactly): that is contact, not a crossing. Pushed past each
// other, they cross (moved a little across too: surfaces that overlap only
// where they lie in one plane are not counted).
TEST(SurfaceCrossing, FacesThatMeetPointForPointAreClosedNotCrossed)
{
  int second = 0;
  const Mesh mesh = twoBlocks(Eigen::Vector3d::Zero(), second);
  const std::vector<ElementFace> faces = boundaryOf(mesh);
  EXPECT_EQ(checkSurfaceCrossings(mesh, faces, pushed(mesh, second, 2.0)).crossingPairs, 0);
  EXPECT_GT(checkSurfaceCrossings(mesh, faces, pushed(mesh, second, 2.5, {0.0, 0.3, 0.2})).crossingPairs, 0);
}

/// A 100 x 10 x 2 strip rolled about the y axis into 1.3 turns of a
/// spiral: the mid-line angle grows with x, the radius by @a pitch per turn,
/// the thickness stays radial.
Eigen::VectorXd rolled(const Mesh& strip, double pitch)
{
  constexpr double length = 100.0, turns = 1.3, innerRadius = 10.0;
  Eigen::VectorXd u(3 * strip.nodeCount());
  for (Eigen::Index n = 0; n < strip.nodeCount(); ++n)
  {
    const Eigen::Vector3d x = strip.nodes.col(n);
    const double theta = 2.0 * kPi * turns * x.x() / length;
    const double r = innerRadius + x.z() + pitch * theta / (2.0 * kPi);
    u.segment<3>(3 * n) = Eigen::Vector3d(r * std::sin(theta), x.y(), r * std::cos(theta) - innerRadius) - x;
  }
  return u;
}

TEST(SurfaceCrossing, AStripRolledTighterThanItsThicknessPassesThroughItselfWithEveryElementABody)
{
  const Mesh strip = test::boxMesh(60, 2, 1, 100.0, 10.0, 2.0);
  const std::vector<ElementFace> faces = boundaryOf(strip);
  for (double pitch : {3.0, 2.2, 1.8, 1.0})
  {
    const Eigen::VectorXd u = rolled(strip, pitch);
    const DeformationCheck body = checkDeformation(strip, u);
    EXPECT_GT(body.minDetF, 0.5) << "pitch " << pitch << ": every element is a body";
    EXPECT_EQ(body.invertedElements, 0);
    const SurfaceCrossingCheck crossing = checkSurfaceCrossings(strip, faces, u);
    if (pitch > 2.0) // the turns lie on each other with a gap of pitch - thickness
      EXPECT_EQ(crossing.crossingPairs, 0) << "pitch " << pitch;
    else
      EXPECT_GT(crossing.crossingPairs, 0) << "pitch " << pitch;
  }
}

TEST(SurfaceCrossing, WrongInputIsRefused)
{
  const Mesh block = test::boxMesh(1, 1, 1, 1.0, 1.0, 1.0);
  const std::vector<ElementFace> faces = boundaryOf(block);
  EXPECT_THROW(checkSurfaceCrossings(block, faces, Eigen::VectorXd::Zero(5)), std::invalid_argument);
  EXPECT_THROW(checkSurfaceCrossings(block, faces, Eigen::VectorXd::Zero(3 * block.nodeCount()), 0.0, 0),
               std::invalid_argument);
  EXPECT_EQ(checkSurfaceCrossings(block, {}, Eigen::VectorXd::Zero(3 * block.nodeCount())).crossingPairs, 0);
}

} // namespace
} // namespace caps::fem
