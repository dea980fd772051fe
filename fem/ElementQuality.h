#pragma once
/// @file ElementQuality.h
/// @brief Shape quality of a volume mesh: the scaled Jacobian at the nodes
/// and the integration points of each element, and its edge ratio.

#include "fem/Mesh.h"

#include <Eigen/Core>

namespace caps::fem {

/// Limits below which an element is too badly shaped to trust its answer
/// under large motion. Defaults follow the usual practice of meshing
/// guides (Abaqus and ANSYS warn below a scaled Jacobian of about 0.2 and
/// above an aspect ratio of 10).
struct ElementQualityLimits
{
  double minScaledJacobian = 0.2;
  double maxEdgeRatio = 10.0;
};

/// The quality of one element.
struct ElementQuality
{
  /// Smallest scaled Jacobian over the element's nodes and integration
  /// points: 1 for a cube or an equilateral prism, 0 collapsed, < 0 inverted.
  double scaledJacobian = 1.0;
  Eigen::Vector3d worstPoint = Eigen::Vector3d::Zero(); ///< natural (r, s, t) where it is smallest
  /// Longest over shortest corner-to-corner edge (Verdict's edge ratio); 1
  /// for a cube, 10 for a 20 x 2 x 2 brick.
  double edgeRatio = 1.0;
};

/**
 * @brief The quality of element @a element of @a mesh, with its own
 *        (quadratic) interpolation.
 *
 * Scaled Jacobian at a point (Knupp, "Achieving finite element mesh quality
 * via optimization of the Jacobian matrix norm and associated quantities",
 * Int J Numer Meth Eng 48, 2000; the definitions of the Verdict library that
 * VTK's vtkMeshQuality uses): det J over the product of the lengths of J's
 * rows, dx/dr, dx/ds, dx/dt. On a wedge the triangle's frame is taken at its
 * worst corner and normalised so an equilateral prism scores 1:
 * 2/sqrt(3) det J / (|dx/dt| max(|a||b|, |a||c|, |b||c|)), a = dx/dr,
 * b = dx/ds, c = b - a. Evaluated at every node of the element (where a
 * straight-sided element has its extremes) and at the points of the
 * @a pointsPerDirection rule; the nodes where a degenerate brick (thesis
 * Fig. 3.2) collapses are left out, since it is collapsed there by
 * construction. Throws std::out_of_range for an element not in the mesh.
 */
ElementQuality elementQuality(const Mesh& mesh, int element, int pointsPerDirection = 3);

/// The quality of a whole mesh: its worst elements and how many elements
/// are outside the limits.
struct MeshQualityCheck
{
  int elements = 0;
  double minScaledJacobian = 1.0;
  int worstJacobianElement = -1;
  Eigen::Vector3d worstJacobianAt = Eigen::Vector3d::Zero(); ///< world position (mm)
  double maxEdgeRatio = 1.0;
  int worstEdgeRatioElement = -1;
  Eigen::Vector3d worstEdgeRatioAt = Eigen::Vector3d::Zero(); ///< the element's centre (mm)
  /// Elements below ElementQualityLimits::minScaledJacobian or above
  /// maxEdgeRatio.
  int poorJacobian = 0;
  int poorEdgeRatio = 0;
  int poorElements = 0; ///< outside either limit

  bool withinLimits() const { return poorJacobian == 0 && poorEdgeRatio == 0; }
};

/// elementQuality() over every element of @a mesh, against @a limits.
MeshQualityCheck checkMeshQuality(const Mesh& mesh, const ElementQualityLimits& limits = {},
                                  int pointsPerDirection = 3);

} // namespace caps::fem
