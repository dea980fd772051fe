#include "fem/SparseCholeskySolver.h"

#include <cholmod.h>
#include <dlfcn.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace caps::fem {

namespace {

// Wraps an Eigen matrix as a cholmod_sparse without copying. stype = 1: CHOLMOD
// reads the upper triangle only, so both upper and full input work.
cholmod_sparse viewOf(const Eigen::SparseMatrix<double>& a)
{
  cholmod_sparse s{};
  s.nrow = static_cast<size_t>(a.rows());
  s.ncol = static_cast<size_t>(a.cols());
  s.nzmax = static_cast<size_t>(a.nonZeros());
  s.p = const_cast<int*>(a.outerIndexPtr());
  s.i = const_cast<int*>(a.innerIndexPtr());
  s.nz = nullptr;
  s.x = const_cast<double*>(a.valuePtr());
  s.z = nullptr;
  s.stype = 1;
  s.itype = CHOLMOD_INT;
  s.xtype = CHOLMOD_REAL;
  s.dtype = CHOLMOD_DOUBLE;
  s.sorted = 1;
  s.packed = 1;
  return s;
}

cholmod_dense denseViewOf(const double* data, Eigen::Index rows, Eigen::Index cols)
{
  cholmod_dense b{};
  b.nrow = static_cast<size_t>(rows);
  b.ncol = static_cast<size_t>(cols);
  b.nzmax = b.nrow * b.ncol;
  b.d = b.nrow;
  b.x = const_cast<double*>(data);
  b.z = nullptr;
  b.xtype = CHOLMOD_REAL;
  b.dtype = CHOLMOD_DOUBLE;
  return b;
}

/// The columns by group: groups renumbered 0..count-1 in order of their
/// first column (id: original -> renumbered, -1 if absent), the group of each
/// column, and each group's columns (columns[first[k]] .. columns[first[k+1]-1]).
struct ColumnGroups
{
  int count = 0;
  std::vector<int> id, groupOf, first, columns;
};

ColumnGroups columnGroups(int n, const std::vector<int>& group)
{
  ColumnGroups c;
  int& ng = c.count;
  std::vector<int>& id = c.id;
  std::vector<int>& g = c.groupOf;
  id.assign(std::size_t(*std::max_element(group.begin(), group.end())) + 1, -1);
  g.assign(static_cast<std::size_t>(n), 0);
  for (int j = 0; j < n; ++j)
  {
    int& k = id[std::size_t(group[std::size_t(j)])];
    if (k < 0)
      k = ng++;
    g[std::size_t(j)] = k;
  }
  std::vector<int>& first = c.first;
  first.assign(std::size_t(ng) + 1, 0);
  for (int j = 0; j < n; ++j)
    ++first[std::size_t(g[std::size_t(j)]) + 1];
  for (int k = 0; k < ng; ++k)
    first[std::size_t(k) + 1] += first[std::size_t(k)];
  c.columns.assign(static_cast<std::size_t>(n), 0);
  std::vector<int> fill(first.begin(), first.end() - 1);
  for (int j = 0; j < n; ++j)
    c.columns[std::size_t(fill[std::size_t(g[std::size_t(j)])]++)] = j;
  return c;
}

/// Attached groups (renumbered) with their ends, and the others, the
/// primary groups, numbered 0..count-1 for the graph.
struct PrimaryGroups
{
  std::vector<std::array<int, 2>> ends; ///< per group: its ends, or -1
  std::vector<int> primary;             ///< per group: its primary number, or -1
  std::vector<int> groupOfPrimary;
  int count = 0;
  bool isAttached(int k) const { return ends[std::size_t(k)][0] >= 0 || ends[std::size_t(k)][1] >= 0; }
};

PrimaryGroups primaryGroups(const ColumnGroups& groups,
                            const std::vector<SparseCholeskySolver::AttachedGroup>& attachedGroups)
{
  const int ng = groups.count;
  const std::vector<int>& id = groups.id;
  auto renumbered = [&id](int original) {
    return original >= 0 && std::size_t(original) < id.size() ? id[std::size_t(original)] : -1;
  };
  PrimaryGroups p;
  p.ends.assign(std::size_t(ng), {-1, -1});
  for (const auto& at : attachedGroups)
  {
    const int k = renumbered(at.group);
    if (k >= 0)
      p.ends[std::size_t(k)] = {renumbered(at.first), renumbered(at.second)};
  }
  { // ends must not be attached groups themselves
    std::vector<char> wasAttached(std::size_t(ng), 0);
    for (int k = 0; k < ng; ++k)
      wasAttached[std::size_t(k)] = p.isAttached(k);
    for (auto& pair : p.ends)
      for (int& e : pair)
        if (e >= 0 && wasAttached[std::size_t(e)])
          e = -1;
  }
  int& np = p.count;
  p.primary.assign(std::size_t(ng), -1);
  for (int k = 0; k < ng; ++k)
    if (!p.isAttached(k))
      p.primary[std::size_t(k)] = np++;
  p.groupOfPrimary.assign(std::size_t(np), 0);
  for (int k = 0; k < ng; ++k)
    if (p.primary[std::size_t(k)] >= 0)
      p.groupOfPrimary[std::size_t(p.primary[std::size_t(k)])] = k;
  return p;
}

/// The graph of the primary groups, upper triangle with the diagonal, in
/// compressed columns (sorted, no repeats).
struct GroupGraph
{
  std::vector<int> outer, inner;
};

GroupGraph primaryGraph(const Eigen::SparseMatrix<double>& a, const ColumnGroups& groups,
                        const PrimaryGroups& primaries)
{
  const int np = primaries.count;
  const std::vector<int>& first = groups.first;
  // Primary pairs (lo < hi) from the upper triangle, once per group column
  // (stamps), counted into the column of the higher one, then each column
  // sorted (a pair can come from both of its groups).
  std::vector<int> stamp(std::size_t(np), -1);
  GroupGraph graph;
  std::vector<int>& outer = graph.outer;
  std::vector<int>& inner = graph.inner;
  outer.assign(std::size_t(np) + 1, 0);
  auto eachPair = [&](auto&& visit) {
    std::fill(stamp.begin(), stamp.end(), -1);
    for (int p = 0; p < np; ++p)
    {
      const int k = primaries.groupOfPrimary[std::size_t(p)];
      for (int c = first[std::size_t(k)]; c < first[std::size_t(k) + 1]; ++c)
        for (Eigen::SparseMatrix<double>::InnerIterator it(a, groups.columns[std::size_t(c)]); it; ++it)
        {
          if (it.row() > it.col())
            continue;
          const int h = primaries.primary[std::size_t(groups.groupOf[std::size_t(it.row())])];
          if (h < 0 || h == p || stamp[std::size_t(h)] == p)
            continue;
          stamp[std::size_t(h)] = p;
          visit(std::min(h, p), std::max(h, p));
        }
    }
  };
  eachPair([&outer](int, int hi) { ++outer[std::size_t(hi) + 1]; });
  for (int p = 0; p < np; ++p)
    outer[std::size_t(p) + 1] += outer[std::size_t(p)] + 1; // + the diagonal
  inner.resize(std::size_t(outer.back()));
  std::vector<int> fill(outer.begin(), outer.end() - 1);
  eachPair([&](int lo, int hi) { inner[std::size_t(fill[std::size_t(hi)]++)] = lo; });
  for (int p = 0; p < np; ++p)
    inner[std::size_t(fill[std::size_t(p)]++)] = p;
  // Sort and drop repeats, compacting in place.
  int write = 0;
  for (int p = 0; p < np; ++p)
  {
    const auto begin = inner.begin() + outer[std::size_t(p)], end = inner.begin() + fill[std::size_t(p)];
    std::sort(begin, end);
    const int start = write;
    for (auto it = begin; it != end; ++it)
      if (write == start || inner[std::size_t(write - 1)] != *it)
        inner[std::size_t(write++)] = *it;
    outer[std::size_t(p)] = start;
  }
  outer[std::size_t(np)] = write;
  inner.resize(std::size_t(write));
  return graph;
}

/// A fill-reducing permutation of the @a np vertices of @a g: nested
/// dissection, AMD if CHOLMOD has no METIS.
std::vector<int> orderGraph(GroupGraph& g, int np, cholmod_common& common)
{
  cholmod_sparse graph{};
  graph.nrow = graph.ncol = std::size_t(np);
  graph.nzmax = g.inner.size();
  graph.p = g.outer.data();
  graph.i = g.inner.data();
  graph.stype = 1;
  graph.itype = CHOLMOD_INT;
  graph.xtype = CHOLMOD_PATTERN;
  graph.dtype = CHOLMOD_DOUBLE;
  graph.sorted = 1;
  graph.packed = 1;
  // CHOLMOD's nested dissection (METIS bisections, then constrained
  // minimum degree inside each part): on the vertex graph of the 100k-DOF
  // skin patch 32.6 GFlop against 37.0 for METIS_NodeND on the same graph.
  std::vector<int> primaryPerm(static_cast<std::size_t>(np), 0);
  std::vector<int> componentParent(static_cast<std::size_t>(np), 0);
  std::vector<int> componentOf(static_cast<std::size_t>(np), 0);
  if (cholmod_nested_dissection(&graph, nullptr, 0, primaryPerm.data(), componentParent.data(), componentOf.data(),
                                &common) < 0)
  {
    common.status = CHOLMOD_OK;
    if (!cholmod_amd(&graph, nullptr, 0, primaryPerm.data(), &common))
      throw std::runtime_error("CHOLMOD could not order the matrix (status " + std::to_string(common.status) + ")");
  }
  return primaryPerm;
}

/// The columns in the order of @a primaryPerm, each group's together, each
/// attached group before the first of its ends to be eliminated.
std::vector<int> columnPermutation(int n, const ColumnGroups& groups, const PrimaryGroups& primaries,
                                   const std::vector<int>& primaryPerm)
{
  const int np = primaries.count;
  std::vector<int> position(std::size_t(np), 0);
  for (int q = 0; q < np; ++q)
    position[std::size_t(primaryPerm[std::size_t(q)])] = q;
  std::vector<std::vector<int>> before(static_cast<std::size_t>(np) + 1); // [np]: ends without columns
  for (int k = 0; k < groups.count; ++k)
  {
    if (!primaries.isAttached(k))
      continue;
    int at = np;
    for (int e : primaries.ends[std::size_t(k)])
      if (e >= 0)
        at = std::min(at, position[std::size_t(primaries.primary[std::size_t(e)])]);
    before[std::size_t(at)].push_back(k);
  }
  std::vector<int> perm;
  perm.reserve(std::size_t(n));
  auto emit = [&](int k) {
    for (int c = groups.first[std::size_t(k)]; c < groups.first[std::size_t(k) + 1]; ++c)
      perm.push_back(groups.columns[std::size_t(c)]);
  };
  for (int q = 0; q < np; ++q)
  {
    for (int k : before[std::size_t(q)])
      emit(k);
    emit(primaries.groupOfPrimary[std::size_t(primaryPerm[std::size_t(q)])]);
  }
  for (int k : before[std::size_t(np)])
    emit(k);
  return perm;
}

// A fill-reducing ordering of the columns computed on the graph of column
// groups (a node's three DOFs): nested dissection of the group graph,
// each group's columns kept together in their own order. Attached groups
// (SparseCholeskySolver::AttachedGroup) stay out of the graph and go right
// before the first of their ends. Falls back to AMD on the group graph if
// CHOLMOD was built without METIS.
std::vector<int> groupedOrdering(const Eigen::SparseMatrix<double>& a, const std::vector<int>& group,
                                 const std::vector<SparseCholeskySolver::AttachedGroup>& attachedGroups,
                                 cholmod_common& common)
{
  const int n = int(a.cols());
  // Renumber the groups 0..ng-1 and list each group's columns.
  const ColumnGroups groups = columnGroups(n, group);
  const PrimaryGroups primaries = primaryGroups(groups, attachedGroups);
  GroupGraph graph = primaryGraph(a, groups, primaries);
  const std::vector<int> primaryPerm = orderGraph(graph, primaries.count, common);
  return columnPermutation(n, groups, primaries, primaryPerm);
}

// CHOLMOD's supernodal factorization parallelises its small scatter loops
// with OpenMP while OpenBLAS runs its own threads inside the dense kernels.
// On few cores the two sets of threads spin against each other (measured on
// 2 cores: a third of the factor time in sched_yield, 2.1 s instead of 1.4 s
// at 100k DOF), so the OpenMP regions run on the calling thread while the
// factorization lasts and the BLAS keeps the cores. Looked up at run time:
// only the OpenMP runtime CHOLMOD itself loaded matters.
class SerialOpenMpRegions
{
public:
  SerialOpenMpRegions()
  {
    using Get = int (*)();
    const auto get = reinterpret_cast<Get>(dlsym(RTLD_DEFAULT, "omp_get_max_active_levels"));
    set_ = reinterpret_cast<Set>(dlsym(RTLD_DEFAULT, "omp_set_max_active_levels"));
    if (!get || !set_)
    {
      set_ = nullptr;
      return;
    }
    previous_ = get();
    set_(0); // no active parallel region: every region runs on one thread
  }
  ~SerialOpenMpRegions()
  {
    if (set_)
      set_(previous_);
  }
  SerialOpenMpRegions(const SerialOpenMpRegions&) = delete;
  SerialOpenMpRegions& operator=(const SerialOpenMpRegions&) = delete;

private:
  using Set = void (*)(int);
  Set set_ = nullptr;
  int previous_ = 1;
};

std::string notPositiveDefiniteMessage(Eigen::Index column, const std::string& detail)
{
  std::ostringstream out;
  out << "The stiffness matrix is not positive definite: the Cholesky factorization "
      << "failed at column " << column << ", i.e. degree of freedom " << column << " of the assembled system ("
      << detail << "). The model probably still has rigid-body freedom (not enough "
      << "fixed nodes to stop it translating or rotating) or contains an inverted "
      << "element (zero or negative volume). Check the boundary conditions and the "
      << "elements around that degree of freedom.";
  return out.str();
}

} // namespace

