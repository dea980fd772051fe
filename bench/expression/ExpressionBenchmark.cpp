// "A slider moved" → "the expression face updated" on the sample CT's whole
// face (target: under 16 ms), against solving the same combined
// muscle load with the finite element model (factor kept) in the same run:
// the superposition of §3.1.2 is a weighted sum of the unit responses and a
// rewrite of the surface's points, no finite element work.
//
// Also prints what the one-time preparation costs (mesh, factorisation, one
// solve per muscle, interpolation to the display skin) and, per muscle at
// activation 1, how far the skin moves (the calibration of data/muscles).
//
// Usage: caps_bench_expression [--element-size MM] [--resolution N] [--updates N]
// Not a test: prints times and ratios only.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataNormals.h>

#include "bench/BestOf.h"
#include "fem/DisplaySurface.h"
#include "fem/StaticAnalysis.h"
#include "planning/FaceModel.h"
#include "planning/MuscleResponses.h"
#include "planning/MuscleSet.h"
#include "planning/PlanUnderExpression.h"
#include "modules/incision/IncisionLogic.h"
#include "planning/PlanDisplay.h"
#include "modules/rangemap/RangeMapLogic.h"
#include "modules/volumes/CommandLine.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"
#include "segmentation/LandmarkPlacement.h"

using namespace caps;

