#pragma once

#include "fem/ElementNumbering.h"
#include "fem/Hex20Shape.h"

#include <Eigen/Core>

namespace caps::fem {

/**
 * @brief Interpolation functions of the native 15-node serendipity wedge
 *        (the curved 5-sided element of thesis §3.1.3, Fig. 3.2, without
 *        collapsing a hexahedron).
 *
 * With area coordinates L = (1 - r - s, r, s) and tau = t_k t (node numbering
 * in ElementNumbering.h):
 *   - corner k at triangle vertex i: h_k = L_i (1 + tau) (2 L_i - 2 + tau) / 2,
 *   - mid-edge k of triangle edge i-j: h_k = 2 L_i L_j (1 + tau),
 *   - mid-edge k along t at vertex i:  h_k = L_i (1 - t^2),
 * i.e. quadratic triangles times quadratic lines, less the terms that would
 * need face and centre nodes (the same serendipity family as eq. 4.16).
 * These are CalculiX's C3D15 functions (shape15w) in another node order.
 *
 * Results use the 20-slot vectors of Hex20Shape; slots 15..19 are 0, so the
 * element integrators treat a wedge like a hexahedron without those nodes.
 */
class Wedge15Shape
{
public:
  /// h_k(r, s, t) into @a h (slots 15..19 zero).
  void values(const Eigen::Vector3d& rst, ShapeVector& h) const;
  /// h_k and their natural derivatives (d/dr, d/ds, d/dt) at (r, s, t).
  void evaluate(const Eigen::Vector3d& rst, ShapeVector& h, ShapeDerivatives& dh) const;
};

} // namespace caps::fem
