#include "modules/simulate/SimulateLogic.h"

#include <charconv>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <map>
#include <thread>
#include <type_traits>

#include "fem/CalculixReader.h"
#include "fem/ElementGeometry.h"
#include "fem/FiniteStrainStress.h"
#include "fem/NodalStress.h"
#include "fem/NonlinearStaticAnalysis.h"
#include "fem/StressRecovery.h"
#include "fem/VtuWriter.h"

#include <algorithm>
#include <cmath>

namespace fs = std::filesystem;

namespace caps {
namespace {

/// The deck's number of CAPS node @a node (0-based), or the index if out of range.
std::string deckNode(const fem::CalculixModel& model, int node)
{
  if (node >= 0 && std::size_t(node) < model.nodeIds.size())
    return std::to_string(model.nodeIds[std::size_t(node)]);
  return "(index " + std::to_string(node) + ")";
}

/// The text of @a e with the deck's node and element numbers in place of
/// CAPS's 0-based indices (constraint and element errors carry them).
std::string deckMessage(const std::exception& e, const fem::CalculixModel& model)
{
  if (const auto* c = dynamic_cast<const fem::ConstraintError*>(&e))
  {
    fem::ConstraintError::Naming naming;
    naming.node = [&model](int node) { return deckNode(model, node); };
    // Ties read as sutures leave the list, so its order is not the deck's:
    // an equation is named by its first term (the DOF it eliminates).
    naming.equation = [&model](int k) {
      const auto& equations = model.constraints.equations;
      if (k < 0 || std::size_t(k) >= equations.size() || equations[std::size_t(k)].terms.empty())
        return "equation " + std::to_string(k);
      const fem::ConstraintTerm& t = equations[std::size_t(k)].terms.front();
      return "the *EQUATION " + deckNode(model, t.node) + "," + std::to_string(t.direction + 1) + ",...";
    };
    return c->message(naming);
  }
  if (const auto* el = dynamic_cast<const fem::ElementError*>(&e))
  {
    // ElementError's text begins "element <index> ...": the deck's number instead.
    const int i = el->element();
    const std::string text = e.what();
    if (i < 0 || std::size_t(i) >= model.elementIds.size())
      return text;
    const std::string ours = "element " + std::to_string(i);
    const std::string deck = "element " + std::to_string(model.elementIds[std::size_t(i)]);
    if (text.rfind(ours + " ", 0) == 0)
      return deck + text.substr(ours.size());
    return deck + " of the deck: " + text;
  }
  return e.what();
}

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0)
{
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::ofstream openForWriting(const fs::path& path)
{
  std::ofstream f(path);
  if (!f)
    throw std::runtime_error("cannot write " + path.string());
  f << std::setprecision(12);
  return f;
}

/// A CSV file's text as it grows, numbers formatted by std::to_chars: the
/// bytes of an ostream with precision(12) (printf's %.12g), at a tenth of
/// the cost; written at once by save().
class CsvText
{
public:
  explicit CsvText(std::size_t reserve) { text_.reserve(reserve); }
  CsvText& operator<<(const char* s)
  {
    text_ += s;
    return *this;
  }
  CsvText& operator<<(char c)
  {
    text_ += c;
    return *this;
  }
  CsvText& operator<<(double v)
  {
    char buffer[32];
    const auto r = std::to_chars(buffer, buffer + sizeof buffer, v, std::chars_format::general, 12);
    text_.append(buffer, r.ptr);
    return *this;
  }
  template <class Integer, class = std::enable_if_t<std::is_integral_v<Integer>>> CsvText& operator<<(Integer v)
  {
    char buffer[24];
    const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
    text_.append(buffer, r.ptr);
    return *this;
  }
  /// Writes the text to @a path; throws std::runtime_error if it cannot.
  void save(const fs::path& path) const
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f)
      throw std::runtime_error("cannot write " + path.string());
    const bool written = std::fwrite(text_.data(), 1, text_.size(), f) == text_.size();
    if (std::fclose(f) != 0 || !written)
      throw std::runtime_error("error while writing " + path.string());
  }

private:
  std::string text_;
};

