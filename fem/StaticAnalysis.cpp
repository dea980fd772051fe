#include "fem/StaticAnalysis.h"

#include <algorithm>
#include <array>
#include <exception>
#include <thread>

#include <chrono>
#include <sstream>
#include <stdexcept>
#include <string>

namespace caps::fem {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0)
{
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Mid-edge slots of each element kind with the two corner slots of their
// edge: the corners whose natural coordinates average to the mid-edge node's.
struct EdgeSlots
{
  int middle, first, second;
};
std::vector<EdgeSlots> edgeSlots(ElementKind kind)
{
  const bool hex = kind == ElementKind::Hex20;
  const int corners = hex ? kHex20CornerCount : kWedge15CornerCount;
  const int all = hex ? kHex20NodeCount : kWedge15NodeCount;
  auto at = [hex](int slot) { return hex ? batheNaturalCoordinates(slot) : wedge15NaturalCoordinates(slot); };
  std::vector<EdgeSlots> edges;
  for (int m = corners; m < all; ++m)
    for (int a = 0; a < corners; ++a)
      for (int b = a + 1; b < corners; ++b)
        if (((at(a) + at(b)) / 2.0 - at(m)).norm() < 1e-12)
          edges.push_back({m, a, b});
  return edges;
}

// For each mid-edge node the two ends of its edge (the first element that
// has it as a mid-edge node decides); {-1, -1} for element vertices and for
// nodes in no element.
std::vector<std::array<int, 2>> edgeEndsOf(const Mesh& mesh)
{
  const std::size_t n = std::size_t(mesh.nodeCount());
  std::vector<std::array<int, 2>> ends(n, {-1, -1});
  std::vector<char> isVertex(n, 0);
  for (const Element& el : mesh.elements)
  {
    const int corners = el.kind == ElementKind::Hex20 ? kHex20CornerCount : kWedge15CornerCount;
    for (int k = 0; k < corners; ++k)
      isVertex[std::size_t(el.nodes[std::size_t(k)])] = 1;
  }
  const std::vector<EdgeSlots> hexEdges = edgeSlots(ElementKind::Hex20);
  const std::vector<EdgeSlots> wedgeEdges = edgeSlots(ElementKind::Wedge15);
  for (const Element& el : mesh.elements)
    for (const EdgeSlots& e : el.kind == ElementKind::Hex20 ? hexEdges : wedgeEdges)
    {
      const int m = el.nodes[std::size_t(e.middle)];
      if (m < 0 || isVertex[std::size_t(m)] || ends[std::size_t(m)][0] >= 0)
        continue;
      ends[std::size_t(m)] = {el.nodes[std::size_t(e.first)], el.nodes[std::size_t(e.second)]};
    }
  return ends;
}

} // namespace

void useNodeGroupedOrdering(const Mesh& mesh, const ConstraintMap& map, SparseCholeskySolver& solver)
{
  // Order by nodes (a node's DOFs together), and only the element vertices
  // by nested dissection: each mid-edge node goes right before the first end
  // of its edge. The vertex graph is ~30x smaller than the DOF graph, with
  // the same fill (measured on the 100k-DOF skin patch of caps_bench_fem:
  // METIS 0.42 s -> 0.05 s, same flops).
  std::vector<int> nodeOfDof(map.masterOf.size());
  for (std::size_t d = 0; d < nodeOfDof.size(); ++d)
    nodeOfDof[d] = map.masterOf[d] / 3;
  std::vector<SparseCholeskySolver::AttachedGroup> midEdges;
  const std::vector<std::array<int, 2>> ends = edgeEndsOf(mesh);
  // The group of a node: the node its free DOFs stand for (a sutured node's
  // are its target's), -1 if it has none (a node whose DOFs are all
  // prescribed or dependent in equations).
  auto masterNode = [&map](int node) {
    for (int c = 0; c < 3; ++c)
      if (const int r = map.reduced[std::size_t(3 * node + c)]; r >= 0)
        return map.masterOf[std::size_t(r)] / 3;
    return -1;
  };
  for (std::size_t i = 0; i < ends.size(); ++i)
    if (ends[i][0] >= 0 && masterNode(int(i)) == int(i))
      midEdges.push_back({int(i), masterNode(ends[i][0]), masterNode(ends[i][1])});
  solver.setColumnGroups(std::move(nodeOfDof), std::move(midEdges));
}

