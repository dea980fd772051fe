#include "modules/expression/PlanStudy.h"

#include <chrono>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Geometry>

#include <vtkCellArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkUnsignedCharArray.h>

#include "planning/PlanDisplay.h"
#include "segmentation/SkinShade.h"

namespace caps::expression {
namespace {

double secondsSince(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

std::unique_ptr<PlanStudy> PlanStudy::build(const PlanStudyInput& input, const TaskProgress& progress)
{
  const auto start = std::chrono::steady_clock::now();
  const auto step = [&progress](double fraction, const std::string& what) {
    return !progress || progress(fraction, what);
  };
  if (!input.model)
    throw std::invalid_argument("build the face model first: the plan is studied inside it");
  if (input.skin.frame() != input.model->frame)
    throw std::invalid_argument("plan \"" + input.planName +
                                "\" lies on another skin map than the face model: "
                                "build the face model again from the plan's range maps");
  std::unique_ptr<PlanStudy> study(new PlanStudy());
  study->planName_ = input.planName;
  study->frame_ = input.skin.frame();
  study->window_ = input.window;

  // The prediction as it was made (the plan's recorded options), as the
  // report predicts it again: the scene keeps its result, not its model.
  if (!step(0.0, "Predicting " + input.planName + " again"))
    return nullptr;
  auto t = std::chrono::steady_clock::now();
  planning::SimulationOptions options = input.options;
  options.threads = 2;
  if (progress)
    options.progress = [&progress](double fraction, const std::string& phase) {
      return progress(0.6 * fraction, "Predicting: " + phase);
    };
  try
  {
    study->prediction_ = planning::simulatePlan(input.skin, input.bone, input.plan, options);
  }
  catch (const seg::Cancelled&)
  {
    return nullptr;
  }
  study->predictSeconds = secondsSince(t);

  // The plan's model with its rim following the face model under each
  // muscle: one factorisation, one solve per muscle (§3.1.2).
  if (!step(0.6, "The plan's model under each muscle of the face"))
    return nullptr;
  t = std::chrono::steady_clock::now();
  std::vector<std::vector<fem::Muscle>> functions;
  for (const FittedMuscle& m : input.model->muscles)
    functions.push_back(m.functions);
  study->responses_ = std::make_unique<PlanExpressionResponses>(study->prediction_, input.model->face.continuum.mesh,
                                                                input.model->responses, functions);
  study->responseSeconds = secondsSince(t);

  // The display skin (§4.7) with the scan's detail, shaded as the face is.
  if (!step(0.85, "The plan's skin and its shade"))
    return nullptr;
  t = std::chrono::steady_clock::now();
  const planning::SkinShade shade = planning::skinShadeOfCt(input.ct, input.skin);
  study->shadeNote_ = shade.note;
  planning::PlanDisplayOptions displayOptions;
  displayOptions.resolution = input.resolution;
  displayOptions.maxRangeDetail = input.maxRangeDetail;
  planning::PlanDisplay display =
    planning::buildPlanDisplay(study->prediction_, input.skin, shade.map(), displayOptions);
  study->shade_ = display.skinShade;
  study->surface_ = ExpressionSurface(study->prediction_.continuum.mesh, std::move(display.surface),
                                      study->responses_->responses(), study->prediction_.displacements);
  study->displaySeconds = secondsSince(t);

  if (!step(0.95, "The contour bumps at rest"))
    return nullptr;
  study->restBumps_ = contourBumps(study->prediction_, study->frame_, study->prediction_.displacements, input.window);
  study->totalSeconds = secondsSince(start);
  step(1.0, "Plan ready");
  return study;
}

void PlanStudy::positions(const Eigen::VectorXd& activations, Eigen::Matrix3Xd& out) const
{
  surface_.positions(activations, true, out);
}

Eigen::VectorXd PlanStudy::displacement(const Eigen::VectorXd& activations) const
{
  return responses_->displacement(activations);
}

ContourComparison PlanStudy::compare(const Eigen::VectorXd& activations) const
{
  return compareContours(prediction_, frame_, prediction_.displacements, displacement(activations), window_);
}

Fingertip PlanStudy::fingertip(const Eigen::Vector3d& centre, double radius) const
{
  const auto start = std::chrono::steady_clock::now();
  Fingertip out;
  out.centre = centre;
  out.radius = radius;
  out.push = std::make_shared<PushResponses>(prediction_, centre, radius);
  out.surface =
    ExpressionSurface(prediction_.continuum.mesh, surface_.surface(), out.push->responses(), out.push->closure());
  // The surgeon's frame at the fingertip: up the head, across the face
  // (θ growing), into the face.
  const seg::CylindricalPoint c = frame_.toCylindrical(centre);
  const Eigen::Vector3d up = frame_.direction().normalized();
  const Eigen::Vector3d in = -frame_.radialDirection(c.theta).normalized();
  out.directions.col(0) = up;
  out.directions.col(1) = up.cross(-in).normalized(); // d(point)/dθ: axis × radial
  out.directions.col(2) = in;
  out.seconds = secondsSince(start);
  return out;
}

void PlanStudy::setFingertip(Fingertip fingertip)
{
  if (!fingertip.push || fingertip.surface.vertexCount() != surface_.vertexCount())
    throw std::invalid_argument("the fingertip was not made on this plan");
  fingertip_ = std::make_unique<Fingertip>(std::move(fingertip));
}

const Fingertip& PlanStudy::currentFingertip() const
{
  if (!fingertip_)
    throw std::logic_error("no fingertip on the plan's skin yet");
  return *fingertip_;
}

void PlanStudy::pushedPositions(const Eigen::Vector3d& travel, Eigen::Matrix3Xd& out) const
{
  currentFingertip().surface.positions(travel, true, out);
}

Eigen::VectorXd PlanStudy::pushedDisplacement(const Eigen::Vector3d& travel) const
{
  return currentFingertip().push->displacement(travel);
}

ContourComparison PlanStudy::comparePush(const Eigen::Vector3d& travel) const
{
  return compareContours(prediction_, frame_, prediction_.displacements, pushedDisplacement(travel), window_);
}

Eigen::Index PlanStudy::nearestVertex(const Eigen::Matrix3Xd& positions, const Eigen::Vector3d& point, double tolerance)
{
  if (positions.cols() == 0)
    return -1;
  Eigen::Index nearest = 0;
  const double d2 = (positions.colwise() - point).colwise().squaredNorm().minCoeff(&nearest);
  return d2 <= tolerance * tolerance ? nearest : -1;
}

Eigen::Vector3d PlanStudy::restSkinPoint(Eigen::Index v) const
{
  if (v < 0 || v >= surface_.vertexCount())
    throw std::out_of_range("no such vertex of the plan's skin");
  Eigen::Matrix3Xd at;
  surface_.positions(Eigen::VectorXd::Zero(muscleCount()), false, at);
  return at.col(v);
}

namespace {

/// (arc mm from @a theta0 at radius @a r0, z) of @a x about the frame's axis.
Eigen::Vector2d onCylinder(const seg::CylindricalFrame& frame, const Eigen::Vector3d& x, double theta0, double r0)
{
  const seg::CylindricalPoint c = frame.toCylindrical(x);
  return {r0 * std::remainder(c.theta - theta0, 2.0 * std::numbers::pi), c.z};
}

/// Even-odd rule: whether @a p lies inside the closed polygon @a ring.
bool inside(const std::vector<Eigen::Vector2d>& ring, const Eigen::Vector2d& p)
{
  bool in = false;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++)
    if ((ring[i].y() > p.y()) != (ring[j].y() > p.y()) &&
        p.x() < ring[j].x() + (ring[i].x() - ring[j].x()) * (p.y() - ring[j].y()) / (ring[i].y() - ring[j].y()))
      in = !in;
  return in;
}

} // namespace

std::vector<Eigen::Vector2d> PlanStudy::rimOnSkin() const
{
  const fem::ContinuumMesh& c = prediction_.continuum;
  const std::vector<int>& border = prediction_.surface.mesh.outerBorder;
  if (border.size() < 3)
    return {};
  // The skin nodes of the rim before the operation (the undeformed mesh).
  const Eigen::Vector3d first = c.mesh.nodes.col(c.vertexColumns[std::size_t(border.front())].front());
  const seg::CylindricalPoint origin = frame_.toCylindrical(first);
  std::vector<Eigen::Vector2d> ring;
  for (int v : border)
    ring.push_back(
      onCylinder(frame_, c.mesh.nodes.col(c.vertexColumns[std::size_t(v)].front()), origin.theta, origin.r));
  return ring;
}

std::vector<char> PlanStudy::faceCellsUnderPlan(vtkPolyData* face) const
{
  std::vector<char> under(face ? std::size_t(face->GetNumberOfCells()) : 0, 0);
  const std::vector<Eigen::Vector2d> ring = rimOnSkin();
  if (!face || ring.empty())
    return under;
  const fem::ContinuumMesh& c = prediction_.continuum;
  const seg::CylindricalPoint origin = frame_.toCylindrical(
    c.mesh.nodes.col(c.vertexColumns[std::size_t(prediction_.surface.mesh.outerBorder.front())].front()));
  vtkIdType n = 0;
  const vtkIdType* ids = nullptr;
  vtkCellArray* polys = face->GetPolys();
  polys->InitTraversal();
  // A cell is under the plan when all its corners are: a cell the rim cuts
  // stays, overlapping the plan's skin by less than a cell where both follow
  // the same face, rather than leaving a gap.
  for (std::size_t cell = 0; polys->GetNextCell(n, ids) && cell < under.size(); ++cell)
  {
    bool all = n > 0;
    for (vtkIdType k = 0; k < n && all; ++k)
      all = inside(ring, onCylinder(frame_, Eigen::Vector3d(face->GetPoint(ids[k])), origin.theta, origin.r));
    under[cell] = all;
  }
  return under;
}

vtkSmartPointer<vtkPolyData> PlanStudy::polyData() const
{
  return shadedSkinPolyData(surface_, shade_);
}

double setPoints(vtkPolyData* polyData, const Eigen::Matrix3Xd& positions, const Eigen::Matrix3Xd& rest)
{
  vtkPoints* points = polyData ? polyData->GetPoints() : nullptr;
  if (!points || points->GetNumberOfPoints() != vtkIdType(positions.cols()) || rest.cols() != positions.cols())
    throw std::invalid_argument("the surface does not belong to this plan's skin");
  double largest = 0.0;
  for (Eigen::Index v = 0; v < positions.cols(); ++v)
  {
    points->SetPoint(vtkIdType(v), positions(0, v), positions(1, v), positions(2, v));
    largest = std::max(largest, (positions.col(v) - rest.col(v)).squaredNorm());
  }
  points->Modified();
  return std::sqrt(largest);
}

} // namespace caps::expression
