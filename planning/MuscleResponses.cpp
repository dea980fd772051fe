#include "planning/MuscleResponses.h"

#include <stdexcept>
#include <string>

#include "fem/BodyCoordinates.h"

namespace caps::expression {
namespace {

void checkActivations(const Eigen::VectorXd& activations, Eigen::Index muscles)
{
  if (activations.size() != muscles)
  {
    std::string message = "got ";
    message += std::to_string(activations.size());
    message += " activations for ";
    message += std::to_string(muscles);
    message += " muscles";
    throw std::invalid_argument(message);
  }
}

} // namespace

MuscleResponses::MuscleResponses(fem::LinearStaticAnalysis& analysis,
                                 const std::vector<std::vector<fem::Muscle>>& muscles)
{
  if (analysis.status() != fem::SolverStatus::Success)
    throw std::logic_error("the muscle responses need a factored model: " + analysis.message());
  const Eigen::Index dofs = analysis.mesh().dofCount();
  loads_.resize(dofs, Eigen::Index(muscles.size()));
  forces_.reserve(muscles.size());
  for (std::size_t k = 0; k < muscles.size(); ++k)
  {
    // Each muscle's loads alone (eq. 4.42 over its functions): its column of R.
    const fem::MuscleLoad load = fem::assembleMuscleLoad(analysis.mesh(), muscles[k]);
    loads_.col(Eigen::Index(k)) = load.load;
    forces_.push_back(load.muscles);
  }
  // One substitution with as many right-hand sides as muscles (§3.1.2),
  // plus one without load: a model with sutures (a plan after the operation)
  // moves under no load at all, since the closure is prescribed (U = T Ū + g);
  // a muscle's response is what its load adds to that.
  Eigen::MatrixXd rhs(dofs, loads_.cols() + 1);
  rhs.leftCols(loads_.cols()) = loads_;
  rhs.col(loads_.cols()).setZero();
  const Eigen::MatrixXd u = analysis.solve(rhs);
  displacements_ = u.leftCols(loads_.cols()).colwise() - u.col(loads_.cols());
}

Eigen::VectorXd MuscleResponses::combined(const Eigen::VectorXd& activations) const
{
  checkActivations(activations, muscleCount());
  return displacements_ * activations;
}

ExpressionSurface::ExpressionSurface(const fem::Mesh& mesh, fem::DisplaySurface surface,
                                     const MuscleResponses& responses)
  : ExpressionSurface(mesh, std::move(surface), responses.displacements())
{}

ExpressionSurface::ExpressionSurface(const fem::Mesh& mesh, fem::DisplaySurface surface,
                                     const Eigen::MatrixXd& responses, const Eigen::VectorXd& base)
  : surface_(std::move(surface))
{
  const Eigen::Index vertices = surface_.vertexCount();
  if (responses.rows() != mesh.dofCount() || (base.size() != 0 && base.size() != mesh.dofCount()))
    throw std::invalid_argument("the responses are of another mesh than the display surface's");
  // Each response interpolated to the vertices once (eq. 4.14).
  const auto atVertices = [&](const Eigen::VectorXd& u, auto&& column) {
    for (Eigen::Index v = 0; v < vertices; ++v)
      column.template segment<3>(3 * v) = fem::displacementAt(mesh, u, surface_.bodyPoints()[std::size_t(v)]);
  };
  vertexResponses_.resize(3 * vertices, responses.cols());
  for (Eigen::Index k = 0; k < responses.cols(); ++k)
    atVertices(responses.col(k), vertexResponses_.col(k));
  if (base.size() != 0)
  {
    vertexBase_.resize(3 * vertices);
    atVertices(base, vertexBase_);
  }
}

void ExpressionSurface::positions(const Eigen::VectorXd& activations, bool rangeDetail, Eigen::Matrix3Xd& out) const
{
  checkActivations(activations, muscleCount());
  out = surface_.undeformedPositions();
  if (rangeDetail && surface_.rangeDetail().cols() == out.cols())
    out += surface_.rangeDetail();
  Eigen::Map<Eigen::VectorXd> flat(out.data(), out.size());
  if (vertexBase_.size() == flat.size())
    flat += vertexBase_;
  flat.noalias() += vertexResponses_ * activations;
}

} // namespace caps::expression
