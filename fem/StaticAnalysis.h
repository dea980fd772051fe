#pragma once

#include "fem/Assembly.h"
#include "fem/Constraints.h"
#include "fem/FacePressure.h"
#include "fem/Mesh.h"
#include "fem/MuscleLoad.h"
#include "fem/SparseCholeskySolver.h"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <string>
#include <utility>
#include <vector>

namespace caps::fem {

/// One load condition (§4.6.1 step 3): nodal forces, gravity, muscles and
/// pressures on element faces.
struct LoadCase
{
  std::vector<std::pair<int, Eigen::Vector3d>> nodalForces; ///< (node, force N)
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();        ///< acceleration, mm/s^2
  std::vector<Muscle> muscles;                              ///< muscle force functions (eq. 4.40-4.42), summed
  std::vector<FacePressure> facePressures;                  ///< uniform pressures (MPa) on element faces
};

/// Wall-clock seconds of each phase of the last prepare()/solve().
struct PhaseTimes
{
  double assemble = 0.0;  ///< master-slave map, K's pattern, element stiffnesses into K
  double constrain = 0.0; ///< K̄'s pattern, K̄ = T^T K T, K g
  double analyse = 0.0;   ///< ordering and symbolic factorization (on its own thread, beside assemble)
  double factor = 0.0;    ///< numeric factorization
  double solve = 0.0;     ///< loads, reduction, substitution, expansion (last solve())
};

/// The nodal forces of a full force vector @a f (3N, N) as a load case:
/// one entry per node with a force (a computed load such as a pre-stress's
/// balance or a released traction, applied through either analysis).
LoadCase nodalLoadCase(const Eigen::VectorXd& f);

/// Full load vector R (3N) of @a load on @a mesh (eq. 4.35-4.42): nodal
/// forces, gravity (each region's density from @a materials), face
/// pressures on the undeformed faces, muscle forces. Throws
/// std::invalid_argument for a force on a node the mesh does not have.
Eigen::VectorXd assembleLoadVector(const Mesh& mesh, const MaterialTable& materials, const LoadCase& load,
                                   const AssemblyOptions& options = {});

/// Tells @a solver to order the reduced system of @a map on @a mesh by nodes
/// (a node's DOFs together), nested dissection on the element vertices only,
/// each mid-edge node beside its edge: far cheaper to analyse than the DOF
/// graph, with the same fill. Shared by the linear and nonlinear analyses.
void useNodeGroupedOrdering(const Mesh& mesh, const ConstraintMap& map, SparseCholeskySolver& solver);

/**
 * @brief Linear static analysis K U = R with constraints by master-slave
 *        elimination, factored once and solved for any number of load cases.
 *
 * prepare() validates the mesh, assembles K, builds U = T Ubar + g, reduces
 * to K̄ = T^T K T and factors it with CHOLMOD. It returns the solver status;
 * a model left with rigid-body freedom gives NotPositiveDefinite and a
 * message naming the node and direction that is free. Bad input throws
 * (std::invalid_argument, ElementError) with a message naming the culprit;
 * status() is then InvalidInput and message() the same text.
 */
class LinearStaticAnalysis
{
public:
  LinearStaticAnalysis(Mesh mesh, MaterialTable materials, Constraints constraints, AssemblyOptions options = {});

  SolverStatus prepare();
  SolverStatus status() const { return status_; }
  const std::string& message() const { return message_; }

  /// Full load vector R (3N) of @a load.
  Eigen::VectorXd loadVector(const LoadCase& load) const;
  /// Displacements U (3N x cases) for full load vectors @a r (3N x cases).
  /// Throws std::logic_error unless prepare() succeeded.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& r);
  /// Displacements (3N) of one load case.
  Eigen::VectorXd solve(const LoadCase& load);
  /// Displacements (3N x cases) for full load vectors @a r under
  /// @a constraints: the same DOFs prescribed, the same sutures and equations
  /// with the same coefficients as the model was prepared with, other
  /// prescribed values and equation right-hand sides (a submodel's boundary
  /// moved by the model around it, a fingertip's travel). K̄ does not change,
  /// so the factorization is reused: U = T Ū + g', K̄ Ū = T^T (R - K g').
  /// Throws std::invalid_argument when @a constraints constrain other DOFs,
  /// std::logic_error unless prepare() succeeded.
  Eigen::MatrixXd solveWithPrescribed(const Eigen::MatrixXd& r, const Constraints& constraints);

  /// Internal nodal forces K U (N, 3N) of displacements @a u (3N). Where no
  /// load acts, they are the reactions of the constraints: at a fixed node
  /// the force the support exerts, at a sutured node the force its suture
  /// carries (thesis eq. 4.43: the suture is a constraint). Throws
  /// std::logic_error unless prepare() assembled K, std::invalid_argument if
  /// @a u has the wrong size.
  Eigen::VectorXd internalForces(const Eigen::VectorXd& u) const;

  const PhaseTimes& times() const { return times_; }
  const Mesh& mesh() const { return mesh_; }
  const MaterialTable& materials() const { return materials_; }
  const ConstraintMap& constraintMap() const { return map_; }
  /// Upper triangle of the full K (3N x 3N).
  const Eigen::SparseMatrix<double>& stiffness() const { return k_; }
  /// Upper triangle of K̄.
  const Eigen::SparseMatrix<double>& reducedStiffness() const { return kbar_; }
  /// The factorization (flop count, fill, CHOLMOD's peak memory).
  const SparseCholeskySolver& solver() const { return solver_; }

private:
  SolverStatus prepareStages();
  /// U = T Ū + g with K̄ Ū = T^T (R − K g): @a kg = K g, g and T from @a prescribed.
  Eigen::MatrixXd substitute(const Eigen::MatrixXd& r, const Eigen::VectorXd& kg, const ConstraintMap& prescribed);

  Mesh mesh_;
  MaterialTable materials_;
  Constraints constraints_;
  AssemblyOptions options_;
  Eigen::SparseMatrix<double> k_, kbar_;
  ConstraintMap map_;
  Eigen::VectorXd kg_; ///< K g
  SparseCholeskySolver solver_;
  SolverStatus status_ = SolverStatus::InvalidInput;
  std::string message_ = "prepare() has not been called";
  PhaseTimes times_;
};

} // namespace caps::fem