/// Index into @a points (one element's rule, gaussRule()/wedgeRule() order)
/// of each integration point in CalculiX's order: for a brick the first
/// natural coordinate runs fastest, then the second, then the third (our
/// gaussRule() runs the third fastest); a wedge's rule is already in ccx's
/// order (triangle points fastest, t slowest).
std::vector<std::size_t> ccxPointOrder(const std::vector<fem::StressPoint>& points, fem::ElementKind kind)
{
  std::vector<std::size_t> order(points.size());
  for (std::size_t p = 0; p < points.size(); ++p)
    order[p] = p;
  if (kind == fem::ElementKind::Wedge15)
    return order;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    for (int d = 2; d >= 0; --d)
    {
      const double x = points[a].natural[d], y = points[b].natural[d];
      if (std::abs(x - y) > 1e-9)
        return x < y;
    }
    return false;
  });
  return order;
}

/// Each region's law in a large-deformation step, as CalculiX reads the
/// deck: its *HYPERELASTIC material, or St. Venant-Kirchhoff for *ELASTIC.
fem::HyperelasticTable largeDeformationMaterials(const fem::CalculixModel& model)
{
  fem::HyperelasticTable table;
  for (const auto& [region, linear] : model.materials)
  {
    const auto it = model.hyperelastic.find(region);
    table[region] = it != model.hyperelastic.end()
                      ? it->second
                      : fem::HyperelasticMaterial::fromLinear(fem::HyperelasticLaw::StVenantKirchhoff, linear);
  }
  return table;
}

/// The deck's *STATIC increments as fractions of the step.
fem::IncrementControl incrementsOf(const fem::StaticStep& step)
{
  fem::IncrementControl c;
  const double period = step.period > 0.0 ? step.period : 1.0;
  c.initial = std::clamp(step.initialIncrement / period, 1e-12, 1.0);
  c.minimum = std::min(c.initial, std::max(step.minimumIncrement / period, 1e-12));
  c.maximum = std::max(c.initial, std::min(step.maximumIncrement / period, 1.0));
  c.fixed = step.direct;
  return c;
}

/// increments.csv: every attempted increment, accepted or cut back.
fs::path writeIncrementLog(const fs::path& outDir, const fem::NonlinearResult& r)
{
  fs::create_directories(outDir);
  const fs::path path = outDir / "increments.csv";
  auto f = openForWriting(path);
  f << "increment,start_fraction,end_fraction,iterations,residual,accepted,reason\n";
  for (const auto& i : r.increments)
  {
    std::string reason = i.rejection;
    std::replace(reason.begin(), reason.end(), '"', '\'');
    f << i.increment << ',' << i.startFraction << ',' << i.endFraction << ',' << i.iterations << ',' << i.residual
      << ',' << (i.accepted ? 1 : 0) << ",\"" << reason << "\"\n";
  }
  if (!f)
    throw std::runtime_error("error while writing " + path.string());
  return path;
}

/// What a solve of a deck hands to the writers.
struct DeckResults
{
  fem::NodalStressMatrix nodalStress;                     ///< 6 x N (Cauchy in large deformation), MPa
  std::vector<std::vector<fem::StressPoint>> gaussStress; ///< per element, its rule's points
  std::vector<fem::VtuArray> extraArrays;                 ///< more point data for result.vtu
  std::vector<fs::path> extraFiles;                       ///< written before (the increment log)
};

/// The stress invariants at each node of the report's stress field.
struct NodalInvariants
{
  Eigen::VectorXd vonMises, mean;
  Eigen::Matrix3Xd principal;
};

NodalInvariants invariantsOf(const fem::NodalStressMatrix& nodalStress)
{
  const Eigen::Index n = nodalStress.cols();
  NodalInvariants v{Eigen::VectorXd(n), Eigen::VectorXd(n), Eigen::Matrix3Xd(3, n)};
  for (Eigen::Index i = 0; i < n; ++i)
  {
    const fem::Vector6d s = nodalStress.col(i);
    v.vonMises[i] = fem::vonMisesStress(s);
    v.mean[i] = s.head<3>().sum() / 3.0;
    v.principal.col(i) = fem::principalStresses(s);
  }
  return v;
}

