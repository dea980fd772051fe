// caps_bench_fem_nonlinear: the same large-deformation model solved by
// CAPS's Newton solver (NonlinearStaticAnalysis) and by CalculiX with
// NLGEOM in the same run, on the same cores, printing the time per Newton
// iteration, the iterations, the totals and ccx time / ours, for our full
// Newton (a tangent and a factorization per iteration) and our modified
// Newton (a factorization kept while it contracts the residual tenfold).
//
// The model: the skin patch of caps_bench_fem (80 x 80 x 8 mm, three
// neo-Hookean layers, base fixed) pressed by a fingertip: the top nodes
// within 10 mm of the centre are moved 3 mm down and 4 mm sideways, in
// increments of a quarter (both solvers grow and cut them alike). Both
// converge tightly (our residual 1e-8 of the force; ccx's *CONTROLS 1e-8),
// so both give the same answer, which the benchmark checks (the largest
// difference of the displacements, relative).
//
// Our side is timed from reading the deck ccx reads to the converged
// displacements, in this process; ccx as a whole process (reading, solving,
// writing its .dat/.frd), with OMP_NUM_THREADS set to the cores we use.
//
// Usage: caps_bench_fem_nonlinear [--no-ccx] [DOFS ...]   (default 10000 50000 100000)

#include "fem/BlasKernels.h"
#include "fem/CalculixIO.h"
#include "fem/CalculixReader.h"
#include "fem/NonlinearStaticAnalysis.h"

#include "SkinPatch.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace caps::fem;
using caps::bench::skinPatchMaterials;
using caps::bench::skinPatchOfSize;
using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point t0)
{
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

} // namespace

