#pragma once

#include "fem/Constraints.h"
#include "fem/HyperelasticMaterial.h"
#include "fem/LinearElasticMaterial.h"
#include "fem/Mesh.h"
#include "fem/StaticAnalysis.h"

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace caps::fem {

/// A deck that cannot be read: names the file, the line and the culprit.
class InputDeckError : public std::runtime_error
{
public:
  InputDeckError(const std::string& source, int line, const std::string& what)
    : std::runtime_error(source + ":" + std::to_string(line) + ": " + what), line_(line)
  {}
  int line() const { return line_; }

private:
  int line_;
};

/// The deck's step: *STEP (NLGEOM or not) and the increment line of *STATIC
/// (initial increment, step period, minimum and maximum increment), as
/// fractions of the step period when the period is 1.
struct StaticStep
{
  bool nlgeom = false; ///< *STEP, NLGEOM: large deformation
  double initialIncrement = 1.0;
  double period = 1.0;
  double minimumIncrement = 1e-5;
  double maximumIncrement = 1.0;
  bool direct = false; ///< *STATIC, DIRECT: fixed increments, no cut-back
};

/// A model read from a CalculiX/Abaqus input deck.
struct CalculixModel
{
  Mesh mesh;
  /// Region id = index of the material in the deck (0, 1, ...). A material
  /// given by *HYPERELASTIC is here as its small-strain limit
  /// (HyperelasticMaterial::smallStrainLimit()) and in @a hyperelastic.
  MaterialTable materials;
  HyperelasticTable hyperelastic; ///< regions whose material is *HYPERELASTIC
  StaticStep step;
  Constraints constraints;
  LoadCase load;
  std::vector<long> nodeIds;              ///< deck number of each CAPS node
  std::vector<long> elementIds;           ///< deck number of each CAPS element
  std::vector<std::string> materialNames; ///< by region id
};

/// How parseCalculixInput() builds elements.
struct CalculixReadOptions
{
  /// C3D15 as native 15-node wedges (ElementKind::Wedge15, the default: the
  /// element ccx itself uses, and far stiffer-free in bending than the
  /// degenerate 20-node wedge of Fig. 3.2, which false selects).
  bool nativeWedges = true;
};

/**
 * @brief Reads the CalculiX/Abaqus `.inp` subset that calculixInput() writes,
 *        and hand-written decks of the same kind.
 *
 * Keywords (case-insensitive; `**` comments; a keyword line ending in a
 * comma continues on the next line): *HEADING, *NODE, *ELEMENT with TYPE
 * C3D20 (3x3x3 points), C3D20R (2x2x2, ccx's reduced brick), C3D15 (a
 * native 15-node wedge with ccx's 9 points, wedgeRule(2); or with
 * options.nativeWedges = false the degenerate 20-node wedge of Fig. 3.2,
 * integrated with the analysis's rule) or C3D8 (corners only, 2x2x2 as
 * ccx), each element's rule in Element::integrationPoints; *NSET and *ELSET
 * (with GENERATE); *MATERIAL with *ELASTIC (isotropic) or *HYPERELASTIC
 * (NEO HOOKE: C10, D1; MOONEY-RIVLIN: C10, C01, D1; other types are
 * refused), and *DENSITY; *SOLID SECTION; *BOUNDARY (node or set, first and
 * last DOF, value; DOFs above 3 are ignored for solids); *CLOAD; *DLOAD GRAV
 * (one acceleration for every element with a density); *DLOAD Pn uniform
 * face pressure (element or element set; P1..P6 for C3D20/C3D20R/C3D8,
 * P1..P5 for C3D15, mapped onto the faces of the degenerate brick unless
 * the wedge is native; pressures repeated on a face add up, as in ccx;
 * *DLOAD parameters such as AMPLITUDE are ignored); *EQUATION of any
 * number of terms (first term dependent, as in ccx): ties u_a,i - u_b,i = 0
 * of all three directions of two coincident nodes, or u_a,i - u_b,i +
 * c u_aux,1 = 0 with an auxiliary node prescribed to (1, 0, 0) where -c
 * equals the coordinate difference (a suture as written by calculixInput())
 * become Constraints::sutures, every other equation a LinearConstraint in
 * Constraints::equations (zero coefficients dropped); one *STEP (NLGEOM
 * read into CalculixModel::step) with *STATIC (DIRECT, and the increment
 * line); *CONTROLS (convergence only), *ORIENTATION and *EXPANSION (every
 * material here is isotropic, and no temperatures are read, so neither
 * changes the result), *NODE FILE, *EL FILE, *NODE PRINT, *EL PRINT
 * accepted and ignored. A field of *BOUNDARY, *CLOAD, *DLOAD or a
 * set's members is a number if it is wholly an integer, else a set name
 * (names may start with a digit: 1E). A step with a hyperelastic material
 * is NLGEOM even without the parameter: ccx 2.20 solves it geometrically
 * nonlinear (measured). Any other keyword, element type or load (e.g.
 * non-uniform pressure PnNU) throws InputDeckError naming it and its line.
 * Nodes in no element (e.g. the auxiliary node) are kept.
 */
CalculixModel parseCalculixInput(const std::string& text, const std::string& sourceName = "input",
                                 const CalculixReadOptions& options = {});

/// Reads @a path; throws std::runtime_error if unreadable, InputDeckError if bad.
CalculixModel readCalculixInput(const std::string& path, const CalculixReadOptions& options = {});

} // namespace caps::fem