/// gauss_stresses.csv: the stress at each element's own integration points,
/// in the order and columns of ccx's *EL PRINT S, for comparison with its .dat.
void writeGaussStresses(const fem::CalculixModel& model, const DeckResults& results, const fs::path& file)
{
  std::size_t count = 0;
  for (const auto& p : results.gaussStress)
    count += p.size();
  CsvText f(count * 120 + 64);
  f << "element,point,sxx,syy,szz,sxy,sxz,syz\n";
  // The order depends on the rule only: one per (kind, number of points).
  std::map<std::pair<fem::ElementKind, std::size_t>, std::vector<std::size_t>> orders;
  for (std::size_t e = 0; e < results.gaussStress.size(); ++e)
  {
    const auto& points = results.gaussStress[e];
    const fem::ElementKind kind = model.mesh.elements[e].kind;
    auto it = orders.find({kind, points.size()});
    if (it == orders.end())
      it = orders.emplace(std::make_pair(kind, points.size()), ccxPointOrder(points, kind)).first;
    const auto& order = it->second;
    for (std::size_t k = 0; k < order.size(); ++k)
    {
      const fem::Vector6d& s = points[order[k]].stress; // xx yy zz xy yz zx
      f << model.elementIds[e] << ',' << k + 1 << ',' << s[0] << ',' << s[1] << ',' << s[2] << ',' << s[3] << ','
        << s[5] << ',' << s[4] << '\n';
    }
  }
  f.save(file);
}

/// displacements.csv, stresses.csv and result.vtu.
void writeNodalResults(const fem::CalculixModel& model, const Eigen::VectorXd& u, const DeckResults& results,
                       const NodalInvariants& v, const fs::path& displacements, const fs::path& stresses,
                       const fs::path& vtu)
{
  const Eigen::Index n = model.mesh.nodeCount();
  {
    CsvText f(std::size_t(n) * 140 + 64);
    f << "node,x,y,z,ux,uy,uz\n";
    for (Eigen::Index i = 0; i < n; ++i)
      f << model.nodeIds[std::size_t(i)] << ',' << model.mesh.nodes(0, i) << ',' << model.mesh.nodes(1, i) << ','
        << model.mesh.nodes(2, i) << ',' << u[3 * i] << ',' << u[3 * i + 1] << ',' << u[3 * i + 2] << '\n';
    f.save(displacements);
  }
  {
    CsvText f(std::size_t(n) * 160 + 64);
    f << "node,sxx,syy,szz,sxy,syz,szx,von_mises\n";
    for (Eigen::Index i = 0; i < n; ++i)
    {
      f << model.nodeIds[std::size_t(i)];
      for (int c = 0; c < 6; ++c)
        f << ',' << results.nodalStress(c, i);
      f << ',' << v.vonMises[i] << '\n';
    }
    f.save(stresses);
  }
  Eigen::MatrixXd ids(1, n);
  for (Eigen::Index i = 0; i < n; ++i)
    ids(0, i) = double(model.nodeIds[std::size_t(i)]);
  std::vector<fem::VtuArray> arrays = {{"displacement", Eigen::Map<const Eigen::MatrixXd>(u.data(), 3, n)},
                                       {"stress", results.nodalStress},
                                       {"von_mises", v.vonMises.transpose()},
                                       {"mean_stress", v.mean.transpose()},
                                       {"principal_stress", v.principal},
                                       {"node_id", ids}};
  arrays.insert(arrays.end(), results.extraArrays.begin(), results.extraArrays.end());
  fem::writeVtu(vtu.string(), model.mesh, arrays);
}

