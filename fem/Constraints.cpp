#include "fem/Constraints.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace caps::fem {

namespace {

const char* axisName(int d) { return d == 0 ? "x" : (d == 1 ? "y" : "z"); }

void checkNode(int node, Eigen::Index n, const std::string& what) {
  if (node < 0 || node >= n)
    throw std::invalid_argument(what + " refers to node " + std::to_string(node) +
                                ", but the mesh has nodes 0.." + std::to_string(n - 1));
}

}  // namespace

ConstraintMap resolveConstraints(const Mesh& mesh, const Constraints& c) {
  const Eigen::Index n = mesh.nodeCount();
  const Eigen::Index ndof = 3 * n;
  // State per full DOF: free, prescribed (value), or slave of a node.
  std::vector<char> isPrescribed(ndof, 0);
  Eigen::VectorXd value = Eigen::VectorXd::Zero(ndof);
  std::vector<int> sutureTarget(n, -1);

  for (const PrescribedDof& p : c.prescribed) {
    checkNode(p.node, n, "a prescribed displacement");
    if (p.direction < 0 || p.direction > 2)
      throw std::invalid_argument("a prescribed displacement of node " + std::to_string(p.node) +
                                  " has direction " + std::to_string(p.direction) + " (0, 1, 2 for x, y, z)");
    if (!std::isfinite(p.value))
      throw std::invalid_argument("node " + std::to_string(p.node) + " has a non-finite prescribed " +
                                  axisName(p.direction) + " displacement");
    const Eigen::Index d = 3 * p.node + p.direction;
    if (isPrescribed[d] && value[d] != p.value) {
      std::ostringstream m;
      m << "node " << p.node << " " << axisName(p.direction) << " is prescribed twice, to " << value[d]
        << " and " << p.value << " mm";
      throw std::invalid_argument(m.str());
    }
    isPrescribed[d] = 1;
    value[d] = p.value;
  }
  for (const Suture& s : c.sutures) {
    checkNode(s.node, n, "a suture");
    checkNode(s.target, n, "a suture");
    if (s.node == s.target)
      throw std::invalid_argument("node " + std::to_string(s.node) + " is sutured to itself");
    if (sutureTarget[s.node] >= 0 && sutureTarget[s.node] != s.target)
      throw std::invalid_argument("node " + std::to_string(s.node) + " is sutured to two nodes, " +
                                  std::to_string(sutureTarget[s.node]) + " and " + std::to_string(s.target));
    for (int d = 0; d < 3; ++d)
      if (isPrescribed[3 * s.node + d])
        throw std::invalid_argument("node " + std::to_string(s.node) + " is sutured to node " +
                                    std::to_string(s.target) + " but its " + axisName(d) +
                                    " displacement is also prescribed; suture the other way round");
    sutureTarget[s.node] = s.target;
  }

  // Follow each suture chain to its root node (cycle check on the way).
  std::vector<int> root(n, -2);  // -2 unknown, -3 on the current path
  for (int start = 0; start < n; ++start) {
    if (root[start] != -2) continue;
    std::vector<int> path;
    int v = start;
    while (root[v] == -2 && sutureTarget[v] >= 0) {
      root[v] = -3;
      path.push_back(v);
      v = sutureTarget[v];
    }
    if (root[v] == -3) {
      std::string loop;
      for (int p : path) loop += std::to_string(p) + " -> ";
      throw std::invalid_argument("sutures form a closed loop: " + loop + std::to_string(v));
    }
    const int r = root[v] == -2 ? v : root[v];
    root[v] = r;
    for (int p : path) root[p] = r;
  }

  ConstraintMap map;
  map.reduced.assign(ndof, -1);
  map.offset = Eigen::VectorXd::Zero(ndof);
  // Free DOFs of root nodes get reduced indices in node order.
  for (int i = 0; i < n; ++i) {
    if (root[i] != i) continue;
    for (int d = 0; d < 3; ++d) {
      const int dof = 3 * i + d;
      if (isPrescribed[dof]) {
        map.offset[dof] = value[dof];
      } else {
        map.reduced[dof] = int(map.masterOf.size());
        map.masterOf.push_back(dof);
      }
    }
  }
  // Slaves: u_i = u_root + (x_root - x_i), summed along the chain telescopes to this.
  for (int i = 0; i < n; ++i) {
    const int r = root[i];
    if (r == i) continue;
    for (int d = 0; d < 3; ++d) {
      const int dof = 3 * i + d, rdof = 3 * r + d;
      map.reduced[dof] = map.reduced[rdof];
      map.offset[dof] = map.offset[rdof] + (mesh.nodes(d, r) - mesh.nodes(d, i));
    }
  }
  return map;
}

