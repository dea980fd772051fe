#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <memory>
#include <string>
#include <vector>

namespace caps::fem {

/// Outcome of the last stage run by a SparseCholeskySolver.
enum class SolverStatus
{
  Success,             ///< the stage finished; solve() may be called after factorize()
  NotPositiveDefinite, ///< the factorization met a zero, negative or vanishing pivot
  InvalidInput         ///< the matrix was rejected before any numerical work
};

/**
 * @brief Staged direct solver for symmetric positive definite sparse systems,
 *        such as the global stiffness equations K U = R.
 *
 * Thesis §4.6.1 decomposes K once (step 2g, eq. 4.32) and then solves for
 * every load condition (step 3); the stages below keep that split.
 *
 * Wraps CHOLMOD's supernodal Cholesky factorization (L L^T with a
 * fill-reducing ordering), which hands the dense supernode blocks to BLAS.
 * The stages follow Eigen's SimplicialCholesky:
 *   - analyzePattern(): ordering and symbolic factorization. Reuse it for as
 *     long as the sparsity pattern stays the same (e.g. new material
 *     parameters on the same mesh);
 *   - factorize(): numeric factorization of a matrix with that pattern;
 *   - compute(): both;
 *   - solve(): forward/back substitution, one or many load cases at once.
 * Each stage sets status() and message(); solve() throws if the last
 * factorization did not succeed.
 *
 * Input: a square, compressed or uncompressed column-major matrix. Only the
 * upper triangle (including the diagonal) is read, so pass either the upper
 * triangle alone or the full symmetric matrix; in the full case the strict
 * lower triangle is ignored (its values are not checked for symmetry, but its
 * entry count must match the upper triangle's). A matrix with entries only
 * below the diagonal is rejected as InvalidInput, since reading it as upper
 * would silently drop the couplings.
 *
 * Besides CHOLMOD's own test (a pivot <= 0), a pivot that keeps less than
 * pivotTolerance() of its diagonal entry after elimination is reported as
 * NotPositiveDefinite: rounding turns the exact zero pivot of a rigid-body
 * mode into a tiny positive number, and the "solution" would be garbage.
 *
 * @warning Not thread-safe: solve() reuses the CHOLMOD workspace.
 */
class SparseCholeskySolver
{
public:
  using SparseMatrix = Eigen::SparseMatrix<double>;

  SparseCholeskySolver();
  ~SparseCholeskySolver();
  SparseCholeskySolver(const SparseCholeskySolver&) = delete;
  SparseCholeskySolver& operator=(const SparseCholeskySolver&) = delete;
  SparseCholeskySolver(SparseCholeskySolver&&) noexcept;
  SparseCholeskySolver& operator=(SparseCholeskySolver&&) noexcept;

  /// Ordering and symbolic factorization; reads only the pattern of @a a
  /// (never its values, which another thread may be filling meanwhile).
  void analyzePattern(const SparseMatrix& a);
  /// Numeric factorization; @a a must have the pattern given to analyzePattern().
  void factorize(const SparseMatrix& a);
  /// analyzePattern() then factorize().
  void compute(const SparseMatrix& a);

  /// Solves A x = b. @a b has rows() entries. Throws std::logic_error if the
  /// last factorization failed, std::invalid_argument on a size mismatch.
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;
  /// Solves A X = B for every column of @a b (one load case per column).
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;
  /// Evaluates an expression argument (e.g. VectorXd::Ones(n)), which would
  /// otherwise convert equally well to either overload above.
  template <typename Derived> auto solve(const Eigen::MatrixBase<Derived>& b) const
  {
    if constexpr (Derived::ColsAtCompileTime == 1)
    {
      return solve(Eigen::VectorXd(b));
    }
    else
    {
      return solve(Eigen::MatrixXd(b));
    }
  }

  SolverStatus status() const;
  /// Empty on success; otherwise what went wrong and what to check.
  std::string message() const;
  /// Original column (DOF) where the factorization failed, or -1.
  Eigen::Index failedColumn() const;
  /// Order of the analyzed matrix (0 before analyzePattern()).
  Eigen::Index rows() const;

  /// Smallest accepted ratio pivot / diagonal entry; 0 disables the check.
  void setPivotTolerance(double tolerance);
  double pivotTolerance() const;

  /// Columns that belong together, e.g. the three DOFs of a node: @a group[j]
  /// for column j (any non-negative ids). analyzePattern() then orders the
  /// graph of groups by nested dissection (METIS; about 9x fewer edges than the
  /// DOF graph, so the analysis takes a fraction of the time for the same fill)
  /// and keeps each group's columns together. Empty (the default), or a size
  /// that does not match the matrix: CHOLMOD chooses (AMD, then METIS if AMD
  /// fills badly).
  void setColumnGroups(std::vector<int> group);

  /// A group ordered beside its neighbours instead of by nested dissection:
  /// placed right before whichever of groups @a first and @a second comes
  /// first in the order (-1: none). For a mid-edge node beside the ends of
  /// its edge: its neighbours are all neighbours of either end, so this adds
  /// no fill, and the graph left to dissect holds the element vertices only.
  struct AttachedGroup
  {
    int group = -1;
    int first = -1;
    int second = -1;
  };
  /// setColumnGroups() with some groups attached to others (ids as in
  /// @a group). An attached group whose ends have no column is ordered by
  /// itself; so is one attached to another attached group.
  void setColumnGroups(std::vector<int> group, std::vector<AttachedGroup> attached);

  /// @name Statistics of the last successful factorization (CHOLMOD's counts)
  ///@{
  /// Floating-point operations of the numeric factorization.
  double factorFlops() const;
  /// Entries of the factor L.
  double factorNonZeros() const;
  /// Peak memory CHOLMOD held, bytes (its own accounting).
  double peakMemoryBytes() const;
  ///@}

private:
  struct Impl;
  std::unique_ptr<Impl> d;
};

} // namespace caps::fem