struct SparseCholeskySolver::Impl
{
  cholmod_common common{};
  cholmod_factor* factor = nullptr;
  Eigen::Index n = 0;
  // Pattern given to analyzePattern(), to catch factorize() on another pattern.
  std::vector<int> outer;
  std::vector<int> inner;
  bool factorized = false;
  SolverStatus status = SolverStatus::InvalidInput;
  std::string message = "no matrix has been analyzed yet";
  Eigen::Index failedColumn = -1;
  // Below about 1e-12 only rounding is left of a zero pivot; real soft-tissue
  // models with fixed bone stay far above it.
  double pivotTolerance = 1e-12;
  std::vector<int> groups; // setColumnGroups()
  std::vector<SparseCholeskySolver::AttachedGroup> attached;

  Impl()
  {
    cholmod_start(&common);
    common.supernodal = CHOLMOD_SUPERNODAL; // dense supernodes go to BLAS
    common.final_ll = 1;                    // keep L L^T, as factorized
    common.print = 0;                       // failures are reported via message()
  }
  ~Impl()
  {
    cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }

  void fail(SolverStatus s, std::string text, Eigen::Index column = -1)
  {
    status = s;
    message = std::move(text);
    failedColumn = column;
    factorized = false;
  }
  void succeed()
  {
    status = SolverStatus::Success;
    message.clear();
    failedColumn = -1;
  }

