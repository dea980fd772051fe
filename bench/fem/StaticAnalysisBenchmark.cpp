// caps_bench_fem: time per phase (assemble, constrain, analyse, factor,
// solve, a second load case) of LinearStaticAnalysis on structured layered
// meshes shaped like a patch of skin (80 x 80 x 8 mm, 3 layers of 20-node
// bricks through the thickness, base fixed), and optionally the same mesh
// solved by CalculiX in the same run, printing our time / ccx time.
//
// Usage: caps_bench_fem [--ccx] [DOFS ...]   (default 10000 50000 100000)

#include "fem/CalculixIO.h"
#include "fem/StaticAnalysis.h"

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace {

using namespace caps::fem;
using Clock = std::chrono::steady_clock;

// n x n x layers bricks over 80 x 80 x 8 mm; nodes on the doubled grid.
Mesh skinPatch(int n, int layers) {
  Mesh mesh;
  std::map<std::array<int, 3>, int> ids;
  std::vector<Eigen::Vector3d> xs;
  const double hx = 80.0 / (2 * n), hz = 8.0 / (2 * layers);
  for (int k = 0; k < layers; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        Element el;
        el.region = k;
        for (int b = 0; b < kHex20NodeCount; ++b) {
          const Eigen::Vector3d r = batheNaturalCoordinates(b);
          const std::array<int, 3> key{2 * i + 1 + int(r[0]), 2 * j + 1 + int(r[1]), 2 * k + 1 + int(r[2])};
          auto [it, inserted] = ids.emplace(key, int(xs.size()));
          if (inserted) xs.emplace_back(key[0] * hx, key[1] * hx, key[2] * hz);
          el.nodes[std::size_t(b)] = it->second;
        }
        mesh.elements.push_back(el);
      }
  mesh.nodes.resize(3, Eigen::Index(xs.size()));
  for (std::size_t i = 0; i < xs.size(); ++i) mesh.nodes.col(Eigen::Index(i)) = xs[i];
  return mesh;
}

double seconds(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

int main(int argc, char** argv) {
  bool runCcx = false;
  std::vector<long> targets;
  for (int a = 1; a < argc; ++a) {
    if (std::string(argv[a]) == "--ccx")
      runCcx = true;
    else
      targets.push_back(std::atol(argv[a]));
  }
  if (targets.empty()) targets = {10000, 50000, 100000};
  const int layers = 3;
  std::printf("%8s %7s %9s %9s %9s %9s %9s %9s %9s %9s\n", "DOF", "elems", "assemble", "constrain", "analyse",
              "factor", "solve", "2nd case", "total", "ccx/ours");
  for (long target : targets) {
    int n = 2;
    while (3L * skinPatch(n + 1, layers).nodeCount() <= target) ++n;
    const Mesh mesh = skinPatch(n, layers);
    MaterialTable materials{{0, {0.015, 0.45, 1.1e-9}}, {1, {0.005, 0.45, 0.95e-9}}, {2, {0.03, 0.45, 1.05e-9}}};
    Constraints c;
    for (Eigen::Index i = 0; i < mesh.nodeCount(); ++i)
      if (mesh.nodes(2, i) < 1e-9) c.fixNode(int(i));
    LoadCase gravity;
    gravity.gravity = Eigen::Vector3d(0, -9810.0, -9810.0);
    LoadCase push;
    push.nodalForces.push_back({int(mesh.nodeCount()) - 1, Eigen::Vector3d(0, 0, -0.01)});

    const auto t0 = Clock::now();
    LinearStaticAnalysis analysis(mesh, materials, c);
    if (analysis.prepare() != SolverStatus::Success) {
      std::printf("failed: %s\n", analysis.message().c_str());
      return 1;
    }
    analysis.solve(gravity);
    const PhaseTimes first = analysis.times();
    analysis.solve(push);
    const double second = analysis.times().solve;
    const double total = seconds(t0);
    double ratio = 0.0;
    if (runCcx) {
      const auto dir = std::filesystem::temp_directory_path() / "caps_bench_fem_ccx";
      std::filesystem::create_directories(dir);
      writeCalculixInput((dir / "job.inp").string(), mesh, materials, c, gravity);
      const auto t1 = Clock::now();
      const std::string cmd = "cd '" + dir.string() + "' && ccx -i job > ccx.log 2>&1";
      if (std::system(cmd.c_str()) != 0) std::printf("ccx failed, see %s/ccx.log\n", dir.c_str());
      ratio = seconds(t1) / total;
      std::filesystem::remove_all(dir);
    }
    std::printf("%8ld %7zu %9.3f %9.3f %9.3f %9.3f %9.3f %9.3f %9.3f %9.2f\n", long(mesh.dofCount()),
                mesh.elements.size(), first.assemble, first.constrain, first.analyse, first.factor, first.solve,
                second, total, ratio);
  }
  return 0;
}
