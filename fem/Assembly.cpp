#include "fem/Assembly.h"

#include "fem/ElasticityIntegrator.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <exception>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

namespace caps::fem {

namespace {

/// The upper triangle's pattern of K in compressed columns, built from the
/// node adjacency (two nodes couple when an element holds both): column
/// 3n + d holds rows 3m..3m+2 of every neighbour m < n, then 3n..3n+d.
struct StiffnessPattern
{
  std::vector<std::vector<int>> lowerNeighbours; ///< per node n: sorted neighbours m < n
  std::vector<int> outer;                        ///< column starts, size 3N + 1
  std::vector<int> inner;                        ///< row indices

  explicit StiffnessPattern(const Mesh& mesh)
  {
    const std::size_t nodes = std::size_t(mesh.nodeCount());
    // Elements of each node (compressed), then each node's neighbours by a
    // stamp array: no per-pair pushes, no global sort.
    std::vector<int> firstElement(nodes + 1, 0), lastSeen(nodes, -1);
    for (std::size_t e = 0; e < mesh.elements.size(); ++e)
      for (int a : mesh.elements[e].nodes)
        if (a >= 0 && lastSeen[std::size_t(a)] != int(e))
        { // a wedge repeats a node
          lastSeen[std::size_t(a)] = int(e);
          ++firstElement[std::size_t(a) + 1];
        }
    for (std::size_t n = 0; n < nodes; ++n)
      firstElement[n + 1] += firstElement[n];
    std::vector<int> elementsOf(std::size_t(firstElement.back()));
    {
      std::vector<int> fill(firstElement.begin(), firstElement.end() - 1);
      std::fill(lastSeen.begin(), lastSeen.end(), -1);
      for (std::size_t e = 0; e < mesh.elements.size(); ++e)
        for (int a : mesh.elements[e].nodes)
          if (a >= 0 && lastSeen[std::size_t(a)] != int(e))
          {
            lastSeen[std::size_t(a)] = int(e);
            elementsOf[std::size_t(fill[std::size_t(a)]++)] = int(e);
          }
    }
    lowerNeighbours.resize(nodes);
    std::vector<int> stamp(nodes, -1);
    for (std::size_t n = 0; n < nodes; ++n)
    {
      auto& nb = lowerNeighbours[n];
      for (int k = firstElement[n]; k < firstElement[n + 1]; ++k)
        for (int m : mesh.elements[std::size_t(elementsOf[std::size_t(k)])].nodes)
          if (m >= 0 && std::size_t(m) < n && stamp[std::size_t(m)] != int(n))
          {
            stamp[std::size_t(m)] = int(n);
            nb.push_back(m);
          }
      std::sort(nb.begin(), nb.end());
    }
    outer.assign(3 * nodes + 1, 0);
    for (std::size_t n = 0; n < nodes; ++n)
      for (int d = 0; d < 3; ++d)
        outer[3 * n + d + 1] = outer[3 * n + d] + 3 * int(lowerNeighbours[n].size()) + d + 1;
    inner.resize(std::size_t(outer.back()));
    for (std::size_t n = 0; n < nodes; ++n)
      for (int d = 0; d < 3; ++d)
      {
        int* row = &inner[std::size_t(outer[3 * n + d])];
        for (int m : lowerNeighbours[n])
          for (int c = 0; c < 3; ++c)
            *row++ = 3 * m + c;
        for (int c = 0; c <= d; ++c)
          *row++ = int(3 * n) + c;
      }
  }
};

/// Adds one element matrix into K's values. Column 3 q of the pattern lists
/// rows 3 m of q's lower neighbours m (every third entry), then q's own; for
/// each column node one walk along that list finds the rank of every element
/// node below it (the element's nodes sorted), so no search per entry.
void scatter(const int* outer, const int* inner, const Element& el, const ElementMatrix& ke, double* values)
{
  std::array<std::pair<int, int>, kHex20NodeCount> sorted; // (node, slot)
  int count = 0;
  for (int p = 0; p < kHex20NodeCount; ++p)
    if (el.nodes[std::size_t(p)] >= 0)
      sorted[std::size_t(count++)] = {el.nodes[std::size_t(p)], p};
  std::sort(sorted.begin(), sorted.begin() + count);
  std::array<int, kHex20NodeCount> rank{};
  for (int k = 0; k < count; ++k)
  {
    const auto [nq, q] = sorted[std::size_t(k)];
    const int* column = inner + outer[3 * nq];
    const int neighbours = (outer[3 * nq + 1] - outer[3 * nq] - 1) / 3;
    int walk = 0;
    for (int i = 0; i < count; ++i)
    {
      const int np = sorted[std::size_t(i)].first;
      if (np >= nq)
      {
        rank[std::size_t(i)] = neighbours; // the node itself (np == nq), after its neighbours
        continue;
      }
      while (column[3 * walk] < 3 * np)
        ++walk;
      rank[std::size_t(i)] = walk;
    }
    for (int d = 0; d < 3; ++d)
    {
      const int base = outer[3 * nq + d];
      for (int i = 0; i < count; ++i)
      {
        const auto [np, p] = sorted[std::size_t(i)];
        if (np > nq)
          break;
        // On one node (the diagonal block; twice for a degenerate wedge's
        // repeated node, (p, q) and (q, p) both) only the upper part c <= d.
        const int rows = np == nq ? d + 1 : 3;
        double* v = values + base + 3 * rank[std::size_t(i)];
        for (int c = 0; c < rows; ++c)
          v[c] += ke(3 * p + c, 3 * q + d);
      }
    }
  }
}

} // namespace

Eigen::SparseMatrix<double> stiffnessPattern(const Mesh& mesh)
{
  const StiffnessPattern pattern(mesh);
  const Eigen::Index dofs = mesh.dofCount();
  Eigen::SparseMatrix<double> k(dofs, dofs);
  k.resizeNonZeros(Eigen::Index(pattern.inner.size()));
  std::copy(pattern.outer.begin(), pattern.outer.end(), k.outerIndexPtr());
  std::copy(pattern.inner.begin(), pattern.inner.end(), k.innerIndexPtr());
  std::fill_n(k.valuePtr(), pattern.inner.size(), 0.0);
  return k;
}

void assembleElements(const Mesh& mesh, int threads, const ElementKernel& kernel, Eigen::SparseMatrix<double>* k,
                      Eigen::VectorXd* r)
{
  if (k && (k->rows() != mesh.dofCount() || k->cols() != mesh.dofCount() || !k->isCompressed()))
    throw std::invalid_argument("assembleElements: the matrix does not have the mesh's stiffness pattern");
  if (k)
    std::fill_n(k->valuePtr(), k->nonZeros(), 0.0);
  if (r)
    r->setZero(mesh.dofCount());
  const std::size_t ne = mesh.elements.size();
  const std::size_t workers = std::size_t(std::max(1, threads));

  // Element matrices in batches, into one of two buffers, while this thread
  // scatters the batch before from the other; then it joins the workers on
  // what is left of the batch. The scatter runs in element order, so the
  // sums are bit-identical for any thread count. Straight into the
  // pattern's places: no triplet list to sort.
  constexpr std::size_t kBatch = 256;
  std::array<std::vector<ElementMatrix>, 2> matrices;
  std::array<std::vector<ElementVector>, 2> vectors;
  for (int b = 0; b < 2; ++b)
  {
    if (k)
      matrices[std::size_t(b)].resize(kBatch);
    if (r)
      vectors[std::size_t(b)].resize(kBatch);
  }
  // The lowest-numbered failing element of a batch.
  struct Failure
  {
    std::mutex mutex;
    std::size_t element = std::numeric_limits<std::size_t>::max();
    std::exception_ptr error;
    void record(std::size_t e, std::exception_ptr p)
    {
      const std::lock_guard<std::mutex> lock(mutex);
      if (e < element)
      {
        element = e;
        error = std::move(p);
      }
    }
  };
  auto compute = [&](std::size_t begin, std::size_t end, std::size_t buffer, std::atomic<std::size_t>& next,
                     Failure& failure) {
    for (std::size_t e = next.fetch_add(1); e < end; e = next.fetch_add(1))
    {
      try
      {
        kernel(e, k ? &matrices[buffer][e - begin] : nullptr, r ? &vectors[buffer][e - begin] : nullptr);
      }
      catch (...)
      {
        failure.record(e, std::current_exception());
      }
    }
  };
  auto scatterBatch = [&](std::size_t begin, std::size_t end, std::size_t buffer) {
    for (std::size_t e = begin; e < end; ++e)
    {
      const Element& el = mesh.elements[e];
      if (k)
        scatter(k->outerIndexPtr(), k->innerIndexPtr(), el, matrices[buffer][e - begin], k->valuePtr());
      if (r)
        for (int a = 0; a < kHex20NodeCount; ++a)
          if (el.nodes[std::size_t(a)] >= 0)
            r->segment<3>(3 * el.nodes[std::size_t(a)]) += vectors[buffer][e - begin].segment<3>(3 * a);
    }
  };
  std::size_t pendingBegin = 0, pendingEnd = 0, pendingBuffer = 1; // computed, not yet scattered
  for (std::size_t begin = 0, batch = 0; begin < ne; begin += kBatch, ++batch)
  {
    const std::size_t end = std::min(ne, begin + kBatch);
    const std::size_t buffer = batch % 2;
    std::atomic<std::size_t> next{begin};
    Failure failure;
    std::vector<std::thread> pool;
    for (std::size_t t = 1; t < std::min(workers, end - begin); ++t)
      pool.emplace_back(compute, begin, end, buffer, std::ref(next), std::ref(failure));
    scatterBatch(pendingBegin, pendingEnd, pendingBuffer);
    compute(begin, end, buffer, next, failure);
    for (auto& w : pool)
      w.join();
    if (failure.error)
      std::rethrow_exception(failure.error);
    pendingBegin = begin;
    pendingEnd = end;
    pendingBuffer = buffer;
  }
  scatterBatch(pendingBegin, pendingEnd, pendingBuffer);
}

void assembleStiffnessValues(const Mesh& mesh, const MaterialTable& materials, const AssemblyOptions& options,
                             Eigen::SparseMatrix<double>& k)
{
  // Fail early on a bad rule, not in a worker thread.
  gaussRule(options.gaussPointsPerDirection);
  for (const Element& el : mesh.elements)
    integrationRule(el.kind, integrationPointsOf(el, options.gaussPointsPerDirection));
  if (k.rows() != mesh.dofCount() || k.cols() != mesh.dofCount() || !k.isCompressed())
    throw std::invalid_argument("assembleStiffnessValues: the matrix does not have the mesh's stiffness pattern");
  assembleElements(
    mesh, options.threads,
    [&](std::size_t e, ElementMatrix* ke, ElementVector*) {
      const Element& el = mesh.elements[e];
      const ElementShape shape = ElementShape::fromConnectivity(el.kind, el.nodes);
      assembleElementStiffness(shape, mesh.elementCoordinates(e), materials.at(el.region),
                               integrationRule(el.kind, integrationPointsOf(el, options.gaussPointsPerDirection)),
                               int(e), *ke);
    },
    &k, nullptr);
}

Eigen::SparseMatrix<double> assembleStiffness(const Mesh& mesh, const MaterialTable& materials,
                                              const AssemblyOptions& options)
{
  Eigen::SparseMatrix<double> k = stiffnessPattern(mesh);
  assembleStiffnessValues(mesh, materials, options, k);
  return k;
}

Eigen::VectorXd assembleGravityLoad(const Mesh& mesh, const MaterialTable& materials,
                                    const Eigen::Vector3d& acceleration, const AssemblyOptions& options)
{
  Eigen::VectorXd r = Eigen::VectorXd::Zero(mesh.dofCount());
  ElementVector re;
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    const Element& el = mesh.elements[e];
    const double rho = materials.at(el.region).density;
    if (rho == 0.0)
      continue;
    assembleElementBodyForce(
      ElementShape::fromConnectivity(el.kind, el.nodes), mesh.elementCoordinates(e), rho * acceleration,
      integrationRule(el.kind, integrationPointsOf(el, options.gaussPointsPerDirection)), int(e), re);
    for (int k = 0; k < kHex20NodeCount; ++k)
      if (el.nodes[k] >= 0)
        r.segment<3>(3 * el.nodes[k]) += re.segment<3>(3 * k);
  }
  return r;
}

} // namespace caps::fem