  // CHOLMOD errors other than "not positive definite" are resource failures
  // or bugs on our side, not something a model change can fix.
  void throwOnCholmodError(const char* stage) const
  {
    if (common.status == CHOLMOD_OUT_OF_MEMORY)
      throw std::bad_alloc();
    if (common.status < CHOLMOD_OK)
    {
      throw std::runtime_error(std::string("CHOLMOD ") + stage + " failed with status " +
                               std::to_string(common.status));
    }
  }

  // Checks shape and triangle; returns false (with status set) on bad input.
  bool validate(const Eigen::SparseMatrix<double>& a)
  {
    if (a.rows() != a.cols())
    {
      fail(SolverStatus::InvalidInput,
           "The matrix must be square but is " + std::to_string(a.rows()) + " x " + std::to_string(a.cols()) + ".");
      return false;
    }
    if (a.rows() == 0)
    {
      fail(SolverStatus::InvalidInput, "The matrix is empty: the model has no free degrees of freedom.");
      return false;
    }
    if (a.nonZeros() > std::numeric_limits<int>::max())
    {
      fail(SolverStatus::InvalidInput, "The matrix has too many entries for 32-bit indices.");
      return false;
    }
    Eigen::Index upper = 0;
    Eigen::Index lower = 0;
    for (Eigen::Index j = 0; j < a.outerSize(); ++j)
    {
      for (Eigen::SparseMatrix<double>::InnerIterator it(a, j); it; ++it)
      {
        if (it.row() < j)
          ++upper;
        if (it.row() > j)
          ++lower;
      }
    }
    if (upper == 0 && lower > 0)
    {
      fail(SolverStatus::InvalidInput,
           "Only the lower triangle of the matrix is stored; pass the upper triangle or the "
           "full symmetric matrix.");
      return false;
    }
    if (lower > 0 && lower != upper)
    {
      fail(SolverStatus::InvalidInput, "The matrix is not symmetric in pattern: " + std::to_string(upper) +
                                         " entries above the diagonal but " + std::to_string(lower) + " below.");
      return false;
    }
    return true;
  }

