#include "fem/Constraints.h"

#include <Eigen/LU>
#include <Eigen/SparseLU>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace caps::fem {

namespace {

const char* axisName(int d)
{
  return d == 0 ? "x" : (d == 1 ? "y" : "z");
}

std::string defaultNodeName(int node)
{
  return std::to_string(node);
}
std::string defaultEquationName(int e)
{
  return "equation " + std::to_string(e);
}

std::string render(const std::string& pattern, const std::vector<int>& nodes, const std::vector<int>& equations,
                   const ConstraintError::Naming& naming)
{
  std::string out;
  out.reserve(pattern.size());
  for (std::size_t i = 0; i < pattern.size(); ++i)
  {
    const char kind = i + 1 < pattern.size() ? pattern[i + 1] : '\0';
    if (pattern[i] == '{' && (kind == 'N' || kind == 'E'))
    {
      const std::size_t close = pattern.find('}', i);
      const std::string digits = close == std::string::npos ? "" : pattern.substr(i + 2, close - i - 2);
      const bool number = !digits.empty() && std::all_of(digits.begin(), digits.end(),
                                                         [](unsigned char ch) { return ch >= '0' && ch <= '9'; });
      const std::vector<int>& refs = kind == 'N' ? nodes : equations;
      if (number && std::stoul(digits) < refs.size())
      {
        const int ref = refs[std::stoul(digits)];
        if (kind == 'N')
          out += naming.node ? naming.node(ref) : defaultNodeName(ref);
        else
          out += naming.equation ? naming.equation(ref) : defaultEquationName(ref);
        i = close;
        continue;
      }
    }
    out += pattern[i];
  }
  return out;
}

/// A node of the mesh, a DOF (3 node + direction) and an equation, as
/// references in a Message.
struct NodeRef
{
  int node;
};
struct DofRef
{
  int dof;
};
struct EquationRef
{
  int equation;
};

/// Builds a ConstraintError: text, with nodes and equations as references.
class Message
{
public:
  Message& operator<<(const std::string& text)
  {
    pattern_ += text;
    return *this;
  }
  Message& operator<<(const char* text) { return *this << std::string(text); }
  Message& operator<<(double x)
  {
    std::ostringstream s;
    s << x;
    return *this << s.str();
  }
  Message& operator<<(NodeRef n)
  {
    pattern_ += "{N" + std::to_string(nodes_.size()) + "}";
    nodes_.push_back(n.node);
    return *this;
  }
  Message& operator<<(DofRef d) { return *this << "node " << NodeRef{d.dof / 3} << " " << axisName(d.dof % 3); }
  Message& operator<<(EquationRef e)
  {
    pattern_ += "{E" + std::to_string(equations_.size()) + "}";
    equations_.push_back(e.equation);
    return *this;
  }
  ConstraintError error() const { return ConstraintError(pattern_, nodes_, equations_); }

private:
  std::string pattern_;
  std::vector<int> nodes_, equations_;
};

/// Out of range: the number goes into the text, as it names no node.
void checkNode(int node, Eigen::Index n, Message what)
{
  if (node < 0 || node >= n)
    throw(what << " refers to node " << std::to_string(node) << ", but the mesh has nodes 0.." + std::to_string(n - 1))
      .error();
}

/// One equation with its terms moved to root DOFs (through sutures), summed,
/// zeros dropped: lead u_dependent + sum others = value.
struct RootEquation
{
  int dependent = -1;
  int source = -1; ///< index into Constraints::equations
  double lead = 0.0;
  std::vector<std::pair<int, double>> others; ///< (root DOF, coefficient)
  double value = 0.0;
};

/// A resolved row of T: sum c Ubar_i + constant.
struct ResolvedRow
{
  std::vector<std::pair<int, double>> terms; ///< (reduced DOF, coefficient), ascending, merged
  double constant = 0.0;
};

/// Sorts by reduced DOF, sums duplicates, drops exact zeros.
void mergeTerms(ResolvedRow& r)
{
  std::sort(r.terms.begin(), r.terms.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<std::pair<int, double>> merged;
  for (const auto& t : r.terms)
    if (!merged.empty() && merged.back().first == t.first)
      merged.back().second += t.second;
    else
      merged.push_back(t);
  merged.erase(std::remove_if(merged.begin(), merged.end(), [](const auto& t) { return t.second == 0.0; }),
               merged.end());
  r.terms = std::move(merged);
}

/// Resolves the dependent DOF of every equation into a row of T.
///
/// Equation e refers to equation f when a term of e is f's dependent DOF.
/// The strongly connected groups of that graph (Tarjan) come out after every
/// group they refer to, so each group is resolved once the rows it refers to
/// are known: a single equation by substitution (a cascade, as before), a
/// group of coupled dependents by solving its square system.
class EquationResolver
{
public:
  EquationResolver(const std::vector<RootEquation>& equations, const std::vector<int>& equationOf,
                   const std::vector<char>& isPrescribed, const Eigen::VectorXd& value, const std::vector<int>& reduced)
    : equations_(equations), equationOf_(equationOf), isPrescribed_(isPrescribed), value_(value), reduced_(reduced),
      rows_(equations.size())
  {}

  std::vector<ResolvedRow> resolve()
  {
    for (const std::vector<int>& group : stronglyConnectedGroups())
    {
      if (group.size() == 1)
        substitute(group[0]);
      else
        solveGroup(group);
    }
    return std::move(rows_);
  }

private:
  /// The equation whose dependent DOF @a dof is, or -1.
  int dependentOf(int dof) const { return isPrescribed_[std::size_t(dof)] ? -1 : equationOf_[std::size_t(dof)]; }

  /// Tarjan's algorithm, without recursion (cascades may be long).
  std::vector<std::vector<int>> stronglyConnectedGroups() const
  {
    const int m = int(equations_.size());
    std::vector<int> index(std::size_t(m), -1), low(std::size_t(m), 0);
    std::vector<char> onStack(std::size_t(m), 0);
    std::vector<int> stack;
    std::vector<std::vector<int>> groups;
    std::vector<std::pair<int, std::size_t>> call; // (equation, next term to visit)
    int counter = 0;
    for (int start = 0; start < m; ++start)
    {
      if (index[std::size_t(start)] >= 0)
        continue;
      call.push_back({start, 0});
      while (!call.empty())
      {
        auto& [e, next] = call.back();
        const std::size_t ue = std::size_t(e);
        if (next == 0 && index[ue] < 0)
        {
          index[ue] = low[ue] = counter++;
          stack.push_back(e);
          onStack[ue] = 1;
        }
        const auto& others = equations_[ue].others;
        bool descended = false;
        while (next < others.size())
        {
          const int f = dependentOf(others[next++].first);
          if (f < 0)
            continue;
          if (index[std::size_t(f)] < 0)
          {
            call.push_back({f, 0});
            descended = true;
            break;
          }
          if (onStack[std::size_t(f)])
            low[ue] = std::min(low[ue], index[std::size_t(f)]);
        }
        if (descended)
          continue;
        if (low[ue] == index[ue])
        {
          std::vector<int> group;
          int f;
          do
          {
            f = stack.back();
            stack.pop_back();
            onStack[std::size_t(f)] = 0;
            group.push_back(f);
          } while (f != e);
          std::sort(group.begin(), group.end());
          groups.push_back(std::move(group));
        }
        const int done = e;
        call.pop_back();
        if (!call.empty())
        {
          const std::size_t parent = std::size_t(call.back().first);
          low[parent] = std::min(low[parent], low[std::size_t(done)]);
        }
      }
    }
    return groups;
  }

  /// One equation that refers to no dependent of its own group: substitute.
  void substitute(int e)
  {
    const RootEquation& q = equations_[std::size_t(e)];
    ResolvedRow r;
    r.constant = q.value / q.lead;
    for (const auto& [dof, c] : q.others)
    {
      const double f = -c / q.lead;
      if (isPrescribed_[std::size_t(dof)])
      {
        r.constant += f * value_[dof];
      }
      else if (const int other = equationOf_[std::size_t(dof)]; other >= 0)
      {
        const ResolvedRow& sub = rows_[std::size_t(other)];
        r.constant += f * sub.constant;
        for (const auto& [i, ci] : sub.terms)
          r.terms.push_back({i, f * ci});
      }
      else
      {
        r.terms.push_back({reduced_[std::size_t(dof)], f});
      }
    }
    mergeTerms(r);
    rows_[std::size_t(e)] = std::move(r);
  }

  /// Coupled dependents: A x = B ubar + b over the group, A square (one row
  /// per equation, one column per dependent), rows scaled to a largest
  /// coefficient of 1; x = A^-1 [B b].
  void solveGroup(const std::vector<int>& group)
  {
    const Eigen::Index m = Eigen::Index(group.size());
    const std::vector<int> columns = groupColumns(group);
    const Eigen::Index k = Eigen::Index(columns.size());
    Eigen::SparseMatrix<double> as(m, m);
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m, k + 1); // last column: the constant
    assembleGroup(group, columns, as, rhs);
    Eigen::MatrixXd x;
    const Eigen::Index undetermined = solveSquare(as, rhs, x);
    if (undetermined >= 0)
      throwUndetermined(group, undetermined);
    for (Eigen::Index row = 0; row < m; ++row)
    {
      ResolvedRow r;
      r.constant = x(row, k);
      for (Eigen::Index c = 0; c < k; ++c)
        if (x(row, c) != 0.0)
          r.terms.push_back({columns[std::size_t(c)], x(row, c)});
      rows_[std::size_t(group[std::size_t(row)])] = std::move(r);
    }
  }

  /// The position of equation @a e in the sorted @a group, or -1.
  static Eigen::Index localIndex(const std::vector<int>& group, int e)
  {
    const auto at = std::lower_bound(group.begin(), group.end(), e);
    return at != group.end() && *at == e ? Eigen::Index(at - group.begin()) : Eigen::Index(-1);
  }

  /// Columns of the right-hand side: the reduced DOFs the group involves, ascending.
  std::vector<int> groupColumns(const std::vector<int>& group) const
  {
    std::vector<int> columns;
    for (int e : group)
      for (const auto& [dof, c] : equations_[std::size_t(e)].others)
      {
        if (isPrescribed_[std::size_t(dof)])
          continue;
        const int f = equationOf_[std::size_t(dof)];
        if (f < 0)
          columns.push_back(reduced_[std::size_t(dof)]);
        else if (localIndex(group, f) < 0)
          for (const auto& t : rows_[std::size_t(f)].terms)
            columns.push_back(t.first);
      }
    std::sort(columns.begin(), columns.end());
    columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
    return columns;
  }

  /// A (@a as) and [B b] (@a rhs) of the group, rows scaled.
  void assembleGroup(const std::vector<int>& group, const std::vector<int>& columns, Eigen::SparseMatrix<double>& as,
                     Eigen::MatrixXd& rhs) const
  {
    const Eigen::Index m = Eigen::Index(group.size());
    const Eigen::Index k = Eigen::Index(columns.size());
    auto local = [&group](int e) { return localIndex(group, e); };
    auto column = [&columns](int i) {
      return Eigen::Index(std::lower_bound(columns.begin(), columns.end(), i) - columns.begin());
    };
    std::vector<Eigen::Triplet<double>> a;
    for (Eigen::Index row = 0; row < m; ++row)
    {
      const RootEquation& q = equations_[std::size_t(group[std::size_t(row)])];
      double scale = std::abs(q.lead);
      for (const auto& o : q.others)
        if (!isPrescribed_[std::size_t(o.first)] && local(equationOf_[std::size_t(o.first)]) >= 0)
          scale = std::max(scale, std::abs(o.second));
      const double s = 1.0 / scale;
      a.emplace_back(row, row, s * q.lead);
      rhs(row, k) = s * q.value;
      for (const auto& [dof, c] : q.others)
      {
        if (isPrescribed_[std::size_t(dof)])
        {
          rhs(row, k) -= s * c * value_[dof];
        }
        else if (const int f = equationOf_[std::size_t(dof)]; f < 0)
        {
          rhs(row, column(reduced_[std::size_t(dof)])) -= s * c;
        }
        else if (const Eigen::Index j = local(f); j >= 0)
        {
          a.emplace_back(row, j, s * c);
        }
        else
        {
          const ResolvedRow& sub = rows_[std::size_t(f)];
          rhs(row, k) -= s * c * sub.constant;
          for (const auto& [i, ci] : sub.terms)
            rhs(row, column(i)) -= s * c * ci;
        }
      }
    }
    as.setFromTriplets(a.begin(), a.end()); // sums the terms on one dependent
  }

  /// Solves @a as x = @a rhs into @a x; returns the local index of a
  /// dependent the group leaves free, or -1 when it determines them all.
  static Eigen::Index solveSquare(const Eigen::SparseMatrix<double>& as, const Eigen::MatrixXd& rhs, Eigen::MatrixXd& x)
  {
    const Eigen::Index m = as.rows();
    Eigen::Index undetermined = -1; // local index of a dependent the group leaves free
    // Relative to the largest pivot (rows scaled to 1): below it the system is
    // singular for any purpose here.
    constexpr double kPivotThreshold = 1e-12;
    constexpr Eigen::Index kDenseGroup = 400;
    if (m <= kDenseGroup)
    {
      const Eigen::MatrixXd dense(as);
      Eigen::FullPivLU<Eigen::MatrixXd> lu(dense);
      lu.setThreshold(kPivotThreshold);
      if (lu.rank() < m)
        undetermined = lu.permutationQ().indices()[lu.rank()];
      else
        x = lu.solve(rhs);
    }
    else
    {
      Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
      lu.compute(as);
      if (lu.info() != Eigen::Success)
      {
        undetermined = 0;
      }
      else
      {
        x = lu.solve(rhs);
        const double residual = (Eigen::MatrixXd(as * x) - rhs).cwiseAbs().maxCoeff();
        if (!x.allFinite() || residual > 1e-9 * std::max(1.0, rhs.cwiseAbs().maxCoeff()))
          undetermined = 0;
      }
    }
    return undetermined;
  }

  [[noreturn]] void throwUndetermined(const std::vector<int>& group, Eigen::Index undetermined) const
  {
    const int free = equations_[std::size_t(group[std::size_t(undetermined)])].dependent;
    Message msg;
    msg << "equations whose dependent DOFs (first terms) depend on each other (";
    constexpr std::size_t kListed = 8;
    for (std::size_t g = 0; g < group.size() && g < kListed; ++g)
    {
      const RootEquation& q = equations_[std::size_t(group[g])];
      msg << (g ? ", " : "") << EquationRef{q.source} << " on " << DofRef{q.dependent};
    }
    if (group.size() > kListed)
      msg << " and " << std::to_string(group.size() - kListed) << " more";
    msg << ") form a singular system that does not determine " << DofRef{free}
        << ": they are linearly dependent or contradict each other; drop one or change its coefficients";
    throw msg.error();
  }

  const std::vector<RootEquation>& equations_;
  const std::vector<int>& equationOf_;
  const std::vector<char>& isPrescribed_;
  const Eigen::VectorXd& value_;
  const std::vector<int>& reduced_;
  std::vector<ResolvedRow> rows_;
};

/// resolveConstraints() in steps, sharing the state per full DOF (free,
/// prescribed with a value, or a slave of a node), the suture roots and the
/// equations moved to root DOFs.
class ConstraintResolver
{
public:
  ConstraintResolver(const Mesh& mesh, const Constraints& c)
    : mesh_(mesh), c_(c), n_(mesh.nodeCount()), ndof_(3 * n_), isPrescribed_(ndof_, 0),
      value_(Eigen::VectorXd::Zero(ndof_)), sutureTarget_(n_, -1)
  {}