/// displacements.csv, stresses.csv, gauss_stresses.csv and result.vtu into
/// @a outDir; fills the report's maxima and files.
FemRunReport writeResults(const fem::CalculixModel& model, const Eigen::VectorXd& u, const DeckResults& results,
                          const fs::path& outDir, FemRunReport& report)
{
  const Eigen::Index n = model.mesh.nodeCount();
  const NodalInvariants invariants = invariantsOf(results.nodalStress);
  for (Eigen::Index i = 0; i < n; ++i)
  {
    const double norm = u.segment<3>(3 * i).norm();
    if (norm > report.maxDisplacement || i == 0)
    {
      report.maxDisplacement = norm;
      report.maxDisplacementNode = model.nodeIds[std::size_t(i)];
    }
  }
  report.maxVonMises = n ? invariants.vonMises.maxCoeff() : 0.0;

  const auto t0 = Clock::now();
  try
  {
    fs::create_directories(outDir);
    const fs::path displacements = outDir / "displacements.csv";
    const fs::path stresses = outDir / "stresses.csv";
    const fs::path gaussStresses = outDir / "gauss_stresses.csv";
    const fs::path vtu = outDir / "result.vtu";
    // The Gauss-point file is the largest: formatted on a second thread
    // beside the others.
    std::exception_ptr gaussError;
    std::thread gaussWriter([&]() {
      try
      {
        writeGaussStresses(model, results, gaussStresses);
      }
      catch (...)
      {
        gaussError = std::current_exception();
      }
    });
    try
    {
      writeNodalResults(model, u, results, invariants, displacements, stresses, vtu);
    }
    catch (...)
    {
      gaussWriter.join();
      throw;
    }
    gaussWriter.join();
    if (gaussError)
      std::rethrow_exception(gaussError);
    report.files = {displacements, stresses, gaussStresses, vtu};
    report.files.insert(report.files.end(), results.extraFiles.begin(), results.extraFiles.end());
  }
  catch (const std::exception& e)
  {
    report.status = FemRunStatus::WriteFailed;
    report.message = e.what();
    return report;
  }
  report.writeSeconds = secondsSince(t0);
  report.status = FemRunStatus::Success;
  return report;
}

/// Cauchy stress, det F and the largest stretch at the nodes (averaged
/// within each region, fem::recoverFiniteStrainNodalField), and the Cauchy
/// stress at each element's integration points for gauss_stresses.csv.
DeckResults largeDeformationStresses(const fem::Mesh& mesh, const fem::HyperelasticTable& materials,
                                     const Eigen::VectorXd& u, int defaultPoints, int nodalPoints)
{
  DeckResults out;
  const fem::FiniteStrainNodalField field = fem::recoverFiniteStrainNodalField(mesh, materials, u, nodalPoints);
  out.nodalStress = field.cauchy;
  out.extraArrays = {{"det_F", field.detF.transpose()}, {"largest_stretch", field.maxStretch().transpose()}};
  for (std::size_t e = 0; e < mesh.elements.size(); ++e)
  {
    std::vector<fem::StressPoint> points;
    for (const fem::FiniteStrainPoint& p :
         fem::recoverFiniteStrainAtGaussPoints(mesh, materials, u, int(e), defaultPoints))
      points.push_back({p.natural, p.world, p.greenLagrange, p.cauchy});
    out.gaussStress.push_back(std::move(points));
  }
  return out;
}