  // Supernodal L L^T: pivot_j = L_jj^2 is what is left of the diagonal entry
  // after eliminating the columns before it. Returns the permuted column with
  // the smallest pivot / diagonal ratio.
  std::pair<Eigen::Index, double> smallestPivotRatio(const std::vector<double>& diagonal) const
  {
    const auto* super = static_cast<const int*>(factor->super);
    const auto* pi = static_cast<const int*>(factor->pi);
    const auto* px = static_cast<const int*>(factor->px);
    const auto* x = static_cast<const double*>(factor->x);
    const auto* perm = static_cast<const int*>(factor->Perm);
    Eigen::Index worst = -1;
    double worstRatio = std::numeric_limits<double>::infinity();
    for (size_t s = 0; s < factor->nsuper; ++s)
    {
      const int firstColumn = super[s];
      const int columns = super[s + 1] - firstColumn;
      const int rowsInSupernode = pi[s + 1] - pi[s];
      for (int jj = 0; jj < columns; ++jj)
      {
        const double ljj = x[px[s] + jj + static_cast<Eigen::Index>(jj) * rowsInSupernode];
        const int original = perm ? perm[firstColumn + jj] : firstColumn + jj;
        const double ratio = ljj * ljj / diagonal[static_cast<size_t>(original)];
        if (ratio < worstRatio)
        {
          worstRatio = ratio;
          worst = firstColumn + jj;
        }
      }
    }
    return {worst, worstRatio};
  }

