#pragma once

#include "fem/Mesh.h"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <vector>

namespace caps::fem {

/// A suture (thesis §4.6, eq. 4.43): node @a node ends where node @a target ends.
struct Suture {
  int node = -1;
  int target = -1;
};

/// One prescribed DOF: u(node, direction) = value (mm). Fixed is value 0.
struct PrescribedDof {
  int node = -1;
  int direction = 0;  ///< 0 x, 1 y, 2 z
  double value = 0.0;
};

/**
 * @brief Essential conditions of a model: fixed and prescribed DOFs, sutures.
 *
 * Only records them; resolveConstraints() turns them into the master-slave
 * map U = T Ubar + g.
 */
struct Constraints {
  std::vector<PrescribedDof> prescribed;
  std::vector<Suture> sutures;

  void fix(int node, int direction) { prescribed.push_back({node, direction, 0.0}); }
  void fixNode(int node) {
    for (int d = 0; d < 3; ++d) fix(node, d);
  }
  void prescribe(int node, int direction, double value) {
    prescribed.push_back({node, direction, value});
  }
  void suture(int node, int target) { sutures.push_back({node, target}); }
};

/**
 * @brief Master-slave elimination U = T Ubar + g (thesis eq. 4.43-4.46 done
 *        by substitution, so the reduced system stays symmetric positive
 *        definite).
 *
 * Each full DOF d maps to at most one reduced DOF with coefficient 1:
 * U_d = Ubar_{reduced[d]} + g_d, or U_d = g_d when reduced[d] = -1
 * (prescribed, or sutured, maybe through a chain, onto a prescribed DOF).
 * For a suture of node i onto s, u_i = u_s + (x_s - x_i) per direction
 * (eq. 4.44-4.45); chains i -> s -> m resolve to m with summed offsets.
 */
struct ConstraintMap {
  std::vector<int> reduced;     ///< per full DOF: reduced index or -1
  Eigen::VectorXd offset;       ///< g, size 3N
  std::vector<int> masterOf;    ///< per reduced DOF: the full DOF it stands for
  Eigen::Index reducedCount() const { return Eigen::Index(masterOf.size()); }

  /// K̄ = T^T K T from @a kUpper (upper triangle of K) to an upper-triangle K̄.
  Eigen::SparseMatrix<double> reduceMatrix(const Eigen::SparseMatrix<double>& kUpper) const;
  /// The values of T^T K T into @a kbar, which holds reduceMatrix()'s result
  /// for a matrix with @a kUpper's pattern (e.g. made from the pattern alone,
  /// before the values were known): no new arrays.
  void reduceValues(const Eigen::SparseMatrix<double>& kUpper, Eigen::SparseMatrix<double>& kbar) const;
  /// T^T r for full-size vectors (one column per load case).
  Eigen::MatrixXd reduceVector(const Eigen::MatrixXd& r) const;
  /// U = T Ubar + g (one column per load case).
  Eigen::MatrixXd expand(const Eigen::MatrixXd& ubar) const;
};

/**
 * @brief Builds the map. Throws std::invalid_argument naming the culprit for
 *        a node or direction out of range, a DOF prescribed twice with
 *        different values, a suture of a node to itself, a node sutured to two
 *        different targets, a prescribed node that is also sutured onto
 *        another, or a closed loop of sutures.
 */
ConstraintMap resolveConstraints(const Mesh& mesh, const Constraints& constraints);

}  // namespace caps::fem
