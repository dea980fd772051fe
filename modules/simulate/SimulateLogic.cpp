#include "modules/simulate/SimulateLogic.h"

#include <chrono>
#include <fstream>
#include <iomanip>

#include "fem/CalculixReader.h"
#include "fem/NodalStress.h"
#include "fem/VtuWriter.h"

namespace fs = std::filesystem;

namespace caps {
namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0)
{
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::ofstream openForWriting(const fs::path& path)
{
  std::ofstream f(path);
  if (!f)
    throw std::runtime_error("cannot write " + path.string());
  f << std::setprecision(12);
  return f;
}

} // namespace

FemRunReport SimulateLogic::solveDeck(const fs::path& deck, const fs::path& outDir,
                                      const FemRunOptions& options)
{
  FemRunReport report;
  fem::CalculixModel model;
  auto t0 = Clock::now();
  try
  {
    model = fem::readCalculixInput(deck.string());
  }
  catch (const std::exception& e)
  {
    report.message = e.what();
    return report;
  }
  report.readSeconds = secondsSince(t0);
  report.nodes = model.mesh.nodeCount();
  report.elements = Eigen::Index(model.mesh.elements.size());
  report.dofs = model.mesh.dofCount();

  // Nodes in no element carry no stiffness: fix those nothing else holds.
  std::vector<char> used(std::size_t(model.mesh.nodeCount()), 0);
  for (const auto& el : model.mesh.elements)
    for (int n : el.nodes)
      if (n >= 0)
        used[std::size_t(n)] = 1;
  for (const auto& p : model.constraints.prescribed)
    if (p.node >= 0 && p.node < model.mesh.nodeCount())
      used[std::size_t(p.node)] = 1;
  for (const auto& s : model.constraints.sutures)
    for (int n : {s.node, s.target})
      if (n >= 0 && n < model.mesh.nodeCount())
        used[std::size_t(n)] = 1;
  for (std::size_t i = 0; i < used.size(); ++i)
    if (!used[i])
      model.constraints.fixNode(int(i));

  fem::AssemblyOptions assembly;
  assembly.threads = options.threads;
  fem::LinearStaticAnalysis analysis(model.mesh, model.materials, model.constraints, assembly);
  Eigen::VectorXd u;
  try
  {
    const fem::SolverStatus status = analysis.prepare();
    report.times = analysis.times();
    if (status != fem::SolverStatus::Success)
    {
      report.status = status == fem::SolverStatus::NotPositiveDefinite ? FemRunStatus::Unconstrained
                                                                       : FemRunStatus::SolverFailed;
      report.message = analysis.message();
      // The reduced system numbers CAPS nodes from 0: name the deck's node too.
      return report;
    }
    u = analysis.solve(model.load);
    report.times = analysis.times();
  }
  catch (const std::exception& e)
  {
    report.status = FemRunStatus::InvalidInput;
    report.message = e.what();
    return report;
  }

  t0 = Clock::now();
  fem::NodalStressField stress;
  try
  {
    stress = fem::recoverNodalStresses(model.mesh, model.materials, u, options.stressPointsPerDirection);
  }
  catch (const std::exception& e)
  {
    report.status = FemRunStatus::InvalidInput;
    report.message = e.what();
    return report;
  }
  const Eigen::VectorXd vonMises = stress.vonMises();
  report.recoverSeconds = secondsSince(t0);
  for (Eigen::Index i = 0; i < model.mesh.nodeCount(); ++i)
  {
    const double norm = u.segment<3>(3 * i).norm();
    if (norm > report.maxDisplacement || i == 0)
    {
      report.maxDisplacement = norm;
      report.maxDisplacementNode = model.nodeIds[std::size_t(i)];
    }
  }
  report.maxVonMises = vonMises.size() ? vonMises.maxCoeff() : 0.0;

  t0 = Clock::now();
  try
  {
    fs::create_directories(outDir);
    const fs::path displacements = outDir / "displacements.csv";
    {
      auto f = openForWriting(displacements);
      f << "node,x,y,z,ux,uy,uz\n";
      for (Eigen::Index i = 0; i < model.mesh.nodeCount(); ++i)
        f << model.nodeIds[std::size_t(i)] << ',' << model.mesh.nodes(0, i) << ','
          << model.mesh.nodes(1, i) << ',' << model.mesh.nodes(2, i) << ',' << u[3 * i] << ','
          << u[3 * i + 1] << ',' << u[3 * i + 2] << '\n';
      if (!f)
        throw std::runtime_error("error while writing " + displacements.string());
    }
    const fs::path stresses = outDir / "stresses.csv";
    {
      auto f = openForWriting(stresses);
      f << "node,sxx,syy,szz,sxy,syz,szx,von_mises\n";
      for (Eigen::Index i = 0; i < model.mesh.nodeCount(); ++i)
      {
        f << model.nodeIds[std::size_t(i)];
        for (int c = 0; c < 6; ++c)
          f << ',' << stress.stress(c, i);
        f << ',' << vonMises[i] << '\n';
      }
      if (!f)
        throw std::runtime_error("error while writing " + stresses.string());
    }
    const fs::path vtu = outDir / "result.vtu";
    Eigen::MatrixXd displacement = Eigen::Map<const Eigen::MatrixXd>(u.data(), 3, model.mesh.nodeCount());
    Eigen::MatrixXd ids(1, model.mesh.nodeCount());
    for (Eigen::Index i = 0; i < ids.cols(); ++i)
      ids(0, i) = double(model.nodeIds[std::size_t(i)]);
    fem::writeVtu(vtu.string(), model.mesh,
                  {{"displacement", displacement},
                   {"stress", stress.stress},
                   {"von_mises", vonMises.transpose()},
                   {"mean_stress", stress.meanStress().transpose()},
                   {"principal_stress", stress.principal()},
                   {"node_id", ids}});
    report.files = {displacements, stresses, vtu};
  }
  catch (const std::exception& e)
  {
    report.status = FemRunStatus::WriteFailed;
    report.message = e.what();
    return report;
  }
  report.writeSeconds = secondsSince(t0);
  report.status = FemRunStatus::Success;
  return report;
}

} // namespace caps
