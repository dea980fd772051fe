#include "fem/StaticAnalysis.h"

#include <chrono>
#include <sstream>
#include <stdexcept>

namespace caps::fem {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

LinearStaticAnalysis::LinearStaticAnalysis(Mesh mesh, MaterialTable materials, Constraints constraints,
                                           AssemblyOptions options)
    : mesh_(std::move(mesh)),
      materials_(std::move(materials)),
      constraints_(std::move(constraints)),
      options_(options) {}

SolverStatus LinearStaticAnalysis::prepare() {
  times_ = {};
  status_ = SolverStatus::InvalidInput;
  try {
    return prepareStages();
  } catch (const std::exception& e) {
    status_ = SolverStatus::InvalidInput;
    message_ = e.what();
    throw;
  }
}

SolverStatus LinearStaticAnalysis::prepareStages() {
  validateMesh(mesh_, materials_);

  auto t0 = Clock::now();
  k_ = assembleStiffness(mesh_, materials_, options_);
  times_.assemble = secondsSince(t0);

  t0 = Clock::now();
  map_ = resolveConstraints(mesh_, constraints_);
  kbar_ = map_.reduceMatrix(k_);
  kg_ = k_.selfadjointView<Eigen::Upper>() * map_.offset;
  times_.constrain = secondsSince(t0);

  if (map_.reducedCount() == 0) {
    status_ = SolverStatus::Success;
    message_.clear();
    return status_;
  }
  t0 = Clock::now();
  solver_.analyzePattern(kbar_);
  times_.analyse = secondsSince(t0);
  if (solver_.status() != SolverStatus::Success) {
    status_ = solver_.status();
    message_ = solver_.message();
    return status_;
  }
  t0 = Clock::now();
  solver_.factorize(kbar_);
  times_.factor = secondsSince(t0);
  status_ = solver_.status();
  message_ = solver_.message();
  if (status_ == SolverStatus::NotPositiveDefinite) {
    std::ostringstream m;
    m << "the model is not sufficiently constrained (rigid-body motion or a loose part)";
    const Eigen::Index col = solver_.failedColumn();
    if (col >= 0 && col < map_.reducedCount()) {
      const int dof = map_.masterOf[std::size_t(col)];
      m << ": node " << dof / 3 << " is free to move in " << "xyz"[dof % 3]
        << "; fix or suture more nodes";
    }
    m << " [solver, numbering the reduced system after constraints: " << message_ << "]";
    message_ = m.str();
  }
  return status_;
}

Eigen::VectorXd LinearStaticAnalysis::loadVector(const LoadCase& load) const {
  Eigen::VectorXd r = Eigen::VectorXd::Zero(mesh_.dofCount());
  for (const auto& [node, f] : load.nodalForces) {
    if (node < 0 || node >= mesh_.nodeCount())
      throw std::invalid_argument("a nodal force is applied to node " + std::to_string(node) +
                                  ", but the mesh has nodes 0.." + std::to_string(mesh_.nodeCount() - 1));
    r.segment<3>(3 * node) += f;
  }
  if (!load.gravity.isZero(0.0)) r += assembleGravityLoad(mesh_, materials_, load.gravity, options_);
  if (!load.facePressures.empty()) r += assembleFacePressureLoad(mesh_, load.facePressures);
  if (!load.muscles.empty()) r += assembleMuscleLoad(mesh_, load.muscles, options_).load;
  return r;
}

Eigen::MatrixXd LinearStaticAnalysis::solve(const Eigen::MatrixXd& r) {
  if (status_ != SolverStatus::Success)
    throw std::logic_error("LinearStaticAnalysis::solve: the model was not prepared: " + message_);
  if (r.rows() != mesh_.dofCount())
    throw std::invalid_argument("LinearStaticAnalysis::solve: load vectors must have 3N rows");
  const auto t0 = Clock::now();
  Eigen::MatrixXd rhs = r;
  rhs.colwise() -= kg_;
  const Eigen::MatrixXd rbar = map_.reduceVector(rhs);
  Eigen::MatrixXd ubar = map_.reducedCount() > 0 ? solver_.solve(rbar) : rbar;
  Eigen::MatrixXd u = map_.expand(ubar);
  times_.solve = secondsSince(t0);
  return u;
}

Eigen::VectorXd LinearStaticAnalysis::solve(const LoadCase& load) {
  const Eigen::VectorXd r = loadVector(load);
  return solve(Eigen::MatrixXd(r)).col(0);
}

}  // namespace caps::fem