int main(int argc, char** argv)
{
  useBestBlasKernels(argv);
  bool runCcx = true;
  std::vector<long> targets;
  for (int a = 1; a < argc; ++a)
  {
    if (std::string(argv[a]) == "--no-ccx")
      runCcx = false;
    else
      targets.push_back(std::atol(argv[a]));
  }
  if (targets.empty())
    targets = {10000, 50000, 100000};
  const int layers = 3;
  const unsigned cores = std::max(1U, std::thread::hardware_concurrency());
  std::printf("ours on %u threads; ccx with OMP_NUM_THREADS=%u; both to a residual of 1e-8\n", cores, cores);
  // Full Newton and the modified Newton that keeps a factorization while it contracts fast.
  const std::vector<std::pair<TangentUpdate, const char*>> modes{{TangentUpdate::EveryIteration, "full"},
                                                                 {TangentUpdate::WhenSlow, "modified"}};
  std::printf("%8s %7s %-8s %5s %5s %5s %5s %9s %9s %9s %9s %9s %5s %9s %9s %9s %10s\n", "DOF", "elems", "newton",
              "incs", "its", "facts", "evals", "read s", "solve s", "assem s", "factor s", "s/it", "ccxIt", "ccx s",
              "ccx s/it", "ccx/ours", "max rel du");
  for (long target : targets)
  {
    const Mesh mesh = skinPatchOfSize(target, layers);
    const MaterialTable linear = skinPatchMaterials();
    HyperelasticTable hyperelastic;
    for (const auto& [region, m] : linear)
      hyperelastic[region] = HyperelasticMaterial::fromLinear(HyperelasticLaw::NeoHookean, m);
    Constraints c;
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    {
      const Eigen::Vector3d x = mesh.nodes.col(i);
      if (x[2] < 1e-9)
        c.fixNode(int(i));
      if (x[2] > 8.0 - 1e-9 && std::hypot(x[0] - 40.0, x[1] - 40.0) <= 10.0)
      {
        c.prescribe(int(i), 0, 4.0);
        c.prescribe(int(i), 1, 0.0);
        c.prescribe(int(i), 2, -3.0);
      }
    }
    StaticStep step;
    step.nlgeom = true;
    step.initialIncrement = 0.25;
    step.minimumIncrement = 1e-4;
    step.maximumIncrement = 0.5;
    CalculixExportOptions exportOptions;
    exportOptions.step = step;
    exportOptions.hyperelastic = hyperelastic;
    exportOptions.tightControls = true;
    const auto dir = std::filesystem::temp_directory_path() / ("caps_bench_nonlinear_" + std::to_string(target));
    std::filesystem::create_directories(dir);
    writeCalculixInput((dir / "job.inp").string(), mesh, linear, c, LoadCase{}, exportOptions);

    // ccx first, once: the reference of both our runs.
    double ccxSeconds = 0.0;
    int ccxIterations = 0;
    Eigen::Matrix3Xd theirs;
    if (runCcx)
    {
      const auto t0 = Clock::now();
      const std::string cmd = "cd '" + dir.string() + "' && env OMP_NUM_THREADS=" + std::to_string(cores) +
                              " CCX_NPROC_EQUATION_SOLVER=" + std::to_string(cores) + " ccx -i job > ccx.log 2>&1";
      const bool ok = std::system(cmd.c_str()) == 0;
      ccxSeconds = seconds(t0);
      if (!ok)
      {
        std::printf("ccx failed, see %s/ccx.log\n", dir.c_str());
      }
      else
      {
        // ccx's log has a line " iteration N" per Newton iteration.
        const std::string count = "cd '" + dir.string() + "' && grep -c '^ iteration' ccx.log > its.txt";
        (void)std::system(count.c_str()); // grep -c exits 1 on no match, which leaves 0 in the file
        if (FILE* f = std::fopen((dir / "its.txt").c_str(), "r"))
        {
          if (std::fscanf(f, "%d", &ccxIterations) != 1)
            ccxIterations = 0;
          std::fclose(f);
        }
        theirs = readDatDisplacements((dir / "job.dat").string(), mesh.nodeCount());
      }
    }

    // Ours, in each tangent update: read the deck, solve.
    for (const auto& [mode, modeName] : modes)
    {
      auto t0 = Clock::now();
      const CalculixModel model = readCalculixInput((dir / "job.inp").string());
      const double read = seconds(t0);
      t0 = Clock::now();
      AssemblyOptions assembly;
      assembly.threads = int(cores);
      NonlinearStaticAnalysis analysis(model.mesh, model.hyperelastic, model.constraints, assembly);
      IncrementControl control;
      control.initial = step.initialIncrement;
      control.minimum = step.minimumIncrement;
      control.maximum = step.maximumIncrement;
      NewtonOptions newton;
      newton.tangentUpdate = mode;
      const NonlinearResult r = analysis.solve(model.load, control, newton);
      const double solve = seconds(t0);
      if (r.status != NonlinearStatus::Converged)
      {
        std::printf("%8ld %-8s: ours did not converge: %s\n", long(mesh.dofCount()), modeName, r.message.c_str());
        continue;
      }
      int increments = 0;
      for (const auto& i : r.increments)
        increments += i.accepted;
      const int iterations = int(r.iterations.size());
      double difference = NAN;
      if (theirs.cols() > 0)
      {
        const Eigen::Map<const Eigen::VectorXd> flat(theirs.data(), theirs.size());
        difference =
          (flat - r.displacements.head(flat.size())).cwiseAbs().maxCoeff() / r.displacements.cwiseAbs().maxCoeff();
      }
      std::printf("%8ld %7zu %-8s %5d %5d %5d %5d %9.3f %9.3f %9.3f %9.3f %9.4f %5d %9.3f %9.4f %9.2f %10.2e\n",
                  long(mesh.dofCount()), mesh.elements.size(), modeName, increments, iterations, r.factorizations,
                  r.assemblies, read, solve, r.assembleSeconds, r.factorSeconds, solve / std::max(1, iterations),
                  ccxIterations, ccxSeconds, ccxSeconds / std::max(1, ccxIterations),
                  runCcx ? ccxSeconds / (read + solve) : NAN, difference);
      std::fflush(stdout);
    }
    std::filesystem::remove_all(dir);
  }
  return 0;
}