/// The deck's large-deformation step (*STEP, NLGEOM): Newton in the deck's
/// increments; only a converged step is written as a result, a failed one
/// leaves its increment log and a message.
FemRunReport solveLargeDeformation(const fem::CalculixModel& model, const fs::path& outDir,
                                   const FemRunOptions& options, FemRunReport& report)
{
  fem::AssemblyOptions assembly;
  assembly.threads = options.threads;
  const fem::HyperelasticTable materials = largeDeformationMaterials(model);
  fem::NonlinearStaticAnalysis analysis(model.mesh, materials, model.constraints, assembly);
  fem::NewtonOptions newton;
  fem::NonlinearResult r;
  const auto t0 = Clock::now();
  try
  {
    r = analysis.solve(model.load, incrementsOf(model.step), newton, [&](const fem::NewtonIteration& it) {
      if (options.progress)
        options.progress(it);
      return !(options.cancel && options.cancel());
    });
  }
  catch (const std::exception& e)
  {
    report.status = FemRunStatus::InvalidInput;
    report.message = deckMessage(e, model);
    return report;
  }
  report.times.factor = secondsSince(t0); // the whole Newton solve
  report.largeDeformation = true;
  report.increments = 0;
  for (const auto& i : r.increments)
    report.increments += i.accepted ? 1 : 0;
  report.iterations = int(r.iterations.size());
  report.check = r.check;
  DeckResults results;
  try
  {
    const fs::path log = writeIncrementLog(outDir, r);
    if (r.status != fem::NonlinearStatus::Converged)
    {
      report.status =
        r.status == fem::NonlinearStatus::Cancelled ? FemRunStatus::Cancelled : FemRunStatus::NotConverged;
      const int worst = r.failedElement >= 0 ? r.failedElement : r.check.minDetFElement;
      report.message = r.message;
      if (worst >= 0 && std::size_t(worst) < model.elementIds.size())
        report.message += " [element " + std::to_string(worst) + " is element " +
                          std::to_string(model.elementIds[std::size_t(worst)]) + " of the deck]";
      report.message += " (the increments are in " + log.string() + "; no result was written)";
      report.files = {log};
      return report;
    }
    const auto t1 = Clock::now();
    results = largeDeformationStresses(model.mesh, materials, r.displacements, assembly.gaussPointsPerDirection,
                                       options.stressPointsPerDirection);
    report.recoverSeconds = secondsSince(t1);
    results.extraFiles = {log};
  }
  catch (const std::exception& e)
  {
    report.status = FemRunStatus::WriteFailed;
    report.message = e.what();
    return report;
  }
  return writeResults(model, r.displacements, results, outDir, report);
}

} // namespace

namespace {

/// DOFs of nodes in no element carry no stiffness: fix those nothing else
/// holds (ccx leaves them out of the system). Per DOF, as an auxiliary node
/// of an *EQUATION often has only its x prescribed.
void fixDofsNothingHolds(fem::CalculixModel& model)
{
  const Eigen::Index dofs = model.mesh.dofCount();
  std::vector<char> used(std::size_t(dofs), 0);
  auto use = [&](int node, int direction) {
    if (node >= 0 && node < model.mesh.nodeCount() && direction >= 0 && direction < 3)
      used[std::size_t(3 * node + direction)] = 1;
  };
  for (const auto& el : model.mesh.elements)
    for (int n : el.nodes)
      for (int d = 0; d < 3; ++d)
        use(n, d);
  for (const auto& p : model.constraints.prescribed)
    use(p.node, p.direction);
  for (const auto& s : model.constraints.sutures)
    for (int d = 0; d < 3; ++d)
    {
      use(s.node, d);
      use(s.target, d);
    }
  for (const auto& eq : model.constraints.equations)
    for (const auto& t : eq.terms)
      use(t.node, t.direction);
  for (Eigen::Index k = 0; k < dofs; ++k)
    if (!used[std::size_t(k)])
      model.constraints.fix(int(k / 3), int(k % 3));
}

/// Why the prepared analysis failed, in the deck's terms: a model that is
/// not positive definite names the deck's node that is free to move.
void reportPrepareFailure(const fem::CalculixModel& model, const fem::LinearStaticAnalysis& analysis,
                          fem::SolverStatus status, FemRunReport& report)
{
  report.status =
    status == fem::SolverStatus::NotPositiveDefinite ? FemRunStatus::Unconstrained : FemRunStatus::SolverFailed;
  report.message = analysis.message();
  // The analysis numbers CAPS nodes from 0: name the deck's node.
  const Eigen::Index col = analysis.solver().failedColumn();
  const fem::ConstraintMap& map = analysis.constraintMap();
  if (status == fem::SolverStatus::NotPositiveDefinite && col >= 0 && col < map.reducedCount())
  {
    const int dof = map.masterOf[std::size_t(col)];
    report.message = "the model is not sufficiently constrained (rigid-body motion or a loose part): node " +
                     deckNode(model, dof / 3) + " of the deck is free to move in " + "xyz"[dof % 3] +
                     "; fix or suture more nodes" +
                     (map.hasGeneralRows() ? " (or check that the equations do not leave it free)" : "") +
                     " [solver: " + analysis.solver().message() + "]";
  }
}

/// The linear solve: the load vector (one thread over the elements) beside
/// the assembly and factorization, which leave a core idle while they build
/// K's pattern; the same vector as analysis.solve(model.load) would make.
/// False, with the report filled, when the model cannot be solved.
bool solveLinear(const fem::CalculixModel& model, fem::LinearStaticAnalysis& analysis,
                 const fem::AssemblyOptions& assembly, Eigen::VectorXd& u, FemRunReport& report)
{
  Eigen::VectorXd load;
  std::exception_ptr loadError;
  std::thread loadThread([&]() {
    try
    {
      fem::AssemblyOptions one = assembly;
      one.threads = 1;
      load = fem::assembleLoadVector(model.mesh, model.materials, model.load, one);
    }
    catch (...)
    {
      loadError = std::current_exception();
    }
  });
  fem::SolverStatus status = fem::SolverStatus::InvalidInput;
  try
  {
    status = analysis.prepare();
  }
  catch (...)
  {
    loadThread.join();
    throw;
  }
  loadThread.join();
  report.times = analysis.times();
  if (status != fem::SolverStatus::Success)
  {
    reportPrepareFailure(model, analysis, status, report);
    return false;
  }
  if (loadError)
    std::rethrow_exception(loadError);
  u = analysis.solve(Eigen::MatrixXd(load)).col(0);
  report.times = analysis.times();
  return true;
}

/// Every element's own points, on the analysis's threads; the nodal
/// stresses are extrapolated from the same points when each element's rule
/// is the same for both (a deck's C3D20 and C3D20R always are).
DeckResults linearStresses(const fem::CalculixModel& model, const Eigen::VectorXd& u,
                           const fem::AssemblyOptions& assembly, const FemRunOptions& options)
{
  DeckResults results;
  results.gaussStress = fem::recoverStressAtAllGaussPoints(model.mesh, model.materials, u,
                                                           assembly.gaussPointsPerDirection, options.threads);
  const bool samePoints = std::all_of(model.mesh.elements.begin(), model.mesh.elements.end(), [&](const auto& el) {
    return fem::integrationPointsOf(el, options.stressPointsPerDirection) ==
           fem::integrationPointsOf(el, assembly.gaussPointsPerDirection);
  });
  results.nodalStress = samePoints ? fem::nodalStressesFromGaussPoints(model.mesh, model.materials, results.gaussStress,
                                                                       options.stressPointsPerDirection)
                                       .stress
                                   : fem::recoverNodalStresses(model.mesh, model.materials, u,
                                                               options.stressPointsPerDirection, options.threads)
                                       .stress;
  return results;
}

} // namespace

