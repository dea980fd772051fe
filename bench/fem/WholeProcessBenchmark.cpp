// caps_bench_fem_whole: `caps fem` against `ccx`, whole process against
// whole process, on the same deck and the same two threads.
//
// The model: the skin patch of caps_bench_fem (80 x 80 x 8 mm, three
// linear-elastic layers of C3D20 bricks, base fixed) under gravity and
// pushed by a fingertip: the top nodes within 10 mm of the centre are moved
// 0.5 mm down. It is written as a CalculiX deck (writeCalculixInput, which
// asks for *NODE PRINT U), then solved by two child processes, each timed
// from start to exit (reading the deck, solving, recovering stresses,
// writing every output file):
//
//   caps fem job.inp --out DIR --threads T    (the caps binary beside this one)
//   ccx -i job                                (OMP_NUM_THREADS=T, CCX_NPROC_EQUATION_SOLVER=T)
//
// Prints both wall times, ccx / ours, the largest difference of the two
// displacement fields relative to the largest displacement (ours from
// displacements.csv, ccx's from its .dat, 7 digits), and caps fem's own
// phase times. Each size runs --runs times (default 1); the fastest run of
// each program counts, as the machine may be shared.
//
// Usage: caps_bench_fem_whole [--threads T] [--runs N] [--keep] [DOFS ...]
//        (default T = 2, sizes 10000 50000 107000)

#include "fem/CalculixIO.h"

#include "SkinPatch.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace caps::fem;
using caps::bench::skinPatchMaterials;
using caps::bench::skinPatchOfSize;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

double seconds(Clock::time_point t0)
{
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// Wall seconds of @a command run by the shell; negative when it failed.
double timed(const std::string& command)
{
  const auto t0 = Clock::now();
  const int status = std::system(command.c_str());
  const double s = seconds(t0);
  return status == 0 ? s : -1.0;
}

/// displacements.csv of caps fem (node, x, y, z, ux, uy, uz; deck nodes 1..n).
Eigen::Matrix3Xd readDisplacementsCsv(const fs::path& path, Eigen::Index nodes)
{
  std::ifstream f(path);
  if (!f)
    throw std::runtime_error("cannot read " + path.string());
  Eigen::Matrix3Xd u = Eigen::Matrix3Xd::Constant(3, nodes, NAN);
  std::string line;
  std::getline(f, line); // header
  while (std::getline(f, line))
  {
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream s(line);
    long node = 0;
    double x, y, z, ux, uy, uz;
    if (!(s >> node >> x >> y >> z >> ux >> uy >> uz))
      continue;
    if (node >= 1 && node <= nodes)
      u.col(node - 1) = Eigen::Vector3d(ux, uy, uz);
  }
  return u;
}

/// The line of caps fem's output that starts with @a prefix, or "".
std::string lineStarting(const fs::path& log, const std::string& prefix)
{
  std::ifstream f(log);
  std::string line;
  while (std::getline(f, line))
    if (line.rfind(prefix, 0) == 0)
      return line;
  return {};
}

} // namespace

int main(int argc, char** argv)
{
  int threads = 2, runs = 1;
  bool keep = false;
  std::vector<long> targets;
  for (int a = 1; a < argc; ++a)
  {
    const std::string arg = argv[a];
    if ((arg == "--threads" || arg == "--runs") && a + 1 < argc)
      (arg == "--threads" ? threads : runs) = std::max(1, std::atoi(argv[++a]));
    else if (arg == "--keep")
      keep = true;
    else
      targets.push_back(std::atol(argv[a]));
  }
  if (targets.empty())
    targets = {10000, 50000, 107000};
  const fs::path caps = fs::read_symlink("/proc/self/exe").parent_path() / "caps";
  if (!fs::exists(caps))
  {
    std::printf("no caps binary beside this benchmark (%s): build the target caps\n", caps.c_str());
    return 1;
  }
  const int layers = 3;
  std::printf("caps fem --threads %d against ccx with OMP_NUM_THREADS=%d CCX_NPROC_EQUATION_SOLVER=%d; "
              "whole processes, best of %d\n",
              threads, threads, threads, runs);
  std::printf("%8s %7s %9s %9s %9s %10s  %s\n", "DOF", "elems", "ccx s", "caps s", "ccx/caps", "max |du|",
              "caps fem's phases");
  for (long target : targets)
  {
    const Mesh mesh = skinPatchOfSize(target, layers);
    MaterialTable materials = skinPatchMaterials();
    Constraints c;
    const double top = mesh.nodes.row(2).maxCoeff();
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
    {
      if (mesh.nodes(2, i) < 1e-9)
        c.fixNode(int(i));
      if (std::abs(mesh.nodes(2, i) - top) < 1e-9 &&
          std::hypot(mesh.nodes(0, i) - 40.0, mesh.nodes(1, i) - 40.0) < 10.0)
        c.prescribe(int(i), 2, -0.5);
    }
    LoadCase load;
    load.gravity = Eigen::Vector3d(0, -9810.0, -9810.0);

    const fs::path dir = fs::temp_directory_path() / ("caps_bench_fem_whole_" + std::to_string(target));
    fs::remove_all(dir);
    fs::create_directories(dir);
    writeCalculixInput((dir / "job.inp").string(), mesh, materials, c, load);

    const std::string t = std::to_string(threads);
    const std::string ccxCommand = "cd '" + dir.string() + "' && env OMP_NUM_THREADS=" + t +
                                   " CCX_NPROC_EQUATION_SOLVER=" + t + " ccx -i job > ccx.log 2>&1";
    const std::string capsCommand = "cd '" + dir.string() + "' && env OMP_NUM_THREADS=" + t + " '" + caps.string() +
                                    "' fem job.inp --out out --threads " + t + " > caps.log 2>&1";
    double ccxSeconds = INFINITY, capsSeconds = INFINITY;
    for (int r = 0; r < runs; ++r)
    {
      const double a = timed(ccxCommand), b = timed(capsCommand);
      if (a < 0 || b < 0)
      {
        std::printf("%8ld: %s failed, see %s\n", long(mesh.dofCount()), a < 0 ? "ccx" : "caps fem",
                    (dir / (a < 0 ? "ccx.log" : "caps.log")).c_str());
        return 1;
      }
      ccxSeconds = std::min(ccxSeconds, a);
      capsSeconds = std::min(capsSeconds, b);
    }
    const Eigen::Matrix3Xd theirs = readDatDisplacements((dir / "job.dat").string(), mesh.nodeCount());
    const Eigen::Matrix3Xd ours = readDisplacementsCsv(dir / "out" / "displacements.csv", mesh.nodeCount());
    const double difference = (theirs - ours).cwiseAbs().maxCoeff() / ours.cwiseAbs().maxCoeff();
    std::string phases = lineStarting(dir / "caps.log", "time (s): ");
    if (!phases.empty())
      phases = phases.substr(10);
    std::printf("%8ld %7zu %9.2f %9.2f %9.2f %10.1e  %s\n", long(mesh.dofCount()), mesh.elements.size(), ccxSeconds,
                capsSeconds, ccxSeconds / capsSeconds, difference, phases.c_str());
    if (!(difference < 1e-4))
      std::printf("         the displacements differ (see %s)\n", dir.c_str());
    std::fflush(stdout);
    if (!keep && difference < 1e-4)
      fs::remove_all(dir);
  }
  return 0;
}