  // Column-major right-hand sides in, solutions out; shared by both solve()s.
  Eigen::MatrixXd solveDense(const double* data, Eigen::Index rows, Eigen::Index cols)
  {
    if (!factorized)
    {
      throw std::logic_error("solve() needs a successful factorization: " +
                             (message.empty() ? std::string("call factorize() first") : message));
    }
    if (rows != n)
    {
      throw std::invalid_argument("solve(): the right-hand side has " + std::to_string(rows) +
                                  " rows but the matrix has " + std::to_string(n) + ".");
    }
    if (cols == 0)
      return Eigen::MatrixXd(n, 0);
    cholmod_dense view = denseViewOf(data, rows, cols);
    cholmod_dense* x = cholmod_solve(CHOLMOD_A, factor, &view, &common);
    if (!x)
    {
      throwOnCholmodError("solve");
      throw std::runtime_error("CHOLMOD solve returned no result");
    }
    Eigen::MatrixXd result = Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(x->x), rows, cols);
    cholmod_free_dense(&x, &common);
    return result;
  }

  Eigen::Index originalColumn(Eigen::Index permuted) const
  {
    const auto* perm = static_cast<const int*>(factor->Perm);
    return perm ? perm[permuted] : permuted;
  }
};

SparseCholeskySolver::SparseCholeskySolver() : d(std::make_unique<Impl>()) {}
SparseCholeskySolver::~SparseCholeskySolver() = default;
SparseCholeskySolver::SparseCholeskySolver(SparseCholeskySolver&&) noexcept = default;
SparseCholeskySolver& SparseCholeskySolver::operator=(SparseCholeskySolver&&) noexcept = default;

