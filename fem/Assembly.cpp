#include "fem/Assembly.h"

#include "fem/ElasticityIntegrator.h"

#include <algorithm>
#include <exception>
#include <thread>
#include <vector>

namespace caps::fem {

namespace {

using Triplet = Eigen::Triplet<double>;

struct ChunkResult {
  std::vector<Triplet> triplets;
  std::exception_ptr error;
};

void assembleRange(const Mesh& mesh, const MaterialTable& materials, int pointsPerDirection,
                   std::size_t first, std::size_t last, ChunkResult& out) {
  try {
    ElementMatrix ke;
    out.triplets.reserve((last - first) * (kHex20DofCount * (kHex20DofCount + 1) / 2));
    for (std::size_t e = first; e < last; ++e) {
      const Element& el = mesh.elements[e];
      const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
      assembleElementStiffness(shape, mesh.elementCoordinates(e), materials.at(el.region),
                               integrationRule(el.kind, pointsPerDirection), int(e), ke);
      for (int p = 0; p < kHex20DofCount; ++p) {
        const int np = el.nodes[p / 3];
        if (np < 0) continue;
        const int gp = 3 * np + p % 3;
        for (int q = 0; q < kHex20DofCount; ++q) {
          const int nq = el.nodes[q / 3];
          if (nq < 0) continue;
          const int gq = 3 * nq + q % 3;
          if (gp <= gq) out.triplets.emplace_back(gp, gq, ke(p, q));
        }
      }
    }
  } catch (...) {
    out.error = std::current_exception();
  }
}

}  // namespace

Eigen::SparseMatrix<double> assembleStiffness(const Mesh& mesh, const MaterialTable& materials,
                                              const AssemblyOptions& options) {
  // Fail early on a bad rule, not in a worker thread.
  gaussRule(options.gaussPointsPerDirection);
  for (const Element& el : mesh.elements)
    if (el.kind == ElementKind::Wedge15) {
      wedgeRule(options.gaussPointsPerDirection);
      break;
    }
  const int n = options.gaussPointsPerDirection;
  const std::size_t ne = mesh.elements.size();
  const std::size_t threads =
      std::max<std::size_t>(1, std::min<std::size_t>(std::size_t(std::max(1, options.threads)), ne));
  std::vector<ChunkResult> chunks(threads);
  std::vector<std::thread> workers;
  for (std::size_t t = 0; t < threads; ++t) {
    const std::size_t first = ne * t / threads, last = ne * (t + 1) / threads;
    if (t + 1 == threads) {
      assembleRange(mesh, materials, n, first, last, chunks[t]);
    } else {
      workers.emplace_back(assembleRange, std::cref(mesh), std::cref(materials), n, first, last,
                           std::ref(chunks[t]));
    }
  }
  for (auto& w : workers) w.join();
  for (auto& c : chunks)
    if (c.error) std::rethrow_exception(c.error);  // chunks are in element order

  std::size_t total = 0;
  for (auto& c : chunks) total += c.triplets.size();
  std::vector<Triplet> all;
  all.reserve(total);
  for (auto& c : chunks) {
    all.insert(all.end(), c.triplets.begin(), c.triplets.end());
    std::vector<Triplet>().swap(c.triplets);
  }
  Eigen::SparseMatrix<double> k(mesh.dofCount(), mesh.dofCount());
  k.setFromTriplets(all.begin(), all.end());
  k.makeCompressed();
  return k;
}

Eigen::VectorXd assembleGravityLoad(const Mesh& mesh, const MaterialTable& materials,
                                    const Eigen::Vector3d& acceleration, const AssemblyOptions& options) {
  Eigen::VectorXd r = Eigen::VectorXd::Zero(mesh.dofCount());
  ElementVector re;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e) {
    const Element& el = mesh.elements[e];
    const double rho = materials.at(el.region).density;
    if (rho == 0.0) continue;
    assembleElementBodyForce(ElementShape::fromConnectivity(el.kind, el.nodes), mesh.elementCoordinates(e),
                             rho * acceleration, integrationRule(el.kind, options.gaussPointsPerDirection), int(e),
                             re);
    for (int k = 0; k < kHex20NodeCount; ++k)
      if (el.nodes[k] >= 0) r.segment<3>(3 * el.nodes[k]) += re.segment<3>(3 * k);
  }
  return r;
}

}  // namespace caps::fem
