#pragma once

#include "fem/Mesh.h"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace caps::fem {

/// A suture (thesis §4.6, eq. 4.43): node @a node ends where node @a target ends.
struct Suture
{
  int node = -1;
  int target = -1;
};

/// One prescribed DOF: u(node, direction) = value (mm). Fixed is value 0.
struct PrescribedDof
{
  int node = -1;
  int direction = 0; ///< 0 x, 1 y, 2 z
  double value = 0.0;
};

/// One term c u(node, direction) of a linear multi-point constraint.
struct ConstraintTerm
{
  int node = -1;
  int direction = 0; ///< 0 x, 1 y, 2 z
  double coefficient = 0.0;
};

/**
 * @brief A linear multi-point constraint sum_k c_k u(node_k, direction_k) =
 *        value (CalculiX/Abaqus *EQUATION, any number of terms). The first
 *        term's DOF is the dependent one: it is eliminated, as in CalculiX.
 *        Sliding on a plane (u . n = 0) and general ties are such equations.
 */
struct LinearConstraint
{
  std::vector<ConstraintTerm> terms;
  double value = 0.0; ///< mm (scaled with the load in a large-deformation step)
};

/**
 * @brief Essential conditions of a model: fixed and prescribed DOFs, sutures,
 *        general linear multi-point constraints.
 *
 * Only records them; resolveConstraints() turns them into the master-slave
 * map U = T Ubar + g.
 */
struct Constraints
{
  std::vector<PrescribedDof> prescribed;
  std::vector<Suture> sutures;
  std::vector<LinearConstraint> equations;

  void fix(int node, int direction) { prescribed.push_back({node, direction, 0.0}); }
  void fixNode(int node)
  {
    for (int d = 0; d < 3; ++d)
      fix(node, d);
  }
  void prescribe(int node, int direction, double value) { prescribed.push_back({node, direction, value}); }
  void suture(int node, int target) { sutures.push_back({node, target}); }
  void equation(LinearConstraint c) { equations.push_back(std::move(c)); }
};

/**
 * @brief Master-slave elimination U = T Ubar + g (thesis eq. 4.43-4.46 done
 *        by substitution, so the reduced system stays symmetric positive
 *        definite).
 *
 * Most full DOFs map to at most one reduced DOF with coefficient 1:
 * U_d = Ubar_{reduced[d]} + g_d, or U_d = g_d when reduced[d] = -1
 * (prescribed, or sutured, maybe through a chain, onto a prescribed DOF).
 * For a suture of node i onto s, u_i = u_s + (x_s - x_i) per direction
 * (eq. 4.44-4.45); chains i -> s -> m resolve to m with summed offsets.
 *
 * The dependent DOF of a general equation (and any DOF sutured onto one)
 * has reduced[d] = -1 too, but a general row of T: U_d = sum_k c_k
 * Ubar_{i_k} + g_d, listed in @ref general. Without equations @ref general
 * is empty and every operation takes the plain copying path it always had.
 */
struct ConstraintMap
{
  std::vector<int> reduced;  ///< per full DOF: reduced index, or -1 (prescribed, or a general row)
  Eigen::VectorXd offset;    ///< g, size 3N
  std::vector<int> masterOf; ///< per reduced DOF: the full DOF it stands for
  /// Full DOFs with a general row of T (dependent DOFs of equations and the
  /// DOFs sutured onto them), ascending.
  std::vector<int> general;
  /// Row of T of general[k]: entries generalStart[k] .. generalStart[k+1]-1 of
  /// generalIndex (reduced DOFs, ascending) and generalCoefficient; may be
  /// empty (U_d = g_d, every term of its equation prescribed).
  std::vector<int> generalStart{0};
  std::vector<int> generalIndex;
  std::vector<double> generalCoefficient;

  Eigen::Index reducedCount() const { return Eigen::Index(masterOf.size()); }
  bool hasGeneralRows() const { return !general.empty(); }
  /// T (3N x reducedCount()) as a sparse matrix, for checks and exporters.
  Eigen::SparseMatrix<double> transformation() const;
  /// True when @a other has the same T (only g may differ): K̄ is the same.
  bool sameTransformation(const ConstraintMap& other) const;

