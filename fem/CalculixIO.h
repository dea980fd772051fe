#pragma once

#include "fem/Constraints.h"
#include "fem/Mesh.h"
#include "fem/StaticAnalysis.h"

#include <Eigen/Core>

#include <string>

namespace caps::fem {

/**
 * @brief The model as a CalculiX (ccx) input deck, so any CAPS analysis can
 *        be checked by an independent solver.
 *
 * Nodes and elements are numbered from 1 (CAPS index + 1). 20-node elements
 * are C3D20 with the node order translated (batheToC3D20); elements without
 * any mid-side node are C3D8; degenerate wedges stay degenerate C3D20;
 * native 15-node wedges are C3D15 (node order translated by wedge15ToC3D15;
 * ccx integrates them with the 9-point rule of wedgeRule(2)). One ELSET R<id>,
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
                          const LoadCase& load);

/// Writes calculixInput() to @a path; throws std::runtime_error if it cannot.
void writeCalculixInput(const std::string& path, const Mesh& mesh, const MaterialTable& materials,
                        const Constraints& constraints, const LoadCase& load);

/**
 * @brief Nodal displacements of the last DISP block of a ccx .frd result
 *        file (ASCII), one column per CAPS node (0..nodeCount-1). Throws
 *        std::runtime_error if the file is unreadable, has no DISP block, or
 *        lacks one of the nodes. The .frd holds 6 significant digits.
 */
Eigen::Matrix3Xd readFrdDisplacements(const std::string& path, Eigen::Index nodeCount);

/// The same from the *NODE PRINT table of a ccx .dat file (7 significant digits).
Eigen::Matrix3Xd readDatDisplacements(const std::string& path, Eigen::Index nodeCount);

}  // namespace caps::fem