Eigen::SparseMatrix<double> ConstraintMap::reduceMatrix(const Eigen::SparseMatrix<double>& k) const {
  // Each full DOF stands for at most one reduced DOF with coefficient 1, so
  // T^T K T just renames rows and columns and sums what lands together.
  // Counted into compressed columns directly (a triplet sort took most of
  // the time); columns are then sorted and their duplicates summed.
  const Eigen::Index n = reducedCount();
  // Fixed and prescribed DOFs only (no sutures): K-bar is K without their
  // rows and columns, renumbered in the same order, so one copying pass.
  bool selection = true;
  for (std::size_t d = 0, last = 0; d < reduced.size() && selection; ++d)
    if (reduced[d] >= 0) {
      selection = std::size_t(reduced[d]) == last;
      ++last;
    }
  if (selection && k.isCompressed()) {
    // Straight into the result's arrays: an extra copy of ~100 MB of
    // entries costs as much as the pass itself (page faults).
    Eigen::SparseMatrix<double> r(n, n);
    r.resizeNonZeros(k.nonZeros());
    int* outer = r.outerIndexPtr();
    int* inner = r.innerIndexPtr();
    double* values = r.valuePtr();
    Eigen::Index at = 0;
    outer[0] = 0;
    for (Eigen::Index j = 0; j < k.outerSize(); ++j) {
      const int b = reduced[std::size_t(j)];
      if (b < 0) continue;
      for (Eigen::SparseMatrix<double>::InnerIterator it(k, j); it; ++it) {
        if (it.row() > j) break;  // rows are sorted: the rest is below the diagonal
        const int a = reduced[std::size_t(it.row())];
        if (a < 0) continue;
        inner[at] = a;
        values[at] = it.value();
        ++at;
      }
      outer[b + 1] = int(at);
    }
    r.resizeNonZeros(at);  // shrinks without reallocating
    return r;
  }

  std::vector<int> count(std::size_t(n) + 1, 0);
  auto target = [this](Eigen::Index i, Eigen::Index j, int& a, int& b) {
    a = reduced[std::size_t(i)];
    b = reduced[std::size_t(j)];
    if (a > b) std::swap(a, b);
  };
  for (Eigen::Index j = 0; j < k.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(k, j); it; ++it) {
      if (it.row() > j) continue;  // upper triangle only
      int a, b;
      target(it.row(), j, a, b);
      if (a >= 0) ++count[std::size_t(b) + 1];
    }
  for (std::size_t c = 0; c < std::size_t(n); ++c) count[c + 1] += count[c];
  std::vector<int> rows(std::size_t(count.back()));
  std::vector<double> vals(rows.size());
  std::vector<int> fill(count.begin(), count.end() - 1);
  for (Eigen::Index j = 0; j < k.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(k, j); it; ++it) {
      const Eigen::Index i = it.row();
      if (i > j) continue;
      int a, b;
      target(i, j, a, b);
      if (a < 0) continue;
      double v = it.value();
      if (a == b && i != j) v *= 2.0;  // K_ij and K_ji both land on the diagonal
      const int at = fill[std::size_t(b)]++;
      rows[std::size_t(at)] = a;
      vals[std::size_t(at)] = v;
    }

  Eigen::SparseMatrix<double> r(n, n);
  std::vector<int> order;
  std::vector<int> outer(std::size_t(n) + 1, 0);
  std::vector<int> inner;
  std::vector<double> values;
  inner.reserve(rows.size());
  values.reserve(rows.size());
  for (Eigen::Index c = 0; c < n; ++c) {
    const int first = count[std::size_t(c)], last = count[std::size_t(c) + 1];
    order.resize(std::size_t(last - first));
    for (int e = first; e < last; ++e) order[std::size_t(e - first)] = e;
    // By row, then by position: duplicates are summed in the order K holds
    // them (deterministic).
    const auto byRow = [&rows](int x, int y) {
      return rows[std::size_t(x)] < rows[std::size_t(y)] || (rows[std::size_t(x)] == rows[std::size_t(y)] && x < y);
    };
    if (!std::is_sorted(order.begin(), order.end(), byRow)) std::sort(order.begin(), order.end(), byRow);
    for (int e : order) {
      if (int(inner.size()) > outer[std::size_t(c)] && inner.back() == rows[std::size_t(e)])
        values.back() += vals[std::size_t(e)];
      else {
        inner.push_back(rows[std::size_t(e)]);
        values.push_back(vals[std::size_t(e)]);
      }
    }
    outer[std::size_t(c) + 1] = int(inner.size());
  }
  r.resizeNonZeros(Eigen::Index(inner.size()));
  std::copy(outer.begin(), outer.end(), r.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), r.innerIndexPtr());
  std::copy(values.begin(), values.end(), r.valuePtr());
  return r;
}

