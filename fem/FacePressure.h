#pragma once

#include "fem/ElasticityIntegrator.h"
#include "fem/ElementNumbering.h"
#include "fem/ElementShape.h"
#include "fem/Mesh.h"
#include "fem/Quadrature.h"

#include <Eigen/Core>

#include <vector>

namespace caps::fem {

/**
 * @brief A uniform pressure on one face of one element: a surface load, the
 *        companion of the body forces of thesis §4.6.2 (eq. 4.35-4.39).
 *
 * Faces are numbered exactly as CalculiX/Abaqus number the faces of the
 * element's type (the Pn of *DLOAD), so a deck and a FacePressure name the
 * same face. A hexahedron (ElementKind::Hex20, including the degenerate
 * wedge of Fig. 3.2) has the C3D20 faces 1..6, in the natural coordinates
 * of the Bathe element (which C3D20 shares):
 *
 *   face 1: t = -1 (C3D20 nodes 1-2-3-4)   face 2: t = +1 (5-8-7-6)
 *   face 3: s = -1 (1-5-6-2)               face 4: r = +1 (2-6-7-3)
 *   face 5: s = +1 (3-7-8-4)               face 6: r = -1 (4-8-5-1)
 *
 * (thesis Table 4.8 numbers the same faces 1, 0, 4, 5, 2, 3 from 0). A
 * native wedge (ElementKind::Wedge15) has the C3D15 faces 1..5: 1 the
 * triangle t = -1 (1-2-3), 2 the triangle t = +1 (4-5-6), 3 s = 0
 * (1-2-5-4), 4 r + s = 1 (2-3-6-5), 5 r = 0 (3-1-4-6).
 *
 * Positive pressure pushes into the element (compression), as in CalculiX:
 * the traction is -p n with n the outward normal.
 */
struct FacePressure
{
  int element = -1;      ///< index into Mesh::elements
  int face = 0;          ///< 1..6 for a hexahedron, 1..5 for a native wedge
  double pressure = 0.0; ///< MPa = N/mm^2, positive into the element
};

/// One face of one element, numbered as FacePressure numbers them (the
/// CalculiX faces: 1..6 of a hexahedron, 1..5 of a native wedge; thesis
/// Table 4.8 numbers the hexahedron's faces 1, 0, 4, 5, 2, 3 from 0).
struct ElementFace
{
  int element = -1;
  int face = 0;
};

/// Number of faces of an element of @a kind: 6 (Hex20) or 5 (Wedge15).
int faceCount(ElementKind kind);

/// Node slots (ascending) on face @a face of an element of @a kind: 8 on a
/// quadrilateral face (4 corners, 4 mid-sides), 6 on a triangle of a native
/// wedge. Throws std::invalid_argument for a face outside 1..faceCount(kind).
std::vector<int> faceNodes(ElementKind kind, int face);

/// A face as a linear map of the natural coordinates, xi = origin + a p + b q
/// with a, b in [-1, 1], or for a triangle a, b >= 0, a + b <= 1. sign = +1
/// if p × q points out of the reference element, so stepping a then b (Table
/// 4.8's scan directions) winds polygons outwards.
struct FaceChart
{
  Eigen::Vector3d origin, p, q;
  bool triangle = false;
  double sign = 1.0;
};
/// The chart of face @a face (CalculiX numbering) of an element of @a kind.
/// Throws std::invalid_argument for a face outside 1..faceCount(kind).
FaceChart faceChart(ElementKind kind, int face);

/**
 * @brief Consistent nodal forces of a uniform pressure on one face of one
 *        element: R_k = -p ∫ h_k n dA.
 *
 * The face is the curved surface x(a, b) of the element's own interpolation
 * (Table 4.1, eq. 4.16, or the wedge functions) on the face, so any subset
 * of mid-side nodes is honoured. n dA = ±(dx/da × dx/db) da db, the sign
 * chosen so n points out of an element with positive det J. Because n dA is
 * not normalised, h_k (dx/da × dx/db) is a polynomial: of degree <= 5 in
 * each of a, b on any 8-node face, flat or curved, so the 3-point Gauss
 * rule @a rule along each direction (which ccx also uses on C3D20 faces)
 * integrates a uniform pressure exactly; a triangle of a native wedge is
 * integrated with the same points collapsed onto it (Duffy), exact too for
 * its degree-4 integrand. A face collapsed to an edge (the degenerate side
 * of a Fig. 3.2 wedge) has zero area and gets zero load; a triangular face
 * of such a wedge is integrated as the collapsed quad it is.
 *
 * @a re (60) is overwritten; rows of nodes off the face and absent nodes are 0.
 * Throws std::invalid_argument for a face outside 1..faceCount().
 */
void assembleElementFacePressure(const ElementShape& shape, const ElementCoordinates& x, int face, double pressure,
                                 const LineRule& rule, ElementVector& re);

/// Area (mm^2) of face @a face of one element, by the same rule (not exact
/// on curved faces: |n| is not polynomial).
double elementFaceArea(const ElementShape& shape, const ElementCoordinates& x, int face, const LineRule& rule);

/**
 * @brief Checks face loads against @a mesh. Throws std::invalid_argument
 *        naming the load (its index in @a loads) for an element index out of
 *        range, a face the element does not have, or a non-finite pressure.
 */
void validateFacePressures(const Mesh& mesh, const std::vector<FacePressure>& loads);

/**
 * @brief Global load vector (3N, N) of the face pressures @a loads, each
 *        integrated with the @a pointsPerDirection Gauss points along each
 *        face direction (3: exact, see assembleElementFacePressure()).
 *        Validates @a loads first (validateFacePressures); the mesh is
 *        assumed validated (validateMesh).
 */
Eigen::VectorXd assembleFacePressureLoad(const Mesh& mesh, const std::vector<FacePressure>& loads,
                                         int pointsPerDirection = 3);

} // namespace caps::fem
