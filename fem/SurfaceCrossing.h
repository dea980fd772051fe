#pragma once
/// @file SurfaceCrossing.h
/// @brief Whether a deformed body passes through itself: its boundary
/// surface tested for faces that cross each other.

#include "fem/FacePressure.h"
#include "fem/Mesh.h"

#include <Eigen/Core>

#include <vector>

namespace caps::fem {

/// What checkSurfaceCrossings() found.
struct SurfaceCrossingCheck
{
  /// Pairs of surface triangles that cross each other deeper than
  /// depthTolerance (0: the boundary does not pass through itself at the
  /// resolution it was sampled at).
  int crossingPairs = 0;
  /// Pairs that cross by at most depthTolerance: surfaces that lie on each
  /// other (an undermined flap sliding on the plane below it) and cross
  /// where the sampled surfaces' chords do.
  int shallowPairs = 0;
  double depthTolerance = 0.0; ///< mm
  /// The deepest crossing: how deep (mm), its boundary faces (into the
  /// faces given) and a point on it, deformed (mm); 0, -1 when none.
  double deepest = 0.0;
  int faceA = -1, faceB = -1;
  Eigen::Vector3d where = Eigen::Vector3d::Zero();
  int triangles = 0; ///< triangles tested
};

/**
 * @brief The boundary @a faces of @a mesh under the displacements @a u,
 *        sampled at @a resolution steps per face edge (the faces' own
 *        quadratic interpolation, DisplaySurface), tested pairwise for
 *        triangles that cross each other.
 *
 * det F > 0 at every integration point says each element is a body; it does
 * not say two parts of the body stay apart. A flap folded back onto itself,
 * or a wound wall pushed through the one facing it, passes every element
 * check and is still not a physical deformation: the model has no contact.
 *
 * Surface points that meet in the deformed state (the two sides of a
 * sutured wound, which the constraints bring together exactly) are welded
 * first: their positions agree to @a weldTolerance (relative to the
 * surface's size). Triangles sharing a welded vertex are neighbours and are
 * not tested. Two triangles cross when an edge of one passes through the
 * interior of the other (Möller & Trumbore, J. Graphics Tools 2(1), 1997,
 * for the segment against the triangle); touching without crossing, or
 * lying in one plane, is not counted. A crossing's depth is the lesser
 * reach of either triangle through the other's plane; crossings no deeper
 * than @a depthTolerance (mm) are counted apart, as surfaces lying on each
 * other. Candidates come from a uniform grid of
 * the triangles' bounding boxes, so the cost grows with the surface, not
 * its square.
 *
 * Throws std::invalid_argument for a wrong size of @a u or a resolution
 * below 1 (and what DisplaySurface throws for bad faces).
 */
SurfaceCrossingCheck checkSurfaceCrossings(const Mesh& mesh, const std::vector<ElementFace>& faces,
                                           const Eigen::VectorXd& u, double depthTolerance = 0.0, int resolution = 2,
                                           double weldTolerance = 1e-7);

} // namespace caps::fem
