#pragma once

#include "fem/CalculixReader.h"
#include "fem/Constraints.h"
#include "fem/HyperelasticMaterial.h"
#include "fem/Mesh.h"
#include "fem/StaticAnalysis.h"

#include <Eigen/Core>

#include <string>

namespace caps::fem {

/// What calculixInput() writes beyond the model: the rule of elements that
/// leave it to the analysis, and the large-deformation step.
struct CalculixExportOptions
{
  /// Points per direction of the analysis to reproduce, for elements whose
  /// integrationPoints is 0 (AssemblyOptions::gaussPointsPerDirection): 2
  /// writes their 20-node bricks as C3D20R.
  int defaultIntegrationPoints = 3;
  /// The step. With step.nlgeom (or any region in @a hyperelastic, which
  /// ccx solves nonlinearly anyway) the deck has *STEP, NLGEOM, INC= enough
  /// for every increment down to the minimum, and *STATIC[, DIRECT] with
  /// the line initial, period, minimum, maximum increment.
  StaticStep step;
  /// Regions written as *HYPERELASTIC (NEO HOOKE: C10, D1; MOONEY-RIVLIN:
  /// C10, C01, D1) or, for St. Venant-Kirchhoff, *ELASTIC (its law under
  /// NLGEOM); Veronda-Westmann has no ccx keyword and throws. Density comes
  /// from the MaterialTable, as for the gravity load.
  HyperelasticTable hyperelastic;
  /// In an NLGEOM step, *CONTROLS that make ccx's Newton iterations converge
  /// to residuals of 1e-8 of the average force and corrections of 1e-8 of
  /// the increment (ccx's defaults: 0.005 and 0.01), for comparisons to
  /// 1e-5 relative displacement.
  bool tightControls = false;
};

/**
 * @brief The model as a CalculiX (ccx) input deck, so any CAPS analysis can
 *        be checked by an independent solver.
 *
 * Nodes and elements are numbered from 1 (CAPS index + 1). 20-node elements
 * are C3D20 with the node order translated (batheToC3D20); elements without
 * any mid-side node are C3D8; degenerate wedges stay degenerate C3D20;
 * native 15-node wedges are C3D15 (node order translated by wedge15ToC3D15;
 * ccx integrates them with the 9-point rule of wedgeRule(2), whatever the
 * element's integrationPoints). A 20-node brick integrated with 2 points per
 * direction (integrationPointsOf(element, options.defaultIntegrationPoints))
 * is C3D20R, ccx's reduced 2x2x2 brick; C3D8 is always ccx's 2x2x2.
 * Numbers have 13 significant digits, so no field exceeds the 20
 * characters ccx reads (it silently cuts longer ones); coordinates within
 * 1e-13 of the largest one of zero are written as 0. One ELSET R<id>,
 * MATERIAL M<id> and SOLID SECTION per region. Constraints are written as
 * resolved by resolveConstraints(), i.e. the same U = T Ubar + g:
 * prescribed DOFs (also those sutured onto prescribed ones) as *BOUNDARY,
 * sutured DOFs as *EQUATION u_i - u_m - beta u_aux = 0 where the auxiliary
 * node (number N + 1, in no element) has its x DOF fixed to 1. A node
 * repeated in a degenerate (wedge) element is kept independent in the
 * equations where possible: ccx 2.20 gives wrong results when such a node is
 * the dependent DOF (measured: 76 % off against the merged mesh). Loads:
 * *CLOAD (muscles as their consistent nodal loads), *DLOAD GRAV per region,
 * *DLOAD Pn face pressures (summed per element face; our face numbers are
 * ccx's). Output: *NODE FILE U (.frd) and *NODE PRINT U (.dat, one more
 * digit than the .frd).
 *
 * Throws std::invalid_argument for an element with only some mid-side nodes
 * (no C3D20 equivalent).
 */
std::string calculixInput(const Mesh& mesh, const MaterialTable& materials, const Constraints& constraints,
                          const LoadCase& load, const CalculixExportOptions& options);
/// The same with the default options (a linear step, the elements' own rules or 3x3x3).
std::string calculixInput(const Mesh& mesh, const MaterialTable& materials, const Constraints& constraints,
                          const LoadCase& load);

/// Writes calculixInput() to @a path; throws std::runtime_error if it cannot.
void writeCalculixInput(const std::string& path, const Mesh& mesh, const MaterialTable& materials,
                        const Constraints& constraints, const LoadCase& load,
                        const CalculixExportOptions& options = {});

/**
 * @brief Nodal displacements of the last DISP block of a ccx .frd result
 *        file (ASCII), one column per CAPS node (0..nodeCount-1). Throws
 *        std::runtime_error if the file is unreadable, has no DISP block, or
 *        lacks one of the nodes. The .frd holds 6 significant digits.
 */
Eigen::Matrix3Xd readFrdDisplacements(const std::string& path, Eigen::Index nodeCount);

/// The same from the *NODE PRINT table of a ccx .dat file (7 significant digits).
Eigen::Matrix3Xd readDatDisplacements(const std::string& path, Eigen::Index nodeCount);

} // namespace caps::fem