namespace {

double secondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

int main(int argc, char** argv)
{
  expression::FaceModelOptions options;
  int resolution = 2, updates = 2000;
  for (int i = 1; i + 1 < argc; i += 2)
  {
    const std::string key = argv[i];
    if (key == "--element-size")
      options.elementSize = std::atof(argv[i + 1]);
    else if (key == "--resolution")
      resolution = std::atoi(argv[i + 1]);
    else if (key == "--updates")
      updates = std::atoi(argv[i + 1]);
    else
    {
      std::fprintf(stderr, "usage: caps_bench_expression [--element-size MM] [--resolution N] [--updates N]\n");
      return 2;
    }
  }

  // Once per patient, before the clock: CT, range maps, landmarks.
  Scene scene;
  RangeMapLogic logic(scene);
  std::ostringstream quiet;
  VolumeNode* volume = cli::loadCt(logic, CAPS_SAMPLE_CT, seg::CtReadOptions{}, quiet);
  RangeMapOutput maps;
  logic.run(*volume, RangeMapLogic::Parameters{}, {}, &maps);
  const seg::LandmarkPlacement landmarks = seg::placeLandmarks(maps.skin, maps.bone);

  // Once per face model.
  auto start = std::chrono::steady_clock::now();
  const expression::FaceMesh face = expression::meshFace(maps.skin, maps.bone, landmarks.landmarks, options);
  const double meshSeconds = secondsSince(start);
  const std::vector<expression::FittedMuscle> muscles = expression::fitMuscleSet(
    expression::readMuscleSet(expression::defaultMuscleSetPath()), landmarks.landmarks, maps.skin, maps.bone);
  std::vector<std::vector<fem::Muscle>> functions;
  for (const auto& m : muscles)
    functions.push_back(m.functions);
  fem::AssemblyOptions assembly;
  assembly.threads = 2;
  fem::LinearStaticAnalysis analysis(face.continuum.mesh, face.materials, face.continuum.constraints(), assembly);
  start = std::chrono::steady_clock::now();
  if (analysis.prepare() != fem::SolverStatus::Success)
  {
    std::fprintf(stderr, "the face model cannot be solved: %s\n", analysis.message().c_str());
    return 1;
  }
  const double prepareSeconds = secondsSince(start);
  start = std::chrono::steady_clock::now();
  const expression::MuscleResponses responses(analysis, functions);
  const double responseSeconds = secondsSince(start);
  start = std::chrono::steady_clock::now();
  const fem::Mesh& mesh = face.continuum.mesh;
  const expression::ExpressionSurface surface(
    mesh, fem::DisplaySurface(mesh, fem::skinFaces(face.continuum), resolution), responses);
  const double surfaceSeconds = secondsSince(start);

  std::printf("Whole-face model of the sample (element size %.1f mm, %d layers): %zu quads, %ld nodes, %ld DOF\n",
              options.elementSize, options.layerCount, face.surface.polygons.size(), long(mesh.nodeCount()),
              long(mesh.dofCount()));
  std::printf("  once: mesh %.3f s, assemble + factor %.3f s, %ld unit responses %.3f s, display skin (%ld "
              "vertices, resolution %d) %.3f s\n",
              meshSeconds, prepareSeconds, long(responses.muscleCount()), responseSeconds, long(surface.vertexCount()),
              resolution, surfaceSeconds);

  // Calibration: each muscle alone at activation 1.
  std::printf("\n  %-44s %10s %12s\n", "muscle at activation 1", "force (N)", "skin moves (mm)");
  for (std::size_t k = 0; k < muscles.size(); ++k)
  {
    Eigen::VectorXd a = Eigen::VectorXd::Zero(responses.muscleCount());
    a[Eigen::Index(k)] = 1.0;
    Eigen::Matrix3Xd x;
    surface.positions(a, false, x);
    const double moved = (x - surface.surface().undeformedPositions()).colwise().norm().maxCoeff();
    double force = 0.0;
    for (const fem::MuscleForces& f : responses.forces()[k])
      force += f.insertionForce.norm();
    std::printf("  %-44s %10.2f %12.2f\n", muscles[k].title.c_str(), force, moved);
  }

  // The display surface as the workstation holds it: points and polygons.
  vtkNew<vtkPolyData> polyData;
  vtkNew<vtkPoints> points;
  points->SetDataTypeToFloat();
  points->SetNumberOfPoints(surface.vertexCount());
  vtkNew<vtkCellArray> polygons;
  for (const auto& p : surface.surface().polygons())
  {
    polygons->InsertNextCell(vtkIdType(p.size()));
    for (int v : p)
      polygons->InsertCellPoint(v);
  }
  polyData->SetPoints(points);
  polyData->SetPolys(polygons);

  // Slider updates: random activations, each a weighted sum and a points rewrite.
  std::mt19937 random(42);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Eigen::VectorXd> mixes(std::size_t(std::max(1, updates)));
  for (auto& a : mixes)
  {
    a.resize(responses.muscleCount());
    for (Eigen::Index k = 0; k < a.size(); ++k)
      a[k] = unit(random);
  }
  Eigen::Matrix3Xd x;
  auto* raw = static_cast<vtkFloatArray*>(points->GetData());
  std::vector<double> updateMs;
  updateMs.reserve(mixes.size());
  for (const Eigen::VectorXd& a : mixes)
  {
    const auto t = std::chrono::steady_clock::now();
    surface.positions(a, true, x);
    float* out = raw->GetPointer(0);
    for (Eigen::Index v = 0; v < x.cols(); ++v)
      for (int c = 0; c < 3; ++c)
        out[3 * v + c] = float(x(c, v));
    points->Modified();
    updateMs.push_back(1e3 * secondsSince(t));
  }
  std::sort(updateMs.begin(), updateMs.end());
  const double median = updateMs[updateMs.size() / 2], worst = updateMs.back();

  // With the normals the renderer shades by, recomputed for the new shape.
  const double normalsMs = 1e3 * bench::secondsOf(
                                   [&] {
                                     vtkNew<vtkPolyDataNormals> normals;
                                     normals->SetInputData(polyData);
                                     normals->SplittingOff();
                                     normals->Update();
                                   },
                                   20);

  // Reference: the same combined load solved by the finite element model
  // (its factorisation kept): load vector, substitution, expansion.
  fem::LoadCase combined;
  for (std::size_t k = 0; k < functions.size(); ++k)
    for (fem::Muscle m : functions[k])
    {
      m.load *= mixes.front()[Eigen::Index(k)];
      combined.muscles.push_back(m);
    }
  const double directMs = 1e3 * bench::secondsOf([&] { analysis.solve(combined); }, 3);

  std::printf("\n  slider update (weighted sum of %ld responses + %ld points rewritten), %zu updates: median %.3f "
              "ms, worst %.3f ms\n",
              long(responses.muscleCount()), long(surface.vertexCount()), updateMs.size(), median, worst);
  std::printf("  + surface normals for shading: %.3f ms -> %.3f ms per update (target 16 ms: %.1f %% of it)\n",
              normalsMs, median + normalsMs, 100.0 * (median + normalsMs) / 16.0);
  std::printf("  reference, the same load solved by the FE model (factor kept): %.1f ms = %.0fx the update\n", directMs,
              directMs / (median + normalsMs));

  // A fingertip pushing the cheek below the demo's Z-plasty (§5.4): three
  // unit pushes solved once, then a point of the path is their weighted sum
  // on the plan's display skin; the reference factors the plan's model
  // afresh for the same travel, as a push without superposition must.
  IncisionLogic incisionLogic(scene);
  const planning::IncisionPlan z = incisionLogic.placeProcedure(
    "z-plasty", maps.skin, planning::SkinPoint{-40.0 * std::numbers::pi / 180.0, -47.0}, {});
  planning::SimulationOptions simulation;
  simulation.threads = 2;
  const planning::PlanPrediction prediction = planning::simulatePlan(maps.skin, maps.bone, z, simulation);
  const auto& columns = prediction.continuum.vertexColumns;
  const int tip = columns[columns.size() / 2].front();
  expression::PushPath path;
  path.centre = prediction.continuum.mesh.nodes.col(tip) + prediction.displacements.segment<3>(3 * Eigen::Index(tip));
  path.radius = 5.0;
  path.waypoints = {Eigen::Vector3d(0.0, 0.0, 6.0), Eigen::Vector3d(3.0, -1.0, 6.0)};
  start = std::chrono::steady_clock::now();
  const expression::PushResponses push(prediction, path.centre, path.radius);
  const double pushSeconds = secondsSince(start);
  const planning::PlanDisplay display = planning::buildPlanDisplay(prediction, maps.skin);
  const expression::ExpressionSurface pushedSkin(prediction.continuum.mesh, display.surface, push.responses(),
                                                 prediction.displacements);
  std::vector<double> travelMs;
  for (int k = 0; k < std::max(1, updates); ++k)
  {
    const auto t = std::chrono::steady_clock::now();
    pushedSkin.positions(path.travelAt(unit(random)), true, x);
    travelMs.push_back(1e3 * secondsSince(t));
  }
  std::sort(travelMs.begin(), travelMs.end());
  expression::SkinPush fresh;
  fresh.centre = path.centre;
  fresh.radius = path.radius;
  fresh.displacement = path.travelAt(0.5);
  const double freshMs = 1e3 * bench::secondsOf([&] { expression::pushedDisplacement(prediction, fresh); }, 2);
  const Eigen::VectorXd half = push.displacement(path.travelAt(0.5));
  const double bumpsMs =
    1e3 * bench::secondsOf(
            [&] { expression::compareContours(prediction, maps.skin.frame(), prediction.displacements, half); }, 3);
  std::printf("\nFingertip on the Z-plasty's model (%ld DOF, %zu skin nodes held, radius %.0f mm):\n",
              long(prediction.continuum.mesh.dofCount()), push.pushedNodes().size(), path.radius);
  std::printf("  once: three unit pushes (one factorisation) %.3f s\n", pushSeconds);
  std::printf("  travel update on the plan's skin (%ld vertices), %zu updates: median %.3f ms, worst %.3f ms\n",
              long(pushedSkin.vertexCount()), travelMs.size(), travelMs[travelMs.size() / 2], travelMs.back());
  std::printf("  reference, the model factored afresh for one travel: %.1f ms = %.0fx the update\n", freshMs,
              freshMs / travelMs[travelMs.size() / 2]);
  std::printf("  contour bumps at rest and pushed compared: %.1f ms\n", bumpsMs);
  return 0;
}
