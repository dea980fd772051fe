#pragma once

#include "fem/ElasticityIntegrator.h"
#include "fem/Mesh.h"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <functional>

namespace caps::fem {

/// How the finite-strain elements treat the volume (NonlinearStaticAnalysis;
/// the linear assembly ignores it).
enum class VolumetricFormulation
{
  /// The plain Total Lagrangian displacement element (assembleElementFiniteStrain):
  /// locks when nearly incompressible (nu -> 0.5).
  Displacement,
  /// The three-field u/p~/J~ element with the pressure and dilatation
  /// condensed per element (assembleElementMixedFiniteStrain): does not lock;
  /// needs a split law (not St. Venant-Kirchhoff).
  MixedPressure,
};

struct AssemblyOptions
{
  int threads = 2; ///< worker threads over elements (>= 1)
  /// 3 (Table 4.6, default) or 2. Native wedges take wedgeRule() of the same
  /// level: 3 -> 18 points (full), 2 -> 9 points (lower, CalculiX C3D15).
  int gaussPointsPerDirection = 3;
  /// Finite-strain element formulation (nonlinear analysis only).
  VolumetricFormulation volumetric = VolumetricFormulation::Displacement;
};

/**
 * @brief Global stiffness K (3N x 3N, upper triangle incl. diagonal, compressed).
 *
 * Elements are split into contiguous ranges, one per thread; each thread
 * fills its own triplet list in element order, and the lists are merged in
 * element order, so the matrix is bit-identical for any thread count.
 * Rethrows the ElementError of the lowest-numbered bad element.
 * The mesh is assumed validated (validateMesh).
 */
Eigen::SparseMatrix<double> assembleStiffness(const Mesh& mesh, const MaterialTable& materials,
                                              const AssemblyOptions& options = {});

/// The pattern of assembleStiffness()'s matrix, values zero: known from the
/// connectivity alone, so the solver can analyse it while the values are
/// computed. Column 3n + d holds rows 3m..3m+2 of each neighbour m < n, then
/// 3n..3n+d.
Eigen::SparseMatrix<double> stiffnessPattern(const Mesh& mesh);

/// Fills the values of @a k, which has stiffnessPattern(mesh)'s pattern
/// (throws std::invalid_argument otherwise, on size).
void assembleStiffnessValues(const Mesh& mesh, const MaterialTable& materials, const AssemblyOptions& options,
                             Eigen::SparseMatrix<double>& k);

/// One element's contribution, computed on a worker thread: its matrix into
/// @a ke and its vector into @a re (either null when the assembly does not
/// want it). Element matrices use the slot layout of ElasticityIntegrator.h.
using ElementKernel = std::function<void(std::size_t element, ElementMatrix* ke, ElementVector* re)>;

/**
 * @brief The element loop every assembly shares: @a kernel on each element,
 *        @a threads at a time, scattered in element order into @a k's values
 *        (which must have stiffnessPattern(mesh)'s pattern; zeroed first) and
 *        into @a r (3N, zeroed first), either of which may be null. The sums
 *        are bit-identical for any thread count. Rethrows the exception of
 *        the lowest-numbered failing element.
 */
void assembleElements(const Mesh& mesh, int threads, const ElementKernel& kernel, Eigen::SparseMatrix<double>* k,
                      Eigen::VectorXd* r);

/**
 * @brief Gravity loads (eq. 4.35-4.39): each element's density times
 *        @a acceleration (mm/s^2, e.g. (0, 0, -9810)) integrated over its
 *        volume. Returns a vector of size 3N (N).
 */
Eigen::VectorXd assembleGravityLoad(const Mesh& mesh, const MaterialTable& materials,
                                    const Eigen::Vector3d& acceleration, const AssemblyOptions& options = {});

} // namespace caps::fem