void SparseCholeskySolver::analyzePattern(const SparseMatrix& input)
{
  cholmod_free_factor(&d->factor, &d->common);
  d->n = 0;
  d->outer.clear();
  d->inner.clear();
  if (!d->validate(input))
    return;

  // CHOLMOD wants packed columns; copy only if Eigen left slack.
  SparseMatrix compressed;
  const SparseMatrix& a = input.isCompressed() ? input : (compressed = input, compressed);
  // The pattern only: the analysis never reads a value, so the caller may
  // fill the values on another thread meanwhile (LinearStaticAnalysis does).
  cholmod_sparse view = viewOf(a);
  view.x = nullptr;
  view.xtype = CHOLMOD_PATTERN;
  if (d->groups.size() == std::size_t(a.rows()))
  {
    const std::vector<int> perm = groupedOrdering(a, d->groups, d->attached, d->common);
    d->common.nmethods = 1;
    d->common.method[0].ordering = CHOLMOD_GIVEN;
    d->factor = cholmod_analyze_p(&view, const_cast<int*>(perm.data()), nullptr, 0, &d->common);
    d->common.nmethods = 0; // back to CHOLMOD's own choice
    d->common.method[0].ordering = CHOLMOD_GIVEN;
  }
  else
  {
    d->factor = cholmod_analyze(&view, &d->common);
  }
  if (!d->factor)
  {
    d->throwOnCholmodError("analysis");
    throw std::runtime_error("CHOLMOD analysis returned no factor");
  }
  d->n = a.rows();
  d->outer.assign(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1);
  d->inner.assign(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros());
  d->factorized = false;
  d->succeed();
}