  void readPrescribed();
  void readSutures();
  void findSutureRoots();
  void readEquations();
  void numberFreeDofs(ConstraintMap& map) const;
  void resolveEquations(ConstraintMap& map) const;
  void placeSlaves(ConstraintMap& map) const;

private:
  void readEquation(std::size_t e);

  const Mesh& mesh_;
  const Constraints& c_;
  const Eigen::Index n_;
  const Eigen::Index ndof_;
  std::vector<char> isPrescribed_;
  Eigen::VectorXd value_;
  std::vector<int> sutureTarget_;
  std::vector<int> root_;
  std::vector<RootEquation> equations_;
  std::vector<int> equationOf_;
};

void ConstraintResolver::readPrescribed()
{
  for (const PrescribedDof& p : c_.prescribed)
  {
    checkNode(p.node, n_, Message() << "a prescribed displacement");
    if (p.direction < 0 || p.direction > 2)
      throw(Message() << "a prescribed displacement of node " << NodeRef{p.node} << " has direction "
                      << std::to_string(p.direction) << " (0, 1, 2 for x, y, z)")
        .error();
    if (!std::isfinite(p.value))
      throw(Message() << "node " << NodeRef{p.node} << " has a non-finite prescribed " << axisName(p.direction)
                      << " displacement")
        .error();
    const Eigen::Index d = 3 * p.node + p.direction;
    if (isPrescribed_[d] && value_[d] != p.value)
      throw(Message() << DofRef{int(d)} << " is prescribed twice, to " << value_[d] << " and " << p.value << " mm")
        .error();
    isPrescribed_[d] = 1;
    value_[d] = p.value;
  }
}

void ConstraintResolver::readSutures()
{
  for (const Suture& s : c_.sutures)
  {
    checkNode(s.node, n_, Message() << "a suture");
    checkNode(s.target, n_, Message() << "a suture");
    if (s.node == s.target)
      throw(Message() << "node " << NodeRef{s.node} << " is sutured to itself").error();
    if (sutureTarget_[s.node] >= 0 && sutureTarget_[s.node] != s.target)
      throw(Message() << "node " << NodeRef{s.node} << " is sutured to two nodes, " << NodeRef{sutureTarget_[s.node]}
                      << " and " << NodeRef{s.target})
        .error();
    for (int d = 0; d < 3; ++d)
      if (isPrescribed_[3 * s.node + d])
        throw(Message() << "node " << NodeRef{s.node} << " is sutured to node " << NodeRef{s.target} << " but its "
                        << axisName(d) << " displacement is also prescribed; suture the other way round")
          .error();
    sutureTarget_[s.node] = s.target;
  }
}

void ConstraintResolver::findSutureRoots()
{
  // Follow each suture chain to its root node (cycle check on the way).
  root_.assign(n_, -2); // -2 unknown, -3 on the current path
  for (int start = 0; start < n_; ++start)
  {
    if (root_[start] != -2)
      continue;
    std::vector<int> path;
    int v = start;
    while (root_[v] == -2 && sutureTarget_[v] >= 0)
    {
      root_[v] = -3;
      path.push_back(v);
      v = sutureTarget_[v];
    }
    if (root_[v] == -3)
    {
      Message loop;
      loop << "sutures form a closed loop: ";
      for (int p : path)
        loop << NodeRef{p} << " -> ";
      throw(loop << NodeRef{v}).error();
    }
    const int r = root_[v] == -2 ? v : root_[v];
    root_[v] = r;
    for (int p : path)
      root_[p] = r;
  }
}

void ConstraintResolver::readEquations()
{
  // Equations: terms moved to root DOFs (u_i = u_root + x_root - x_i), summed.
  equationOf_.assign(c_.equations.empty() ? 0 : std::size_t(ndof_), -1);
  for (std::size_t e = 0; e < c_.equations.size(); ++e)
    readEquation(e);
}

void ConstraintResolver::readEquation(std::size_t e)
{
  const LinearConstraint& q = c_.equations[e];
  const EquationRef which{int(e)};
  if (q.terms.empty())
    throw(Message() << which << " has no terms").error();
  for (const ConstraintTerm& t : q.terms)
  {
    checkNode(t.node, n_, Message() << which);
    if (t.direction < 0 || t.direction > 2)
      throw(Message() << which << " has a term on node " << NodeRef{t.node} << " in direction "
                      << std::to_string(t.direction) << " (0, 1, 2 for x, y, z)")
        .error();
    if (!std::isfinite(t.coefficient))
      throw(Message() << which << " has a non-finite coefficient for " << DofRef{3 * t.node + t.direction}).error();
  }
  const int dependent = 3 * q.terms[0].node + q.terms[0].direction;
  const auto name = [&]() { return Message() << which << " (dependent DOF " << DofRef{dependent} << ")"; };
  if (!std::isfinite(q.value))
    throw(name() << " has a non-finite value").error();
  if (q.terms[0].coefficient == 0.0)
    throw(name() << " has a zero coefficient in its first term, which is the DOF it "
                    "eliminates; begin it with a term whose coefficient is not zero")
      .error();
  if (isPrescribed_[std::size_t(dependent)])
    throw(Message() << DofRef{dependent} << " is prescribed and also the dependent DOF (first term) of " << which
                    << "; begin the equation with another term")
      .error();
  if (sutureTarget_[std::size_t(q.terms[0].node)] >= 0)
    throw(
      Message() << DofRef{dependent} << " is sutured to node " << NodeRef{sutureTarget_[std::size_t(q.terms[0].node)]}
                << " and also the dependent DOF (first term) of " << which << "; begin the equation with another term")
      .error();
  if (const int other = equationOf_[std::size_t(dependent)]; other >= 0)
    throw(Message() << DofRef{dependent} << " is the dependent DOF (first term) of two equations, "
                    << EquationRef{other} << " and " << which << "; begin one of them with another term")
      .error();
  equationOf_[std::size_t(dependent)] = int(equations_.size());
  RootEquation r;
  r.dependent = dependent;
  r.source = int(e);
  r.value = q.value;
  for (const ConstraintTerm& t : q.terms)
  {
    if (t.coefficient == 0.0)
      continue;
    const int rootNode = root_[std::size_t(t.node)];
    const int dof = 3 * rootNode + t.direction;
    r.value -= t.coefficient * (mesh_.nodes(t.direction, rootNode) - mesh_.nodes(t.direction, t.node));
    auto at = std::find_if(r.others.begin(), r.others.end(), [dof](const auto& o) { return o.first == dof; });
    if (at == r.others.end())
      r.others.push_back({dof, t.coefficient});
    else
      at->second += t.coefficient;
  }
  auto lead =
    std::find_if(r.others.begin(), r.others.end(), [dependent](const auto& o) { return o.first == dependent; });
  r.lead = lead->second;
  r.others.erase(lead);
  if (r.lead == 0.0)
    throw(name() << ": the terms on its dependent DOF cancel out (coefficients sum to zero)").error();
  r.others.erase(std::remove_if(r.others.begin(), r.others.end(), [](const auto& o) { return o.second == 0.0; }),
                 r.others.end());
  equations_.push_back(std::move(r));
}

void ConstraintResolver::numberFreeDofs(ConstraintMap& map) const
{
  map.reduced.assign(ndof_, -1);
  map.offset = Eigen::VectorXd::Zero(ndof_);
  // Free DOFs of root nodes get reduced indices in node order.
  for (int i = 0; i < n_; ++i)
  {
    if (root_[i] != i)
      continue;
    for (int d = 0; d < 3; ++d)
    {
      const int dof = 3 * i + d;
      if (isPrescribed_[dof])
      {
        map.offset[dof] = value_[dof];
      }
      else if (!equationOf_.empty() && equationOf_[std::size_t(dof)] >= 0)
      {
        continue; // a general row, below
      }
      else
      {
        map.reduced[dof] = int(map.masterOf.size());
        map.masterOf.push_back(dof);
      }
    }
  }
}

void ConstraintResolver::resolveEquations(ConstraintMap& map) const
{
  if (equations_.empty())
    return;
  // Dependent DOFs of equations: substituted in cascade, coupled ones solved together.
  std::vector<const ResolvedRow*> rowOfRoot(std::size_t(ndof_), nullptr);
  const std::vector<ResolvedRow> rows =
    EquationResolver(equations_, equationOf_, isPrescribed_, value_, map.reduced).resolve();
  for (std::size_t e = 0; e < equations_.size(); ++e)
  {
    map.offset[equations_[e].dependent] = rows[e].constant;
    rowOfRoot[std::size_t(equations_[e].dependent)] = &rows[e];
  }
  // Rows of T for them and for the DOFs sutured onto them, in DOF order.
  for (int dof = 0; dof < ndof_; ++dof)
  {
    const ResolvedRow* r = rowOfRoot[std::size_t(3 * root_[std::size_t(dof / 3)] + dof % 3)];
    if (!r)
      continue;
    map.general.push_back(dof);
    for (const auto& [i, ci] : r->terms)
    {
      map.generalIndex.push_back(i);
      map.generalCoefficient.push_back(ci);
    }
    map.generalStart.push_back(int(map.generalIndex.size()));
  }
}

void ConstraintResolver::placeSlaves(ConstraintMap& map) const
{
  // Slaves: u_i = u_root + (x_root - x_i), summed along the chain telescopes to this.
  for (int i = 0; i < n_; ++i)
  {
    const int r = root_[i];
    if (r == i)
      continue;
    for (int d = 0; d < 3; ++d)
    {
      const int dof = 3 * i + d, rdof = 3 * r + d;
      map.reduced[dof] = map.reduced[rdof];
      map.offset[dof] = map.offset[rdof] + (mesh_.nodes(d, r) - mesh_.nodes(d, i));
    }
  }
}

} // namespace