FemRunReport SimulateLogic::solveDeck(const fs::path& deck, const fs::path& outDir, const FemRunOptions& options)
{
  FemRunReport report;
  fem::CalculixModel model;
  auto t0 = Clock::now();
  try
  {
    model = fem::readCalculixInput(deck.string());
  }
  catch (const std::exception& e)
  {
    report.message = e.what();
    return report;
  }
  report.readSeconds = secondsSince(t0);
  report.nodes = model.mesh.nodeCount();
  report.elements = Eigen::Index(model.mesh.elements.size());
  report.dofs = model.mesh.dofCount();
  fixDofsNothingHolds(model);
  if (model.step.nlgeom)
    return solveLargeDeformation(model, outDir, options, report);

  fem::AssemblyOptions assembly;
  assembly.threads = options.threads;
  fem::LinearStaticAnalysis analysis(model.mesh, model.materials, model.constraints, assembly);
  Eigen::VectorXd u;
  try
  {
    if (!solveLinear(model, analysis, assembly, u, report))
      return report;
  }
  catch (const std::exception& e)
  {
    report.status = FemRunStatus::InvalidInput;
    report.message = deckMessage(e, model);
    return report;
  }

  t0 = Clock::now();
  DeckResults results;
  try
  {
    results = linearStresses(model, u, assembly, options);
  }
  catch (const std::exception& e)
  {
    report.status = FemRunStatus::InvalidInput;
    report.message = deckMessage(e, model);
    return report;
  }
  report.recoverSeconds = secondsSince(t0);
  return writeResults(model, u, results, outDir, report);
}

} // namespace caps