void SparseCholeskySolver::factorize(const SparseMatrix& input)
{
  if (!d->factor)
  {
    d->fail(SolverStatus::InvalidInput,
            "factorize() needs a successful analyzePattern() on a matrix with this pattern first.");
    return;
  }
  SparseMatrix compressed;
  const SparseMatrix& a = input.isCompressed() ? input : (compressed = input, compressed);
  const bool samePattern = a.rows() == d->n && a.cols() == d->n &&
                           static_cast<size_t>(a.nonZeros()) == d->inner.size() &&
                           std::equal(d->outer.begin(), d->outer.end(), a.outerIndexPtr()) &&
                           std::equal(d->inner.begin(), d->inner.end(), a.innerIndexPtr());
  if (!samePattern)
  {
    d->fail(SolverStatus::InvalidInput,
            "The matrix pattern differs from the one given to analyzePattern(); call "
            "analyzePattern() (or compute()) again after changing the mesh or constraints.");
    return;
  }

  // Diagonal entries, for the pivot ratio check; also catch NaN/Inf early.
  std::vector<double> diagonal(static_cast<size_t>(d->n), 0.0);
  for (Eigen::Index j = 0; j < a.outerSize(); ++j)
  {
    for (SparseMatrix::InnerIterator it(a, j); it; ++it)
    {
      if (it.row() > j)
        continue; // strict lower triangle is ignored
      if (!std::isfinite(it.value()))
      {
        d->fail(SolverStatus::InvalidInput,
                "The matrix has a non-finite entry (NaN or infinity) at row " + std::to_string(it.row()) + ", column " +
                  std::to_string(j) + "; check the material parameters and element geometry there.",
                j);
        return;
      }
      if (it.row() == j)
        diagonal[static_cast<size_t>(j)] = it.value();
    }
  }

  cholmod_sparse view = viewOf(a);
  {
    const SerialOpenMpRegions serial;
    cholmod_factorize(&view, d->factor, &d->common);
  }
  if (d->common.status == CHOLMOD_NOT_POSDEF)
  {
    const auto column = d->originalColumn(static_cast<Eigen::Index>(d->factor->minor));
    d->fail(SolverStatus::NotPositiveDefinite, notPositiveDefiniteMessage(column, "zero or negative pivot"), column);
    return;
  }
  d->throwOnCholmodError("factorization");

  if (d->pivotTolerance > 0.0)
  {
    const auto [permuted, ratio] = d->smallestPivotRatio(diagonal);
    if (permuted >= 0 && !(ratio >= d->pivotTolerance))
    {
      const auto column = d->originalColumn(permuted);
      std::ostringstream detail;
      detail << "only " << ratio << " of its diagonal stiffness is left, below the tolerance " << d->pivotTolerance;
      d->fail(SolverStatus::NotPositiveDefinite, notPositiveDefiniteMessage(column, detail.str()), column);
      return;
    }
  }
  d->factorized = true;
  d->succeed();
}

void SparseCholeskySolver::compute(const SparseMatrix& a)
{
  analyzePattern(a);
  if (d->status == SolverStatus::Success)
    factorize(a);
}

Eigen::MatrixXd SparseCholeskySolver::solve(const Eigen::MatrixXd& b) const
{
  return d->solveDense(b.data(), b.rows(), b.cols());
}

Eigen::VectorXd SparseCholeskySolver::solve(const Eigen::VectorXd& b) const
{
  return d->solveDense(b.data(), b.rows(), 1).col(0);
}

SolverStatus SparseCholeskySolver::status() const
{
  return d->status;
}
std::string SparseCholeskySolver::message() const
{
  return d->message;
}
Eigen::Index SparseCholeskySolver::failedColumn() const
{
  return d->failedColumn;
}
Eigen::Index SparseCholeskySolver::rows() const
{
  return d->n;
}
void SparseCholeskySolver::setPivotTolerance(double tolerance)
{
  d->pivotTolerance = tolerance;
}
void SparseCholeskySolver::setColumnGroups(std::vector<int> group)
{
  d->groups = std::move(group);
  d->attached.clear();
}
void SparseCholeskySolver::setColumnGroups(std::vector<int> group, std::vector<AttachedGroup> attached)
{
  d->groups = std::move(group);
  d->attached = std::move(attached);
}
double SparseCholeskySolver::factorFlops() const
{
  return d->common.fl;
}
double SparseCholeskySolver::factorNonZeros() const
{
  return d->common.lnz;
}
double SparseCholeskySolver::peakMemoryBytes() const
{
  return double(d->common.memory_usage);
}
double SparseCholeskySolver::pivotTolerance() const
{
  return d->pivotTolerance;
}

} // namespace caps::fem
