// caps_bench_fem: time per phase (assemble, constrain, analyse, factor,
// solve, a second load case) of LinearStaticAnalysis on structured layered
// meshes shaped like a patch of skin (80 x 80 x 8 mm, 3 layers of 20-node
// bricks through the thickness, base fixed), and optionally the same mesh
// solved by CalculiX in the same run, printing ccx time / our time, for ccx
// as installed (one core) and for ccx on all cores.
//
// Also prints the factorization's flop count and rate (CHOLMOD's count), the
// factor's size and the process's peak resident memory, and which OpenBLAS
// kernels ran (BlasKernels.h: the program re-executes itself with better
// ones when OpenBLAS fell back to generic kernels).
//
// Usage: caps_bench_fem [--ccx] [DOFS ...]   (default 10000 50000 100000)

#include "fem/BlasKernels.h"
#include "fem/CalculixIO.h"
#include "fem/StaticAnalysis.h"

#include "SkinPatch.h"

#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
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
  caps::fem::useBestBlasKernels(argv);
  bool runCcx = false;
  std::vector<long> targets;
  for (int a = 1; a < argc; ++a)
  {
    if (std::string(argv[a]) == "--ccx")
      runCcx = true;
    else
      targets.push_back(std::atol(argv[a]));
  }
  if (targets.empty())
    targets = {10000, 50000, 100000};
  const int layers = 3;
  const std::string blas = blasCoreName();
  std::printf("BLAS kernels: %s\n", blas.empty() ? "not OpenBLAS" : blas.c_str());
  const unsigned cores = std::max(1U, std::thread::hardware_concurrency());
  std::printf("ours on %u cores; ccx as installed (1 core), then with OMP_NUM_THREADS=%u\n", cores, cores);
  std::printf("%8s %7s %9s %9s %9s %9s %9s %9s %9s %8s %7s %8s %8s %9s %9s %9s %9s\n", "DOF", "elems", "assemble",
              "constrain", "analyse", "factor", "solve", "2nd case", "total", "GFlop", "GFlop/s", "L MB", "peak MB",
              "ccx s", "ccx/ours", "ccxN s", "ccxN/ours");
  for (long target : targets)
  {
    const Mesh mesh = skinPatchOfSize(target, layers);
    MaterialTable materials = skinPatchMaterials();
    Constraints c;
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      if (mesh.nodes(2, i) < 1e-9)
        c.fixNode(int(i));
    LoadCase gravity;
    gravity.gravity = Eigen::Vector3d(0, -9810.0, -9810.0);
    LoadCase push;
    push.nodalForces.push_back({int(mesh.nodeCount()) - 1, Eigen::Vector3d(0, 0, -0.01)});

    const auto t0 = Clock::now();
    LinearStaticAnalysis analysis(mesh, materials, c);
    if (analysis.prepare() != SolverStatus::Success)
    {
      std::printf("failed: %s\n", analysis.message().c_str());
      return 1;
    }
    analysis.solve(gravity);
    const PhaseTimes first = analysis.times();
    analysis.solve(push);
    const double second = analysis.times().solve;
    const double total = seconds(t0);
    // ccx as installed runs on one core (it says "Using up to 1 cpu(s)"); we
    // use both. So ccx runs twice: as installed, and told to use every core
    // (OMP_NUM_THREADS), and both ratios are printed.
    double ccxSeconds = 0.0, ccxAllCoresSeconds = 0.0;
    const unsigned cores = std::max(1U, std::thread::hardware_concurrency());
    if (runCcx)
    {
      const auto dir = std::filesystem::temp_directory_path() / "caps_bench_fem_ccx";
      std::filesystem::create_directories(dir);
      writeCalculixInput((dir / "job.inp").string(), mesh, materials, c, gravity);
      auto runCcxWith = [&dir](const std::string& environment) {
        const auto t1 = Clock::now();
        const std::string cmd = "cd '" + dir.string() + "' && env -u OMP_NUM_THREADS -u CCX_NPROC_EQUATION_SOLVER " +
                                environment + " ccx -i job > ccx.log 2>&1";
        if (std::system(cmd.c_str()) != 0)
          std::printf("ccx failed, see %s/ccx.log\n", dir.c_str());
        return seconds(t1);
      };
      ccxSeconds = runCcxWith("");
      ccxAllCoresSeconds = runCcxWith("OMP_NUM_THREADS=" + std::to_string(cores));
      std::filesystem::remove_all(dir);
    }
    // Peak resident memory of the process so far (sizes run in the order
    // given: for ascending sizes it is this size's peak).
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    const double flops = analysis.solver().factorFlops();
    std::printf("%8ld %7zu %9.3f %9.3f %9.3f %9.3f %9.3f %9.3f %9.3f %8.1f %7.1f %8.0f %8.0f %9.2f %9.2f %9.2f %9.2f\n",
                long(mesh.dofCount()), mesh.elements.size(), first.assemble, first.constrain, first.analyse,
                first.factor, first.solve, second, total, flops / 1e9, flops / 1e9 / first.factor,
                analysis.solver().factorNonZeros() * 8.0 / 1e6, double(usage.ru_maxrss) / 1024.0, ccxSeconds,
                ccxSeconds / total, ccxAllCoresSeconds, ccxAllCoresSeconds / total);
    std::fflush(stdout);
  }
  return 0;
}
