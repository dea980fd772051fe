// The whole-face model without a plan (thesis §5.3) on the sample CT, and
// real-time expressions by superposition (§3.1.2): the mesh lies on the skin
// and reaches the bone; unit muscle responses summed with weights equal a
// direct solve of the combined load; the display skin moved by the weighted
// sum equals the skin displaced by that solve, point by point.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "SampleFace.h"
#include "fem/BodyCoordinates.h"
#include "fem/ContinuumMesher.h"
#include "fem/DisplaySurface.h"
#include "fem/StaticAnalysis.h"
#include "planning/FaceModel.h"
#include "planning/MuscleResponses.h"
#include "planning/PlanSimulation.h"

namespace caps::expression {
namespace {

constexpr double kPi = std::numbers::pi;

const seg::Landmark& landmark(const std::string& name)
{
  for (const seg::Landmark& l : test::sampleFace().landmarks.landmarks)
    if (l.name == name)
      return l;
  throw std::runtime_error("the sample has no landmark " + name);
}

/// A point @a depth mm under the skin at (θ, z) of a landmark moved by (dθ, dz).
Eigen::Vector3d underSkin(const std::string& name, double dTheta, double dz, double depth)
{
  const seg::RangeMap& skin = test::sampleFace().maps.skin;
  const seg::Landmark& l = landmark(name);
  const double r = skin.sample(l.theta + dTheta, l.z + dz);
  return skin.frame().toWorld(r - depth, l.theta + dTheta, l.z + dz);
}

/// The coarse face model the tests share (8 mm elements: quick, same code).
struct Model
{
  FaceMesh face;
  std::unique_ptr<fem::LinearStaticAnalysis> analysis;
};

const Model& coarseFace()
{
  static const std::unique_ptr<Model> model = [] {
    auto m = std::make_unique<Model>();
    const auto& sample = test::sampleFace();
    FaceModelOptions options;
    options.elementSize = 8.0;
    m->face = meshFace(sample.maps.skin, sample.maps.bone, sample.landmarks.landmarks, options);
    fem::AssemblyOptions assembly;
    assembly.threads = 2;
    m->analysis = std::make_unique<fem::LinearStaticAnalysis>(m->face.continuum.mesh, m->face.materials,
                                                              m->face.continuum.constraints(), assembly);
    EXPECT_EQ(m->analysis->prepare(), fem::SolverStatus::Success) << m->analysis->message();
    return m;
  }();
  return *model;
}

/// Three muscle-like sets of force functions on the sample's face: a cheek
/// muscle from the left mouth corner to over the zygoma (two functions), one
/// pulling the chin down, one across the forehead, with origins in the bone.
std::vector<std::vector<fem::Muscle>> testMuscles()
{
  const double mouthCorner = 25.0 / 85.0; // rad: about 25 mm of arc from the midline
  fem::Muscle cheekUpper{"cheek upper",
                         underSkin("zygion_left", -0.15, 5.0, 6.0),
                         0.0,
                         underSkin("labrale_superius", mouthCorner, -4.0, 4.0),
                         7.0,
                         5.0e-5,
                         2.0};
  fem::Muscle cheekLower = cheekUpper;
  cheekLower.name = "cheek lower";
  cheekLower.insertion = underSkin("labrale_inferius", mouthCorner, 4.0, 4.0);
  fem::Muscle chin{
    "chin", underSkin("menton", 0.0, -5.0, 8.0), 0.0, underSkin("labrale_inferius", 0.0, -5.0, 4.0), 6.0, 8.0e-5, 1.5};
  fem::Muscle brow{
    "brow", underSkin("forehead", 0.35, 0.0, 5.0), 4.0, underSkin("glabella", 0.08, 5.0, 3.0), 6.0, 5.0e-5, 0.0};
  return {{cheekUpper, cheekLower}, {chin}, {brow}};
}

TEST(FaceModel, TheWholeFaceIsMeshedFromTheSkinToTheBone)
{
  const auto& sample = test::sampleFace();
  const FaceMesh& face = coarseFace().face;
  const fem::ContinuumMesh& c = face.continuum;
  const seg::RangeMap& skin = sample.maps.skin;
  const seg::CylindricalFrame& frame = skin.frame();

  // Zygion to zygion, chin to forehead.
  EXPECT_LT(face.region.thetaMin, landmark("zygion_right").theta);
  EXPECT_GT(face.region.thetaMax, landmark("zygion_left").theta);
  EXPECT_LE(face.region.zMin, landmark("menton").z + 1e-9);
  EXPECT_GE(face.region.zMax, landmark("forehead").z);

  // The counts of §4.5.2 for a mesh without a cut, no sutures, the bone layer fixed.
  const Eigen::Index nv = Eigen::Index(face.surface.vertices.size()), ne = Eigen::Index(c.edges.size());
  const Eigen::Index nl = 3, np = Eigen::Index(face.surface.polygons.size());
  EXPECT_EQ(c.mesh.nodeCount(), nl * (2 * nv + ne) + nv + ne);
  EXPECT_EQ(Eigen::Index(c.mesh.elements.size()), nl * np);
  EXPECT_TRUE(c.sutures.empty());
  EXPECT_EQ(c.fixedNodes, c.boneNodes);
  std::printf("[face model, 8 mm] %ld quads (%d without skin), %ld nodes, %ld DOF, region %.0f..%.0f deg, "
              "z %.0f..%.0f mm\n",
              long(np), face.quadsWithoutSkin, long(c.mesh.nodeCount()), long(c.mesh.dofCount()),
              face.region.thetaMin * 180 / kPi, face.region.thetaMax * 180 / kPi, face.region.zMin, face.region.zMax);

  // Every skin node lies on the skin map, and every column runs along the
  // ray towards the axis down to the depth the mesher was given.
  const seg::RangeMap boneForDepth = planning::boneForTissueDepth(skin, sample.maps.bone, 10.0, 8);
  double worstSkin = 0.0, worstDepth = 0.0, worstRay = 0.0;
  for (std::size_t v = 0; v < c.vertexColumns.size(); ++v)
  {
    const Eigen::Vector3d top = c.mesh.nodes.col(c.vertexColumns[v].front());
    const Eigen::Vector3d bottom = c.mesh.nodes.col(c.vertexColumns[v].back());
    const seg::CylindricalPoint p = frame.toCylindrical(top);
    worstSkin = std::max(worstSkin, std::abs(p.r - skin.sample(p.theta, p.z)));
    const seg::CylindricalPoint q = frame.toCylindrical(bottom);
    worstRay = std::max(worstRay, std::abs(q.theta - p.theta) * p.r + std::abs(q.z - p.z));
    double expected = p.r - boneForDepth.sample(p.theta, p.z);
    expected = std::isfinite(expected) ? std::clamp(expected, 2.0, 40.0) : 10.0;
    worstDepth = std::max(worstDepth, std::abs((p.r - q.r) - expected));
  }
  EXPECT_LT(worstSkin, 1e-6);
  EXPECT_LT(worstRay, 1e-6);
  EXPECT_LT(worstDepth, 1e-6);
}

TEST(FaceModel, MissingLandmarksAreNamed)
{
  const auto& sample = test::sampleFace();
  std::vector<seg::Landmark> some;
  for (const seg::Landmark& l : sample.landmarks.landmarks)
    if (l.name != "zygion_left" && l.name != "forehead")
      some.push_back(l);
  try
  {
    meshFace(sample.maps.skin, sample.maps.bone, some);
    FAIL() << "a face model without its landmarks";
  }
  catch (const std::invalid_argument& e)
  {
    const std::string message = e.what();
    EXPECT_NE(message.find("zygion_left"), std::string::npos) << message;
    EXPECT_NE(message.find("forehead"), std::string::npos) << message;
    EXPECT_EQ(message.find("menton"), std::string::npos) << message;
  }
}

TEST(Superposition, WeightedUnitResponsesEqualTheDirectSolveOfTheCombinedLoad)
{
  const Model& model = coarseFace();
  fem::LinearStaticAnalysis& analysis = *model.analysis;
  const auto muscles = testMuscles();
  const MuscleResponses responses(analysis, muscles);
  ASSERT_EQ(responses.muscleCount(), 3);
  for (Eigen::Index k = 0; k < 3; ++k)
    EXPECT_GT(responses.displacements().col(k).cwiseAbs().maxCoeff(), 0.05) << "muscle " << k << " moves nothing";

  for (const Eigen::Vector3d& a :
       {Eigen::Vector3d(0.3, 1.0, 0.55), Eigen::Vector3d(1.0, 0.0, 0.0), Eigen::Vector3d(0.75, 0.2, 1.0)})
  {
    // The direct way: one load case with every function's load scaled by its muscle's activation.
    fem::LoadCase combined;
    for (std::size_t k = 0; k < muscles.size(); ++k)
      for (fem::Muscle m : muscles[k])
      {
        m.load *= a[Eigen::Index(k)];
        if (m.load > 0.0)
          combined.muscles.push_back(m);
      }
    const Eigen::VectorXd direct = analysis.solve(combined);
    const Eigen::VectorXd summed = responses.combined(a);
    const double relative = (summed - direct).norm() / direct.norm();
    std::printf("[superposition] activations (%.2f, %.2f, %.2f): |U| %.3f mm, relative difference %.2e\n", a[0], a[1],
                a[2], direct.cwiseAbs().maxCoeff(), relative);
    EXPECT_LT(relative, 1e-9);
  }
  EXPECT_THROW(responses.combined(Eigen::VectorXd::Ones(2)), std::invalid_argument);
}

TEST(Superposition, TheDisplaySkinMovesAsTheDisplacedBody)
{
  const Model& model = coarseFace();
  const fem::Mesh& mesh = model.face.continuum.mesh;
  const MuscleResponses responses(*model.analysis, testMuscles());
  const ExpressionSurface surface(mesh, fem::DisplaySurface(mesh, fem::skinFaces(model.face.continuum), 2), responses);
  const Eigen::Vector3d a(0.8, 0.4, 0.6);
  Eigen::Matrix3Xd x;
  surface.positions(a, false, x);
  // The second way: the body points displaced by the combined solution (eq. 4.15).
  const Eigen::VectorXd u = responses.combined(a);
  double worst = 0.0, largest = 0.0;
  for (Eigen::Index v = 0; v < surface.vertexCount(); ++v)
  {
    const Eigen::Vector3d expected = fem::displacedWorldPoint(mesh, u, surface.surface().bodyPoints()[std::size_t(v)]);
    worst = std::max(worst, (x.col(v) - expected).norm());
    largest = std::max(largest, (x.col(v) - surface.surface().undeformedPositions().col(v)).norm());
  }
  std::printf("[expression surface] %ld vertices, largest movement %.3f mm, worst difference %.2e mm\n",
              long(surface.vertexCount()), largest, worst);
  EXPECT_GT(largest, 0.1);
  EXPECT_LT(worst, 1e-9);

  // Muscles pull: the cheek muscle alone moves the skin over its insertion
  // towards its origin (§4.6.2: the insertion tissue is pulled towards the origin).
  const fem::Muscle& cheek = testMuscles()[0][0];
  surface.positions(Eigen::Vector3d(1.0, 0.0, 0.0), false, x);
  Eigen::Index nearest = 0;
  for (Eigen::Index v = 0; v < surface.vertexCount(); ++v)
    if ((surface.surface().undeformedPositions().col(v) - cheek.insertion).norm() <
        (surface.surface().undeformedPositions().col(nearest) - cheek.insertion).norm())
      nearest = v;
  const Eigen::Vector3d moved = x.col(nearest) - surface.surface().undeformedPositions().col(nearest);
  const Eigen::Vector3d pull = (cheek.origin - cheek.insertion).normalized();
  EXPECT_GT(moved.dot(pull), 0.5 * moved.norm()) << "moved " << moved.transpose() << ", pull " << pull.transpose();
}

} // namespace
} // namespace caps::expression