ConstraintError::ConstraintError(std::string pattern, std::vector<int> nodes, std::vector<int> equations)
  : std::invalid_argument(render(pattern, nodes, equations, {})), pattern_(std::move(pattern)),
    nodes_(std::move(nodes)), equations_(std::move(equations))
{}

std::string ConstraintError::message(const Naming& naming) const
{
  return render(pattern_, nodes_, equations_, naming);
}

ConstraintMap resolveConstraints(const Mesh& mesh, const Constraints& c)
{
  ConstraintResolver resolver(mesh, c);
  resolver.readPrescribed();
  resolver.readSutures();
  resolver.findSutureRoots();
  resolver.readEquations();
  ConstraintMap map;
  resolver.numberFreeDofs(map);
  resolver.resolveEquations(map);
  resolver.placeSlaves(map);
  return map;
}

struct ConstraintMap::ReductionPlan
{
  Eigen::Index rows = 0, kNonZeros = 0, kbarNonZeros = 0;
  std::size_t outerHash = 0; ///< of K's column starts: a cheap check of the pattern
  std::vector<int> source;   ///< per contribution, in summation order: K's value index
  std::vector<double> weight;
  std::vector<int> target; ///< K̄'s value index
};

Eigen::SparseMatrix<double> ConstraintMap::reduceMatrix(const Eigen::SparseMatrix<double>& k) const
{
  // Each full DOF stands for at most one reduced DOF with coefficient 1, so
  // T^T K T just renames rows and columns and sums what lands together.
  // Counted into compressed columns directly (a triplet sort took most of
  // the time); columns are then sorted and their duplicates summed.
  const Eigen::Index n = reducedCount();
  // Fixed and prescribed DOFs only (no sutures): K-bar is K without their
  // rows and columns, renumbered in the same order, so one copying pass.
  bool selection = !hasGeneralRows();
  for (std::size_t d = 0, last = 0; d < reduced.size() && selection; ++d)
    if (reduced[d] >= 0)
    {
      selection = std::size_t(reduced[d]) == last;
      ++last;
    }
  if (selection && k.isCompressed())
  {
    // Straight into the result's arrays: an extra copy of ~100 MB of
    // entries costs as much as the pass itself (page faults).
    Eigen::SparseMatrix<double> r(n, n);
    r.resizeNonZeros(k.nonZeros());
    int* outer = r.outerIndexPtr();
    int* inner = r.innerIndexPtr();
    double* values = r.valuePtr();
    Eigen::Index at = 0;
    outer[0] = 0;
    for (Eigen::Index j = 0; j < k.outerSize(); ++j)
    {
      const int b = reduced[std::size_t(j)];
      if (b < 0)
        continue;
      for (Eigen::SparseMatrix<double>::InnerIterator it(k, j); it; ++it)
      {
        if (it.row() > j)
          break; // rows are sorted: the rest is below the diagonal
        const int a = reduced[std::size_t(it.row())];
        if (a < 0)
          continue;
        inner[at] = a;
        values[at] = it.value();
        ++at;
      }
      outer[b + 1] = int(at);
    }
    r.resizeNonZeros(at); // shrinks without reallocating
    return r;
  }

  if (!hasGeneralRows())
    return reduceGeneral(k, nullptr);
  auto plan = std::make_shared<ReductionPlan>();
  Eigen::SparseMatrix<double> r = reduceGeneral(k, plan.get());
  plan_ = plan;
  return r;
}