LinearStaticAnalysis::LinearStaticAnalysis(Mesh mesh, MaterialTable materials, Constraints constraints,
                                           AssemblyOptions options)
  : mesh_(std::move(mesh)), materials_(std::move(materials)), constraints_(std::move(constraints)), options_(options)
{}

SolverStatus LinearStaticAnalysis::prepare()
{
  times_ = {};
  status_ = SolverStatus::InvalidInput;
  try
  {
    return prepareStages();
  }
  catch (const std::exception& e)
  {
    status_ = SolverStatus::InvalidInput;
    message_ = e.what();
    throw;
  }
}

SolverStatus LinearStaticAnalysis::prepareStages()
{
  validateMesh(mesh_, materials_);

  // The pattern of K, and so of K̄, follows from the connectivity and the
  // constraints alone: the solver orders and analyses it on its own thread
  // while the element matrices are computed (§4.6.1 steps 2a-2f beside the
  // ordering), which hides most of the analysis on two cores.
  auto t0 = Clock::now();
  map_ = resolveConstraints(mesh_, constraints_);
  k_ = stiffnessPattern(mesh_);
  const double patternSeconds = secondsSince(t0);
  std::thread analysis;
  std::exception_ptr analysisError;
  if (map_.reducedCount() > 0)
  {
    t0 = Clock::now();
    // K̄'s pattern; the analysis reads only its indices (CHOLMOD's analysis
    // is pattern-only), its values are filled in below once K is known.
    kbar_ = map_.reduceMatrix(k_);
    times_.constrain = secondsSince(t0);
    analysis = std::thread([this, &analysisError]() {
      try
      {
        const auto start = Clock::now();
        useNodeGroupedOrdering(mesh_, map_, solver_);
        solver_.analyzePattern(kbar_);
        times_.analyse = secondsSince(start);
      }
      catch (...)
      {
        analysisError = std::current_exception();
      }
    });
  }
  try
  {
    t0 = Clock::now();
    // One core is busy with the analysis: one thread fewer for the elements.
    AssemblyOptions assembly = options_;
    if (analysis.joinable())
      assembly.threads = std::max(1, assembly.threads - 1);
    assembleStiffnessValues(mesh_, materials_, assembly, k_);
    times_.assemble = patternSeconds + secondsSince(t0);
    t0 = Clock::now();
    if (analysis.joinable())
      map_.reduceValues(k_, kbar_);
    else
      kbar_ = map_.reduceMatrix(k_);
    kg_ = k_.selfadjointView<Eigen::Upper>() * map_.offset;
    times_.constrain += secondsSince(t0);
  }
  catch (...)
  {
    if (analysis.joinable())
      analysis.join();
    throw;
  }
  if (!analysis.joinable())
  {
    status_ = SolverStatus::Success;
    message_.clear();
    return status_;
  }
  analysis.join();
  if (analysisError)
    std::rethrow_exception(analysisError);
  if (solver_.status() != SolverStatus::Success)
  {
    status_ = solver_.status();
    message_ = solver_.message();
    return status_;
  }
  t0 = Clock::now();
  solver_.factorize(kbar_);
  times_.factor = secondsSince(t0);
  status_ = solver_.status();
  message_ = solver_.message();
  if (status_ == SolverStatus::NotPositiveDefinite)
  {
    std::ostringstream m;
    m << "the model is not sufficiently constrained (rigid-body motion or a loose part)";
    const Eigen::Index col = solver_.failedColumn();
    if (col >= 0 && col < map_.reducedCount())
    {
      const int dof = map_.masterOf[std::size_t(col)];
      m << ": node " << dof / 3 << " is free to move in "
        << "xyz"[dof % 3] << "; fix or suture more nodes";
      if (map_.hasGeneralRows())
        m << " (or check that the equations do not leave it free)";
    }
    m << " [solver, numbering the reduced system after constraints: " << message_ << "]";
    message_ = m.str();
  }
  return status_;
}

LoadCase nodalLoadCase(const Eigen::VectorXd& f)
{
  LoadCase load;
  for (Eigen::Index n = 0; n < f.size() / 3; ++n)
    if (!f.segment<3>(3 * n).isZero(0.0))
      load.nodalForces.emplace_back(int(n), f.segment<3>(3 * n));
  return load;
}

