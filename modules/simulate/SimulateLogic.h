#pragma once
/// @file SimulateLogic.h
/// @brief Logic of the Simulate module: a CalculiX/Abaqus deck in, the
///        solved displacements and stresses out (CSV, VTU); no widgets.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "fem/NonlinearStaticAnalysis.h"
#include "fem/StaticAnalysis.h"
#include "modules/core/Module.h"

namespace caps {

/// Outcome of a batch analysis.
enum class FemRunStatus
{
  Success,
  InvalidInput,  ///< the deck or the model is bad (unsupported keyword, bad element, ...)
  Unconstrained, ///< rigid-body freedom left: the stiffness is singular
  SolverFailed,  ///< the sparse solver failed otherwise
  NotConverged,  ///< the large-deformation step did not converge: no result written
  Cancelled,     ///< stopped by the user: no result written
  WriteFailed    ///< the results could not be written
};

struct FemRunOptions
{
  int threads = 2;                  ///< assembly threads
  int stressPointsPerDirection = 2; ///< Gauss points the nodal stresses are extrapolated from
  /// After every Newton iteration of a large-deformation step (progress).
  std::function<void(const fem::NewtonIteration&)> progress;
  /// Asked after every Newton iteration; true stops the solve (Cancelled).
  std::function<bool()> cancel;
};

/// What solveDeck() did: status, message and the numbers worth printing.
struct FemRunReport
{
  FemRunStatus status = FemRunStatus::InvalidInput;
  std::string message;
  Eigen::Index nodes = 0, elements = 0, dofs = 0;
  double readSeconds = 0.0, recoverSeconds = 0.0, writeSeconds = 0.0;
  fem::PhaseTimes times;
  double maxDisplacement = 0.0;       ///< largest |u| (mm)
  long maxDisplacementNode = 0;       ///< its node number in the deck
  double maxVonMises = 0.0;           ///< largest nodal von Mises stress (MPa)
  bool largeDeformation = false;      ///< solved by Newton (*STEP, NLGEOM); times.factor is the whole solve
  int increments = 0, iterations = 0; ///< accepted increments, Newton iterations in all
  fem::DeformationCheck check;        ///< smallest det F, stretches (large deformation)
  std::vector<std::filesystem::path> files;
};

class SimulateLogic : public ModuleLogic
{
public:
  using ModuleLogic::ModuleLogic;

  /// Reads @a deck (fem::readCalculixInput), solves it (fem::LinearStaticAnalysis),
  /// recovers nodal stresses (fem::recoverNodalStresses) and writes into
  /// @a outDir (created if needed) displacements.csv (node, x, y, z, ux, uy,
  /// uz), stresses.csv (node, sxx, syy, szz, sxy, syz, szx, von Mises),
  /// gauss_stresses.csv (element, point 1..n in CalculiX's order, sxx, syy,
  /// szz, sxy, sxz, syz: the columns of ccx's *EL PRINT S, at each element's
  /// own integration points) and result.vtu. A large-deformation step
  /// (*STEP, NLGEOM, or a *HYPERELASTIC material) is solved by
  /// fem::NonlinearStaticAnalysis in the deck's *STATIC increments (a region
  /// with *ELASTIC is St. Venant-Kirchhoff, as in CalculiX); its stresses are
  /// Cauchy stresses, result.vtu also holds det F and the largest stretch,
  /// and increments.csv logs every increment; a step that does not converge
  /// writes only that log (NotConverged). DOFs of nodes in no element that
  /// nothing constrains are fixed (they carry no stiffness; ccx leaves them
  /// at zero too). Never throws: errors come back as the status and a
  /// message naming the culprit.
  static FemRunReport solveDeck(const std::filesystem::path& deck, const std::filesystem::path& outDir,
                                const FemRunOptions& options = {});
};

} // namespace caps