namespace {

std::size_t outerHash(const Eigen::SparseMatrix<double>& k)
{
  std::size_t h = 1469598103934665603ull;
  for (Eigen::Index j = 0; j <= k.outerSize(); ++j)
    h = (h ^ std::size_t(k.outerIndexPtr()[j])) * 1099511628211ull;
  return h;
}

/// Rows of T per full DOF: row d is entries start[d] .. start[d + 1] - 1 of
/// index (reduced DOFs) and coefficient.
struct RowsOfT
{
  std::vector<int> start;
  std::vector<int> index;
  std::vector<double> coefficient;
};

RowsOfT rowsOfT(const ConstraintMap& map)
{
  RowsOfT t;
  t.start.assign(map.reduced.size() + 1, 0);
  t.index.reserve(map.reduced.size() + map.generalIndex.size());
  t.coefficient.reserve(t.index.capacity());
  for (std::size_t d = 0, g = 0; d < map.reduced.size(); ++d)
  {
    if (map.reduced[d] >= 0)
    {
      t.index.push_back(map.reduced[d]);
      t.coefficient.push_back(1.0);
    }
    else if (g < map.general.size() && map.general[g] == int(d))
    {
      for (int e = map.generalStart[g]; e < map.generalStart[g + 1]; ++e)
      {
        t.index.push_back(map.generalIndex[std::size_t(e)]);
        t.coefficient.push_back(map.generalCoefficient[std::size_t(e)]);
      }
      ++g;
    }
    t.start[d + 1] = int(t.index.size());
  }
  return t;
}

/// Calls f(K's value index, a, b, weight) for every contribution, in K's order.
template <class F> void forEachContribution(const Eigen::SparseMatrix<double>& k, const RowsOfT& t, F&& f)
{
  const int* outerK = k.outerIndexPtr();
  const int* innerK = k.innerIndexPtr();
  const auto columnEnd = [&k, outerK](Eigen::Index j) {
    return k.isCompressed() ? outerK[j + 1] : outerK[j] + k.innerNonZeroPtr()[j];
  };
  for (Eigen::Index j = 0; j < k.outerSize(); ++j)
    for (int p = outerK[j], end = columnEnd(j); p < end; ++p)
    {
      const int i = innerK[p];
      if (i > j)
        continue; // upper triangle only
      for (int x = t.start[std::size_t(i)]; x < t.start[std::size_t(i) + 1]; ++x)
        for (int y = t.start[std::size_t(j)]; y < t.start[std::size_t(j) + 1]; ++y)
        {
          int a = t.index[std::size_t(x)], b = t.index[std::size_t(y)];
          if (i == j && a > b)
            continue; // the pair (b, a) of the same row gives it
          if (a > b)
            std::swap(a, b);
          double w = t.coefficient[std::size_t(x)] * t.coefficient[std::size_t(y)];
          if (a == b && i != j)
            w *= 2.0; // K_ij and K_ji both land on the diagonal
          f(p, a, b, w);
        }
    }
}

/// The contributions counted into K̄'s columns (start count[b]), in K's
/// order within a column; with a plan also their sources and weights.
struct Contributions
{
  std::vector<int> count;
  std::vector<int> rows;
  std::vector<double> vals;
  std::vector<int> sources;
  std::vector<double> weights;
};

Contributions scatterContributions(const Eigen::SparseMatrix<double>& k, const RowsOfT& t, Eigen::Index n,
                                   bool withPlan)
{
  Contributions s;
  std::vector<int>& count = s.count;
  count.assign(std::size_t(n) + 1, 0);
  forEachContribution(k, t, [&count](int, int, int b, double) { ++count[std::size_t(b) + 1]; });
  for (std::size_t c = 0; c < std::size_t(n); ++c)
    count[c + 1] += count[c];
  s.rows.resize(std::size_t(count.back()));
  s.vals.resize(s.rows.size());
  s.sources.resize(withPlan ? s.rows.size() : 0);
  s.weights.resize(withPlan ? s.rows.size() : 0);
  std::vector<int> fill(count.begin(), count.end() - 1);
  const double* valuesK = k.valuePtr();
  forEachContribution(k, t, [&](int p, int a, int b, double w) {
    const int at = fill[std::size_t(b)]++;
    s.rows[std::size_t(at)] = a;
    s.vals[std::size_t(at)] = valuesK[p] * w;
    if (withPlan)
    {
      s.sources[std::size_t(at)] = p;
      s.weights[std::size_t(at)] = w;
    }
  });
  return s;
}

/// K̄ from the scattered contributions: each column sorted by row and its
/// duplicates summed; with @a plan, where each contribution went.
Eigen::SparseMatrix<double> sumContributions(const Contributions& s, Eigen::Index n, ConstraintMap::ReductionPlan* plan)
{
  const std::vector<int>& count = s.count;
  const std::vector<int>& rows = s.rows;
  Eigen::SparseMatrix<double> r(n, n);
  std::vector<int> order;
  std::vector<int> outer(std::size_t(n) + 1, 0);
  std::vector<int> inner;
  std::vector<double> values;
  inner.reserve(rows.size());
  values.reserve(rows.size());
  if (plan)
  {
    plan->source.clear();
    plan->weight.clear();
    plan->target.clear();
    plan->source.reserve(rows.size());
    plan->weight.reserve(rows.size());
    plan->target.reserve(rows.size());
  }
  for (Eigen::Index c = 0; c < n; ++c)
  {
    const int first = count[std::size_t(c)], last = count[std::size_t(c) + 1];
    order.resize(std::size_t(last - first));
    for (int e = first; e < last; ++e)
      order[std::size_t(e - first)] = e;
    // By row, then by position: duplicates are summed in the order K holds
    // them (deterministic).
    const auto byRow = [&rows](int x, int y) {
      return rows[std::size_t(x)] < rows[std::size_t(y)] || (rows[std::size_t(x)] == rows[std::size_t(y)] && x < y);
    };
    if (!std::is_sorted(order.begin(), order.end(), byRow))
      std::sort(order.begin(), order.end(), byRow);
    for (int e : order)
    {
      if (int(inner.size()) > outer[std::size_t(c)] && inner.back() == rows[std::size_t(e)])
        values.back() += s.vals[std::size_t(e)];
      else
      {
        inner.push_back(rows[std::size_t(e)]);
        values.push_back(s.vals[std::size_t(e)]);
      }
      if (plan)
      {
        plan->source.push_back(s.sources[std::size_t(e)]);
        plan->weight.push_back(s.weights[std::size_t(e)]);
        plan->target.push_back(int(inner.size()) - 1);
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

} // namespace

Eigen::SparseMatrix<double> ConstraintMap::reduceGeneral(const Eigen::SparseMatrix<double>& k,
                                                         ReductionPlan* plan) const
{
  // T^T K T entry by entry: K_ij (i <= j) times each pair of row i's and row
  // j's terms lands on K̄(min, max); from an off-diagonal K_ij a pair on one
  // reduced DOF lands there twice (K_ij and K_ji). Rows with one coefficient-1
  // term (sutures) give the weights 1 and 2 of a plain renaming. Counted into
  // compressed columns directly (a triplet sort took most of the time);
  // columns are then sorted and their duplicates summed.
  const Eigen::Index n = reducedCount();
  const RowsOfT t = rowsOfT(*this);
  const Contributions s = scatterContributions(k, t, n, plan != nullptr);
  Eigen::SparseMatrix<double> r = sumContributions(s, n, plan);
  if (plan)
  {
    plan->rows = k.rows();
    plan->kNonZeros = k.nonZeros();
    plan->kbarNonZeros = r.nonZeros();
    plan->outerHash = outerHash(k);
  }
  return r;
}

void ConstraintMap::reduceValues(const Eigen::SparseMatrix<double>& k, Eigen::SparseMatrix<double>& kbar) const
{
  bool selection = k.isCompressed() && !hasGeneralRows();
  for (std::size_t d = 0, last = 0; d < reduced.size() && selection; ++d)
    if (reduced[d] >= 0)
    {
      selection = std::size_t(reduced[d]) == last;
      ++last;
    }
  if (!selection && hasGeneralRows() && k.isCompressed())
  {
    // Replay the scatter plan (made once per pattern): the same products,
    // summed in the same order as reduceMatrix(), so the same values.
    std::shared_ptr<const ReductionPlan> plan = plan_;
    if (!plan || plan->rows != k.rows() || plan->kNonZeros != k.nonZeros() || plan->outerHash != outerHash(k))
    {
      auto fresh = std::make_shared<ReductionPlan>();
      reduceGeneral(k, fresh.get());
      plan_ = plan = fresh;
    }
    if (plan->kbarNonZeros != kbar.nonZeros() || kbar.rows() != reducedCount())
      throw std::invalid_argument("reduceValues: the reduced matrix was made from another pattern");
    double* values = kbar.valuePtr();
    const double* valuesK = k.valuePtr();
    std::fill(values, values + kbar.nonZeros(), 0.0);
    const std::size_t m = plan->source.size();
    const int* source = plan->source.data();
    const int* target = plan->target.data();
    const double* weight = plan->weight.data();
    for (std::size_t e = 0; e < m; ++e)
      values[target[e]] += valuesK[source[e]] * weight[e];
    return;
  }
  if (!selection)
  {
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
  for (Eigen::Index j = 0; j < k.outerSize(); ++j)
  {
    if (reduced[std::size_t(j)] < 0)
      continue;
    for (Eigen::SparseMatrix<double>::InnerIterator it(k, j); it; ++it)
    {
      if (it.row() > j)
        break;
      if (reduced[std::size_t(it.row())] < 0)
        continue;
      if (at >= kbar.nonZeros())
        throw std::invalid_argument("reduceValues: the reduced matrix was made from another pattern");
      values[at++] = it.value();
    }
  }
  if (at != kbar.nonZeros())
    throw std::invalid_argument("reduceValues: the reduced matrix was made from another pattern");
}

Eigen::MatrixXd ConstraintMap::reduceVector(const Eigen::MatrixXd& r) const
{
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(reducedCount(), r.cols());
  for (std::size_t d = 0; d < reduced.size(); ++d)
    if (reduced[d] >= 0)
      out.row(reduced[d]) += r.row(Eigen::Index(d));
  for (std::size_t g = 0; g < general.size(); ++g)
    for (int e = generalStart[g]; e < generalStart[g + 1]; ++e)
      out.row(generalIndex[std::size_t(e)]) += generalCoefficient[std::size_t(e)] * r.row(general[g]);
  return out;
}

Eigen::MatrixXd ConstraintMap::expand(const Eigen::MatrixXd& ubar) const
{
  return expand(ubar, 1.0);
}

Eigen::MatrixXd ConstraintMap::expand(const Eigen::MatrixXd& ubar, double offsetScale) const
{
  Eigen::MatrixXd u(Eigen::Index(reduced.size()), ubar.cols());
  for (std::size_t d = 0; d < reduced.size(); ++d)
  {
    u.row(Eigen::Index(d)).setConstant(offsetScale * offset[Eigen::Index(d)]);
    if (reduced[d] >= 0)
      u.row(Eigen::Index(d)) += ubar.row(reduced[d]);
  }
  for (std::size_t g = 0; g < general.size(); ++g)
    for (int e = generalStart[g]; e < generalStart[g + 1]; ++e)
      u.row(general[g]) += generalCoefficient[std::size_t(e)] * ubar.row(generalIndex[std::size_t(e)]);
  return u;
}

Eigen::SparseMatrix<double> ConstraintMap::transformation() const
{
  std::vector<Eigen::Triplet<double>> t;
  for (std::size_t d = 0; d < reduced.size(); ++d)
    if (reduced[d] >= 0)
      t.emplace_back(int(d), reduced[d], 1.0);
  for (std::size_t g = 0; g < general.size(); ++g)
    for (int e = generalStart[g]; e < generalStart[g + 1]; ++e)
      t.emplace_back(general[g], generalIndex[std::size_t(e)], generalCoefficient[std::size_t(e)]);
  Eigen::SparseMatrix<double> m(Eigen::Index(reduced.size()), reducedCount());
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

bool ConstraintMap::sameTransformation(const ConstraintMap& other) const
{
  return reduced == other.reduced && masterOf == other.masterOf && general == other.general &&
         generalStart == other.generalStart && generalIndex == other.generalIndex &&
         generalCoefficient == other.generalCoefficient;
}

} // namespace caps::fem
