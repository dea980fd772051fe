// Checks caps::fem::SparseCholeskySolver against independent answers: Eigen's
// SimplicialLDLT, the closed-form displacements of a spring chain, and
// matrices that are singular by construction.

#include "fem/SparseCholeskySolver.h"

#include "TestMatrices.h"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <stdexcept>

namespace caps::fem {
namespace {

using test::latticeStiffness;
using test::SparseMatrix;
using test::springChain;

double relativeError(const Eigen::MatrixXd& x, const Eigen::MatrixXd& reference)
{
  return (x - reference).norm() / reference.norm();
}

Eigen::VectorXd deterministicLoad(Eigen::Index n, double phase = 0.0)
{
  Eigen::VectorXd f(n);
  for (Eigen::Index i = 0; i < n; ++i)
    f[i] = std::sin(0.7 * double(i) + phase) + 0.25;
  return f;
}

TEST(SparseCholeskySolver, MatchesSimplicialLDLTOnElasticLattice)
{
  const SparseMatrix k = latticeStiffness(12, true, 0.5);
  ASSERT_GT(k.rows(), 4000);
  const Eigen::VectorXd f = deterministicLoad(k.rows());

  SparseCholeskySolver solver;
  solver.compute(k);
  ASSERT_EQ(solver.status(), SolverStatus::Success) << solver.message();
  EXPECT_TRUE(solver.message().empty());
  EXPECT_EQ(solver.rows(), k.rows());
  const Eigen::VectorXd u = solver.solve(f);

  Eigen::SimplicialLDLT<SparseMatrix> reference(k);
  ASSERT_EQ(reference.info(), Eigen::Success);
  EXPECT_LT(relativeError(u, reference.solve(f)), 1e-10);
  EXPECT_LT((k * u - f).norm() / f.norm(), 1e-10);
}

TEST(SparseCholeskySolver, UpperTriangleGivesTheSameSolutionAsFullMatrix)
{
  const SparseMatrix k = latticeStiffness(8, true, 0.3);
  const SparseMatrix upper = k.triangularView<Eigen::Upper>();
  const Eigen::VectorXd f = deterministicLoad(k.rows());

  SparseCholeskySolver full, upperOnly;
  full.compute(k);
  upperOnly.compute(upper);
  ASSERT_EQ(full.status(), SolverStatus::Success) << full.message();
  ASSERT_EQ(upperOnly.status(), SolverStatus::Success) << upperOnly.message();
  EXPECT_LT(relativeError(upperOnly.solve(f), full.solve(f)), 1e-13);
}

TEST(SparseCholeskySolver, SpringChainMatchesClosedForm)
{
  // Fixed left end, load P at the free right end: every spring carries P, so
  // u_j = P * sum_{i <= j} 1 / k_i.
  std::vector<double> k;
  for (int i = 0; i < 200; ++i)
    k.push_back(1.0 + 0.5 * std::cos(0.3 * i) + 0.01 * i);
  const double p = 7.5;
  const SparseMatrix a = springChain(k, true);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(a.rows());
  f[f.size() - 1] = p;

  SparseCholeskySolver solver;
  solver.compute(a);
  ASSERT_EQ(solver.status(), SolverStatus::Success) << solver.message();
  const Eigen::VectorXd u = solver.solve(f);

  double expected = 0.0;
  for (Eigen::Index j = 0; j < a.rows(); ++j)
  {
    expected += p / k[static_cast<size_t>(j)];
    EXPECT_NEAR(u[j], expected, 1e-12 * expected) << "node " << j + 1;
  }
}

TEST(SparseCholeskySolver, SolvesManyLoadCasesAtOnce)
{
  const SparseMatrix k = latticeStiffness(9, true, 0.4);
  Eigen::MatrixXd loads(k.rows(), 7);
  for (int c = 0; c < loads.cols(); ++c)
    loads.col(c) = deterministicLoad(k.rows(), 0.9 * c);

  SparseCholeskySolver solver;
  solver.compute(k);
  ASSERT_EQ(solver.status(), SolverStatus::Success) << solver.message();
  const Eigen::MatrixXd u = solver.solve(loads);
  ASSERT_EQ(u.rows(), k.rows());
  ASSERT_EQ(u.cols(), loads.cols());

  Eigen::SimplicialLDLT<SparseMatrix> reference(k);
  for (int c = 0; c < loads.cols(); ++c)
  {
    const Eigen::VectorXd one = solver.solve(Eigen::VectorXd(loads.col(c)));
    EXPECT_LT(relativeError(u.col(c), one), 1e-14) << "load case " << c;
    EXPECT_LT(relativeError(u.col(c), reference.solve(Eigen::VectorXd(loads.col(c)))), 1e-10) << "load case " << c;
  }
  EXPECT_EQ(solver.solve(Eigen::MatrixXd(k.rows(), 0)).cols(), 0);
}

TEST(SparseCholeskySolver, RefactorizesNewValuesOnTheSamePattern)
{
  const SparseMatrix first = latticeStiffness(8, true, 0.3);
  // Same pattern, new values: stiffer overall and a varying extra diagonal.
  SparseMatrix second = 2.5 * first;
  for (Eigen::Index i = 0; i < second.rows(); ++i)
    second.coeffRef(i, i) += 1.0 + std::sin(0.1 * double(i));
  ASSERT_EQ(first.nonZeros(), second.nonZeros());
  const Eigen::VectorXd f = deterministicLoad(first.rows());

  SparseCholeskySolver solver;
  solver.analyzePattern(first);
  ASSERT_EQ(solver.status(), SolverStatus::Success) << solver.message();
  solver.factorize(first);
  ASSERT_EQ(solver.status(), SolverStatus::Success) << solver.message();
  const Eigen::VectorXd u1 = solver.solve(f);
  solver.factorize(second);
  ASSERT_EQ(solver.status(), SolverStatus::Success) << solver.message();
  const Eigen::VectorXd u2 = solver.solve(f);

  EXPECT_LT(relativeError(u1, Eigen::SimplicialLDLT<SparseMatrix>(first).solve(f)), 1e-10);
  EXPECT_LT(relativeError(u2, Eigen::SimplicialLDLT<SparseMatrix>(second).solve(f)), 1e-10);
  EXPECT_GT(relativeError(u1, u2), 1e-3); // the new values really were used
}

void expectNotPositiveDefinite(const SparseCholeskySolver& solver, Eigen::Index n)
{
  EXPECT_EQ(solver.status(), SolverStatus::NotPositiveDefinite);
  EXPECT_GE(solver.failedColumn(), 0);
  EXPECT_LT(solver.failedColumn(), n);
  const std::string text = solver.message();
  EXPECT_NE(text.find("column " + std::to_string(solver.failedColumn())), std::string::npos) << text;
  EXPECT_NE(text.find("rigid-body"), std::string::npos) << text;
  EXPECT_NE(text.find("inverted element"), std::string::npos) << text;
  EXPECT_THROW(solver.solve(Eigen::VectorXd::Ones(n)), std::logic_error);
}

TEST(SparseCholeskySolver, FreeChainWithExactZeroPivotIsNotPositiveDefinite)
{
  // Integer stiffnesses: elimination reaches an exact zero pivot.
  const SparseMatrix a = springChain(std::vector<double>(50, 1.0), false);
  SparseCholeskySolver solver;
  solver.compute(a);
  expectNotPositiveDefinite(solver, a.rows());
}

TEST(SparseCholeskySolver, FreeChainWithRoundedPivotIsNotPositiveDefinite)
{
  // Irregular stiffnesses: rounding may leave a tiny positive pivot, which the
  // pivot tolerance must still catch.
  std::vector<double> k;
  for (int i = 0; i < 50; ++i)
    k.push_back(0.3 + std::sqrt(2.0 + i) / 3.0);
  const SparseMatrix a = springChain(k, false);
  SparseCholeskySolver solver;
  solver.compute(a);
  expectNotPositiveDefinite(solver, a.rows());
}

TEST(SparseCholeskySolver, PivotToleranceIsApplied)
{
  // In an SPD matrix no pivot exceeds its diagonal entry, so a tolerance of 2
  // must reject any matrix, and 0 must accept this one.
  const SparseMatrix k = latticeStiffness(5, true, 0.2);
  SparseCholeskySolver solver;
  EXPECT_EQ(solver.pivotTolerance(), 1e-12);
  solver.setPivotTolerance(2.0);
  solver.compute(k);
  expectNotPositiveDefinite(solver, k.rows());
  EXPECT_NE(solver.message().find("tolerance"), std::string::npos) << solver.message();
  solver.setPivotTolerance(0.0);
  solver.factorize(k);
  EXPECT_EQ(solver.status(), SolverStatus::Success) << solver.message();
}

TEST(SparseCholeskySolver, UnconstrainedLatticeIsNotPositiveDefinite)
{
  const SparseMatrix k = latticeStiffness(6, false, 0.3);
  SparseCholeskySolver solver;
  solver.compute(k);
  expectNotPositiveDefinite(solver, k.rows());
}

TEST(SparseCholeskySolver, NamesTheOriginalColumnOfANegativePivot)
{
  // A strongly negative diagonal entry (as from an inverted element) fails at
  // exactly that DOF, whatever the fill-reducing ordering did to it.
  SparseMatrix k = latticeStiffness(7, true, 0.2);
  const Eigen::Index bad = 123;
  k.coeffRef(bad, bad) = -1e3;
  SparseCholeskySolver solver;
  solver.compute(k);
  expectNotPositiveDefinite(solver, k.rows());
  EXPECT_EQ(solver.failedColumn(), bad);
}

TEST(SparseCholeskySolver, RejectsNonSquareMatrix)
{
  SparseMatrix a(4, 3);
  a.insert(0, 0) = 1.0;
  a.makeCompressed();
  SparseCholeskySolver solver;
  solver.compute(a);
  EXPECT_EQ(solver.status(), SolverStatus::InvalidInput);
  EXPECT_NE(solver.message().find("square"), std::string::npos) << solver.message();
  EXPECT_THROW(solver.solve(Eigen::VectorXd::Ones(4)), std::logic_error);
}

TEST(SparseCholeskySolver, RejectsLowerTriangleOnly)
{
  const SparseMatrix k = latticeStiffness(4, true);
  const SparseMatrix lower = k.triangularView<Eigen::Lower>();
  SparseCholeskySolver solver;
  solver.compute(lower);
  EXPECT_EQ(solver.status(), SolverStatus::InvalidInput);
  EXPECT_NE(solver.message().find("lower triangle"), std::string::npos) << solver.message();
}

TEST(SparseCholeskySolver, RejectsFactorizeOnAnotherPattern)
{
  SparseCholeskySolver solver;
  solver.factorize(latticeStiffness(4, true));
  EXPECT_EQ(solver.status(), SolverStatus::InvalidInput); // nothing analyzed yet

  solver.analyzePattern(latticeStiffness(4, true));
  ASSERT_EQ(solver.status(), SolverStatus::Success);
  solver.factorize(latticeStiffness(5, true));
  EXPECT_EQ(solver.status(), SolverStatus::InvalidInput);
  EXPECT_NE(solver.message().find("analyzePattern"), std::string::npos) << solver.message();
}

TEST(SparseCholeskySolver, RejectsRightHandSideOfWrongSize)
{
  const SparseMatrix k = latticeStiffness(4, true);
  SparseCholeskySolver solver;
  solver.compute(k);
  ASSERT_EQ(solver.status(), SolverStatus::Success);
  EXPECT_THROW(solver.solve(Eigen::VectorXd::Ones(k.rows() + 1)), std::invalid_argument);
}

TEST(SparseCholeskySolver, MovedSolverKeepsItsFactor)
{
  const SparseMatrix k = latticeStiffness(5, true, 0.1);
  const Eigen::VectorXd f = deterministicLoad(k.rows());
  SparseCholeskySolver first;
  first.compute(k);
  ASSERT_EQ(first.status(), SolverStatus::Success);
  const SparseCholeskySolver second = std::move(first);
  EXPECT_LT((k * second.solve(f) - f).norm() / f.norm(), 1e-12);
}

} // namespace
} // namespace caps::fem
