#include "planning/PlanUnderExpression.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

#include "fem/BodyCoordinates.h"

namespace caps::expression {
namespace {

/// The skin vertices of the plan's surface mesh within @a window of a hole-loop vertex.
std::vector<int> windowVertices(const planning::PlanPrediction& prediction, double window)
{
  const fem::SurfaceMesh& surface = prediction.surface.mesh;
  std::vector<int> out;
  for (int v = 0; v < int(surface.vertices.size()); ++v)
    for (int h = 0; h < surface.holeVertexCount; ++h)
      if ((surface.vertices[std::size_t(v)] - surface.vertices[std::size_t(h)]).norm() <= window)
      {
        out.push_back(v);
        break;
      }
  return out;
}

Eigen::Vector3d displaced(const planning::PlanPrediction& prediction, const Eigen::VectorXd& u, int node)
{
  return prediction.continuum.mesh.nodes.col(node) + u.segment<3>(3 * Eigen::Index(node));
}

void checkSize(const planning::PlanPrediction& prediction, const Eigen::VectorXd& u)
{
  if (u.size() != prediction.continuum.mesh.dofCount())
    throw std::invalid_argument("the displacement is not of the plan's model (" + std::to_string(u.size()) +
                                " values for " + std::to_string(prediction.continuum.mesh.dofCount()) + " DOF)");
}

} // namespace

PlanExpressionResponses::PlanExpressionResponses(const planning::PlanPrediction& prediction, const fem::Mesh& faceMesh,
                                                 const MuscleResponses& faceResponses,
                                                 const std::vector<std::vector<fem::Muscle>>& muscles, int threads)
  : closure_(prediction.displacements)
{
  const fem::ContinuumMesh& c = prediction.continuum;
  checkSize(prediction, closure_);
  if (Eigen::Index(muscles.size()) != faceResponses.muscleCount())
    throw std::invalid_argument("the face model's responses are of another muscle list");
  // The rim nodes the face model moves: the bone holds the fixed ones in
  // both models, and a sutured node follows its suture.
  std::vector<char> held(std::size_t(c.mesh.nodeCount()), 0);
  for (int node : c.fixedNodes)
    held[std::size_t(node)] = 1;
  for (const fem::Suture& s : c.sutures)
    held[std::size_t(s.node)] = 1;
  for (int node : c.rimNodes)
    if (!held[std::size_t(node)])
      rimNodes_.push_back(node);

  // Where each rim node lies in the face model. The two meshes follow the
  // same skin and bone with different elements, so a node on the skin or
  // the bone may fall just outside the face mesh: look a little way along
  // the ray to the axis as well.
  const fem::BodyCoordinateLocator locator(faceMesh);
  std::vector<fem::BodyPoint> inFace;
  inFace.reserve(rimNodes_.size());
  for (int node : rimNodes_)
  {
    const Eigen::Vector3d x = c.mesh.nodes.col(node);
    std::optional<fem::BodyPoint> found = locator.find(x);
    const Eigen::Vector3d outward = (x - faceMesh.nodes.rowwise().mean()).normalized();
    for (double step = 0.25; !found && step <= 3.0; step += 0.25)
      for (double sign : {-1.0, 1.0})
        if (!found)
          found = locator.find(x + sign * step * outward);
    if (!found)
      throw std::invalid_argument(
        "the plan's model reaches beyond the whole-face model (a rim node at " +
        std::to_string(int(std::lround(x.x()))) + ", " + std::to_string(int(std::lround(x.y()))) + ", " +
        std::to_string(int(std::lround(x.z()))) + " mm): move the plan onto the face or make the face region larger");
    inFace.push_back(*found);
  }

  // One factorisation with the rim prescribed where the closure put it.
  fem::Constraints atRest = c.constraints();
  for (int node : rimNodes_)
    for (int d = 0; d < 3; ++d)
      atRest.prescribe(node, d, closure_[3 * Eigen::Index(node) + d]);
  fem::AssemblyOptions assembly;
  assembly.threads = threads;
  fem::LinearStaticAnalysis analysis(c.mesh, prediction.materials, atRest, assembly);
  if (analysis.prepare() != fem::SolverStatus::Success)
    throw std::runtime_error("the plan's model cannot be solved under the expression: " + analysis.message());

  // Per muscle: the rim moved as the face moves under it, its load inside.
  responses_.resize(closure_.size(), Eigen::Index(muscles.size()));
  for (std::size_t k = 0; k < muscles.size(); ++k)
  {
    const Eigen::VectorXd faceU = faceResponses.displacements().col(Eigen::Index(k));
    fem::Constraints moved = c.constraints();
    for (std::size_t n = 0; n < rimNodes_.size(); ++n)
    {
      const Eigen::Vector3d follow = fem::displacementAt(faceMesh, faceU, inFace[n]);
      for (int d = 0; d < 3; ++d)
        moved.prescribe(rimNodes_[n], d, closure_[3 * Eigen::Index(rimNodes_[n]) + d] + follow[d]);
    }
    const Eigen::VectorXd load = fem::assembleMuscleLoad(c.mesh, muscles[k]).load;
    responses_.col(Eigen::Index(k)) = analysis.solveWithPrescribed(load, moved).col(0) - closure_;
  }
}

Eigen::VectorXd PlanExpressionResponses::displacement(const Eigen::VectorXd& activations) const
{
  if (activations.size() != responses_.cols())
    throw std::invalid_argument("got " + std::to_string(activations.size()) + " activations for " +
                                std::to_string(responses_.cols()) + " muscles");
  return closure_ + responses_ * activations;
}

std::unique_ptr<fem::LinearStaticAnalysis> postOperativeAnalysis(const planning::PlanPrediction& prediction,
                                                                 int threads)
{
  fem::AssemblyOptions assembly;
  assembly.threads = threads;
  auto analysis = std::make_unique<fem::LinearStaticAnalysis>(prediction.continuum.mesh, prediction.materials,
                                                              prediction.continuum.constraints(), assembly);
  if (analysis->prepare() != fem::SolverStatus::Success)
    throw std::runtime_error("the plan's model cannot be solved under load: " + analysis->message());
  return analysis;
}

namespace {

/// The skin nodes of the plan's model within @a radius of @a centre where the
/// closure put them, sutured nodes left to their sutures.
std::vector<int> fingertipNodes(const planning::PlanPrediction& prediction, const Eigen::Vector3d& centre,
                                double radius)
{
  const fem::ContinuumMesh& c = prediction.continuum;
  checkSize(prediction, prediction.displacements);
  if (!(radius > 0.0) || !centre.allFinite())
    throw std::invalid_argument("a push needs a fingertip radius above 0 mm and a finite centre");
  std::vector<char> sutured(std::size_t(c.mesh.nodeCount()), 0);
  for (const fem::Suture& s : c.sutures)
    sutured[std::size_t(s.node)] = 1;
  // The skin nodes: the top of every vertex and edge column.
  std::vector<int> skinNodes;
  for (const auto& column : c.vertexColumns)
    skinNodes.push_back(column.front());
  for (const auto& column : c.edgeColumns)
    if (!column.empty() && column.front() >= 0)
      skinNodes.push_back(column.front());
  std::vector<int> out;
  for (int node : skinNodes)
    if (!sutured[std::size_t(node)] &&
        (displaced(prediction, prediction.displacements, node) - centre).norm() <= radius)
      out.push_back(node);
  if (out.empty())
    throw std::invalid_argument("no skin of the plan's model lies under the fingertip: put it on the meshed skin "
                                "around the incision");
  return out;
}

/// The plan's constraints with @a nodes held at the closure moved by @a travel.
fem::Constraints heldBy(const planning::PlanPrediction& prediction, const std::vector<int>& nodes,
                        const Eigen::Vector3d& travel)
{
  fem::Constraints constraints = prediction.continuum.constraints();
  for (int node : nodes)
    for (int d = 0; d < 3; ++d)
      constraints.prescribe(node, d, prediction.displacements[3 * Eigen::Index(node) + d] + travel[d]);
  return constraints;
}

} // namespace

Eigen::VectorXd pushedDisplacement(const planning::PlanPrediction& prediction, const SkinPush& push, int threads)
{
  if (!push.displacement.allFinite())
    throw std::invalid_argument("a push needs a finite displacement");
  const std::vector<int> nodes = fingertipNodes(prediction, push.centre, push.radius);
  fem::AssemblyOptions assembly;
  assembly.threads = threads;
  fem::LinearStaticAnalysis analysis(prediction.continuum.mesh, prediction.materials,
                                     heldBy(prediction, nodes, push.displacement), assembly);
  if (analysis.prepare() != fem::SolverStatus::Success)
    throw std::runtime_error("the plan's model cannot be solved under the push: " + analysis.message());
  return analysis.solve(fem::LoadCase{});
}

PushResponses::PushResponses(const planning::PlanPrediction& prediction, const Eigen::Vector3d& centre, double radius,
                             int threads)
  : closure_(prediction.displacements), pushedNodes_(fingertipNodes(prediction, centre, radius))
{
  // One factorisation with the fingertip's nodes held, then one solve per
  // direction with the new prescribed values (the factor depends only on
  // which DOFs are prescribed, not on their values).
  fem::AssemblyOptions assembly;
  assembly.threads = threads;
  fem::LinearStaticAnalysis analysis(prediction.continuum.mesh, prediction.materials,
                                     heldBy(prediction, pushedNodes_, Eigen::Vector3d::Zero()), assembly);
  if (analysis.prepare() != fem::SolverStatus::Success)
    throw std::runtime_error("the plan's model cannot be solved under the push: " + analysis.message());
  const Eigen::VectorXd noLoad = Eigen::VectorXd::Zero(closure_.size());
  responses_.resize(closure_.size(), 3);
  for (int d = 0; d < 3; ++d)
    responses_.col(d) =
      analysis.solveWithPrescribed(noLoad, heldBy(prediction, pushedNodes_, Eigen::Vector3d::Unit(d))).col(0) -
      closure_;
}

Eigen::VectorXd PushResponses::displacement(const Eigen::Vector3d& travel) const
{
  return closure_ + responses_ * travel;
}

double PushPath::length() const
{
  double total = 0.0;
  Eigen::Vector3d from = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& to : waypoints)
  {
    total += (to - from).norm();
    from = to;
  }
  return total;
}