Eigen::VectorXd assembleLoadVector(const Mesh& mesh, const MaterialTable& materials, const LoadCase& load,
                                   const AssemblyOptions& options)
{
  Eigen::VectorXd r = Eigen::VectorXd::Zero(mesh.dofCount());
  for (const auto& [node, f] : load.nodalForces)
  {
    if (node < 0 || node >= mesh.nodeCount())
      throw std::invalid_argument("a nodal force is applied to node " + std::to_string(node) +
                                  ", but the mesh has nodes 0.." + std::to_string(mesh.nodeCount() - 1));
    r.segment<3>(3 * node) += f;
  }
  if (!load.gravity.isZero(0.0))
    r += assembleGravityLoad(mesh, materials, load.gravity, options);
  if (!load.facePressures.empty())
    r += assembleFacePressureLoad(mesh, load.facePressures);
  if (!load.muscles.empty())
    r += assembleMuscleLoad(mesh, load.muscles, options).load;
  return r;
}

Eigen::VectorXd LinearStaticAnalysis::loadVector(const LoadCase& load) const
{
  return assembleLoadVector(mesh_, materials_, load, options_);
}

Eigen::VectorXd LinearStaticAnalysis::internalForces(const Eigen::VectorXd& u) const
{
  if (k_.rows() != mesh_.dofCount() || k_.nonZeros() == 0)
    throw std::logic_error("LinearStaticAnalysis::internalForces: the stiffness was not assembled (call prepare())");
  if (u.size() != mesh_.dofCount())
    throw std::invalid_argument("LinearStaticAnalysis::internalForces: " + std::to_string(u.size()) +
                                " displacements given for a model of " + std::to_string(mesh_.dofCount()) + " DOFs");
  return k_.selfadjointView<Eigen::Upper>() * u;
}

Eigen::MatrixXd LinearStaticAnalysis::solve(const Eigen::MatrixXd& r)
{
  if (status_ != SolverStatus::Success)
    throw std::logic_error("LinearStaticAnalysis::solve: the model was not prepared: " + message_);
  if (r.rows() != mesh_.dofCount())
    throw std::invalid_argument("LinearStaticAnalysis::solve: load vectors must have 3N rows");
  return substitute(r, kg_, map_);
}

Eigen::MatrixXd LinearStaticAnalysis::substitute(const Eigen::MatrixXd& r, const Eigen::VectorXd& kg,
                                                 const ConstraintMap& prescribed)
{
  const auto t0 = Clock::now();
  Eigen::MatrixXd rhs = r;
  rhs.colwise() -= kg;
  const Eigen::MatrixXd rbar = map_.reduceVector(rhs);
  Eigen::MatrixXd ubar = map_.reducedCount() > 0 ? solver_.solve(rbar) : rbar;
  Eigen::MatrixXd u = prescribed.expand(ubar);
  times_.solve = secondsSince(t0);
  return u;
}

Eigen::MatrixXd LinearStaticAnalysis::solveWithPrescribed(const Eigen::MatrixXd& r, const Constraints& constraints)
{
  if (status_ != SolverStatus::Success)
    throw std::logic_error("LinearStaticAnalysis::solveWithPrescribed: the model was not prepared: " + message_);
  if (r.rows() != mesh_.dofCount())
    throw std::invalid_argument("LinearStaticAnalysis::solveWithPrescribed: load vectors must have 3N rows");
  const ConstraintMap other = resolveConstraints(mesh_, constraints);
  if (!other.sameTransformation(map_))
    throw std::invalid_argument("LinearStaticAnalysis::solveWithPrescribed: the constraints fix, suture or tie "
                                "other degrees of freedom (or with other equation coefficients) than the model was "
                                "factored with");
  const Eigen::VectorXd kg = k_.selfadjointView<Eigen::Upper>() * other.offset;
  return substitute(r, kg, other);
}

Eigen::VectorXd LinearStaticAnalysis::solve(const LoadCase& load)
{
  const Eigen::VectorXd r = loadVector(load);
  return solve(Eigen::MatrixXd(r)).col(0);
}

} // namespace caps::fem
