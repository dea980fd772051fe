// caps_bench_cholmod: factor + solve time of our CHOLMOD supernodal solver
// against Eigen's SimplicialLLT on the same elasticity-like matrix, in the
// same run (a ratio, never an absolute threshold).
//
// Usage: caps_bench_cholmod [n]   (n x n x n node grid, 3 DOFs per node,
//                                  bottom layer clamped; default n = 15)

#include "fem/BlasKernels.h"
#include "fem/SparseCholeskySolver.h"

#include <Eigen/SparseCholesky>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using Clock = std::chrono::steady_clock;

// Same construction as tests/fem/TestMatrices.h: bars k (d d^T + 0.1 I)
// between all nodes of each 3x3x3 neighbourhood, z = 0 layer clamped.
SparseMatrix latticeStiffness(int n)
{
  const auto node = [n](int x, int y, int z) { return (z * n + y) * n + x; };
  const int firstFree = n * n;
  const int dofs = 3 * (n * n * n - firstFree);
  std::vector<Eigen::Triplet<double>> t;
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        for (int dz = 0; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx)
            {
              if (dz == 0 && (dy < 0 || (dy == 0 && dx <= 0)))
                continue;
              const int x2 = x + dx, y2 = y + dy, z2 = z + dz;
              if (x2 < 0 || y2 < 0 || x2 >= n || y2 >= n || z2 >= n)
                continue;
              const int a = node(x, y, z), b = node(x2, y2, z2);
              Eigen::Vector3d d(dx, dy, dz);
              d.normalize();
              const double k = 1.0 + 0.5 * std::sin(0.37 * a + 0.11 * b);
              const Eigen::Matrix3d block = k * (d * d.transpose() + 0.1 * Eigen::Matrix3d::Identity());
              const int ab[2] = {a, b};
              for (int i = 0; i < 2; ++i)
                for (int j = 0; j < 2; ++j)
                {
                  if (ab[i] < firstFree || ab[j] < firstFree)
                    continue;
                  for (int p = 0; p < 3; ++p)
                    for (int q = 0; q < 3; ++q)
                      t.emplace_back(3 * (ab[i] - firstFree) + p, 3 * (ab[j] - firstFree) + q,
                                     (i == j ? 1.0 : -1.0) * block(p, q));
                }
            }
  SparseMatrix m(dofs, dofs);
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

// Which BLAS the dynamic linker picked (Debian alternatives): the first
// mapped library whose name says BLAS.
std::string blasInUse()
{
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line))
  {
    const auto slash = line.find('/');
    if (slash == std::string::npos)
      continue;
    const std::string path = line.substr(slash);
    const auto name = path.substr(path.rfind('/') + 1);
    if (name.find("blas") != std::string::npos || name.find("mkl") != std::string::npos ||
        name.find("blis") != std::string::npos)
      return path;
  }
  return "unknown (no BLAS library mapped)";
}

double seconds(Clock::time_point from, Clock::time_point to)
{
  return std::chrono::duration<double>(to - from).count();
}

} // namespace

int main(int argc, char** argv)
{
  caps::fem::useBestBlasKernels(argv);
  const int n = argc > 1 ? std::atoi(argv[1]) : 15;
  if (n < 2)
  {
    std::fprintf(stderr, "usage: %s [n >= 2]\n", argv[0]);
    return 2;
  }
  const SparseMatrix k = latticeStiffness(n);
  Eigen::VectorXd f(k.rows());
  for (Eigen::Index i = 0; i < f.size(); ++i)
    f[i] = std::sin(0.7 * double(i)) + 0.25;
  std::printf("grid %d^3 nodes, %ld DOFs, %ld nonzeros (full matrix)\n", n, long(k.rows()), long(k.nonZeros()));

  const auto t0 = Clock::now();
  caps::fem::SparseCholeskySolver cholmod;
  cholmod.compute(k);
  if (cholmod.status() != caps::fem::SolverStatus::Success)
  {
    std::fprintf(stderr, "CHOLMOD failed: %s\n", cholmod.message().c_str());
    return 1;
  }
  const Eigen::VectorXd uCholmod = cholmod.solve(f);
  const auto t1 = Clock::now();

  Eigen::SimplicialLLT<SparseMatrix> simplicial(k);
  if (simplicial.info() != Eigen::Success)
  {
    std::fprintf(stderr, "SimplicialLLT failed\n");
    return 1;
  }
  const Eigen::VectorXd uSimplicial = simplicial.solve(f);
  const auto t2 = Clock::now();

  const double cholmodTime = seconds(t0, t1);
  const double simplicialTime = seconds(t1, t2);
  std::printf("BLAS: %s\n", blasInUse().c_str());
  std::printf("CHOLMOD supernodal   factor+solve: %8.3f s  (residual %.1e)\n", cholmodTime,
              (k * uCholmod - f).norm() / f.norm());
  std::printf("Eigen SimplicialLLT  factor+solve: %8.3f s  (residual %.1e)\n", simplicialTime,
              (k * uSimplicial - f).norm() / f.norm());
  std::printf("ratio SimplicialLLT / CHOLMOD: %.2fx\n", simplicialTime / cholmodTime);
  std::printf("solutions differ by %.1e (relative)\n", (uCholmod - uSimplicial).norm() / uSimplicial.norm());
  return 0;
}