Eigen::Vector3d PushPath::travelAt(double s) const
{
  const double total = length();
  if (!(total > 0.0))
    return Eigen::Vector3d::Zero();
  double left = std::clamp(s, 0.0, 1.0) * total;
  Eigen::Vector3d from = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& to : waypoints)
  {
    const double leg = (to - from).norm();
    if (left <= leg && leg > 0.0)
      return from + (left / leg) * (to - from);
    left -= leg;
    from = to;
  }
  return waypoints.back();
}

ContourBumps contourBumps(const planning::PlanPrediction& prediction, const seg::CylindricalFrame& frame,
                          const Eigen::VectorXd& u, double window)
{
  checkSize(prediction, u);
  const std::vector<int> inWindow = windowVertices(prediction, window);
  ContourBumps out;
  out.vertices = int(inWindow.size());
  if (inWindow.size() < 12)
    throw std::invalid_argument("too few skin vertices around the incision to measure its contour: widen the window");
  // The skin as it is after the operation (and the load): every skin vertex's
  // displaced point as (arc, z, height r) about the head axis.
  const auto& columns = prediction.continuum.vertexColumns;
  std::vector<Eigen::Vector3d> shape(columns.size()), points(columns.size());
  double radiusSum = 0.0;
  for (std::size_t v = 0; v < columns.size(); ++v)
  {
    points[v] = displaced(prediction, u, columns[v].front());
    const seg::CylindricalPoint c = frame.toCylindrical(points[v]);
    shape[v] = Eigen::Vector3d(c.theta, c.z, c.r);
    // The arc's scale from the skin before the operation, so it does not
    // change with the load (a neighbourhood is the same skin either way).
    radiusSum += frame.toCylindrical(prediction.continuum.mesh.nodes.col(columns[v].front())).r;
  }
  const double r0 = radiusSum / double(columns.size());
  const double centreTheta = shape[std::size_t(inWindow.front())].x();
  for (auto& p : shape) // θ to mm of arc, unwrapped about the window (the seam never falls in it)
    p.x() = r0 * std::remainder(p.x() - centreTheta, 2.0 * std::numbers::pi);

  // A bump is a vertex's height above or below the quadratic that fits the
  // skin around it, within kNeighbourhood but not the vertex itself (moving
  // least squares, leave one out): the cheek's own curve and any smooth
  // movement are taken out exactly, a dog-ear or a ridge stands out of it.
  constexpr double kNeighbourhood = 10.0;
  double sumSquares = 0.0;
  int measured = 0;
  for (int v : inWindow)
  {
    const Eigen::Vector3d& here = shape[std::size_t(v)];
    std::vector<std::size_t> near;
    for (std::size_t w = 0; w < shape.size(); ++w)
      if (w != std::size_t(v) && (shape[w].head<2>() - here.head<2>()).norm() <= kNeighbourhood)
        near.push_back(w);
    if (near.size() < 10)
      continue;
    Eigen::MatrixXd basis(Eigen::Index(near.size()), 6);
    Eigen::VectorXd height(Eigen::Index(near.size()));
    for (std::size_t k = 0; k < near.size(); ++k)
    {
      const double x = shape[near[k]].x() - here.x(), y = shape[near[k]].y() - here.y();
      basis.row(Eigen::Index(k)) << 1.0, x, y, x * x, x * y, y * y;
      height[Eigen::Index(k)] = shape[near[k]].z();
    }
    // The fit's value at the vertex itself is its constant term.
    const double fit = basis.colPivHouseholderQr().solve(height)[0];
    const double bump = here.z() - fit;
    sumSquares += bump * bump;
    ++measured;
    if (std::abs(bump) > out.largest)
    {
      out.largest = std::abs(bump);
      out.where = points[std::size_t(v)];
    }
  }
  out.rms = measured > 0 ? std::sqrt(sumSquares / measured) : 0.0;
  return out;
}

ContourComparison compareContours(const planning::PlanPrediction& prediction, const seg::CylindricalFrame& frame,
                                  const Eigen::VectorXd& rest, const Eigen::VectorXd& loaded, double window)
{
  ContourComparison out;
  out.rest = contourBumps(prediction, frame, rest, window);
  out.loaded = contourBumps(prediction, frame, loaded, window);
  for (int v : windowVertices(prediction, window))
  {
    const int node = prediction.continuum.vertexColumns[std::size_t(v)].front();
    const Eigen::Vector3d a = displaced(prediction, rest, node), b = displaced(prediction, loaded, node);
    const double change = std::abs(frame.toCylindrical(b).r - frame.toCylindrical(a).r);
    if (change > out.largestHeightChange)
    {
      out.largestHeightChange = change;
      out.where = b;
    }
  }
  return out;
}

} // namespace caps::expression