void ConstraintMap::reduceValues(const Eigen::SparseMatrix<double>& k, Eigen::SparseMatrix<double>& kbar) const {
  bool selection = k.isCompressed();
  for (std::size_t d = 0, last = 0; d < reduced.size() && selection; ++d)
    if (reduced[d] >= 0) {
      selection = std::size_t(reduced[d]) == last;
      ++last;
    }
  if (!selection) {
    // Sutures sum entries into shared places: rebuild (same pattern, same order).
    Eigen::SparseMatrix<double> fresh = reduceMatrix(k);
    if (fresh.nonZeros() != kbar.nonZeros())
      throw std::invalid_argument("reduceValues: the reduced matrix was made from another pattern");
    std::copy(fresh.valuePtr(), fresh.valuePtr() + fresh.nonZeros(), kbar.valuePtr());
    return;
  }
  // The same walk as reduceMatrix()'s copying pass, values only.
  double* values = kbar.valuePtr();
  Eigen::Index at = 0;
  for (Eigen::Index j = 0; j < k.outerSize(); ++j) {
    if (reduced[std::size_t(j)] < 0) continue;
    for (Eigen::SparseMatrix<double>::InnerIterator it(k, j); it; ++it) {
      if (it.row() > j) break;
      if (reduced[std::size_t(it.row())] < 0) continue;
      if (at >= kbar.nonZeros())
        throw std::invalid_argument("reduceValues: the reduced matrix was made from another pattern");
      values[at++] = it.value();
    }
  }
  if (at != kbar.nonZeros())
    throw std::invalid_argument("reduceValues: the reduced matrix was made from another pattern");
}

Eigen::MatrixXd ConstraintMap::reduceVector(const Eigen::MatrixXd& r) const {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(reducedCount(), r.cols());
  for (std::size_t d = 0; d < reduced.size(); ++d)
    if (reduced[d] >= 0) out.row(reduced[d]) += r.row(Eigen::Index(d));
  return out;
}

Eigen::MatrixXd ConstraintMap::expand(const Eigen::MatrixXd& ubar) const {
  Eigen::MatrixXd u(Eigen::Index(reduced.size()), ubar.cols());
  for (std::size_t d = 0; d < reduced.size(); ++d) {
    u.row(Eigen::Index(d)).setConstant(offset[Eigen::Index(d)]);
    if (reduced[d] >= 0) u.row(Eigen::Index(d)) += ubar.row(reduced[d]);
  }
  return u;
}

}  // namespace caps::fem