  /// K̄ = T^T K T from @a kUpper (upper triangle of K) to an upper-triangle K̄.
  /// With general rows it also keeps the scatter plan reduceValues() reuses.
  Eigen::SparseMatrix<double> reduceMatrix(const Eigen::SparseMatrix<double>& kUpper) const;
  /// The values of T^T K T into @a kbar, which holds reduceMatrix()'s result
  /// for a matrix with @a kUpper's pattern (e.g. made from the pattern alone,
  /// before the values were known): no new arrays. With general rows the
  /// scatter plan of the last reduceMatrix() call on this map (or one made
  /// here once) is replayed; not to be called on one map from two threads.
  void reduceValues(const Eigen::SparseMatrix<double>& kUpper, Eigen::SparseMatrix<double>& kbar) const;
  /// T^T r for full-size vectors (one column per load case).
  Eigen::MatrixXd reduceVector(const Eigen::MatrixXd& r) const;
  /// U = T Ubar + g (one column per load case).
  Eigen::MatrixXd expand(const Eigen::MatrixXd& ubar) const;
  /// U = T Ubar + @a offsetScale g: a load increment of a large-deformation
  /// step applies that share of the prescribed values and suture gaps.
  Eigen::MatrixXd expand(const Eigen::MatrixXd& ubar, double offsetScale) const;

  /// For each contribution to K̄'s values: K's entry, weight, K̄'s entry.
  struct ReductionPlan;

private:
  Eigen::SparseMatrix<double> reduceGeneral(const Eigen::SparseMatrix<double>& kUpper, ReductionPlan* plan) const;
  mutable std::shared_ptr<const ReductionPlan> plan_;
};

/**
 * @brief An error in the constraints that names nodes and equations by
 *        reference, so a caller with its own numbering (a deck's node
 *        numbers) can say it in its terms.
 *
 * what() numbers nodes and equations as the model does (from 0); message()
 * renders the same text with other names. The pattern holds "{N<k>}" for
 * nodes()[k] (the number alone: "node {N0} x") and "{E<k>}" for
 * equations()[k] (the whole phrase: "equation 3" by default).
 */
class ConstraintError : public std::invalid_argument
{
public:
  /// How to name a node (index into the mesh) and an equation (index into
  /// Constraints::equations); an empty function keeps the default.
  struct Naming
  {
    std::function<std::string(int)> node;
    std::function<std::string(int)> equation;
  };

  ConstraintError(std::string pattern, std::vector<int> nodes, std::vector<int> equations = {});

  const std::vector<int>& nodes() const { return nodes_; }
  const std::vector<int>& equations() const { return equations_; }
  /// The message with nodes and equations named by @a naming.
  std::string message(const Naming& naming) const;

private:
  std::string pattern_;
  std::vector<int> nodes_;
  std::vector<int> equations_;
};

/**
 * @brief Builds the map. Throws ConstraintError naming the culprit for
 *        a node or direction out of range, a DOF prescribed twice with
 *        different values, a suture of a node to itself, a node sutured to two
 *        different targets, a prescribed node that is also sutured onto
 *        another, or a closed loop of sutures; and for equations: no terms, a
 *        non-finite coefficient or value, a zero first coefficient, a
 *        dependent DOF that is prescribed, sutured onto another node, or
 *        dependent in two equations, and equations whose dependent DOFs depend
 *        on each other (a closed loop) in a singular system: linearly
 *        dependent or contradictory equations, which leave a dependent DOF
 *        undetermined. (Out-of-range node numbers come as a ConstraintError
 *        with the number in its text, as it names no node of the mesh.)
 *
 * Equation terms with zero coefficients are dropped and terms on the same DOF
 * (also through sutures) summed; other terms may be prescribed, sutured or
 * dependent in other equations. Equations whose dependents do not refer back
 * to each other are substituted in cascade. Dependents that do (CalculiX's
 * coupled dependents, e.g. u_z = u_y on a node whose u_y is another
 * equation's dependent that involves u_z) are solved together, one strongly
 * connected group of equations at a time (row-scaled, LU with full pivoting;
 * sparse LU for groups above a few hundred equations), after the groups they
 * refer to; each dependent becomes a combination of independent DOFs plus a
 * constant.
 */
ConstraintMap resolveConstraints(const Mesh& mesh, const Constraints& constraints);

} // namespace caps::fem
